// The whole-body crawl on good ground, closed loop: walk, climb, push.
#include <gtest/gtest.h>

#include "tests/scenario/scenario_runner.hpp"

namespace hyq::test {

TEST(Locomotion, FlatWalksStraightForSixtySeconds) {
  ScenarioRun run;
  runScenarioFile("flat.yaml", run);
  EXPECT_FALSE(run.result.fell);
  EXPECT_NEAR(run.result.sim_time, 60.0, 1e-6);
  EXPECT_GE(run.result.distance, 2.5);
  EXPECT_LT(std::fabs(run.path.meanLateral(8.0) - run.scenario.start_y), 0.10);
}

TEST(Locomotion, ClimbsTheGripRampOntoItsTop) {
  ScenarioRun run;
  runScenarioFile("ramp_grip.yaml", run);
  EXPECT_FALSE(run.result.fell);
  const auto& r = run.scenario.terrain.ramps.at(0);
  const double top_start = r.x0 + r.length;
  // The whole robot (hind feet ~0.37 m behind the base) is on the flat top.
  EXPECT_GT(run.path.x.back(), top_start + 0.5);
  const double top_height = r.length * std::tan(r.angle);
  EXPECT_GT(run.path.z.back(), top_height + 0.5);
}

TEST(Locomotion, StandingSurvivesASidewaysPush) {
  ScenarioRun run;
  runScenarioFile("push.yaml", run);
  ASSERT_EQ(run.scenario.disturbances.size(), 1u);
  EXPECT_NEAR(run.scenario.disturbances[0].force[1], 150.0, 1e-9);
  EXPECT_NEAR(run.scenario.disturbances[0].duration, 0.2, 1e-9);
  EXPECT_FALSE(run.result.fell);
  // It was pushed (it moved) and came back to stand near where it was.
  double max_dy = 0.0;
  for (double y : run.path.y) max_dy = std::max(max_dy, std::fabs(y - run.path.y.front()));
  EXPECT_GT(max_dy, 0.005);
  EXPECT_LT(std::fabs(run.path.y.back() - run.path.y.front()), 0.05);
}

}  // namespace hyq::test
