#include "sim_host/run.hpp"

#include <unistd.h>

#include <chrono>
#include <ctime>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

#include "firmware/controller/controller.hpp"
#include "sim_host/metrics.hpp"
#include "sim_host/run_log.hpp"

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
         "                [--out DIR] [--controller " + kinds + "] [--no-log] [--substeps N]\n";
}

}  // namespace

RunResult runScenario(const Scenario& scenario, ControllerPort& controller,
                      const RunOptions& options, const std::vector<TickObserver*>& extra) {
  RunResult result;
  result.out_dir = options.out_dir.empty() ? "out/" + scenario.name : options.out_dir;
  std::filesystem::create_directories(result.out_dir);

  Simulator sim(scenario, options.sim);
  EventLog events(result.out_dir + "/events.csv");
  std::optional<CsvLog> log;
  if (options.write_log) log.emplace(result.out_dir + "/log.csv");
  std::vector<TickObserver*> observers;
  if (log) observers.push_back(&*log);
  observers.push_back(&events);
  observers.insert(observers.end(), extra.begin(), extra.end());

  const bool live = options.progress && isatty(STDERR_FILENO);
  const double dt = options.sim.integration.tick;
  const auto total_ticks = static_cast<uint64_t>(std::llround(scenario.duration / dt));
  const double start_x = sim.robot().basePosition().x();
  uint64_t stop_tick = total_ticks;
  hal::CommandFrame command{};
  TickRecord record;
  const auto wall_start = Clock::now();
  const double cpu_start = cpuSeconds();
  auto last_print = wall_start;

  for (uint64_t k = 0; k < stop_tick; ++k) {
    controller.step(sim.sensorFrame(), command);
    sim.step(command, record);
    for (TickObserver* o : observers) o->onTick(record);
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
  result.distance = sim.robot().basePosition().x() - start_x;
  result.real_time_factor = result.wall_time > 0.0 ? result.sim_time / result.wall_time : 0.0;

  SummaryFields fields = {
      {"scenario", jsonString(scenario.name)},
      {"seed", std::to_string(scenario.seed)},
      {"recovery", scenario.controller_params.recovery.enabled ? "true" : "false"},
      {"controller", jsonString(scenario.controller_kind)},
      {"duration_s", jsonNumber(scenario.duration)},
      {"sim_time_s", jsonNumber(result.sim_time)},
      {"fell", result.fell ? "true" : "false"},
      {"fall_time_s", result.fell ? jsonNumber(result.fall_time) : "null"},
      {"distance_m", jsonNumber(result.distance)},
      {"real_time_factor", jsonNumber(result.real_time_factor)},
      {"wall_time_s", jsonNumber(result.wall_time)},
      {"cpu_time_s", jsonNumber(result.cpu_time)},
      {"cpu_real_time_factor", jsonNumber(result.cpu_time > 0.0 ? result.sim_time / result.cpu_time : 0.0)},
      {"events", std::to_string(events.count())},
  };
  for (TickObserver* o : extra)
    for (auto& f : o->summaryFields()) fields.push_back(std::move(f));
  writeSummaryJson(result.out_dir + "/summary.json", fields);
  return result;
}

int cliMain(int argc, char** argv) {
  if (argc < 2 || std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0) {
    std::cerr << usage();
    return argc < 2 ? 2 : 0;
  }
  if (std::strcmp(argv[1], "run") != 0 || argc < 3) {
    std::cerr << "hyq_sim: expected 'run SCENARIO.yaml'\n" << usage();
    return 2;
  }
  const std::string path = argv[2];
  std::optional<bool> recovery;
  std::optional<uint64_t> seed;
  std::optional<double> duration;
  std::optional<std::string> kind;
  RunOptions options;
  for (int i = 3; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&](const char* what) -> std::string {
      if (i + 1 >= argc) throw ScenarioError("command line: " + arg + ": missing " + what);
      return argv[++i];
    };
    try {
      if (arg == "--recovery") {
        const std::string v = value("on|off");
        if (v != "on" && v != "off") throw ScenarioError("command line: --recovery: expected on or off, got '" + v + "'");
        recovery = v == "on";
      } else if (arg == "--seed") {
        const std::string v = value("an integer");
        if (v.empty() || v.size() > 19 || v.find_first_not_of("0123456789") != std::string::npos)
          throw ScenarioError("command line: --seed: expected a non-negative integer, got '" + v + "'");
        seed = std::stoull(v);
      } else if (arg == "--duration") {
        const std::string v = value("seconds");
        char* end = nullptr;
        const double d = std::strtod(v.c_str(), &end);
        if (end == v.c_str() || *end != '\0' || !std::isfinite(d) || d <= 0.0)
          throw ScenarioError("command line: --duration: expected seconds > 0, got '" + v + "'");
        duration = d;
      } else if (arg == "--out") {
        options.out_dir = value("a directory");
      } else if (arg == "--controller") {
        kind = value("a controller name");
      } else if (arg == "--substeps") {
        const std::string v = value("an integer 1..16");
        if (v.empty() || v.size() > 2 || v.find_first_not_of("0123456789") != std::string::npos ||
            std::stoi(v) < 1 || std::stoi(v) > 16)
          throw ScenarioError("command line: --substeps: expected an integer 1..16, got '" + v + "'");
        options.sim.integration.substeps = std::stoi(v);
      } else if (arg == "--no-log") {
        options.write_log = false;
      } else {
        throw ScenarioError("command line: " + arg + ": unknown option");
      }
    } catch (const ScenarioError& e) {
      std::cerr << "hyq_sim: " << e.what() << "\n" << usage();
      return 2;
    }
  }

  Scenario scenario;
  try {
    scenario = loadScenario(path);
  } catch (const ScenarioError& e) {
    std::cerr << "hyq_sim: " << e.what() << "\n";
    return 2;
  }
  if (recovery) scenario.controller_params.recovery.enabled = *recovery;
  if (seed) scenario.seed = *seed;
  if (duration) scenario.duration = *duration;
  if (kind) scenario.controller_kind = *kind;
  std::unique_ptr<ControllerPort> controller = makeController(scenario.controller_kind, scenario);
  if (!controller) {
    std::cerr << "hyq_sim: " << (kind ? "command line: --controller" : path + ": controller.kind")
              << ": unknown controller '" << scenario.controller_kind << "'\n" << usage();
    return 2;
  }

  RunResult r;
  try {
    Metrics metrics;
    r = runScenario(scenario, *controller, options, {&metrics});
  } catch (const std::exception& e) {
    std::cerr << "hyq_sim: " << e.what() << "\n";
    return 1;
  }
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
