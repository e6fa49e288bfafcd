// The GRF QP alone, as the controller calls it (problem build + solve), on a
// recorded-like sequence of ticks: the desired wrench turns slowly and grows
// past what friction allows now and then, so the active set changes over the
// sequence as it does when walking. Each call is timed on its own to report
// the per-call median and p99, not only the mean.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

#include "firmware/controller/force/grf_qp.hpp"
#include "firmware/controller/model/kinematics.hpp"
#include "firmware/controller/model/robot_params.hpp"

namespace hyq {
namespace {

constexpr int kSequenceTicks = 4000;

std::vector<GrfInput> tickSequence(int stance_feet) {
  std::vector<GrfInput> ticks(kSequenceTicks);
  const double weight = robot::kTotalMass * robot::kGravity;
  for (int k = 0; k < kSequenceTicks; ++k) {
    GrfInput& in = ticks[k];
    const double t = 0.001 * k;
    for (int leg = 0; leg < 4; ++leg) {
      const Vec3 q(robot::standAngle(leg, 0), robot::standAngle(leg, 1), robot::standAngle(leg, 2));
      in.stance[leg] = stance_feet == 4 || leg != robot::LF;
      in.foot_from_com.col(leg) = footPositionBase(leg, q) + Vec3(0.05, -0.03, 0.0);
      const double tilt = 0.15 * std::sin(0.7 * t + leg);
      in.normal.col(leg) = Vec3(std::sin(tilt), 0.0, std::cos(tilt));
      in.mu[leg] = 0.3 + 0.2 * std::cos(0.3 * t + leg);
    }
    const double push = 120.0 + 100.0 * std::sin(1.3 * t);
    in.wrench_des << push * std::cos(0.9 * t), push * std::sin(0.9 * t), weight,
        20.0 * std::sin(2.1 * t), 30.0 * std::cos(1.7 * t), 10.0 * std::sin(0.5 * t);
  }
  return ticks;
}

void BM_GrfQp(benchmark::State& state) {
  const int stance_feet = static_cast<int>(state.range(0));
  const std::vector<GrfInput> ticks = tickSequence(stance_feet);
  GrfQp qp;
  qp.init(QpParams{}, RecoveryParams{}.pyramid_scale);
  GrfOutput out;
  std::vector<double> call_ns;
  call_ns.reserve(1 << 20);
  long iterations_total = 0;
  int iterations_max = 0, flagged = 0;
  size_t k = 0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    qp.solve(ticks[k], out);
    const auto stop = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(out.forces.data());
    if (call_ns.size() < call_ns.capacity()) {
      call_ns.push_back(std::chrono::duration<double, std::nano>(stop - start).count());
    }
    iterations_total += out.iterations;
    iterations_max = std::max(iterations_max, out.iterations);
    flagged += (out.infeasible || out.hit_iteration_limit) ? 1 : 0;
    k = (k + 1) % ticks.size();
  }
  std::sort(call_ns.begin(), call_ns.end());
  if (!call_ns.empty()) {
    state.counters["p50_us"] = 1e-3 * call_ns[call_ns.size() / 2];
    state.counters["p99_us"] = 1e-3 * call_ns[(call_ns.size() * 99) / 100];
  }
  state.counters["iter_mean"] = static_cast<double>(iterations_total) / state.iterations();
  state.counters["iter_max"] = iterations_max;
  state.counters["flagged"] = flagged;
}
BENCHMARK(BM_GrfQp)->ArgNames({"stance"})->Arg(4)->Arg(3);

}  // namespace
}  // namespace hyq
