// qp_record: runs a scenario closed loop with the host controller and writes
// every tick's GRF problem, with the solution the current solver gives it,
// into a QP trace (qp_trace.hpp) for qp_replay.
//
//   qp_record SCENARIO.yaml OUT.bin [--recovery on|off] [--seed N] [--duration S]
//                                     [--freeze-after S]
//
// The solution is reproduced beside the controller: before each tick the
// controller's GrfQp (problem and warm-start state) is copied, and after it
// the copy solves the problem the controller built, the same call from the
// same state. A tick whose problem did not change (a refused frame, no
// solve) is not recorded.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <memory>
#include <string>

#include "firmware/controller/controller.hpp"
#include "sim_host/loop/run.hpp"
#include "tests/bench/qp_trace.hpp"

namespace hyq::bench {
namespace {

class RecordingController final : public sim::ControllerPort {
 public:
  RecordingController(const Params& params, std::FILE* out) : out_(out) { controller_.init(params); }

  void step(const hal::SensorFrame& s, hal::CommandFrame& c) override {
    shadow_ = controller_.grfQp();
    controller_.step(s, c);
    const GrfProblem& problem = controller_.grfQp().lastProblem();
    if (std::memcmp(&problem, &shadow_.lastProblem(), sizeof problem) == 0) return;
    Vec12 x;
    const QpStatus status = shadow_.solveProblem(problem, x);
    if (shadow_.solver().iterations() != controller_.grfQp().solver().iterations()) ++mismatches_;
    QpTraceRecord r{};
    r.tick = s.tick;
    toRecord(problem, r);
    std::memcpy(r.x, x.data(), sizeof r.x);
    r.status = static_cast<int32_t>(status);
    r.iterations = shadow_.solver().iterations();
    r.active = shadow_.solver().activeCount();
    if (std::fwrite(&r, sizeof r, 1, out_) != 1) write_failed_ = true;
    ++records_;
  }

  long records() const { return records_; }
  long mismatches() const { return mismatches_; }
  bool writeFailed() const { return write_failed_; }

 private:
  Controller controller_;
  GrfQp shadow_;
  std::FILE* out_;
  long records_ = 0;
  long mismatches_ = 0;
  bool write_failed_ = false;
};

int run(int argc, char** argv) {
  if (argc < 3) {
    std::cerr << "usage: qp_record SCENARIO.yaml OUT.bin [--recovery on|off] [--seed N] [--duration S]"
                 " [--freeze-after S]\n";
    return 2;
  }
  sim::Scenario scenario;
  try {
    scenario = sim::loadScenario(argv[1]);
  } catch (const std::exception& e) {
    std::cerr << "qp_record: " << e.what() << "\n";
    return 2;
  }
  for (int i = 3; i + 1 < argc; i += 2) {
    const std::string key = argv[i], value = argv[i + 1];
    if (key == "--recovery") {
      scenario.controller_params.recovery.enabled = value == "on";
    } else if (key == "--seed") {
      scenario.seed = std::strtoull(value.c_str(), nullptr, 10);
    } else if (key == "--duration") {
      scenario.duration = std::strtod(value.c_str(), nullptr);
    } else if (key == "--freeze-after") {
      // [s] recovery.freeze_after, as the timing test's freeze trace sets it
      scenario.controller_params.recovery.freeze_after = std::strtod(value.c_str(), nullptr);
    } else {
      std::cerr << "qp_record: unknown option " << key << "\n";
      return 2;
    }
  }
  std::FILE* out = std::fopen(argv[2], "wb");
  if (!out) {
    std::cerr << "qp_record: " << argv[2] << ": cannot open for writing\n";
    return 1;
  }
  QpTraceHeader header{};
  std::memcpy(header.magic, kQpTraceMagic, sizeof header.magic);
  header.variables = kGrfVariables;
  header.inequalities = kGrfConstraints;
  header.max_iterations = scenario.controller_params.qp.max_iterations;
  header.recovery = scenario.controller_params.recovery.enabled ? 1 : 0;
  header.feasibility_tolerance = scenario.controller_params.qp.feasibility_tolerance;
  header.pyramid_scale = scenario.controller_params.recovery.pyramid_scale;
  header.seed = scenario.seed;
  std::snprintf(header.scenario, sizeof header.scenario, "%s", scenario.name.c_str());
  std::fwrite(&header, sizeof header, 1, out);

  RecordingController controller(scenario.controller_params, out);
  sim::RunOptions options;
  options.out_dir = std::string(argv[2]) + ".run";
  options.write_log = false;
  options.progress = false;
  const sim::RunResult result = sim::runScenario(scenario, controller, options);
  const bool ok = std::fclose(out) == 0 && !controller.writeFailed();
  std::printf("%s seed %llu recovery %s: %.2f s simulated%s, %ld problems recorded into %s\n",
              scenario.name.c_str(), static_cast<unsigned long long>(scenario.seed),
              header.recovery ? "on" : "off", result.sim_time, result.fell ? " (fell)" : "",
              controller.records(), argv[2]);
  if (controller.mismatches() > 0)
    std::printf("  WARNING: %ld ticks where the copy's iterations differ from the controller's\n",
                controller.mismatches());
  if (!ok) {
    std::cerr << "qp_record: " << argv[2] << ": write failed\n";
    return 1;
  }
  return 0;
}

}  // namespace
}  // namespace hyq::bench

int main(int argc, char** argv) { return hyq::bench::run(argc, argv); }
