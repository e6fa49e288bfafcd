// Controller::step() on sensor frames recorded from a closed-loop simulator
// run (walking on good ground, then onto a low-friction patch, so swing,
// touch-downs, slip detection, estimation and recovery all run). The frames
// are replayed open loop into a fresh controller; each call is timed on its
// own to report the per-call median and p99.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

#include "firmware/controller/controller.hpp"
#include "sim_host/loop/run.hpp"
#include "sim_host/scenario/scenario.hpp"
#include "sim_host/physics/sim_params.hpp"

namespace hyq {
namespace {

const std::vector<hal::SensorFrame>& recordedFrames() {
  static const std::vector<hal::SensorFrame> frames = [] {
    const sim::Scenario scenario = sim::parseScenario(
        "name: bench\nduration: 20.0\nterrain:\n  mu: 0.8\n  patches:\n"
        "    - {x: [0.35, 2.0], y: [-2.0, 2.0], mu: 0.2}\n",
        "controller-bench");
    const int ticks = static_cast<int>(std::lround(scenario.duration / sim::IntegrationParams{}.tick));
    return sim::recordSensorFrames(scenario, ticks);
  }();
  return frames;
}

void BM_ControllerStep(benchmark::State& state) {
  const std::vector<hal::SensorFrame>& frames = recordedFrames();
  Controller controller;
  controller.init(Params{});
  hal::CommandFrame command{};
  std::vector<double> call_ns;
  call_ns.reserve(1 << 20);
  size_t k = 0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    controller.step(frames[k], command);
    const auto stop = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(command.tau_ff);
    if (call_ns.size() < call_ns.capacity())
      call_ns.push_back(std::chrono::duration<double, std::nano>(stop - start).count());
    if (++k == frames.size()) {
      k = 0;
      controller.init(Params{});
    }
  }
  std::sort(call_ns.begin(), call_ns.end());
  if (!call_ns.empty()) {
    state.counters["p50_us"] = 1e-3 * call_ns[call_ns.size() / 2];
    state.counters["p99_us"] = 1e-3 * call_ns[(call_ns.size() * 99) / 100];
    state.counters["max_us"] = 1e-3 * call_ns.back();
  }
  state.counters["frames"] = static_cast<double>(frames.size());
}
BENCHMARK(BM_ControllerStep);

}  // namespace
}  // namespace hyq
