// qp_replay: replays a QP trace (qp_record) through the GRF solver exactly as
// GrfQp calls it (GrfQp::solveProblem, in the recorded order, so that any
// state carried from tick to tick is as in the run) and reports the host
// time per solve, the iterations and how far each solution is from the
// recorded one.
//
//   qp_replay TRACE.bin [--repeat K] [--cold] [--tolerance N] [--top K]
//
// --repeat K  each problem is solved K times from the same solver state and
//             the fastest is its time (less noise from a shared machine);
// --cold      the GrfQp is initialised afresh before each solve;
// --tolerance largest accepted |x - x_recorded| [N] (default 1e-9): above
//             it, or on a status that differs from the recorded one, the
//             exit code is 1;
// --top K     lists the K slowest and the K most-iterating problems.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "tests/bench/qp_trace.hpp"

namespace hyq::bench {
namespace {

struct Solve {
  double ns;
  int iterations;
  int active;
  QpStatus status;
  double error;
  size_t index;
};

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(p * static_cast<double>(v.size() - 1) + 0.5));
  return v[k];
}

const char* statusName(int s) {
  switch (static_cast<QpStatus>(s)) {
    case QpStatus::kOptimal: return "optimal";
    case QpStatus::kInfeasible: return "infeasible";
    case QpStatus::kMaxIterations: return "max_iterations";
    case QpStatus::kInvalidInput: return "invalid_input";
    case QpStatus::kNumericalFailure: return "numerical_failure";
  }
  return "?";
}

int run(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: qp_replay TRACE.bin [--repeat K] [--cold] [--tolerance N] [--top K]\n");
    return 2;
  }
  int repeat = 5, top = 0;
  bool cold = false;
  double tolerance = 1e-9;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--cold") {
      cold = true;
    } else if (a == "--repeat" && i + 1 < argc) {
      repeat = std::max(1, std::atoi(argv[++i]));
    } else if (a == "--tolerance" && i + 1 < argc) {
      tolerance = std::strtod(argv[++i], nullptr);
    } else if (a == "--top" && i + 1 < argc) {
      top = std::max(0, std::atoi(argv[++i]));
    } else {
      std::fprintf(stderr, "qp_replay: unknown option %s\n", a.c_str());
      return 2;
    }
  }
  QpTraceHeader header;
  std::vector<QpTraceRecord> records;
  std::string error;
  if (!readQpTrace(argv[1], header, records, error)) {
    std::fprintf(stderr, "qp_replay: %s\n", error.c_str());
    return 2;
  }
  QpParams params;
  params.max_iterations = header.max_iterations;
  params.feasibility_tolerance = header.feasibility_tolerance;
  GrfQp qp;
  qp.init(params, header.pyramid_scale);

  std::vector<Solve> solves;
  solves.reserve(records.size());
  GrfProblem problem;
  for (size_t i = 0; i < records.size(); ++i) {
    const QpTraceRecord& r = records[i];
    fromRecord(r, problem);
    if (cold) qp.init(params, header.pyramid_scale);  // forgets any state
    Solve s{};
    s.ns = 1e300;
    GrfQp trial;
    Vec12 x;
    for (int k = 0; k < repeat; ++k) {
      trial = qp;
      const auto start = std::chrono::steady_clock::now();
      s.status = trial.solveProblem(problem, x);
      const auto stop = std::chrono::steady_clock::now();
      asm volatile("" : : "g"(x.data()) : "memory");
      s.ns = std::min(s.ns, std::chrono::duration<double, std::nano>(stop - start).count());
    }
    qp = trial;
    s.iterations = qp.solver().iterations();
    s.active = qp.solver().activeCount();
    s.index = i;
    s.error = 0.0;
    for (int k = 0; k < kGrfVariables; ++k) s.error = std::fmax(s.error, std::fabs(x[k] - r.x[k]));
    if (!(s.error == s.error)) s.error = INFINITY;
    solves.push_back(s);
  }

  std::vector<double> us, iters, rec_iters;
  long unconstrained = 0, status_diff = 0, over = 0, counts[5] = {};
  size_t worst_error = 0, slowest = 0, most_iter = 0;
  for (const Solve& s : solves) {
    const QpTraceRecord& r = records[s.index];
    us.push_back(1e-3 * s.ns);
    iters.push_back(s.iterations);
    rec_iters.push_back(r.iterations);
    if (s.status == QpStatus::kOptimal && s.active == 0) ++unconstrained;
    if (static_cast<int>(s.status) != r.status) ++status_diff;
    if (!(s.error <= tolerance)) ++over;
    ++counts[static_cast<int>(s.status)];
    if (s.error > solves[worst_error].error) worst_error = s.index;
    if (s.ns > solves[slowest].ns) slowest = s.index;
    if (s.iterations > solves[most_iter].iterations) most_iter = s.index;
  }
  const size_t n = solves.size();
  std::printf("%s: %zu problems (%s, seed %llu, recovery %s), %s, fastest of %d per problem\n", argv[1],
              n, header.scenario, static_cast<unsigned long long>(header.seed),
              header.recovery ? "on" : "off", cold ? "cold starts" : "as GrfQp calls it", repeat);
  if (n == 0) return 0;
  std::printf("  time per solve [us]:  median %.3f  p99 %.3f  max %.3f (tick %llu)  mean %.3f\n",
              percentile(us, 0.5), percentile(us, 0.99), us[slowest],
              static_cast<unsigned long long>(records[slowest].tick),
              [&] { double t = 0; for (double u : us) t += u; return t / n; }());
  std::printf("  iterations:           median %.0f  p99 %.0f  max %d (tick %llu)  mean %.3f\n",
              percentile(iters, 0.5), percentile(iters, 0.99), solves[most_iter].iterations,
              static_cast<unsigned long long>(records[most_iter].tick),
              [&] { double t = 0; for (double u : iters) t += u; return t / n; }());
  std::printf("  recorded iterations:  median %.0f  p99 %.0f  max %.0f  mean %.3f\n",
              percentile(rec_iters, 0.5), percentile(rec_iters, 0.99),
              *std::max_element(rec_iters.begin(), rec_iters.end()),
              [&] { double t = 0; for (double u : rec_iters) t += u; return t / n; }());
  std::printf("  unconstrained optimum (no active inequality): %ld (%.1f %%)\n", unconstrained,
              100.0 * unconstrained / n);
  std::printf("  status:");
  for (int k = 0; k < 5; ++k)
    if (counts[k]) std::printf(" %s %ld", statusName(k), counts[k]);
  std::printf("; differs from recorded on %ld\n", status_diff);
  std::printf("  max |x - x_recorded|: %.3g N (tick %llu); over %.3g N: %ld\n", solves[worst_error].error,
              static_cast<unsigned long long>(records[worst_error].tick), tolerance, over);
  if (top > 0) {
    std::vector<Solve> by = solves;
    std::sort(by.begin(), by.end(), [](const Solve& a, const Solve& b) { return a.ns > b.ns; });
    std::printf("  slowest:");
    for (int k = 0; k < top && k < static_cast<int>(n); ++k)
      std::printf(" tick %llu %.2f us %d it%s", static_cast<unsigned long long>(records[by[k].index].tick),
                  1e-3 * by[k].ns, by[k].iterations, k + 1 < top ? ";" : "\n");
    std::sort(by.begin(), by.end(), [](const Solve& a, const Solve& b) { return a.iterations > b.iterations; });
    std::printf("  most iterations:");
    for (int k = 0; k < top && k < static_cast<int>(n); ++k)
      std::printf(" tick %llu %d it (recorded %d)%s",
                  static_cast<unsigned long long>(records[by[k].index].tick), by[k].iterations,
                  records[by[k].index].iterations, k + 1 < top ? ";" : "\n");
  }
  return (over > 0 || status_diff > 0) ? 1 : 0;
}

}  // namespace
}  // namespace hyq::bench

int main(int argc, char** argv) { return hyq::bench::run(argc, argv); }
