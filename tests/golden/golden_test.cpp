// The golden replays: each stored trace through the controller must give its
// stored reference, tick for tick and bit for bit (tests/golden/README.md).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <string>

#include "tests/golden/golden.hpp"

namespace hyq::golden {
namespace {

struct Replay {
  std::vector<hal::SensorFrame> trace;
  std::vector<hal::CommandFrame> commands;
};

const Replay& stored(const Case& c) {
  static std::map<std::string, Replay> replays;
  auto found = replays.find(c.name);
  if (found != replays.end()) return found->second;
  Replay out;
  std::string error;
  out.trace = readTrace(caseDir(c) + "trace.bin", error);
  EXPECT_EQ(error, "");
  out.commands = replay(out.trace, goldenParams(c));
  return replays.emplace(c.name, std::move(out)).first->second;
}

const Case& named(const char* name) {
  const Case* c = findCase(name);
  EXPECT_NE(c, nullptr) << name;
  return *c;
}

class GoldenReplay : public ::testing::TestWithParam<const char*> {};

TEST_P(GoldenReplay, MatchesTheReference) {
  const Case& c = named(GetParam());
  ASSERT_EQ(stored(c).trace.size(), static_cast<size_t>(c.ticks));
  EXPECT_EQ(compare(caseDir(c) + "reference.csv", stored(c).commands), "")
      << "If the change of behaviour is intended, regenerate with `make golden` and say why in the commit.";
}

// Every trace holds its bad frame's safe hold, its tick gap, a flagged slip,
// a friction estimate, swings and touch-downs.
TEST_P(GoldenReplay, TraceHasItsFaultsSlipsAndSwings) {
  const Case& c = named(GetParam());
  const auto& cmd = stored(c).commands;
  ASSERT_EQ(cmd.size(), static_cast<size_t>(c.ticks));
  bool slip = false, estimate = false, swing = false, touchdown = false;
  for (size_t k = 1; k < cmd.size(); ++k) {
    slip |= cmd[k].telemetry.slip_mask != 0;
    for (double mu : cmd[k].telemetry.mu_hat) estimate |= mu > 0.0;
    swing |= cmd[k].telemetry.stance_mask != 0xF;
    touchdown |= (cmd[k].telemetry.stance_mask & ~cmd[k - 1].telemetry.stance_mask) != 0;
  }
  EXPECT_TRUE(slip);
  EXPECT_TRUE(estimate);
  EXPECT_TRUE(swing);
  EXPECT_TRUE(touchdown);
  EXPECT_TRUE(cmd[c.bad_frame_index].flags & hal::kFlagBadSensorFrame);
  const auto& t = stored(c).trace;
  EXPECT_EQ(t[c.gap_index].tick - t[c.gap_index - 1].tick, static_cast<uint32_t>(c.dropped_frames + 1));
}

INSTANTIATE_TEST_SUITE_P(Cases, GoldenReplay, ::testing::Values("crawl", "trot", "switch"));

// The crawl's trace covers a freeze and its exit.
TEST(GoldenCrawl, TraceHasAFreezeAndItsExit) {
  const auto& cmd = stored(named("crawl")).commands;
  bool freeze = false, unfrozen_after_freeze = false;
  for (const hal::CommandFrame& f : cmd) {
    if (f.flags & hal::kFlagFreeze) freeze = true;
    else if (freeze) unfrozen_after_freeze = true;
  }
  EXPECT_TRUE(freeze);
  EXPECT_TRUE(unfrozen_after_freeze);
}

// The trot's trace has both diagonal pairs in swing, the switch's the crawl
// (one foot in swing) before the trot (two).
TEST(GoldenTrot, TraceHasBothPairsInSwing) {
  bool lf_rh = false, rf_lh = false;
  for (const hal::CommandFrame& f : stored(named("trot")).commands) {
    lf_rh |= f.telemetry.stance_mask == 0x6;
    rf_lh |= f.telemetry.stance_mask == 0x9;
  }
  EXPECT_TRUE(lf_rh);
  EXPECT_TRUE(rf_lh);
}

TEST(GoldenSwitch, TraceHasTheCrawlThenTheTrot) {
  int first_crawl_swing = -1, first_trot_swing = -1;
  const auto& cmd = stored(named("switch")).commands;
  for (size_t k = 0; k < cmd.size(); ++k) {
    const int standing = __builtin_popcount(cmd[k].telemetry.stance_mask);
    if (standing == 3 && first_crawl_swing < 0) first_crawl_swing = static_cast<int>(k);
    if (standing == 2 && first_trot_swing < 0) first_trot_swing = static_cast<int>(k);
  }
  ASSERT_GE(first_crawl_swing, 0);
  ASSERT_GE(first_trot_swing, 0);
  EXPECT_LT(first_crawl_swing, first_trot_swing);
}

// The comparison sees a one-bit change of any field and names it.
TEST(GoldenFiles, AOneBitChangeIsReportedWithItsTickAndField) {
  const size_t k = 2000;
  struct Poke {
    const char* field;
    void (*apply)(hal::CommandFrame&);
  };
  const Poke pokes[] = {
      {"tau_ff", [](hal::CommandFrame& c) {
         uint64_t bits;
         std::memcpy(&bits, &c.tau_ff[7], 8);
         bits ^= 1;  // the last bit of the mantissa
         std::memcpy(&c.tau_ff[7], &bits, 8);
       }},
      {"normal_hat", [](hal::CommandFrame& c) { c.telemetry.normal_hat[3][2] = std::nextafter(c.telemetry.normal_hat[3][2], 2.0); }},
      {"flags", [](hal::CommandFrame& c) { c.flags ^= hal::kFlagFreeze; }},
      {"slip_mask", [](hal::CommandFrame& c) { c.telemetry.slip_mask ^= 4u; }},
  };
  for (const Poke& p : pokes) {
    std::vector<hal::CommandFrame> changed = stored(named("crawl")).commands;
    p.apply(changed[k]);
    const std::string message = compare(caseDir(named("crawl")) + "reference.csv", changed);
    EXPECT_NE(message.find("first at frame 2000 "), std::string::npos) << message;
    EXPECT_NE(message.find(std::string("field ") + p.field + ":"), std::string::npos) << message;
  }
}

TEST(GoldenFiles, TraceFileRoundTrips) {
  std::string error;
  const std::string path = std::string(HYQ_BINARY_DIR) + "/golden_roundtrip.bin";
  const auto& trace = stored(named("crawl")).trace;
  std::vector<hal::SensorFrame> part(trace.begin(), trace.begin() + 50);
  ASSERT_TRUE(writeTrace(path, part, error)) << error;
  const auto back = readTrace(path, error);
  ASSERT_EQ(back.size(), part.size()) << error;
  for (size_t k = 0; k < part.size(); ++k) {
    EXPECT_EQ(back[k].tick, part[k].tick);
    EXPECT_EQ(std::memcmp(back[k].q, part[k].q, sizeof part[k].q), 0);
    EXPECT_EQ(std::memcmp(back[k].imu_acc, part[k].imu_acc, sizeof part[k].imu_acc), 0);
  }
}

}  // namespace
}  // namespace hyq::golden
