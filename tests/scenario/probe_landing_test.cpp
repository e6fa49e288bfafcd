// Landings on ground the friction map knows, with the probe and the map on,
// the hyq plant, ODE: two drawn terrains of the validation set (a crawl and
// a trot) whose landings read more force than the ground gives, with the
// foot in the air; the map's early touch-down (kKnownIceTouchdownShare)
// must not make those stances.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "tests/scenario/scenario_runner.hpp"

namespace hyq::test {
namespace {

// Runs drawn terrain `generate_seed` (seed 1), recovery, probe and map on.
void runDrawnWithProbeAndMap(uint64_t generate_seed, ScenarioRun& run) {
  runDrawnTerrain(generate_seed, "recovery: true, friction_probe: true, friction_map: true", run);
  const sim::MetricsResult& m = run.metrics;
  std::printf("terrain %llu, probe and map on: %d false detections, %d probe answers\n",
              static_cast<unsigned long long>(generate_seed), m.false_detections, m.probe_answers);
}

// Terrain 231 (a crawl on ground of mu 0.52 with patches of 0.25-0.42,
// whose cells the probe writes): a hind foot landing hard bounces, and the
// joint torques, 5-8 ms behind the contact, read 40-56 N while the foot
// rises at 0.04-0.07 m/s. Terrain 203 (a trot over mu 0.15): a landing trot
// foot's swing, stopping hard, reads 40 N above the ground. A stance foot in
// the air moves and is flagged as sliding, a false detection: the early
// touch-down waits while the foot rises, and is the crawl's only
// (docs/design-notes.md, "The friction probe").
TEST(ProbeLanding, ALandingOnKnownGroundIsNoStanceInTheAir) {
  for (uint64_t generate_seed : {231u, 203u}) {
    ScenarioRun run;
    runDrawnWithProbeAndMap(generate_seed, run);
    EXPECT_FALSE(run.result.fell) << "terrain " << generate_seed;
    EXPECT_EQ(run.metrics.false_detections, 0) << "terrain " << generate_seed;
  }
}

}  // namespace
}  // namespace hyq::test
