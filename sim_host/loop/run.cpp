#include "sim_host/loop/run.hpp"

#include "sim_host/cli/sweep.hpp"


#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <ctime>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <system_error>

#include "firmware/controller/controller.hpp"
#include "sim_host/records/friction_map_record.hpp"
#include "sim_host/records/metrics.hpp"
#include "sim_host/physics/mujoco_model.hpp"
#include "sim_host/records/replay.hpp"
#include "sim_host/records/run_log.hpp"

namespace hyq::sim {
namespace {

using Clock = std::chrono::steady_clock;
double seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

// CPU time of this process: the simulator's cost on one core, whatever
// else the machine is running.
double cpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

std::string usage() {
  std::string kinds;
  for (const std::string& k : controllerKinds()) kinds += (kinds.empty() ? "" : "|") + k;
  return "usage: hyq_sim run SCENARIO.yaml [--recovery on|off] [--seed N] [--duration S]\n"
         "                [--out DIR] [--controller " + kinds + "] [--no-log] [--replay]\n"
         "                [--substeps N] [--engine ode|mujoco] [--plant hyq|ideal] [--quiet] [--json]\n"
         "  --plant    the plant of a file whose plant section names none (default hyq)\n"
         "  --replay   also write replay.html, the run in 3D in a browser (docs/replay.md)\n"
         "  --quiet    nothing on stdout (the files only); --json: the summary on stdout\n"
         "       hyq_sim sweep SWEEP.yaml [options]   (hyq_sim sweep --help)\n";
}

// The files of a run, and the figures docs/plots.py draws from them into
// the same folder: removed before a run writes there, so that nothing of
// an earlier run stays beside the new summary.
const char* const kRunFiles[] = {"summary.json",  "log.csv",           "events.csv",
                                 "replay.html",   "fig5_mu.png",       "fig6_odometry.png",
                                 "fig7_normal.png", "fig8_slip_flags.png", "friction_map.json",
                                 "fig_friction_map.png"};

void prepareOutputFolder(const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw OutputError(clipForMessage(dir, 200) + ": " + ec.message());
  for (const char* name : kRunFiles) {
    // unlink() removes a symlink itself, never its target.
    const std::string path = dir + "/" + name;
    if (::unlink(path.c_str()) != 0 && errno != ENOENT)
      throw OutputError(clipForMessage(path, 200) + ": " + std::strerror(errno));
  }
  // Temporaries of a run that was killed before it renamed them
  // (".<file>.<pid>.<n>.tmp", run_log.cpp).
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.size() < 5 || name[0] != '.' || name.compare(name.size() - 4, 4, ".tmp") != 0) continue;
    for (const char* run_file : kRunFiles)
      if (name.compare(1, std::strlen(run_file) + 1, std::string(run_file) + ".") == 0) {
        ::unlink(entry.path().c_str());
        break;
      }
  }
}

// One line for stderr, whatever the message holds.
std::string oneLine(const std::string& message) { return clipForMessage(message, 500); }

// Every refusal is one line on stderr, with exit code 2 (bad input).
int refuse(const std::string& message) {
  std::cerr << "hyq_sim: " << oneLine(message) << "\n";
  return 2;
}

// `hyq_sim run`'s command line: the scenario file, what the options
// override in it, and how the run writes.
struct RunCommand {
  std::string path;                 // the scenario file
  std::optional<bool> recovery;
  std::optional<uint64_t> seed;
  std::optional<double> duration;   // [s]
  std::optional<std::string> kind;  // the controller
  std::optional<EngineKind> engine;
  PlantModel plant = PlantModel::hyq;  // where the file names none
  bool quiet = false, json = false, want_replay = false;
  RunOptions options;
};

// The options after SCENARIO.yaml into `c`. Throws ScenarioError, the
// first bad option's refusal; an option given twice is one.
void parseRunOptions(int argc, char** argv, RunCommand& c) {
  std::vector<std::string> seen;
  for (int i = 3; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.rfind("--", 0) == 0 && std::find(seen.begin(), seen.end(), arg) != seen.end())
      throw ScenarioError("command line: " + clipForMessage(arg) + ": given twice");
    seen.push_back(arg);
    // The option's value: the next argument, which must not be empty nor
    // look like an option (`--out --no-log` lacks the directory).
    auto value = [&](const char* what) -> std::string {
      if (i + 1 >= argc) throw ScenarioError("command line: " + arg + ": missing " + what);
      const std::string v = argv[++i];
      if (v.rfind("--", 0) == 0)
        throw ScenarioError("command line: " + arg + ": missing " + what + " (got the option '" +
                            clipForMessage(v) + "')");
      if (v.empty()) throw ScenarioError("command line: " + arg + ": expected " + what + ", got ''");
      return v;
    };
    if (arg == "--recovery") {
      const std::string v = value("on|off");
      if (v != "on" && v != "off")
        throw ScenarioError("command line: --recovery: expected on or off, got '" +
                            clipForMessage(v) + "'");
      c.recovery = v == "on";
    } else if (arg == "--seed") {
      const std::string v = value("an integer");
      if (v.size() > 19 || v.find_first_not_of("0123456789") != std::string::npos)
        throw ScenarioError(
            "command line: --seed: expected an integer 0..9999999999999999999, got '" +
            clipForMessage(v) + "'");
      c.seed = std::stoull(v);
    } else if (arg == "--duration") {
      const std::string v = value("seconds");
      const KeyRange& range = scenarioRange("duration");
      const std::optional<double> d = parseDecimal(v);
      if (!d || !inRange(range, *d))
        throw ScenarioError("command line: --duration: expected seconds " + rangeText(range) +
                            " (a decimal number), got '" + clipForMessage(v) + "'");
      c.duration = *d;
    } else if (arg == "--out") {
      c.options.out_dir = value("a directory");
    } else if (arg == "--controller") {
      c.kind = value("a controller name");
    } else if (arg == "--substeps") {
      const std::string v = value("an integer 1..16");
      if (v.size() > 2 || v.find_first_not_of("0123456789") != std::string::npos ||
          std::stoi(v) < 1 || std::stoi(v) > 16)
        throw ScenarioError("command line: --substeps: expected an integer 1..16, got '" +
                            clipForMessage(v) + "'");
      c.options.sim.integration.substeps = std::stoi(v);
    } else if (arg == "--engine") {
      const std::string v = value("ode|mujoco");
      EngineKind e;
      if (!parseEngineName(v, e))
        throw ScenarioError("command line: --engine: expected ode or mujoco, got '" +
                            clipForMessage(v) + "'");
      c.engine = e;
    } else if (arg == "--plant") {
      const std::string v = value("hyq|ideal");
      if (!parsePlantModelName(v, c.plant))
        throw ScenarioError("command line: --plant: expected hyq or ideal, got '" + clipForMessage(v) + "'");
    } else if (arg == "--no-log") {
      c.options.write_log = false;
    } else if (arg == "--quiet") {
      c.quiet = true;
      c.options.progress = false;
    } else if (arg == "--json") {
      c.json = true;
      c.options.progress = false;
    } else if (arg == "--replay") {
      c.want_replay = true;
    } else {
      throw ScenarioError("command line: " + clipForMessage(arg) +
                          ": unknown option (hyq_sim --help lists them)");
    }
  }
}

// The scenario file with the command line's overrides, checked as the run
// needs it. Throws ScenarioError.
Scenario loadWithOverrides(const RunCommand& c) {
  Scenario scenario = loadScenario(c.path, c.plant);
  if (c.recovery) scenario.controller_params.recovery.enabled = *c.recovery;
  if (c.seed) scenario.seed = *c.seed;
  if (c.duration) scenario.duration = *c.duration;
  if (c.kind) scenario.controller_kind = *c.kind;
  if (c.engine) scenario.physics.engine = *c.engine;
  if (c.options.out_dir.empty()) checkOutputFolderName(scenario);
  if (scenario.physics.engine == EngineKind::mujoco) checkMujocoGround(scenario, Terrain(scenario.terrain));
  return scenario;
}

// The run, with metrics, into `r`; `controller` holds its controller until
// the command ends. An exit code when the run cannot be done.
std::optional<int> runWithController(const RunCommand& c, const Scenario& scenario,
                                     std::unique_ptr<ControllerPort>& controller, RunResult& r) {
  try {
    controller = makeController(scenario.controller_kind, scenario);
    if (!controller) {
      std::string kinds;
      for (const std::string& k : controllerKinds()) kinds += (kinds.empty() ? "" : ", ") + k;
      return refuse((c.kind ? std::string("command line: --controller")
                            : clipForMessage(c.path, 200) + ": controller.kind") +
                    ": unknown controller '" + clipForMessage(scenario.controller_kind) +
                    "' (expected one of: " + kinds + ")");
    }
    Metrics metrics;
    r = runScenario(scenario, *controller, c.options, {&metrics});
  } catch (const ScenarioError& e) {
    return refuse(e.what());
  } catch (const std::exception& e) {
    // Outputs that could not be written, a controller that failed (e.g.
    // the board in QEMU), memory: one line, exit 1.
    std::cerr << "hyq_sim: " << oneLine(e.what()) << "\n";
    return 1;
  }
  return std::nullopt;
}

// The run on stdout: summary.json with --json, nothing with --quiet, else
// a few lines.
void printRun(const RunCommand& c, const Scenario& scenario, const RunResult& r) {
  if (c.json) {
    // summary.json itself, as one document on stdout.
    std::ifstream in(r.out_dir + "/summary.json");
    std::cout << in.rdbuf();
  } else if (!c.quiet) {
    std::printf("%s: %.2f s simulated in %.2f s (%.0fx real time; %.0fx on CPU time), seed %llu, recovery %s\n",
                scenario.name.c_str(), r.sim_time, r.wall_time, r.real_time_factor,
                r.cpu_time > 0.0 ? r.sim_time / r.cpu_time : 0.0,
                static_cast<unsigned long long>(scenario.seed),
                scenario.controller_params.recovery.enabled ? "on" : "off");
    if (r.fell)
      std::printf("  FELL at t = %.3f s\n", r.fall_time);
    else
      std::printf("  did not fall\n");
    std::printf("  distance %.3f m; outputs in %s/\n", r.distance, r.out_dir.c_str());
    if (c.want_replay) std::printf("  3D replay: %s/replay.html\n", r.out_dir.c_str());
  }
}

// summary.json's fields of the run itself.
SummaryFields runFields(const Scenario& scenario, const RunResult& result, int events) {
  return {
      {"scenario", jsonString(scenario.name)},
      {"seed", std::to_string(scenario.seed)},
      {"recovery", scenario.controller_params.recovery.enabled ? "true" : "false"},
      {"controller", jsonString(scenario.controller_kind)},
      {"engine", jsonString(engineName(scenario.physics.engine))},
      {"duration_s", jsonNumber(scenario.duration)},
      {"sim_time_s", jsonNumber(result.sim_time)},
      {"fell", result.fell ? "true" : "false"},
      {"fall_time_s", result.fell ? jsonNumber(result.fall_time) : "null"},
      {"distance_m", jsonNumber(result.distance)},
      {"real_time_factor", jsonNumber(result.real_time_factor)},
      {"wall_time_s", jsonNumber(result.wall_time)},
      {"cpu_time_s", jsonNumber(result.cpu_time)},
      {"cpu_real_time_factor", jsonNumber(result.cpu_time > 0.0 ? result.sim_time / result.cpu_time : 0.0)},
      {"events", std::to_string(events)},
  };
}

}  // namespace

RunResult runScenario(const Scenario& scenario, ControllerPort& controller,
                      const RunOptions& options, const std::vector<TickObserver*>& extra) {
  const double dt = options.sim.integration.tick;
  if (!(scenario.duration / dt >= 0.5))
    throw ScenarioError(
        clipForMessage(scenario.source_file.empty() ? "scenario" : scenario.source_file, 200) +
        ": duration: shorter than one tick");
  const auto total_ticks = static_cast<uint64_t>(std::llround(scenario.duration / dt));
  RunResult result;
  if (options.out_dir.empty()) checkOutputFolderName(scenario);
  result.out_dir = options.out_dir.empty() ? "out/" + scenario.name : options.out_dir;
  prepareOutputFolder(result.out_dir);

  Simulator sim(scenario, options.sim);
  EventLog events(result.out_dir + "/events.csv");
  std::optional<CsvLog> log;
  if (options.write_log) log.emplace(result.out_dir + "/log.csv");
  std::optional<ReplayLog> replay;
  if (!options.replay_template.empty())
    replay.emplace(result.out_dir + "/replay.html", options.replay_template, scenario);
  // The friction map against the truth, when the controller keeps one.
  const RecoveryParams& recovery = scenario.controller_params.recovery;
  std::optional<FrictionMapRecord> map_record;
  if (recovery.enabled && recovery.map.enabled)
    map_record.emplace(recovery.map.cell_size, sim.terrain(), result.out_dir + "/friction_map.json");
  // The records (log, map, events, replay) go on through the time kept
  // after a fall; the caller's observers (the metrics) end at the fall: a
  // fallen robot's slips and estimates are not the controller's to answer
  // for.
  std::vector<TickObserver*> observers;
  if (log) observers.push_back(&*log);
  if (map_record) observers.push_back(&*map_record);
  observers.push_back(&events);
  if (replay) observers.push_back(&*replay);
  const size_t records = observers.size();
  observers.insert(observers.end(), extra.begin(), extra.end());

  const bool live = options.progress && isatty(STDERR_FILENO);
  const Vec3 start_position = sim.engine().basePosition();
  const double start_x = start_position.x();
  uint64_t stop_tick = total_ticks;
  hal::CommandFrame command{};
  TickRecord record;
  const auto wall_start = Clock::now();
  const double cpu_start = cpuSeconds();
  auto last_print = wall_start;

  for (uint64_t k = 0; k < stop_tick; ++k) {
    controller.step(sim.sensorFrame(), command);
    sim.step(command, record);
    const size_t watching = result.fell ? records : observers.size();
    for (size_t i = 0; i < watching; ++i) observers[i]->onTick(record);
    if (!result.fell && sim.fallen()) {
      result.fell = true;
      result.fall_time = record.time;
      events.add(record.time, record.tick, "fall", -1, "trunk low or tilted (see docs/scenarios.md)");
      const auto extra_ticks = static_cast<uint64_t>(std::llround(options.sim.fall.stop_after / dt));
      stop_tick = std::min(stop_tick, k + 1 + extra_ticks);
    }
    if (live && (k & 255) == 0) {
      const auto now = Clock::now();
      if (seconds(now - last_print) > 0.2) {
        last_print = now;
        std::fprintf(stderr, "\r%s  t %.1f / %.1f s  x %+.3f m  %.0fx real time   ",
                     scenario.name.c_str(), record.time, scenario.duration,
                     record.base_pos[0] - start_x, record.time / seconds(now - wall_start));
      }
    }
  }
  result.wall_time = seconds(Clock::now() - wall_start);
  result.cpu_time = cpuSeconds() - cpu_start;
  if (live) std::fprintf(stderr, "\r%*s\r", 70, "");
  for (TickObserver* o : observers) o->onFinish();

  result.sim_time = sim.time();
  // Along the heading the robot started with (x for yaw 0, the default).
  const Vec3 travelled = sim.engine().basePosition() - start_position;
  result.distance = std::cos(scenario.start_yaw) * travelled.x() + std::sin(scenario.start_yaw) * travelled.y();
  result.real_time_factor = result.wall_time > 0.0 ? result.sim_time / result.wall_time : 0.0;

  SummaryFields fields = runFields(scenario, result, events.count());

  for (TickObserver* o : extra)
    for (auto& f : o->summaryFields()) fields.push_back(std::move(f));
  if (map_record)
    for (auto& f : map_record->summaryFields()) fields.push_back(std::move(f));
  else
    fields.push_back({"friction_map", "null"});
  // summary.json last: present only when every file is complete.
  OutputFile summary(result.out_dir + "/summary.json");
  summary.write(summaryJson(fields));
  std::vector<OutputFile*> files;
  if (log) files.push_back(&log->file());
  files.push_back(&events.file());
  if (replay) files.push_back(&replay->file());
  files.push_back(&summary);
  commitAll(files);
  return result;
}

int cliMain(int argc, char** argv) {
  // A file-size limit (ulimit -f) then fails a write with EFBIG, reported
  // like any other write error, instead of killing the process.
  std::signal(SIGXFSZ, SIG_IGN);
  if (argc >= 2 && (std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0)) {
    std::cerr << usage();
    return 0;
  }
  if (argc >= 2 && std::strcmp(argv[1], "sweep") == 0) return sweepMain(argc, argv);
  if (argc < 3 || std::strcmp(argv[1], "run") != 0)
    return refuse("expected 'run SCENARIO.yaml [options]' or 'sweep SWEEP.yaml [options]' "
                  "(hyq_sim --help lists them)");
  RunCommand command;
  command.path = argv[2];
  try {
    parseRunOptions(argc, argv, command);
  } catch (const ScenarioError& e) {
    return refuse(e.what());
  }

  Scenario scenario;
  try {
    scenario = loadWithOverrides(command);
    if (command.want_replay) command.options.replay_template = readReplayTemplate(defaultReplayTemplatePath());
  } catch (const ScenarioError& e) {
    return refuse(e.what());
  } catch (const std::exception& e) {  // e.g. out of memory
    std::cerr << "hyq_sim: " << oneLine(clipForMessage(command.path, 200) + ": " + e.what()) << "\n";
    return 1;
  }

  std::unique_ptr<ControllerPort> controller;
  RunResult r;
  if (const std::optional<int> code = runWithController(command, scenario, controller, r)) return *code;
  printRun(command, scenario, r);
  if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
    std::cerr << "hyq_sim: stdout: " << std::strerror(errno ? errno : EIO) << "\n";
    return 1;
  }
  return 0;
}

std::vector<hal::SensorFrame> recordSensorFrames(const Scenario& scenario, int ticks,
                                                 const FrameFaults& faults) {
  Simulator simulator(scenario);
  auto controller = std::make_unique<Controller>();
  controller->init(scenario.controller_params);
  hal::CommandFrame command{};
  TickRecord record;
  std::vector<hal::SensorFrame> frames;
  frames.reserve(ticks > 0 ? static_cast<size_t>(ticks) : 0);
  for (int k = 0; k < ticks && !simulator.fallen(); ++k) {
    const int dropped = faults.dropped_before ? faults.dropped_before(k) : 0;
    for (int d = 0; d < dropped; ++d) simulator.step(command, record);
    frames.push_back(simulator.sensorFrame());
    if (faults.corrupt) faults.corrupt(k, frames.back());
    controller->step(frames.back(), command);
    simulator.step(command, record);
  }
  return frames;
}

}  // namespace hyq::sim
