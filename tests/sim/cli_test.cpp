// Scenario files and the hyq_sim command line: strict parsing (exit 2 with
// the key named), the specification's example file accepted as written,
// determinism, and the standing scenario.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "sim_host/scenario/scenario.hpp"
#include "tests/sim/test_files.hpp"

namespace hyq::sim {
namespace {

namespace fs = std::filesystem;

const char* const kExample = R"(name: ice_patches
duration: 80.0                 # simulated seconds
seed: 1
terrain:
  mu: 0.8                      # everywhere not covered by a patch
  patches:                     # later entries win where they overlap
    - {x: [0.6, 1.35], y: [-2.0, 2.0], mu: 0.25}
  ramps:                       # along +x
    - {x0: 1.0, angle: 0.25, length: 2.0}
robot:
  payload_kg: 0.0              # extra trunk mass the controller does not know about
  start: {x: 0.0, y: 0.0, yaw: 0.0}
gait:
  speed: 0.05                  # m/s forward
controller:
  recovery: true               # slip detection/estimation/recovery on or off
disturbances:                  # force at the trunk CoM, world frame, N
  - {t: 12.0, duration: 0.2, force: [0.0, 150.0, 0.0]}
)";

fs::path tempDir() { return testTempDir("hyq_cli_test_"); }

struct Outcome {
  int exit_code;
  std::string err;
};

Outcome runSim(const std::string& args) {
  const fs::path err = tempDir() / "stderr.txt";
  const std::string cmd = std::string(HYQ_SIM_BIN) + " " + args + " > /dev/null 2> " + err.string();
  const int status = std::system(cmd.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, readFile(err)};
}

TEST(Scenario, DocumentedExampleParsesAsWritten) {
  const Scenario s = parseScenario(kExample, "example.yaml");
  EXPECT_EQ(s.name, "ice_patches");
  EXPECT_DOUBLE_EQ(s.duration, 80.0);
  EXPECT_EQ(s.seed, 1u);
  EXPECT_DOUBLE_EQ(s.terrain.mu, 0.8);
  ASSERT_EQ(s.terrain.patches.size(), 1u);
  EXPECT_DOUBLE_EQ(s.terrain.patches[0].x0, 0.6);
  EXPECT_DOUBLE_EQ(s.terrain.patches[0].x1, 1.35);
  EXPECT_DOUBLE_EQ(s.terrain.patches[0].y0, -2.0);
  EXPECT_DOUBLE_EQ(s.terrain.patches[0].mu, 0.25);
  ASSERT_EQ(s.terrain.ramps.size(), 1u);
  EXPECT_DOUBLE_EQ(s.terrain.ramps[0].angle, 0.25);
  EXPECT_DOUBLE_EQ(s.terrain.ramps[0].length, 2.0);
  EXPECT_DOUBLE_EQ(s.controller_params.gait.speed, 0.05);
  EXPECT_TRUE(s.controller_params.recovery.enabled);
  ASSERT_EQ(s.disturbances.size(), 1u);
  EXPECT_DOUBLE_EQ(s.disturbances[0].force[1], 150.0);
  EXPECT_DOUBLE_EQ(s.disturbances[0].duration, 0.2);
}

TEST(Scenario, OverridesReachControllerParams) {
  const Scenario s = parseScenario(
      "name: x\nduration: 1\ngait: {cycle_time: 4.0, step_height: 0.08, duty_factor: 0.8}\n"
      "controller: {recovery: false, freeze: true, mu_default: 0.5}\nsensors: {noise: false, q: 0.001}\n",
      "x.yaml");
  EXPECT_TRUE(s.controller_params.recovery.freeze);
  EXPECT_FALSE(parseScenario("name: x\nduration: 1\n", "x.yaml").controller_params.recovery.freeze);
  EXPECT_DOUBLE_EQ(s.controller_params.gait.cycle_time, 4.0);
  EXPECT_DOUBLE_EQ(s.controller_params.gait.step_height, 0.08);
  EXPECT_DOUBLE_EQ(s.controller_params.gait.duty_factor, 0.8);
  EXPECT_FALSE(s.controller_params.recovery.enabled);
  EXPECT_DOUBLE_EQ(s.controller_params.recovery.mu_default, 0.5);
  EXPECT_DOUBLE_EQ(parseScenario("name: x\nduration: 1\ncontroller: {min_estimate_force: 110}\n", "x.yaml")
                       .controller_params.slip.min_estimate_force,
                   110.0);
  const Scenario gates = parseScenario(
      "name: x\nduration: 1\n"
      "controller: {ending_slip_fraction: 0.4, max_estimate_force_sigma: 0.03, min_estimate_samples: 6,\n"
      "             max_slide_acceleration: 0, prior_turn_margin: 0.02}\n",
      "x.yaml");
  EXPECT_DOUBLE_EQ(gates.controller_params.slip.ending_slip_fraction, 0.4);
  EXPECT_DOUBLE_EQ(gates.controller_params.slip.max_estimate_force_sigma, 0.03);
  EXPECT_EQ(gates.controller_params.slip.min_estimate_samples, 6);
  EXPECT_DOUBLE_EQ(gates.controller_params.slip.max_slide_acceleration, 0.0);
  EXPECT_DOUBLE_EQ(gates.controller_params.slip.prior_turn_margin, 0.02);
  EXPECT_FALSE(s.sensors.noise);
  EXPECT_DOUBLE_EQ(s.sensors.magnitudes.q, 0.001);
}

TEST(Scenario, BaseControllerOverridesReachControllerParams) {
  const Scenario s = parseScenario(
      "name: x\nduration: 1\ngait: {liftoff_margin: -1.0, load_time: 0.01, unload_time: 0.05}\n"
      "controller: {qp: {tangential_weight: 1.0e-4, force_smoothing: 0.0}, trunk: {kd_lin: 200}}\n",
      "x.yaml");
  EXPECT_DOUBLE_EQ(s.controller_params.gait.liftoff_margin, -1.0);
  EXPECT_DOUBLE_EQ(s.controller_params.gait.load_time, 0.01);
  EXPECT_DOUBLE_EQ(s.controller_params.gait.unload_time, 0.05);
  EXPECT_DOUBLE_EQ(s.controller_params.qp.tangential_weight, 1.0e-4);
  EXPECT_DOUBLE_EQ(s.controller_params.qp.force_smoothing, 0.0);
  EXPECT_DOUBLE_EQ(s.controller_params.trunk.kd_lin, 200.0);
  EXPECT_DOUBLE_EQ(s.controller_params.trunk.kp_lin, hyq::TrunkParams{}.kp_lin);  // untouched
  EXPECT_THROW(parseScenario("name: x\nduration: 1\ncontroller: {qp: {tangential: 0.1}}\n", "x.yaml"),
               ScenarioError);
  const Scenario weights = parseScenario(
      "name: x\nduration: 1\ncontroller: {qp: {wrench_weight_lin: 2.0, wrench_weight_ang: 10.0, f_normal_min: 25}}\n",
      "x.yaml");
  EXPECT_DOUBLE_EQ(weights.controller_params.qp.wrench_weight_lin, 2.0);
  EXPECT_DOUBLE_EQ(weights.controller_params.qp.wrench_weight_ang, 10.0);
  EXPECT_DOUBLE_EQ(weights.controller_params.qp.f_normal_min, 25.0);
  EXPECT_THROW(parseScenario("name: x\nduration: 1\ncontroller: {qp: {wrench_weight_ang: 0.01}}\n", "x.yaml"),
               ScenarioError);
  EXPECT_THROW(parseScenario("name: x\nduration: 1\ngait: {load_time: 0}\n", "x.yaml"),
               ScenarioError);
  // A lift-off that waits for the CoM further inside than the shift puts it
  // would wait for ever.
  EXPECT_THROW(parseScenario("name: x\nduration: 1\ngait: {liftoff_margin: 0.05}\n", "x.yaml"),
               ScenarioError);
  EXPECT_THROW(parseScenario("name: x\nduration: 1\ngait: {liftoff_margin: 0.2}\n", "x.yaml"),
               ScenarioError);
  EXPECT_DOUBLE_EQ(parseScenario("name: x\nduration: 1\ngait: {liftoff_margin: 0.04}\n", "x.yaml")
                       .controller_params.gait.liftoff_margin,
                   0.04);
  // The shift's own margin, and the lift-off's below it.
  const Scenario wide =
      parseScenario("name: x\nduration: 1\ngait: {stability_margin: 0.08, liftoff_margin: 0.06}\n", "x.yaml");
  EXPECT_DOUBLE_EQ(wide.controller_params.gait.stability_margin, 0.08);
  EXPECT_DOUBLE_EQ(wide.controller_params.gait.liftoff_margin, 0.06);
  EXPECT_THROW(parseScenario("name: x\nduration: 1\ngait: {stability_margin: 0.02}\n", "x.yaml"),
               ScenarioError);  // below the default lift-off margin, 0.03
  EXPECT_THROW(parseScenario("name: x\nduration: 1\ngait: {stability_margin: 0.3}\n", "x.yaml"),
               ScenarioError);
}

// The recovery's mu correction rate, in the controller's range, named by
// its key when out of it.
TEST(Scenario, TheMuCorrectionRateReachesTheController) {
  EXPECT_DOUBLE_EQ(parseScenario("name: x\nduration: 1\n", "x.yaml").controller_params.recovery.k_mu, 100.0);
  EXPECT_DOUBLE_EQ(
      parseScenario("name: x\nduration: 1\ncontroller: {k_mu: 200}\n", "x.yaml").controller_params.recovery.k_mu,
      200.0);
  try {
    parseScenario("name: x\nduration: 1\ncontroller: {k_mu: 2000}\n", "x.yaml");
    ADD_FAILURE() << "k_mu 2000 accepted";
  } catch (const ScenarioError& e) {
    EXPECT_NE(std::string(e.what()).find("controller.k_mu"), std::string::npos) << e.what();
  }
}

TEST(Scenario, TrotKeysReachControllerParams) {
  const Scenario s = parseScenario(
      "name: x\nduration: 1\ngait:\n  kind: trot\n  speed: 0.4\n  yaw_rate: -0.1\n"
      "  trot: {cycle_time: 0.7, duty_factor: 0.65, step_height: 0.1, landing_fraction: 0.25,"
      " touchdown_speed: 0.3, load_time: 0.02, unload_time: 0.04,"
      " foothold_gain: 0.25, acceleration: 0.4, imu_integration_window: 0.35, walk_time: 20,"
      " guess_delay: 0.02, slip_along_ground: false, prior_from_feet_now: false,"
      " prior_row_split: 0.2, prior_row_interior: 0.3, peak_of_loaded_samples: false}\n",
      "x.yaml");
  const GaitParams& g = s.controller_params.gait;
  EXPECT_EQ(g.kind, GaitKind::kTrot);
  EXPECT_DOUBLE_EQ(g.speed, 0.4);
  EXPECT_DOUBLE_EQ(g.yaw_rate, -0.1);
  EXPECT_DOUBLE_EQ(g.trot.cycle_time, 0.7);
  EXPECT_DOUBLE_EQ(g.trot.duty_factor, 0.65);
  EXPECT_DOUBLE_EQ(g.trot.step_height, 0.1);
  EXPECT_DOUBLE_EQ(g.trot.landing_fraction, 0.25);
  EXPECT_DOUBLE_EQ(g.trot.touchdown_speed, 0.3);
  EXPECT_DOUBLE_EQ(g.trot.load_time, 0.02);
  EXPECT_DOUBLE_EQ(g.trot.unload_time, 0.04);
  EXPECT_DOUBLE_EQ(g.trot.foothold_gain, 0.25);
  EXPECT_DOUBLE_EQ(g.trot.acceleration, 0.4);
  EXPECT_DOUBLE_EQ(g.trot.imu_integration_window, 0.35);
  EXPECT_DOUBLE_EQ(g.trot.walk_time, 20.0);
  EXPECT_DOUBLE_EQ(g.trot.guess_delay, 0.02);
  EXPECT_FALSE(g.trot.slip_along_ground);
  EXPECT_FALSE(g.trot.prior_from_feet_now);
  EXPECT_DOUBLE_EQ(g.trot.prior_row_split, 0.2);
  EXPECT_DOUBLE_EQ(g.trot.prior_row_interior, 0.3);
  EXPECT_FALSE(g.trot.peak_of_loaded_samples);
  const GaitSchedule sc =
      parseScenario("name: x\nduration: 1\ngait: {schedule: {trot_at: 12.5, trot_speed: 0.25}}\n", "x.yaml")
          .controller_params.gait.schedule;
  EXPECT_DOUBLE_EQ(sc.trot_at, 12.5);
  EXPECT_DOUBLE_EQ(sc.trot_speed, 0.25);
  EXPECT_EQ(parseScenario("name: x\nduration: 1\n", "x.yaml").controller_params.gait.kind, GaitKind::kCrawl);
  EXPECT_EQ(parseScenario("name: x\nduration: 1\ngait: {kind: crawl}\n", "x.yaml").controller_params.gait.kind,
            GaitKind::kCrawl);
}

// The controller's parameters are checked by the controller's own rules
// (the ones Controller::init applies); the message names the scenario key.
TEST(Scenario, ControllerRangesAreTheControllersOwn) {
  const std::pair<std::string, std::string> cases[] = {
      {"gait: {duty_factor: 1.5}", "x.yaml: gait.duty_factor: out of range: must be in [0.5, 0.99]"},
      {"gait: {cycle_time: 0}", "x.yaml: gait.cycle_time: out of range"},
      {"controller: {mu_default: 5}", "x.yaml: controller.mu_default: out of range"},
      {"controller: {min_estimate_force: -1}", "x.yaml: controller.min_estimate_force: out of range"},
      {"controller: {slide_window: 40}", "x.yaml: controller.slide_window: out of range"},
      {"controller: {slide_travel: 0.05}", "x.yaml: controller.slide_travel: out of range"},
      {"controller: {prior_switch_travel: 1}", "x.yaml: controller.prior_switch_travel: out of range"},
      {"controller: {ending_slip_fraction: 1.5}", "x.yaml: controller.ending_slip_fraction: out of range"},
      {"controller: {max_estimate_force_sigma: -0.1}",
       "x.yaml: controller.max_estimate_force_sigma: out of range"},
      {"controller: {min_estimate_samples: 0}", "x.yaml: controller.min_estimate_samples: out of range"},
      {"controller: {min_estimate_samples: 33}", "x.yaml: controller.min_estimate_samples: out of range"},
      {"controller: {max_slide_acceleration: -1}", "x.yaml: controller.max_slide_acceleration: out of range"},
      {"controller: {prior_turn_margin: 0.6}", "x.yaml: controller.prior_turn_margin: out of range"},
      {"gait: {trot: {prior_row_split: -0.1}}", "x.yaml: gait.trot.prior_row_split: out of range"},
      {"gait: {trot: {carry_agreement_above: -0.1}}", "x.yaml: gait.trot.carry_agreement_above: out of range"},
      {"gait: {trot: {carry_max_samples: 40}}", "x.yaml: gait.trot.carry_max_samples: out of range"},
      {"gait: {trot: {prior_row_interior: 0.6}}", "x.yaml: gait.trot.prior_row_interior: out of range"},
      {"controller: {qp: {force_smoothing: -1}}", "x.yaml: controller.qp.force_smoothing: out of range"},
      {"controller: {trunk: {kd_lin: 1e9}}", "x.yaml: controller.trunk.kd_lin: out of range"},
      {"gait: {liftoff_margin: 0.05}", "x.yaml: gait.liftoff_margin: out of range: must be below"},
      {"gait: {kind: gallop}", "x.yaml: gait.kind: expected crawl or trot, got 'gallop'"},
      {"gait: {yaw_rate: 0.2}", "x.yaml: gait.yaw_rate: out of range: must be 0 with the crawl"},
      {"gait: {kind: trot, trot: {duty_factor: 0.9}}",
       "x.yaml: gait.trot.duty_factor: out of range: must be in [0.5, 0.8]"},
      {"gait: {kind: trot, trot: {walk_time: -1}}", "x.yaml: gait.trot.walk_time: out of range"},
      {"gait: {kind: trot, trot: {guess_delay: 2}}", "x.yaml: gait.trot.guess_delay: out of range"},
      {"gait: {schedule: {trot_speed: 3}}", "x.yaml: gait.schedule.trot_speed: out of range"},
      {"gait: {kind: trot, schedule: {trot_at: 5}}",
       "x.yaml: gait.schedule.trot_at: out of range: must be 0 unless the run starts with the crawl"},
      // Divisors away from 0, times at least one tick (dt, 0.001 s), "off" at 0 only.
      {"gait: {kind: trot, trot: {acceleration: 1e-300}}",
       "x.yaml: gait.trot.acceleration: out of range: must be in [0.01, 10.0]"},
      {"gait: {kind: trot, trot: {walk_time: 0.0005}}",
       "x.yaml: gait.trot.walk_time: out of range: must be 0 or at least dt (one tick)"},
      {"controller: {max_slide_stiffness: 1e-300}",
       "x.yaml: controller.max_slide_stiffness: out of range: must be 0 or in [100.0, 1e7]"},
      {"controller: {landing_drag_travel: 1e-9}",
       "x.yaml: controller.landing_drag_travel: out of range: must be in [-1.0, 0.0] or [0.0001, 1.0]"},
  };
  for (const auto& [yaml, message] : cases) {
    try {
      parseScenario("name: x\nduration: 1\n" + yaml + "\n", "x.yaml");
      ADD_FAILURE() << yaml << ": accepted";
    } catch (const ScenarioError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(message, 0), 0u) << e.what();
    }
  }
}

struct BadCase {
  const char* label;
  std::string yaml;         // replaces the whole file
  std::string expect_key;   // must appear in the one-line message
};

std::string withLine(const std::string& from, const std::string& to) {
  std::string s = kExample;
  const size_t at = s.find(from);
  if (at == std::string::npos) return "name: broken-test\n";
  return s.replace(at, from.size(), to);
}

class BadScenario : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadScenario, ExitsTwoNamingTheKey) {
  const BadCase& c = GetParam();
  const fs::path file = tempDir() / (std::string(c.label) + ".yaml");
  std::ofstream(file) << c.yaml;
  const Outcome o = runSim("run " + file.string() + " --out " + (tempDir() / "bad").string());
  EXPECT_EQ(o.exit_code, 2) << o.err;
  EXPECT_NE(o.err.find(file.string()), std::string::npos) << o.err;
  EXPECT_NE(o.err.find(c.expect_key), std::string::npos) << o.err;
  EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << o.err;
}

INSTANTIATE_TEST_SUITE_P(
    Cli, BadScenario,
    ::testing::Values(
        BadCase{"malformed", "name: x\nduration: [1.0\n", "malformed YAML"},
        BadCase{"unknown_top", withLine("seed: 1", "sede: 1"), "sede: unknown key"},
        BadCase{"unknown_nested", withLine("mu: 0.25}", "muu: 0.25}"),
                "terrain.patches[0].muu: unknown key"},
        BadCase{"unknown_gait", withLine("speed: 0.05", "sped: 0.05"), "gait.sped: unknown key"},
        BadCase{"wrong_type", withLine("duration: 80.0", "duration: eighty"), "duration: expected a number"},
        BadCase{"wrong_type_bool", withLine("recovery: true", "recovery: maybe"),
                "controller.recovery: expected true or false"},
        BadCase{"wrong_type_list", withLine("force: [0.0, 150.0, 0.0]", "force: [0.0, 150.0]"),
                "disturbances[0].force"},
        BadCase{"negative_mu", withLine("mu: 0.8", "mu: -0.8"), "terrain.mu: out of range"},
        BadCase{"negative_patch_mu", withLine("mu: 0.25}", "mu: -0.25}"),
                "terrain.patches[0].mu: out of range"},
        BadCase{"zero_duration", withLine("duration: 80.0", "duration: 0"), "duration: out of range"},
        BadCase{"negative_duration", withLine("duration: 80.0", "duration: -5"), "duration: out of range"},
        BadCase{"patch_x0_gt_x1", withLine("x: [0.6, 1.35]", "x: [1.35, 0.6]"),
                "terrain.patches[0].x: x0 > x1"},
        BadCase{"patch_t0_gt_t1", withLine("mu: 0.25}", "mu: 0.25, t: [5, 2]}"),
                "terrain.patches[0].t: t0 > t1"},
        BadCase{"negative_patch_t", withLine("mu: 0.25}", "mu: 0.25, t: [-1, 2]}"),
                "terrain.patches[0].t[0]: out of range"},
        BadCase{"missing_name", "duration: 1.0\n", "name: missing"},
        BadCase{"duplicate_key", "name: x\nduration: 1.0\nduration: 2.0\n", "duration: given twice"},
        BadCase{"not_a_mapping", withLine("mu: 0.8 ", "mu: {a: 1} "), "terrain.mu: expected a number"},
        BadCase{"empty", "", "empty file"}),
    [](const ::testing::TestParamInfo<BadCase>& info) { return std::string(info.param.label); });

TEST(Cli, MissingFileExitsTwo) {
  const Outcome o = runSim("run /nonexistent/nothing.yaml");
  EXPECT_EQ(o.exit_code, 2);
  EXPECT_NE(o.err.find("/nonexistent/nothing.yaml: cannot open file"), std::string::npos) << o.err;
}

TEST(Cli, BadOptionsExitTwo) {
  const std::string stand = std::string(HYQ_SOURCE_DIR) + "/sim_host/scenarios/stand.yaml";
  EXPECT_EQ(runSim("run " + stand + " --recovery maybe").exit_code, 2);
  EXPECT_EQ(runSim("run " + stand + " --duration -1").exit_code, 2);
  EXPECT_EQ(runSim("run " + stand + " --seed x").exit_code, 2);
  EXPECT_EQ(runSim("run " + stand + " --controller nonesuch").exit_code, 2);
  EXPECT_EQ(runSim("run " + stand + " --frobnicate").exit_code, 2);
  EXPECT_EQ(runSim("run " + stand + " --plant real").exit_code, 2);
  EXPECT_EQ(runSim("").exit_code, 2);
}

// Two runs of the same scenario and seed: identical log.csv bytes. And a
// different seed changes them (the noise is really seeded).
TEST(Cli, DeterministicLogs) {
  const std::string stand = std::string(HYQ_SOURCE_DIR) + "/sim_host/scenarios/stand.yaml";
  const fs::path a = tempDir() / "det_a", b = tempDir() / "det_b", c = tempDir() / "det_c";
  ASSERT_EQ(runSim("run " + stand + " --duration 2 --out " + a.string()).exit_code, 0);
  ASSERT_EQ(runSim("run " + stand + " --duration 2 --out " + b.string()).exit_code, 0);
  ASSERT_EQ(runSim("run " + stand + " --duration 2 --seed 7 --out " + c.string()).exit_code, 0);
  const std::string la = readFile(a / "log.csv"), lb = readFile(b / "log.csv");
  EXPECT_GT(la.size(), 100000u);
  EXPECT_EQ(std::count(la.begin(), la.end(), '\n'), 2001);  // header + 2000 ticks
  EXPECT_TRUE(la == lb) << "log.csv differs between two identical runs";
  EXPECT_FALSE(la == readFile(c / "log.csv"));
  EXPECT_EQ(readFile(a / "events.csv"), readFile(b / "events.csv"));
  for (const fs::path& p : {a, b, c}) fs::remove_all(p);
}

// The acceptance run: stand.yaml, 10 s, no fall; summary has the keys.
TEST(Cli, StandScenarioStandsTenSeconds) {
  const std::string stand = std::string(HYQ_SOURCE_DIR) + "/sim_host/scenarios/stand.yaml";
  const fs::path out = tempDir() / "stand";
  const Outcome o = runSim("run " + stand + " --out " + out.string());
  ASSERT_EQ(o.exit_code, 0) << o.err;
  const std::string summary = readFile(out / "summary.json");
  for (const char* key : {"\"scenario\": \"stand\"", "\"seed\": 1", "\"recovery\": true",
                          "\"sim_time_s\": 10", "\"fell\": false", "\"distance_m\":",
                          "\"real_time_factor\":"})
    EXPECT_NE(summary.find(key), std::string::npos) << key << " in\n" << summary;
  EXPECT_TRUE(fs::exists(out / "events.csv"));
  fs::remove_all(out);
}

// A push no posture can hold: the fall is recorded and the run stops 0.5 s later.
TEST(Cli, FallIsRecordedAndStopsTheRun) {
  const fs::path file = tempDir() / "fall.yaml";
  std::ofstream(file) << "name: fall\nduration: 10.0\nsensors: {noise: false}\n"
                         "disturbances:\n  - {t: 0.5, duration: 0.3, force: [0.0, 2500.0, 0.0]}\n";
  const fs::path out = tempDir() / "fall";
  ASSERT_EQ(runSim("run " + file.string() + " --out " + out.string()).exit_code, 0);
  const std::string summary = readFile(out / "summary.json");
  EXPECT_NE(summary.find("\"fell\": true"), std::string::npos) << summary;
  const size_t at = summary.find("\"sim_time_s\": ");
  ASSERT_NE(at, std::string::npos);
  const double sim_time = std::stod(summary.substr(at + 14));
  EXPECT_GT(sim_time, 0.8);
  EXPECT_LT(sim_time, 2.0);
  const std::string events = readFile(out / "events.csv");
  EXPECT_NE(events.find(",fall,"), std::string::npos) << events;
  EXPECT_NE(events.find(",disturbance_start,"), std::string::npos) << events;
  fs::remove_all(out);
}

TEST(Cli, OverridesReachTheSummary) {
  const std::string stand = std::string(HYQ_SOURCE_DIR) + "/sim_host/scenarios/stand.yaml";
  const fs::path out = tempDir() / "override";
  ASSERT_EQ(runSim("run " + stand + " --recovery off --seed 5 --duration 0.5 --no-log --out " +
                   out.string()).exit_code, 0);
  const std::string summary = readFile(out / "summary.json");
  EXPECT_NE(summary.find("\"recovery\": false"), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"seed\": 5"), std::string::npos) << summary;
  EXPECT_NE(summary.find("\"sim_time_s\": 0.5"), std::string::npos) << summary;
  EXPECT_FALSE(fs::exists(out / "log.csv"));
}

// A file that names no plant runs the hyq plant; --plant ideal runs the
// ideal one; a file's own plant.model stands.
TEST(Cli, PlantOptionPicksThePlantOfAFileThatNamesNone) {
  const std::string stand = std::string(HYQ_SOURCE_DIR) + "/sim_host/scenarios/stand.yaml";
  const fs::path named = tempDir() / "named_plant.yaml";
  std::ofstream(named) << "name: named_plant\nduration: 1.0\nplant: {model: hyq}\n";
  const fs::path out = tempDir() / "plant";
  auto model = [&](const std::string& file, const std::string& option) {
    EXPECT_EQ(runSim("run " + file + " --duration 0.2 --no-log --quiet " + option + " --out " + out.string()).exit_code,
              0);
    const std::string summary = readFile(out / "summary.json");
    const size_t at = summary.find("\"plant\": {\"model\": \"");
    return at == std::string::npos ? std::string("none") : summary.substr(at + 20, summary.find('"', at + 20) - at - 20);
  };
  EXPECT_EQ(model(stand, ""), "hyq");
  EXPECT_EQ(model(stand, "--plant ideal"), "ideal");
  EXPECT_EQ(model(stand, "--plant hyq"), "hyq");
  EXPECT_EQ(model(named.string(), "--plant ideal"), "hyq");
  fs::remove_all(out);
}

// --quiet leaves stdout empty; --json puts the run's summary there, the
// same document as summary.json.
TEST(Cli, QuietPrintsNothingAndJsonPrintsTheSummary) {
  const std::string stand = std::string(HYQ_SOURCE_DIR) + "/sim_host/scenarios/stand.yaml";
  const fs::path out = tempDir() / "quiet";
  const fs::path stdout_file = tempDir() / "stdout.txt";
  const std::string run = std::string(HYQ_SIM_BIN) + " run " + stand + " --duration 0.2 --no-log --out " +
                          out.string();
  ASSERT_EQ(std::system((run + " --quiet > " + stdout_file.string()).c_str()), 0);
  EXPECT_EQ(readFile(stdout_file), "");
  EXPECT_TRUE(fs::exists(out / "summary.json"));
  ASSERT_EQ(std::system((run + " --json > " + stdout_file.string()).c_str()), 0);
  const std::string printed = readFile(stdout_file);
  EXPECT_EQ(printed, readFile(out / "summary.json"));
  EXPECT_NE(printed.find("\"scenario\": \"stand\""), std::string::npos) << printed;
}

}  // namespace
}  // namespace hyq::sim
