// The golden replay: the stored trace through the controller must give the
// stored reference, tick for tick and bit for bit (tests/golden/README.md).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "tests/golden/golden.hpp"

namespace hyq::golden {
namespace {

const std::string kDir = std::string(HYQ_SOURCE_DIR) + "/tests/golden/";

struct Replay {
  std::vector<hal::SensorFrame> trace;
  std::vector<hal::CommandFrame> commands;
};

const Replay& stored() {
  static const Replay r = [] {
    Replay out;
    std::string error;
    out.trace = readTrace(kDir + "trace.bin", error);
    EXPECT_EQ(error, "");
    out.commands = replay(out.trace, goldenParams());
    return out;
  }();
  return r;
}

TEST(GoldenReplay, MatchesTheReference) {
  ASSERT_EQ(stored().trace.size(), static_cast<size_t>(kTraceTicks));
  EXPECT_EQ(compare(kDir + "reference.csv", stored().commands), "")
      << "If the change of behaviour is intended, regenerate with `make golden` and say why in the commit.";
}

// The trace covers what it is meant to: a flagged slip, a freeze and its
// exit, swings and touch-downs, the bad frame's safe hold, the tick gap.
TEST(GoldenReplay, TraceCoversEveryPhaseOfTheTick) {
  const auto& c = stored().commands;
  bool slip = false, freeze = false, unfrozen_after_freeze = false, swing = false, bad = false;
  bool touchdown = false;
  for (size_t k = 0; k < c.size(); ++k) {
    slip |= c[k].telemetry.slip_mask != 0;
    touchdown |= k > 0 && c[k].telemetry.stance_mask == 0xF && c[k - 1].telemetry.stance_mask != 0xF;
    if (c[k].flags & hal::kFlagFreeze) freeze = true;
    else if (freeze) unfrozen_after_freeze = true;
    swing |= c[k].telemetry.stance_mask != 0xF;
    bad |= (c[k].flags & hal::kFlagBadSensorFrame) != 0;
  }
  EXPECT_TRUE(slip);
  EXPECT_TRUE(freeze);
  EXPECT_TRUE(unfrozen_after_freeze);
  EXPECT_TRUE(swing);
  EXPECT_TRUE(touchdown);
  EXPECT_TRUE(bad);
  EXPECT_TRUE(c[kBadFrameIndex].flags & hal::kFlagBadSensorFrame);
  const auto& t = stored().trace;
  EXPECT_EQ(t[kGapIndex].tick - t[kGapIndex - 1].tick, static_cast<uint32_t>(kDroppedFrames + 1));
}

// The comparison sees a one-bit change of any field and names it.
TEST(GoldenReplay, AOneBitChangeIsReportedWithItsTickAndField) {
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
    std::vector<hal::CommandFrame> changed = stored().commands;
    p.apply(changed[k]);
    const std::string message = compare(kDir + "reference.csv", changed);
    EXPECT_NE(message.find("first at frame 2000 "), std::string::npos) << message;
    EXPECT_NE(message.find(std::string("field ") + p.field + ":"), std::string::npos) << message;
  }
}

TEST(GoldenReplay, TraceFileRoundTrips) {
  std::string error;
  const std::string path = std::string(HYQ_BINARY_DIR) + "/golden_roundtrip.bin";
  std::vector<hal::SensorFrame> part(stored().trace.begin(), stored().trace.begin() + 50);
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
