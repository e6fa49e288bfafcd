// The friction map closed loop (ice_patches_map: the paper's ice slab with
// the friction probe and the map on): the map the controller builds,
// against the truth under the feet that wrote it (summary.json's
// friction_map, friction_map.json).
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cstdio>

#include "tests/scenario/scenario_runner.hpp"

namespace hyq::test {

// ODE seeds 1-8: 93 cells, 92 within 10 % of the truth under their feet,
// the largest error 10.7 %; no fall, no false detection.
TEST(FrictionMapClosedLoop, IcePatchesMapHoldsTheTruthCellByCell) {
  for (uint64_t seed : {1u, 2u}) {
    ScenarioRun run;
    run.scenario = sim::loadScenario(std::string(HYQ_SOURCE_DIR) + "/sim_host/scenarios/ice_patches_map.yaml");
    run.scenario.seed = seed;
    runLoadedScenario(run);
    EXPECT_FALSE(run.result.fell) << "seed " << seed;
    const YAML::Node map = YAML::LoadFile(run.result.out_dir + "/friction_map.json");
    const int cells = static_cast<int>(map["cells"].size());
    const int within = map["within_10pct"].as<int>();
    std::printf("seed %llu: %d writes, %d cells, %d within 10 %%, largest error %.1f %%\n",
                static_cast<unsigned long long>(seed), map["writes"].as<int>(), cells, within,
                map["error_max_pct"].IsNull() ? -1.0 : map["error_max_pct"].as<double>());
    EXPECT_GE(map["writes"].as<int>(), cells) << "seed " << seed;
    EXPECT_GE(cells, 8) << "seed " << seed;  // the four patches, on both sides
    EXPECT_GE(within, cells - 1) << "seed " << seed;
    ASSERT_FALSE(map["error_max_pct"].IsNull());
    EXPECT_LE(map["error_max_pct"].as<double>(), 15.0) << "seed " << seed;
    // Every cell on ice: the patches span x 0.4-3.4 m (the controller's
    // world starts within a mm of the simulator's here).
    for (const YAML::Node& c : map["cells"]) {
      EXPECT_LT(c["true_mu"].as<double>(), 0.5) << "seed " << seed;
      EXPECT_GT(c["x"].as<double>(), 0.4 - 0.125) << "seed " << seed;
      EXPECT_LT(c["x"].as<double>(), 3.4 + 0.125) << "seed " << seed;
    }
    EXPECT_EQ(run.metrics.false_detections, 0) << "seed " << seed;
  }
}

}  // namespace hyq::test
