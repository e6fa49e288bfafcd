// replay.html's writer: which ticks it keeps, the data block it puts into
// the page template, the template's refusals, and its size on a real run.
// (The page itself: tests/browser/.)
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "sim_host/records/replay.hpp"
#include "sim_host/loop/run.hpp"
#include "tests/sim/test_files.hpp"

namespace hyq::sim {
namespace {

namespace fs = std::filesystem;

const std::string kTemplate =
    "<html><script id=\"replay-data\" type=\"application/json\">/*HYQ_REPLAY_DATA*/</script></html>\n";

fs::path tempDir() { return testTempDir("hyq_replay_test_"); }

// The page's data block, checked to sit where the template's marker was.
std::string dataBlock(const std::string& page) {
  const std::string head = kTemplate.substr(0, kTemplate.find("/*"));
  const std::string tail = kTemplate.substr(kTemplate.find("*/") + 2);
  EXPECT_EQ(page.compare(0, head.size(), head), 0);
  EXPECT_EQ(page.compare(page.size() - tail.size(), tail.size(), tail), 0);
  return page.substr(head.size(), page.size() - head.size() - tail.size());
}

Scenario flatScenario(double duration) {
  Scenario s;
  s.name = "replay</script>";  // must not end the page's script early
  s.duration = duration;
  s.terrain.patches.push_back({0.4, 1.0, -2.0, 2.0, 0.2});
  s.terrain.patches.push_back({300.0, 301.0, -2.0, 2.0, 0.1});  // far from the path: cut
  s.terrain.ramps.push_back({1.5, 0.2, 1.0});
  return s;
}

// 1000 ticks standing on four feet, with LH truly slipping over ticks
// 105-107, its slip flag up over ticks 110-129 and a freeze over 500-599.
std::string syntheticPage(int& frames) {
  const fs::path path = tempDir() / "synthetic.html";
  const Scenario scenario = flatScenario(1.0);
  {
    ReplayLog replay(path.string(), kTemplate, scenario);
    TickRecord r;
    for (uint32_t k = 0; k < 1000; ++k) {
      r.tick = k;
      r.time = k * 0.001;
      r.base_pos = {0.001 * k, 0.0, 0.6};
      for (int leg = 0; leg < 4; ++leg) {
        r.feet[leg].in_contact = true;
        r.feet[leg].mu = 0.8;
        r.feet[leg].slip_speed = 0.0;
      }
      if (k >= 105 && k < 108) r.feet[2].slip_speed = 0.2;
      r.command.telemetry.stance_mask = 0xF;
      r.command.telemetry.slip_mask = k >= 110 && k < 130 ? 4u : 0u;
      r.command.flags = k >= 500 && k < 600 ? hal::kFlagFreeze : 0u;
      replay.onTick(r);
    }
    replay.onFinish();
    frames = replay.frames();
    replay.file().commit();
  }
  return readFile(path);
}

TEST(Replay, KeepsPeriodicFramesAndEveryEdge) {
  int frames = 0;
  const YAML::Node data = YAML::Load(dataBlock(syntheticPage(frames)));
  std::set<long> kept;
  for (const auto& f : data["frames"]) kept.insert(std::lround(f["t"].as<double>() * 1000));
  EXPECT_EQ(static_cast<int>(kept.size()), frames);
  EXPECT_EQ(static_cast<int>(data["frames"].size()), frames);
  // Every 40th tick, each edge (slip 105/108, flag 110/130, freeze
  // 500/600), and the last tick.
  std::set<long> expected = {105, 108, 110, 130, 500, 600, 999};
  for (long k = 0; k < 1000; k += kReplayEveryTicks) expected.insert(k);
  EXPECT_EQ(kept, expected);
  for (const auto& f : data["frames"]) {
    const long k = std::lround(f["t"].as<double>() * 1000);
    EXPECT_EQ(f["ts"].as<int>(), k >= 105 && k < 108 ? 4 : 0) << k;
    EXPECT_EQ(f["sf"].as<int>(), k >= 110 && k < 130 ? 4 : 0) << k;
    EXPECT_EQ(f["fz"].as<int>(), k >= 500 && k < 600 ? 1 : 0) << k;
    EXPECT_EQ(f["p"].size(), 48u);
    EXPECT_EQ(f["b"].size(), 7u);
  }
}

// A slip flag that chatters every tick for a long run: change frames stop at
// kReplayMaxChangeFrames, the interval lists at their byte cap, and the
// page stays bounded.
TEST(Replay, ChatteringFlagsCannotGrowThePageWithoutBound) {
  const fs::path path = tempDir() / "chatter.html";
  const int ticks = 200000;
  int frames = 0;
  {
    ReplayLog replay(path.string(), kTemplate, flatScenario(ticks * 0.001));
    TickRecord r;
    for (int leg = 0; leg < 4; ++leg) r.feet[leg].in_contact = true;
    r.command.telemetry.stance_mask = 0xF;
    for (uint32_t k = 0; k < static_cast<uint32_t>(ticks); ++k) {
      r.tick = k;
      r.time = k * 0.001;
      r.command.telemetry.slip_mask = k % 2 ? 1u : 0u;
      r.feet[0].slip_speed = k % 2 ? 0.2 : 0.0;
      replay.onTick(r);
    }
    replay.onFinish();
    frames = replay.frames();
    replay.file().commit();
  }
  EXPECT_LE(frames, kReplayMaxChangeFrames + ticks / kReplayEveryTicks + 2);
  EXPECT_GT(frames, kReplayMaxChangeFrames);
  EXPECT_LT(fs::file_size(path), 20u * 1000 * 1000);
}

TEST(Replay, ListsSlipsFlagsFreezesAndTheGroundAroundThePath) {
  int frames = 0;
  const std::string page = syntheticPage(frames);
  EXPECT_EQ(page.find("</script>"), page.rfind("</script>")) << "the name ended the script";
  const YAML::Node data = YAML::Load(dataBlock(page));
  EXPECT_EQ(data["scenario"].as<std::string>(), "replay</script>");
  ASSERT_EQ(data["slips"].size(), 1u);
  EXPECT_DOUBLE_EQ(data["slips"][0][0].as<double>(), 0.105);
  EXPECT_DOUBLE_EQ(data["slips"][0][1].as<double>(), 0.108);
  EXPECT_EQ(data["slips"][0][2].as<int>(), 2);
  ASSERT_EQ(data["slip_flags"].size(), 1u);
  EXPECT_DOUBLE_EQ(data["slip_flags"][0][0].as<double>(), 0.11);
  ASSERT_EQ(data["freezes"].size(), 1u);
  EXPECT_DOUBLE_EQ(data["freezes"][0][1].as<double>(), 0.6);
  // The patch on the path stays, the one 300 m away is cut; the profile
  // has its ramp (1.5 to 2.5 m, rising) between flat pieces.
  const YAML::Node ground = data["ground"];
  ASSERT_EQ(ground["patches"].size(), 1u);
  EXPECT_DOUBLE_EQ(ground["patches"][0][4].as<double>(), 0.2);
  ASSERT_EQ(ground["pieces"].size(), 3u);
  EXPECT_DOUBLE_EQ(ground["pieces"][1][0].as<double>(), 1.5);
  EXPECT_NEAR(ground["pieces"][1][3].as<double>(), std::tan(0.2), 1e-4);
}

TEST(Replay, TemplateMissingOrWithoutMarkerIsRefusedSayingHowToBuildIt) {
  const fs::path missing = tempDir() / "no_such_template.html";
  try {
    readReplayTemplate(missing.string());
    FAIL() << "no refusal";
  } catch (const ScenarioError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("make web"), std::string::npos) << m;
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  }
  const fs::path plain = tempDir() / "plain.html";
  std::ofstream(plain) << "<html></html>";
  EXPECT_THROW(readReplayTemplate(plain.string()), ScenarioError);
  const fs::path good = tempDir() / "good.html";
  std::ofstream(good) << kTemplate;
  EXPECT_EQ(readReplayTemplate(good.string()), kTemplate);
}

// A closed-loop run with a true slip: replay.html is written beside the
// run's other files, and its data stays small (about 20 kB per simulated
// second: a 90 s run under 2 MB before the page's script).
TEST(Replay, RunWritesASmallPage) {
  Scenario s = loadScenario(std::string(HYQ_SOURCE_DIR) + "/sim_host/scenarios/stance_slip.yaml");
  s.duration = 4.0;
  auto controller = makeController(s.controller_kind, s);
  RunOptions options;
  options.out_dir = (tempDir() / "run").string();
  options.write_log = false;
  options.progress = false;
  options.replay_template = kTemplate;
  runScenario(s, *controller, options);
  const std::string page = readFile(fs::path(options.out_dir) / "replay.html");
  const YAML::Node data = YAML::Load(dataBlock(page));
  EXPECT_GE(data["slips"].size(), 1u);
  EXPECT_EQ(data["slips"][0][2].as<int>(), 0) << "LF slips on its spot";
  EXPECT_LT(page.size(), 4.0 * 22000) << "bytes for 4 s";
  // Without a template, no replay.html, and an older one is removed.
  options.replay_template.clear();
  auto again = makeController(s.controller_kind, s);
  runScenario(s, *again, options);
  EXPECT_FALSE(fs::exists(fs::path(options.out_dir) / "replay.html"));
}

}  // namespace
}  // namespace hyq::sim
