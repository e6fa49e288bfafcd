// Timing and memory budgets of the board image, measured on the emulated
// Cortex-M7 (qemu-system-arm -M mps2-an500 with -icount: the board's clock
// counts executed instructions, so every figure here is deterministic).
//
// Each slip scenario runs closed loop on the host controller for its whole
// duration; its sensor frames are then replayed through the board image
// (configured with the scenario's controller parameters) in lock-step, and
// the board reports, for every tick, the counts of each stage
// of Controller::step (firmware/controller/stage_clock.hpp). The budgets
// below sit a small margin above the measured maxima: a regression of a few
// percent fails. The whole step is also held to its target, whatever was
// measured. Each trace's figures go to timing/<trace>.json in the build
// directory; docs/performance.py turns them into docs/performance.md's table.
#include <gtest/gtest.h>

#include <stdio.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <ostream>
#include <string>
#include <sys/stat.h>
#include <unistd.h>
#include <vector>

#include "firmware/controller/stage_clock.hpp"
#include "hal/host/qemu_link.hpp"
#include "sim_host/loop/run.hpp"
#include "sim_host/scenario/scenario.hpp"

namespace wire = hyq::hal::wire;
using hyq::hal::CommandFrame;
using hyq::hal::QemuLink;
using hyq::hal::QemuLinkOptions;
using hyq::hal::SensorFrame;

namespace {

// -icount shift: one instruction per 2^shift ns of virtual time. The board's
// 25 MHz clock then counts one per 40 / 2^shift instructions: 10 here.
constexpr int kIcountShift = 2;

constexpr const char* kStageNames[hyq::kNumStages] = {
    "frame check", "legs",  "slip detection", "state estimate", "surface + recovery",
    "gait",        "wrench", "QP build",      "QP solve",       "probe", "commands"};

// ---------------------------------------------------------------------------
// The budgets [instructions]: each the largest figure measured over all the
// traces below, plus a margin of about 3 %. Update them (and
// docs/performance.md) in the commit that changes the code they measure.
constexpr double kMargin = 1.03;
constexpr double kStageMaxMeasured[hyq::kNumStages] = {
    /* frame check */ 490,          /* legs */ 7870,  /* slip detection */ 2350, /* state estimate */ 9780,
    /* surface + recovery */ 13560, /* gait */ 3270,  /* wrench */ 940,         /* QP build */ 2960,
    /* QP solve */ 22770,           /* probe */ 2020, /* commands */ 5650};
constexpr double kTickMaxMeasured = 47810;   // whole Controller::step, worst tick
// The worst tick's target, a hard limit and not a measured figure: 0.125 ms
// at 480 MHz and one instruction per cycle, an 8x margin on the 1 ms tick.
constexpr double kTickTarget = 60000;
constexpr double kStackPeakMeasured = 9520;  // [bytes] painted stack, deepest use
// [bytes] per board image: flash (.vectors .text .rodata .init_array .data)
// and RAM (.data .bss .fast_bss .stack .noinit), as check_image.sh adds them.
struct ImageBudget {
  const char* board;
  const char* elf;
  double flash_measured;
  double ram_measured;
};
const ImageBudget kImages[] = {
    {"mps2-an500", HYQ_FW_MPS2_ELF, 203760, 100612},
    {"stm32h743", HYQ_FW_STM32_ELF, 203896, 100612},
};
// ---------------------------------------------------------------------------

struct TraceSpec {
  const char* name;
  const char* scenario;       // relative to the source tree
  double freeze_after = 0.0;  // [s] recovery.freeze_after for this trace; 0: the scenario's
  double duration = 0.0;      // [s] the trace's length; 0: the scenario's
  hyq::sim::PlantModel plant = hyq::sim::PlantModel::hyq;  // where the file names none
};

// Test names and ctest's show the trace by its name.
void PrintTo(const TraceSpec& spec, std::ostream* out) { *out << spec.name; }

const TraceSpec kTraces[] = {
    {"ice_patches", "sim_host/scenarios/ice_patches.yaml"},
    // The same with the friction probe on: its pairs, break-aways and holds.
    {"ice_patches_probe", "sim_host/scenarios/ice_patches_probe.yaml"},
    {"ramp", "sim_host/scenarios/ramp.yaml"},
    {"two_feet_ice", "sim_host/scenarios/two_feet_ice.yaml"},
    {"stance_slip", "sim_host/scenarios/stance_slip.yaml"},
    {"ice_to_grip", "sim_host/scenarios/ice_to_grip.yaml"},
    // Down a slippery slope onto flat ground: touch-downs on a plane the
    // prior does not know (the concave change of slope) and slips on it.
    {"slope_down", "sim_host/scenarios/slope_down.yaml"},
    // stance_slip's start with freezing on, after 20 ms of slip instead of
    // 300 ms, so that the stance slip freezes the robot: enters and leaves
    // the freeze (the golden replay's scenario and setting).
    {"freeze", "tests/golden/crawl/scenario.yaml", 0.02},
    // The trot: on flat ground at 0.5 m/s (its start from standing and
    // 20 s of cruise), and across the ice slab at 0.3 m/s with its
    // touch-down slips.
    {"trot_flat", "sim_host/scenarios/trot_flat.yaml", 0.0, 25.0},
    {"trot_ice_patches", "sim_host/scenarios/trot_ice_patches.yaml"},
    // The switch from the crawl to the trot (about 11 s in) and 4 s of trot.
    {"crawl_to_trot", "sim_host/scenarios/crawl_to_trot.yaml", 0.0, 15.0},
    // The traces above run the hyq plant; the ideal plant's frames are
    // inputs the board must meet as well, and where they gave the largest
    // counts (the freeze's QP solve and worst tick, ice_to_grip's surface
    // stage, the trot's first frame) they run here too.
    {"freeze_ideal_plant", "tests/golden/crawl/scenario.yaml", 0.02, 0.0, hyq::sim::PlantModel::ideal},
    {"ice_to_grip_ideal_plant", "sim_host/scenarios/ice_to_grip.yaml", 0.0, 0.0, hyq::sim::PlantModel::ideal},
    {"trot_flat_ideal_plant", "sim_host/scenarios/trot_flat.yaml", 0.0, 25.0, hyq::sim::PlantModel::ideal},
};

const char* imagePath() {
  const char* env = std::getenv("HYQ_FW_MPS2_ELF");
  return env ? env : HYQ_FW_MPS2_ELF;
}

// A scenario's whole run: its sensor frames and the controller parameters
// the host ran them with (the board gets the same).
struct Trace {
  std::vector<SensorFrame> frames;
  hyq::Params params;
};

Trace recordTrace(const TraceSpec& spec) {
  hyq::sim::Scenario scenario =
      hyq::sim::loadScenario(std::string(HYQ_SOURCE_DIR) + "/" + spec.scenario, spec.plant);
  if (spec.freeze_after > 0.0) scenario.controller_params.recovery.freeze_after = spec.freeze_after;
  if (spec.duration > 0.0) scenario.duration = spec.duration;
  const int ticks = static_cast<int>(std::lround(scenario.duration / 0.001));
  return {hyq::sim::recordSensorFrames(scenario, ticks), scenario.controller_params};
}

// Per tick: the whole step and each stage, in instructions.
struct Counts {
  std::vector<double> step;
  std::vector<double> stage[hyq::kNumStages];
  int frozen_ticks = 0;  // commands with the freeze flag
};

// Replays the frames through the board; false (with the reason in `why`)
// when the link fails. Stack peak from the Hello the board sends once the
// host goes quiet (its safe state).
bool replay(const Trace& trace, Counts& counts, uint32_t* stack_peak, std::string& why) {
  const std::vector<SensorFrame>& frames = trace.frames;
  QemuLinkOptions options;
  options.icount_shift = kIcountShift;
  options.reply_timeout_ms = 20000;
  QemuLink link;
  if (!link.open(imagePath(), options)) {
    why = std::string(link.error()) + " (image " + imagePath() + "; `make firmware` builds it)";
    return false;
  }
  if (!link.configure(&trace.params, sizeof trace.params)) {
    why = link.error();
    return false;
  }
  const double per_count = 1e9 / link.hello().clock_hz / (1 << kIcountShift);
  counts = Counts{};
  counts.step.reserve(frames.size());
  for (auto& s : counts.stage) s.reserve(frames.size());
  CommandFrame command{};
  for (const SensorFrame& frame : frames) {
    if (!link.exchange(frame, command)) {
      why = link.error();
      return false;
    }
    counts.frozen_ticks += (command.flags & hyq::hal::kFlagFreeze) != 0;
    const wire::BoardStatus& status = link.lastStatus();
    counts.step.push_back(status.step_counts_last * per_count);
    for (int k = 0; k < hyq::kNumStages; ++k) counts.stage[k].push_back(status.stage_counts[k] * per_count);
  }
  if (stack_peak != nullptr) {
    wire::Message m{};
    bool hello = false;
    while (!hello && link.receive(m, 5000)) hello = m.type == wire::MessageType::kHello;
    if (!hello) {
      why = "no Hello from the board in its safe state";
      return false;
    }
    *stack_peak = m.hello.stack_peak_bytes;
  }
  return true;
}

struct Summary {
  double median, p99, max;
};

Summary summarise(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return {v[n / 2], v[std::min(n - 1, static_cast<size_t>(std::ceil(0.99 * n)) - 1)], v.back()};
}

void writeJson(const std::string& path, const TraceSpec& spec, const Counts& c, uint32_t stack_peak) {
  std::ofstream out(path);
  const Summary step = summarise(c.step);
  const size_t worst = static_cast<size_t>(std::max_element(c.step.begin(), c.step.end()) - c.step.begin());
  out << "{\n  \"trace\": \"" << spec.name << "\",\n  \"scenario\": \"" << spec.scenario << "\",\n"
      << "  \"ticks\": " << c.step.size() << ",\n  \"instructions_per_count\": "
      << 40.0 / (1 << kIcountShift) << ",\n  \"stack_peak_bytes\": " << stack_peak << ",\n"
      << "  \"step\": {\"median\": " << step.median << ", \"p99\": " << step.p99 << ", \"max\": " << step.max
      << "},\n  \"worst_tick\": {\"index\": " << worst << ", \"stages\": [";
  for (int k = 0; k < hyq::kNumStages; ++k) out << (k ? ", " : "") << c.stage[k][worst];
  out << "]},\n  \"stages\": [\n";
  for (int k = 0; k < hyq::kNumStages; ++k) {
    const Summary s = summarise(c.stage[k]);
    const auto at = std::max_element(c.stage[k].begin(), c.stage[k].end()) - c.stage[k].begin();
    out << "    {\"name\": \"" << kStageNames[k] << "\", \"median\": " << s.median << ", \"p99\": " << s.p99
        << ", \"max\": " << s.max << ", \"max_tick\": " << at << "}" << (k + 1 < hyq::kNumStages ? "," : "")
        << "\n";
  }
  out << "  ]\n}\n";
}

// The build directory's timing/, whatever the working directory: the
// nearest folder above this executable that holds CMakeCache.txt (where
// docs/performance.py reads the figures), else the executable's own folder.
std::string timingDir() {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path exe_dir = fs::read_symlink("/proc/self/exe", ec).parent_path();
  for (fs::path dir = exe_dir; !ec && !dir.empty(); dir = dir.parent_path()) {
    if (fs::exists(dir / "CMakeCache.txt", ec)) return (dir / "timing").string();
    if (dir == dir.root_path()) break;
  }
  return (exe_dir / "timing").string();
}

// The trace's figures as timing/<trace>.json in the build directory; the
// file's path.
std::string writeTraceFigures(const TraceSpec& spec, const Counts& counts, uint32_t stack_peak) {
  const std::string dir = timingDir();
  ::mkdir(dir.c_str(), 0755);
  const std::string path = dir + "/" + spec.name + ".json";
  writeJson(path, spec, counts, stack_peak);
  return path;
}

class StageBudgets : public ::testing::TestWithParam<TraceSpec> {};

TEST_P(StageBudgets, WholeTraceFitsEveryStageBudget) {
  const TraceSpec& spec = GetParam();
  const Trace trace = recordTrace(spec);
  ASSERT_GT(trace.frames.size(), 1000u);
  Counts counts;
  uint32_t stack_peak = 0;
  std::string why;
  ASSERT_TRUE(replay(trace, counts, &stack_peak, why)) << why;
  ASSERT_EQ(counts.step.size(), trace.frames.size());
  // A trace named for the freeze has the board frozen for part of it.
  if (spec.freeze_after > 0.0) {
    EXPECT_GT(counts.frozen_ticks, 0) << spec.name << " never froze";
  }

  writeTraceFigures(spec, counts, stack_peak);
  const Summary step = summarise(counts.step);
  std::printf("[ timing ] %s, %zu ticks (%d frozen): step median %.0f p99 %.0f max %.0f instructions; "
              "stack %u bytes\n", spec.name, counts.step.size(), counts.frozen_ticks, step.median, step.p99,
              step.max, stack_peak);
  for (int k = 0; k < hyq::kNumStages; ++k) {
    const Summary s = summarise(counts.stage[k]);
    std::printf("[ timing ]   %-19s median %7.0f p99 %7.0f max %7.0f (budget %7.0f)\n", kStageNames[k], s.median,
                s.p99, s.max, kStageMaxMeasured[k] * kMargin);
    EXPECT_LE(s.max, kStageMaxMeasured[k] * kMargin) << kStageNames[k] << " on " << spec.name;
  }
  EXPECT_LE(step.max, kTickMaxMeasured * kMargin) << "worst tick on " << spec.name;
  EXPECT_LE(step.max, kTickTarget) << "worst tick on " << spec.name << " over the target";
  EXPECT_LE(stack_peak, kStackPeakMeasured * kMargin) << "stack on " << spec.name;
  // The stages account for the step: what is left is the clock reads
  // themselves and the call.
  for (size_t t = 0; t < counts.step.size(); ++t) {
    double sum = 0.0;
    for (int k = 0; k < hyq::kNumStages; ++k) sum += counts.stage[k][t];
    ASSERT_NEAR(sum, counts.step[t], 0.02 * counts.step[t] + 200.0) << "tick " << t;
  }
}

INSTANTIATE_TEST_SUITE_P(Traces, StageBudgets, ::testing::ValuesIn(kTraces),
                         [](const ::testing::TestParamInfo<TraceSpec>& info) { return std::string(info.param.name); });

// Two emulated runs of the same trace count the same, tick for tick, to the
// clock's resolution. (Exactly the same is not possible: the instructions
// the board executes in its idle loop between two frames follow the host's
// scheduling, so the phase of the 10-instruction clock at a step's start
// varies; each reading can differ by one count.)
TEST(TimingDeterminism, TwoRunsOfATraceCountTheSame) {
  Trace trace = recordTrace(kTraces[3]);  // stance_slip
  trace.frames.resize(4000);
  const auto& frames = trace.frames;
  Counts a, b;
  std::string why;
  ASSERT_TRUE(replay(trace, a, nullptr, why)) << why;
  ASSERT_TRUE(replay(trace, b, nullptr, why)) << why;
  const double resolution = 40.0 / (1 << kIcountShift);
  int differing = 0;
  double sum_a = 0.0, sum_b = 0.0;
  for (size_t t = 0; t < frames.size(); ++t) {
    ASSERT_LE(std::fabs(a.step[t] - b.step[t]), resolution) << "tick " << t;
    differing += a.step[t] != b.step[t];
    sum_a += a.step[t];
    sum_b += b.step[t];
    for (int k = 0; k < hyq::kNumStages; ++k) {
      // The state estimate is timed over two intervals (the start and the
      // replan before slip detection, then its own), each a count either way.
      const double stage_resolution =
          k == static_cast<int>(hyq::Stage::kStateEstimate) ? 2.0 * resolution : resolution;
      ASSERT_LE(std::fabs(a.stage[k][t] - b.stage[k][t]), stage_resolution) << kStageNames[k] << " tick " << t;
    }
  }
  std::printf("[ timing ] two runs of %zu ticks: %d ticks differ by one count (%.0f instructions); "
              "totals %.0f and %.0f\n", frames.size(), differing, resolution, sum_a, sum_b);
}

// A trace's figures go to the build directory's timing/ (beside
// CMakeCache.txt, where docs/performance.py reads them), whatever the
// working directory the test runs in.
TEST(TimingFiles, GoToTheBuildDirectoryWhateverTheWorkingDirectory) {
  namespace fs = std::filesystem;
  const fs::path build = fs::read_symlink("/proc/self/exe").parent_path().parent_path().parent_path();
  ASSERT_TRUE(fs::exists(build / "CMakeCache.txt")) << build;
  const fs::path elsewhere = fs::temp_directory_path() / ("hyq_timing_cwd_" + std::to_string(::getpid()));
  fs::create_directories(elsewhere);
  const fs::path here = fs::current_path();
  fs::current_path(elsewhere);
  Counts counts;
  counts.step = {3.0, 1.0, 2.0};
  for (auto& stage : counts.stage) stage = {1.0, 1.0, 1.0};
  const TraceSpec spec{"working_directory_check", "none"};
  const fs::path written = fs::absolute(writeTraceFigures(spec, counts, 100));
  fs::current_path(here);
  EXPECT_FALSE(fs::exists(elsewhere / "timing"));
  EXPECT_EQ(written, build / "timing" / "working_directory_check.json");
  EXPECT_TRUE(fs::exists(build / "timing" / "working_directory_check.json"));
  fs::remove(build / "timing" / "working_directory_check.json");
  fs::remove_all(elsewhere);
}

// Flash and RAM of each board image, from its section sizes.
TEST(MemoryBudgets, EachBoardImageFitsItsFlashAndRamBudget) {
  for (const ImageBudget& image : kImages) {
    const std::string command = std::string("arm-none-eabi-size -A ") + image.elf;
    FILE* pipe = ::popen(command.c_str(), "r");
    ASSERT_NE(pipe, nullptr) << command;
    char name[128];
    unsigned long size = 0, address = 0;
    double flash = 0.0, ram = 0.0;
    char line[256];
    while (std::fgets(line, sizeof line, pipe) != nullptr) {
      if (std::sscanf(line, "%127s %lu %lu", name, &size, &address) != 3) continue;
      const std::string section = name;
      if (section == ".vectors" || section == ".text" || section == ".rodata" || section == ".init_array" ||
          section == ".data")
        flash += size;
      if (section == ".data" || section == ".bss" || section == ".fast_bss" || section == ".stack" ||
          section == ".noinit")
        ram += size;
    }
    ASSERT_EQ(::pclose(pipe), 0) << command << " (`make firmware` builds the images)";
    std::printf("[ memory ] %s: flash %.0f bytes (budget %.0f), RAM %.0f bytes (budget %.0f)\n", image.board, flash,
                image.flash_measured * kMargin, ram, image.ram_measured * kMargin);
    EXPECT_GT(flash, 0.0);
    EXPECT_LE(flash, image.flash_measured * kMargin) << image.board;
    EXPECT_LE(ram, image.ram_measured * kMargin) << image.board;
  }
}

}  // namespace
