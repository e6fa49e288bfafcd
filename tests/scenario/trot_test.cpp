// The trot on good ground, closed loop: from standing to 0.5 m/s, held,
// without a false slip flag; and back to standing. The trot over the ice
// slab.
#include <gtest/gtest.h>

#include <cmath>

#include "tests/scenario/scenario_runner.hpp"

namespace hyq::test {

// [m/s] ground-truth forward speed of the trunk from t0 to the end.
double heldSpeed(const TrunkPath& path, double t0) {
  size_t i = 0;
  while (i + 1 < path.time.size() && path.time[i] < t0) ++i;
  return (path.x.back() - path.x[i]) / (path.time.back() - path.time[i]);
}

TEST(Trot, HoldsHalfAMetrePerSecondWithoutFalseDetections) {
  // Three seeds of 15 s (the whole scenario, 60 s over seeds 1-32:
  // docs/scenarios.md).
  for (uint64_t seed : {1u, 2u, 3u}) {
    ScenarioRun run;
    runScenarioFile("trot_flat.yaml", run, -1, 15.0, {}, seed);
    ASSERT_EQ(run.scenario.controller_params.gait.kind, GaitKind::kTrot);
    EXPECT_FALSE(run.result.fell) << "seed " << seed;
    EXPECT_NEAR(heldSpeed(run.path, 5.0), 0.5, 0.01) << "seed " << seed;
    EXPECT_EQ(run.metrics.false_detections, 0) << "seed " << seed;
    EXPECT_LT(std::fabs(run.path.y.back() - run.path.y.front()), 0.05) << "seed " << seed;
  }
}

TEST(Trot, StopsAndStandsAfterItsWalkTime) {
  ScenarioRun run;
  run.scenario = sim::loadScenario(std::string(HYQ_SOURCE_DIR) + "/sim_host/scenarios/trot_flat.yaml");
  run.scenario.duration = 8.0;
  run.scenario.controller_params.gait.trot.walk_time = 4.0;  // from 1 s to 5 s, then 1 s of ramp down
  runLoadedScenario(run);
  EXPECT_FALSE(run.result.fell);
  EXPECT_EQ(run.metrics.false_detections, 0);
  EXPECT_GT(run.path.x.back() - run.path.x.front(), 1.5);
  // Standing still for the last second.
  EXPECT_LT(std::fabs(heldSpeed(run.path, 7.0)), 0.01);
}

// The paper's ice slab at 0.3 m/s, recovery on: every run crosses (the hind
// feet, 0.37 m behind the base, past x = 3.4 m) without a fall, as over
// seeds 1-32 (docs/scenarios.md); seeds 1-4 here.
TEST(Trot, CrossesTheIceSlabWithRecovery) {
  for (uint64_t seed : {1u, 2u, 3u, 4u}) {
    ScenarioRun run;
    runScenarioFile("trot_ice_patches.yaml", run, -1, -1.0, {}, seed);
    EXPECT_FALSE(run.result.fell) << "seed " << seed;
    EXPECT_GT(run.path.x.back() - 0.37, 3.4) << "seed " << seed;
    EXPECT_EQ(run.metrics.false_detections, 0) << "seed " << seed;
  }
}

// Every patch at mu 0.05, recovery on, the two seeds that fell while two
// stance feet could not anchor the IMU integration (the detector then
// flagged both feet of every two-foot phase): both cross, and no foot is
// flagged while it holds.
TEST(Trot, CrossesPatchesOfMuFiveHundredthsWithRecovery) {
  for (uint64_t seed : {15u, 24u}) {
    ScenarioRun run;
    run.scenario = sim::loadScenario(std::string(HYQ_SOURCE_DIR) + "/sim_host/scenarios/trot_ice_patches.yaml");
    for (auto& patch : run.scenario.terrain.patches) patch.mu = 0.05;
    run.scenario.seed = seed;
    runLoadedScenario(run);
    EXPECT_FALSE(run.result.fell) << "seed " << seed;
    EXPECT_GT(run.path.x.back() - 0.37, 3.4) << "seed " << seed;
    EXPECT_EQ(run.metrics.false_detections, 0) << "seed " << seed;
  }
}

}  // namespace hyq::test
