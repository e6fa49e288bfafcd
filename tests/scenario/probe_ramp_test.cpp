// The friction probe walking: ramp.yaml (mu 0.5, a 0.25 rad slope from
// x = 1 m to 3 m) with the probe and the friction map on, the hyq plant,
// ODE. The probe reads the ramp's friction while the crawl climbs it,
// without a step in a stance leg's torque, and reads none about a ground
// plane that is a blend of two slopes.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "tests/scenario/scenario_runner.hpp"

namespace hyq::test {
namespace {

// Measured, seeds 1-8: 8-10 answers a run, every one within 4.8 % (the
// worst estimate of any kind 2.9-6.0 %); the largest stance torque step
// 17.8-20.3 N m; no fall, every run on the top. With the pair's whole step
// in one tick and the answer's mu taken at once (not kProbeStepRate and the
// correction's law): 48-51 N m in every run. With a foot probed whose
// ground plane stands in for a blend of two slopes: answers 22.0-23.4 %
// off in 5 of the 8 runs (seed 2 among them: 22.0 %), read about cones 8 deg off the slope under a hind
// foot near the top's edge. MuJoCo
// (seeds 1-4) is not asserted: in seed 4 the front row, at the ramp's foot,
// had a ground plane of its own (not a stand-in) 8 deg off the slope, and
// RF's answer is 30 % off (docs/design-notes.md, "The friction probe").
TEST(ProbeOnTheRamp, ReadsTheRampsFrictionWithoutATorqueStep) {
  for (uint64_t seed : {1u, 2u}) {
    ScenarioRun run;
    run.scenario =
        sim::loadScenario(std::string(HYQ_SOURCE_DIR) + "/sim_host/scenarios/ramp.yaml", sim::PlantModel::hyq);
    run.scenario.controller_params.recovery.probe.enabled = true;
    run.scenario.controller_params.recovery.map.enabled = true;
    run.scenario.seed = seed;
    runLoadedScenario(run);
    const sim::MetricsResult& m = run.metrics;
    std::printf("ramp, probe on, seed %llu: %u probes, %d answers, worst %.1f %%; worst estimate %.1f %%; "
                "torque step %.1f N m\n",
                static_cast<unsigned long long>(seed), m.probes_started, m.probe_answers,
                m.probe_answer_error_max_pct, m.mu_error_max_pct, m.max_stance_torque_step_nm);
    EXPECT_FALSE(run.result.fell) << "seed " << seed;
    const auto& ramp = run.scenario.terrain.ramps.at(0);
    EXPECT_GT(run.path.x.back() - 0.37, ramp.x0 + ramp.length) << "seed " << seed;  // on the top
    EXPECT_GE(m.probe_answers, 4) << "seed " << seed;
    EXPECT_EQ(m.probe_answers_within_10pct, m.probe_answers) << "seed " << seed;
    EXPECT_LE(m.mu_error_max_pct, 10.0) << "seed " << seed;
    // The ramp's own bound without the probe (SlipRecovery.SlipperyRampIsClimbedWithoutTorqueSteps).
    EXPECT_LT(m.max_stance_torque_step_nm, 25.0) << "seed " << seed;
  }
}

}  // namespace
}  // namespace hyq::test
