// Runs a scenario file of sim_host/scenarios/ closed loop with the host
// controller and collects what the acceptance tests assert on.
#pragma once
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "sim_host/loop/controller_port.hpp"
#include "sim_host/records/metrics.hpp"
#include "sim_host/loop/run.hpp"
#include "sim_host/scenario/scenario.hpp"

namespace hyq::test {

// Ground-truth trunk path, for drift and progress checks.
class TrunkPath final : public sim::TickObserver {
 public:
  void onTick(const sim::TickRecord& r) override {
    time.push_back(r.time);
    x.push_back(r.base_pos[0]);
    y.push_back(r.base_pos[1]);
    z.push_back(r.base_pos[2]);
  }
  // Mean lateral position [m] over the last `window` seconds: the drift,
  // free of the crawl's sideways sway.
  double meanLateral(double window) const {
    double sum = 0.0;
    int n = 0;
    for (size_t i = 0; i < time.size(); ++i)
      if (time[i] >= time.back() - window) {
        sum += y[i];
        ++n;
      }
    return n ? sum / n : 0.0;
  }
  std::vector<double> time, x, y, z;
};

struct ScenarioRun {
  // The plant runScenarioFile loads the file onto where it names none.
  sim::PlantModel plant = sim::PlantModel::hyq;
  sim::Scenario scenario;
  sim::RunResult result;
  sim::MetricsResult metrics;
  TrunkPath path;
};

// A test's own change to a loaded scenario (a harsher one), made before it runs.
using ScenarioChange = std::function<void(sim::Scenario&)>;

// recovery: -1 keeps the file's setting, 0 off, 1 on. seed: 0 keeps the
// file's seed (sensor noise and biases). physics: replaces the file's
// engine and contact settings when given. change: applied last, when given.
inline void runScenarioFile(const std::string& file, ScenarioRun& run, int recovery = -1,
                            double duration = -1.0,
                            const std::vector<sim::TickObserver*>& extra = {},
                            uint64_t seed = 0, const sim::PhysicsSpec* physics = nullptr,
                            const ScenarioChange& change = {});

// Runs run.scenario as it is (loaded, then changed by the test).
inline void runLoadedScenario(ScenarioRun& run, const std::vector<sim::TickObserver*>& extra = {}) {
  auto controller = sim::makeController(run.scenario.controller_kind, run.scenario);
  sim::Metrics metrics;
  sim::RunOptions options;
  // One folder per test and run: ctest runs tests in parallel, and two of
  // them may run the same scenario.
  const ::testing::TestInfo* test = ::testing::UnitTest::GetInstance()->current_test_info();
  options.out_dir = std::string(HYQ_BINARY_DIR) + "/scenario_out/" +
                    (test ? std::string(test->test_suite_name()) + "." + test->name() + "/" : "") +
                    run.scenario.name + (run.scenario.controller_params.recovery.enabled ? "_on" : "_off") +
                    "_" + sim::engineName(run.scenario.physics.engine);
  options.write_log = false;
  options.progress = false;
  std::vector<sim::TickObserver*> observers = {&metrics, &run.path};
  observers.insert(observers.end(), extra.begin(), extra.end());
  run.result = sim::runScenario(run.scenario, *controller, options, observers);
  run.metrics = metrics.result();
}

inline void runScenarioFile(const std::string& file, ScenarioRun& run, int recovery, double duration,
                            const std::vector<sim::TickObserver*>& extra, uint64_t seed,
                            const sim::PhysicsSpec* physics, const ScenarioChange& change) {
  run.scenario = sim::loadScenario(std::string(HYQ_SOURCE_DIR) + "/sim_host/scenarios/" + file, run.plant);
  if (physics) run.scenario.physics = *physics;
  if (recovery >= 0) run.scenario.controller_params.recovery.enabled = recovery == 1;
  if (duration > 0.0) run.scenario.duration = duration;
  if (seed > 0) run.scenario.seed = seed;
  if (change) change(run.scenario);
  runLoadedScenario(run, extra);
}

// Runs drawn terrain `generate_seed` (sim_host/scenarios/generated.yaml's
// generator; sensor seed 1) on the hyq plant, ODE, with `controller` as the
// entries of the scenario's controller map (e.g. "recovery: true").
inline void runDrawnTerrain(uint64_t generate_seed, const std::string& controller, ScenarioRun& run) {
  const std::string yaml = "name: drawn\nduration: 60\nseed: 1\nterrain: {generate: {seed: " +
                           std::to_string(generate_seed) + "}}\ncontroller: {" + controller +
                           "}\nplant: {model: hyq}\n";
  run.scenario = sim::parseScenario(yaml, "drawn.yaml");
  runLoadedScenario(run);
}

// [ms] The run's longest slip after its detection (0: none detected).
inline double longestAfterDetectionMs(const ScenarioRun& run) {
  const std::vector<double>& a = run.metrics.after_detection_ms;
  return a.empty() ? 0.0 : *std::max_element(a.begin(), a.end());
}

// A long slip: more than this much contact-point travel [m], on a watched
// foot.
constexpr double kLongSlip = 0.005;

inline bool isLongSlip(const sim::TrueSlip& e) { return e.monitored && e.distance > kLongSlip; }

// Expects every long slip of the run flagged within `latency_ms` of its
// start (latencies are whole ticks: half a tick absorbs their rounding);
// failures name `label`. Returns how many long slips the run had; the
// worst latency [ms] goes into `worst_ms` when it is larger.
inline int expectLongSlipsCaughtWithin(const ScenarioRun& run, double latency_ms, const std::string& label,
                                       double& worst_ms) {
  int count = 0;
  for (const sim::TrueSlip& e : run.metrics.events) {
    if (!isLongSlip(e)) continue;
    ++count;
    EXPECT_TRUE(e.detected) << label << " leg " << e.leg << " at " << e.start << " s";
    if (!e.detected) continue;
    const double latency = 1000.0 * std::max(0.0, e.detected_at - e.start);
    worst_ms = std::max(worst_ms, latency);
    EXPECT_LE(latency, latency_ms + 0.5) << label << " leg " << e.leg << " at " << e.start << " s";
  }
  return count;
}

}  // namespace hyq::test
