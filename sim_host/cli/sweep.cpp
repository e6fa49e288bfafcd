#include "sim_host/cli/sweep.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/file.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <ctime>
#include <functional>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <optional>
#include <sstream>
#include <thread>

#include "sim_host/loop/controller_port.hpp"
#include "sim_host/physics/mujoco_model.hpp"
#include "sim_host/records/run_log.hpp"
#include "sim_host/scenario/scenario.hpp"
#include "sim_host/physics/terrain.hpp"

extern char** environ;

namespace hyq::sim {
namespace {

namespace fs = std::filesystem;

// A sweep's cases at most: each is a folder of its own, written before any
// runs (docs/sweeps.md).
constexpr size_t kMaxCases = 10000;
constexpr size_t kMaxValuesPerKey = 10000;
// Slurm's default MaxArraySize is 1001 (indices 0..1000): larger sweeps go
// in several arrays.
constexpr size_t kSlurmArrayChunk = 1000;

std::string usage() {
  return "usage: hyq_sim sweep SWEEP.yaml [--out DIR] [--jobs N] [--backend parallel|slurm]\n"
         "                [--no-wait] [--aggregate] [--fresh] [--retry-failed] [--timeout S]\n"
         "                [--sim PATH]\n"
         "                [--quiet] [--json] [--no-plots]\n"
         "  --out DIR      the sweep's folder (default out/sweeps/<name>)\n"
         "  --jobs N       cases at once (parallel: on this machine; slurm: the array's\n"
         "                 limit); default the number of processors\n"
         "  --backend      parallel: GNU parallel on this machine (default);\n"
         "                 slurm: sbatch --array (SBATCH_* variables reach sbatch)\n"
         "  --no-wait      slurm: submit and return; aggregate later with --aggregate\n"
         "  --aggregate    run nothing: aggregate the cases already done\n"
         "  --fresh        run every case again\n"
         "  --retry-failed run again the cases that failed, crashed or timed out\n"
         "  --timeout S    per case, instead of the sweep file's timeout_s\n"
         "  --sim PATH     the simulator each case runs (default this hyq_sim)\n"
         "  --quiet        no progress and no table; --json: sweep.json's totals on stdout\n";
}

// A sweep file's or a scenario file's text, with the scenario reader's bound.
std::string readBounded(const std::string& path) {
  std::string text = readScenarioFile(path);
  if (text.size() > kMaxScenarioFileBytes)
    throw ScenarioError(clipForMessage(path, 200) + ": too large: at most " +
                        std::to_string(kMaxScenarioFileBytes) + " bytes");
  return text;
}

// Writes `text` to `path` through a temporary and a rename.
void writeFile(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out << text;
    if (!out.flush()) throw std::runtime_error(clipForMessage(tmp, 200) + ": cannot write");
  }
  fs::rename(tmp, path);
}

std::string flowYaml(const YAML::Node& n) {
  YAML::Emitter e;
  e.SetMapFormat(YAML::Flow);
  e.SetSeqFormat(YAML::Flow);
  e << n;
  return e.c_str();
}

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

std::string shellQuote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// The dotted path's element `part` of `node`, or the node's elements.
void applyAt(YAML::Node node, const std::vector<std::string>& parts, size_t i,
             const YAML::Node& value, const std::string& key) {
  const std::string& part = parts[i];
  const bool last = i + 1 == parts.size();
  auto fail = [&](const std::string& why) {
    throw ScenarioError("set: " + clipForMessage(key) + ": " + why);
  };
  if (node.IsSequence()) {
    std::vector<size_t> indices;
    if (part == "*") {
      for (size_t k = 0; k < node.size(); ++k) indices.push_back(k);
      if (indices.empty()) fail("'" + part + "': the list is empty");
    } else {
      if (part.empty() || part.size() > 6 || part.find_first_not_of("0123456789") != std::string::npos)
        fail("'" + clipForMessage(part) + "': expected a list index or '*'");
      const size_t k = std::stoul(part);
      if (k >= node.size()) fail("index " + part + " beyond the list's " + std::to_string(node.size()) + " entries");
      indices.push_back(k);
    }
    for (size_t k : indices) {
      if (last) {
        node[k] = YAML::Clone(value);
      } else {
        applyAt(node[k], parts, i + 1, value, key);
      }
    }
    return;
  }
  if (node.IsScalar()) fail("'" + clipForMessage(part) + "' under a value that is not a map or a list");
  if (part == "*" || part.empty()) fail("'" + clipForMessage(part) + "' needs a list");
  if (last) {
    node[part] = YAML::Clone(value);
    return;
  }
  if (!node[part] || node[part].IsNull()) node[part] = YAML::Node(YAML::NodeType::Map);
  applyAt(node[part], parts, i + 1, value, key);
}

// One axis's values as flow-YAML texts: a list, or {from, to, step|count}.
std::vector<std::string> axisValues(const YAML::Node& n, const std::string& where) {
  auto fail = [&](const std::string& why) { throw ScenarioError(where + ": " + why); };
  std::vector<std::string> out;
  if (n.IsSequence()) {
    if (n.size() == 0) fail("empty list");
    if (n.size() > kMaxValuesPerKey) fail("more than " + std::to_string(kMaxValuesPerKey) + " values");
    for (const auto& v : n) out.push_back(flowYaml(v));
    return out;
  }
  if (!n.IsMap()) fail("expected a list of values or {from, to, step} or {from, to, count}");
  std::vector<std::string> seen;
  for (const auto& kv : n) {
    const std::string k = kv.first.as<std::string>();
    if (k != "from" && k != "to" && k != "step" && k != "count")
      fail("unknown key '" + clipForMessage(k) + "' (expected from, to, step or count)");
    if (std::find(seen.begin(), seen.end(), k) != seen.end()) fail(k + ": given twice");
    seen.push_back(k);
  }
  if (!n["from"] || !n["to"] || (!n["step"] == !n["count"]))
    fail("expected {from, to, step} or {from, to, count}");
  double from = 0, to = 0;
  try {
    from = n["from"].as<double>();
    to = n["to"].as<double>();
  } catch (const YAML::Exception&) {
    fail("from and to must be numbers");
  }
  if (!std::isfinite(from) || !std::isfinite(to)) fail("from and to must be finite");
  if (n["count"]) {
    long count = 0;
    try {
      count = n["count"].as<long>();
    } catch (const YAML::Exception&) {
      fail("count must be an integer");
    }
    if (count < 1 || count > static_cast<long>(kMaxValuesPerKey))
      fail("count: expected 1.." + std::to_string(kMaxValuesPerKey));
    for (long k = 0; k < count; ++k)
      out.push_back(number(count == 1 ? from : from + (to - from) * k / (count - 1)));
    return out;
  }
  double step = 0;
  try {
    step = n["step"].as<double>();
  } catch (const YAML::Exception&) {
    fail("step must be a number");
  }
  if (!(std::fabs(step) > 0) || !std::isfinite(step) || (to - from) * step < 0)
    fail("step must be non-zero, finite and lead from 'from' to 'to'");
  const double steps = std::floor((to - from) / step + 1e-9);
  if (steps + 1 > kMaxValuesPerKey) fail("more than " + std::to_string(kMaxValuesPerKey) + " values");
  for (long k = 0; k <= static_cast<long>(steps); ++k) out.push_back(number(from + k * step));
  return out;
}

std::vector<unsigned long long> seedList(const YAML::Node& n, const std::string& where) {
  auto fail = [&](const std::string& why) { throw ScenarioError(where + ": " + why); };
  std::vector<unsigned long long> out;
  try {
    if (n.IsSequence()) {
      for (const auto& v : n) out.push_back(v.as<unsigned long long>());
    } else if (n.IsMap() && n["from"] && n["to"] && n.size() == 2) {
      const auto from = n["from"].as<unsigned long long>();
      const auto to = n["to"].as<unsigned long long>();
      if (to < from) fail("expected from <= to");
      if (to - from >= kMaxCases)
        fail((to - from == std::numeric_limits<unsigned long long>::max() ? std::string("more than 10^19")
                                                                          : std::to_string(to - from + 1)) +
             " seeds: a sweep has at most " + std::to_string(kMaxCases) + " cases");
      for (unsigned long long k = 0; k <= to - from; ++k) out.push_back(from + k);
    } else if (n.IsScalar()) {
      out.push_back(n.as<unsigned long long>());
    } else {
      fail("expected a seed, a list of seeds or {from, to}");
    }
  } catch (const YAML::Exception&) {
    fail("seeds are integers 0..18446744073709551615");
  }
  if (out.empty()) fail("no seed");
  std::vector<unsigned long long> sorted = out;
  std::sort(sorted.begin(), sorted.end());
  const auto twice = std::adjacent_find(sorted.begin(), sorted.end());
  if (twice != sorted.end()) fail("seed " + std::to_string(*twice) + " twice");
  return out;
}

// A scalar or a list of scalars, as texts.
std::vector<std::string> scalars(const YAML::Node& n) {
  std::vector<std::string> out;
  if (n.IsSequence()) {
    for (const auto& v : n) out.push_back(v.IsScalar() ? v.Scalar() : flowYaml(v));
  } else {
    out.push_back(n.IsScalar() ? n.Scalar() : flowYaml(n));
  }
  return out;
}

std::string padded(int v, int width) {
  std::string s = std::to_string(v);
  return std::string(s.size() < static_cast<size_t>(width) ? width - s.size() : 0, '0') + s;
}

// A sweep file's refusal: one line naming the file and the key.
[[noreturn]] void failAt(const std::string& file, const std::string& key, const std::string& why) {
  throw ScenarioError(file + ": " + key + ": " + why);
}

// The sweep file's mapping, refused when malformed or when it has a key
// the sweep does not know.
YAML::Node sweepRoot(const std::string& text, const std::string& file) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw ScenarioError(file + ": malformed YAML at line " + std::to_string(e.mark.line + 1) + ": " +
                        clipForMessage(e.msg));
  }
  if (!root.IsMap()) failAt(file, "(top level)", "expected a map");
  std::vector<std::string> seen;
  for (const auto& kv : root) {
    const std::string k = kv.first.as<std::string>();
    // YAML takes the first of a repeated key: refused, as the scenario
    // reader does.
    if (std::find(seen.begin(), seen.end(), k) != seen.end()) failAt(file, clipForMessage(k), "given twice");
    seen.push_back(k);
    static const char* const kKeys[] = {"name",    "scenario", "seeds",           "recovery", "engines",
                                        "duration", "timeout_s", "goal_distance_m", "set"};
    if (std::none_of(std::begin(kKeys), std::end(kKeys), [&](const char* a) { return k == a; }))
      failAt(file, clipForMessage(k), "unknown key (expected name, scenario, seeds, recovery, engines, "
                                      "duration, timeout_s, goal_distance_m or set)");
  }
  return root;
}

// name, scenario (relative to the sweep file `path`), timeout_s and goal_distance_m.
void readSweepHead(const YAML::Node& root, const std::string& path, const std::string& file, Sweep& sweep) {
  try {
    if (!root["name"]) failAt(file, "name", "missing");
    sweep.name = root["name"].as<std::string>();
    if (!isPlainFileName(sweep.name))
      failAt(file, "name", "'" + clipForMessage(sweep.name) +
                               "': use 1..64 letters, digits, '_', '-' or '.' (it names the folder)");
    if (!root["scenario"]) failAt(file, "scenario", "missing");
    const fs::path rel = root["scenario"].as<std::string>();
    sweep.scenario_file = (rel.is_absolute() ? rel : fs::path(path).parent_path() / rel).lexically_normal().string();
    if (root["timeout_s"]) {
      sweep.timeout_s = root["timeout_s"].as<double>();
      if (!(sweep.timeout_s >= 1 && sweep.timeout_s <= 86400)) failAt(file, "timeout_s", "expected 1..86400 s");
    }
    if (root["goal_distance_m"]) sweep.goal_distance_m = root["goal_distance_m"].as<double>();
    if (!(sweep.goal_distance_m < 1000)) failAt(file, "goal_distance_m", "expected < 1000 m");
  } catch (const YAML::Exception&) {
    failAt(file, "(top level)", "a value of the wrong type (name and scenario are text, timeout_s and "
                                "goal_distance_m numbers)");
  }
}

// What every parameter combination runs: each seed, recovery setting and
// engine (the sweep file's lists, or else the scenario's own).
struct CaseAxes {
  std::vector<unsigned long long> seeds;
  std::vector<bool> recoveries;
  std::vector<std::string> engines;
};

CaseAxes readCaseAxes(const YAML::Node& root, const std::string& file, const Scenario& base) {
  CaseAxes each{{base.seed}, {base.controller_params.recovery.enabled}, {engineName(base.physics.engine)}};
  if (root["seeds"]) each.seeds = seedList(root["seeds"], file + ": seeds");
  if (root["recovery"]) {
    each.recoveries.clear();
    const YAML::Node r = root["recovery"];
    for (const std::string& t : scalars(r)) {
      if (t == "on" || t == "true") each.recoveries.push_back(true);
      else if (t == "off" || t == "false") each.recoveries.push_back(false);
      else failAt(file, "recovery", "expected on or off, got '" + clipForMessage(t) + "'");
    }
  }
  if (root["engines"]) {
    each.engines.clear();
    const YAML::Node r = root["engines"];
    for (const std::string& t : scalars(r)) {
      EngineKind e;
      if (!parseEngineName(t, e)) failAt(file, "engines", "expected ode or mujoco, got '" + clipForMessage(t) + "'");
      each.engines.push_back(t);
    }
  }
  if (std::count(each.recoveries.begin(), each.recoveries.end(), true) > 1 ||
      std::count(each.recoveries.begin(), each.recoveries.end(), false) > 1)
    failAt(file, "recovery", "a setting twice");
  for (const std::string& e : each.engines)
    if (std::count(each.engines.begin(), each.engines.end(), e) > 1) failAt(file, "engines", e + " twice");
  return each;
}

// Parameter axes (set:), in the file's order; their keys into sweep.set_keys.
std::vector<std::vector<std::string>> readSetAxes(const YAML::Node& root, const std::string& file, Sweep& sweep) {
  std::vector<std::vector<std::string>> axes;
  if (!root["set"]) return axes;
  if (!root["set"].IsMap()) failAt(file, "set", "expected a map of scenario keys to values");
  for (const auto& kv : root["set"]) {
    const std::string key = kv.first.as<std::string>();
    if (key == "seed" || key == "controller.recovery" || key == "physics.engine")
      failAt(file, "set." + clipForMessage(key), "use seeds, recovery or engines");
    if (std::find(sweep.set_keys.begin(), sweep.set_keys.end(), key) != sweep.set_keys.end())
      failAt(file, "set." + clipForMessage(key), "given twice");
    sweep.set_keys.push_back(key);
    axes.push_back(axisValues(kv.second, file + ": set." + clipForMessage(key)));
  }
  return axes;
}

// The values of parameter combination `p`, one per axis: the last axis
// counts fastest.
std::vector<std::pair<std::string, std::string>> pointValues(const std::vector<std::vector<std::string>>& axes,
                                                             const std::vector<std::string>& set_keys, size_t p) {
  std::vector<std::pair<std::string, std::string>> values;
  size_t rest = p;
  for (size_t a = axes.size(); a-- > 0;) {
    const std::string& v = axes[a][rest % axes[a].size()];
    rest /= axes[a].size();
    values.insert(values.begin(), {set_keys[a], v});
  }
  return values;
}

// The cases of parameter combination `p` (`values`; `yaml` its scenario)
// into sweep.cases: one per engine, recovery setting and seed.
void addCases(const std::string& yaml, const std::vector<std::pair<std::string, std::string>>& values, size_t p,
              int point_width, const CaseAxes& each, Sweep& sweep) {
  for (const std::string& engine : each.engines)
    for (bool recovery : each.recoveries)
      for (unsigned long long seed : each.seeds) {
        SweepCase c;
        c.point = static_cast<int>(p);
        c.values = values;
        c.engine = engine;
        c.recovery = recovery;
        c.seed = seed;
        c.id = (values.empty() ? std::string() : "p" + padded(static_cast<int>(p), point_width) + "_") +
               engine + "_" + (recovery ? "on" : "off") + "_s" + std::to_string(seed);
        std::string y = setScenarioKey(yaml, "seed", std::to_string(seed));
        y = setScenarioKey(y, "controller.recovery", recovery ? "true" : "false");
        c.scenario_yaml = setScenarioKey(y, "physics.engine", engine);
        sweep.cases.push_back(std::move(c));
      }
}

// A parameter combination's scenario (its case `c`) checked as a run would
// check it, so that a value no run takes stops the sweep before any case
// folder is written: the scenario reader's ranges, the controller's name
// and, with MuJoCo among the engines, its ground. The refusal names the
// case, its set values and the key.
void checkCombination(const std::string& file, const SweepCase& c, bool mujoco) {
  std::string set;
  for (const auto& [key, value] : c.values) set += (set.empty() ? "" : ", ") + key + " = " + value;
  const std::string origin = "case " + c.id + (set.empty() ? "" : " (set " + set + ")");
  try {
    const Scenario s = parseScenario(c.scenario_yaml, origin);
    const std::vector<std::string> kinds = controllerKinds();
    if (std::find(kinds.begin(), kinds.end(), s.controller_kind) == kinds.end()) {
      std::string list;
      for (const std::string& k : kinds) list += (list.empty() ? "" : ", ") + k;
      throw ScenarioError(clipForMessage(origin, 200) + ": controller.kind: unknown controller '" +
                          clipForMessage(s.controller_kind) + "' (expected one of: " + list + ")");
    }
    if (mujoco) checkMujocoGround(s, Terrain(s.terrain));
  } catch (const ScenarioError& e) {
    throw ScenarioError(file + ": " + e.what());
  }
}

// ---------------------------------------------------------------------------
// Running

enum class Status { pending, ok, failed, crashed, timeout, damaged };

// A case's exit status as its wrapper wrote it: "<status> <seconds>", with
// timeout(1)'s conventions (124: timed out; 128 + n: killed by signal n;
// 137 also when timeout had to KILL after its TERM, told apart by the time).
// An exit_code that is not a regular file of a few bytes is `damaged`, the
// reason in `why` (one line naming it); it is never waited on.
Status caseStatus(const std::string& case_dir, double timeout_s, std::string* why = nullptr) {
  constexpr size_t kMaxExitCodeBytes = 64;
  const std::string path = case_dir + "/exit_code";
  std::error_code ec;
  if (!fs::exists(path, ec)) return Status::pending;
  std::string text;
  try {
    text = readRegularFile(path, kMaxExitCodeBytes);
    if (text.size() > kMaxExitCodeBytes)
      throw ScenarioError(path + ": too large: at most " + std::to_string(kMaxExitCodeBytes) + " bytes");
  } catch (const ScenarioError& e) {
    if (why != nullptr) *why = e.what();
    return Status::damaged;
  }
  std::istringstream in(text);
  int code = 0;
  double seconds = 0.0;
  if (!(in >> code)) return Status::pending;
  in >> seconds;
  if (code == 0) return fs::exists(case_dir + "/summary.json", ec) ? Status::ok : Status::failed;
  if (code == 124 || (code == 137 && seconds >= timeout_s)) return Status::timeout;
  if (code > 128) return Status::crashed;
  return Status::failed;
}

// The shell line that runs one case. The simulator runs in the background
// under timeout(1) so that a TERM or INT to the line (a stopped sweep, a
// cancelled array task) is passed on to it and waited for, leaving no run
// behind; then the exit status is written, last and through a rename: a
// case with exit_code is done, whatever ended it. With `sweep_pid` (> 0)
// the line first checks that the sweep still runs, and ends without
// running its case when it does not.
std::string caseLine(const std::string& dir, const std::string& sim, double timeout_s, pid_t sweep_pid = 0) {
  const std::string guard = sweep_pid > 0 ? "kill -0 " + std::to_string(sweep_pid) + " 2>/dev/null || exit 98; " : "";
  return guard + "cd " + shellQuote(dir) + " || exit 97; s=$SECONDS; timeout -k 10 " + number(timeout_s) + " " +
         shellQuote(sim) + " run scenario.yaml --out . --no-log --quiet > run.log 2>&1 & t=$!; " +
         "trap 'kill -TERM $t 2>/dev/null; wait $t; exit 130' INT TERM HUP; wait $t; c=$?; " +
         "echo \"$c $((SECONDS - s))\" > .exit_code.tmp && mv .exit_code.tmp exit_code";
}

volatile std::sig_atomic_t g_stop_signal = 0;
extern "C" void onStopSignal(int signal) { g_stop_signal = signal; }

// INT, TERM and HUP stop the sweep (its cases are stopped and waited for)
// while this lives.
class StopSignals {
 public:
  StopSignals() {
    g_stop_signal = 0;
    struct sigaction a {};
    a.sa_handler = onStopSignal;
    sigemptyset(&a.sa_mask);
    for (int k = 0; k < 3; ++k) ::sigaction(kSignals[k], &a, &old_[k]);
  }
  ~StopSignals() {
    for (int k = 0; k < 3; ++k) ::sigaction(kSignals[k], &old_[k], nullptr);
  }
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;

 private:
  static constexpr int kSignals[3] = {SIGINT, SIGTERM, SIGHUP};
  struct sigaction old_[3];
};

// Runs `args` with stdout and stderr into `log` (appended), in a process
// group of its own that ends with the sweep however the sweep ends (SIGKILL
// included): the kernel sends it TERM then (PR_SET_PDEATHSIG), which GNU
// parallel passes on to its cases (--termseq). Returns its pid once it has
// started; throws when it cannot start.
pid_t spawn(const std::vector<std::string>& args, const std::string& log) {
  std::vector<char*> argv;
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const int out = ::open(log.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (out < 0) throw std::runtime_error(log + ": " + std::strerror(errno));
  // The child writes exec's errno here; the pipe closes unread on success.
  int started[2];
  if (::pipe2(started, O_CLOEXEC) != 0) {
    const int error = errno;
    ::close(out);
    throw std::runtime_error(args[0] + ": cannot start: " + std::strerror(error));
  }
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid == 0) {
    // Only async-signal-safe calls until exec.
    ::setpgid(0, 0);
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (::getppid() != parent) ::_exit(127);  // the sweep ended before the line above
    const int in = ::open("/dev/null", O_RDONLY);
    if (in < 0 || ::dup2(in, STDIN_FILENO) < 0 || ::dup2(out, STDOUT_FILENO) < 0 || ::dup2(out, STDERR_FILENO) < 0)
      ::_exit(127);
    ::execvp(argv[0], argv.data());
    const int error = errno;
    (void)!::write(started[1], &error, sizeof error);
    ::_exit(127);
  }
  const int fork_error = errno;
  ::close(started[1]);
  ::close(out);
  int error = pid < 0 ? fork_error : 0;
  if (pid > 0) {
    ssize_t n;
    while ((n = ::read(started[0], &error, sizeof error)) < 0 && errno == EINTR) {
    }
    if (n != static_cast<ssize_t>(sizeof error)) error = 0;
    if (error != 0) ::waitpid(pid, nullptr, 0);
  }
  ::close(started[0]);
  if (error != 0) throw std::runtime_error(args[0] + ": cannot start: " + std::strerror(error));
  return pid;
}

// Runs `args` (output into `log`) and waits for it; its exit status, -1 if
// it could not start or was killed.
int runAndWait(const std::vector<std::string>& args, const std::string& log) {
  pid_t pid = -1;
  try {
    pid = spawn(args, log);
  } catch (const std::runtime_error&) {
    return -1;
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

bool onPath(const std::string& program) {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "/usr/bin:/bin");
  std::string dir;
  while (std::getline(dirs, dir, ':'))
    if (!dir.empty() && ::access((dir + "/" + program).c_str(), X_OK) == 0) return true;
  return false;
}

std::string clockText(double s) {
  char buf[32];
  const long t = std::lround(std::max(0.0, s));
  if (t >= 3600)
    std::snprintf(buf, sizeof buf, "%ldh%02ldm", t / 3600, (t / 60) % 60);
  else
    std::snprintf(buf, sizeof buf, "%ldm%02lds", t / 60, t % 60);
  return buf;
}

// The Slurm job ids that sbatch --parsable wrote into the folder's
// slurm/sbatch-*.log files.
std::vector<std::string> submittedJobs(const std::string& out_dir) {
  std::vector<std::string> ids;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(out_dir + "/slurm", ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind("sbatch-", 0) != 0) continue;
    std::ifstream in(e.path());
    std::string line;
    while (std::getline(in, line)) {
      const std::string id = line.substr(0, line.find(';'));
      if (!id.empty() && id.size() < 20 && id.find_first_not_of("0123456789") == std::string::npos)
        ids.push_back(id);
    }
  }
  return ids;
}

// Those of `ids` that Slurm still has queued or running (empty if squeue is
// not there to ask).
std::string stillQueued(const std::vector<std::string>& ids) {
  if (ids.empty() || !onPath("squeue")) return "";
  std::string list;
  for (const std::string& id : ids) list += (list.empty() ? "" : ",") + id;
  FILE* pipe = ::popen(("squeue -h -o %i -j " + list + " 2>/dev/null").c_str(), "r");
  if (pipe == nullptr) return "";
  std::string out;
  char buf[256];
  while (std::fgets(buf, sizeof buf, pipe) != nullptr && out.size() < 400) out += buf;
  ::pclose(pipe);
  for (char& c : out)
    if (c == '\n') c = ' ';
  return out;
}

enum class Outcome { done, backend_failed, interrupted };

// Waits for the backend's processes, printing progress from the cases'
// exit_code files. On INT, TERM or HUP: `stop` (which stops the cases),
// then waits for the backend (its process groups are killed after 30 s).
Outcome waitWithProgress(const std::vector<pid_t>& pids, const std::vector<std::string>& pending_dirs,
                         double timeout_s, const std::string& name, int jobs, bool quiet,
                         const std::function<void()>& stop, std::string& failure) {
  const bool tty = isatty(STDERR_FILENO);
  const auto start = std::chrono::steady_clock::now();
  std::vector<bool> alive(pids.size(), true);
  std::vector<bool> recorded(pending_dirs.size(), false);
  size_t running = pids.size(), done = 0, failed = 0;
  int last_decile = -1;
  bool ok = true, stopping = false;
  auto stop_deadline = start;
  for (int poll = 0;; ++poll) {
    for (size_t k = 0; k < pids.size(); ++k) {
      if (!alive[k]) continue;
      int status = 0;
      if (::waitpid(pids[k], &status, WNOHANG) != pids[k]) continue;
      alive[k] = false;
      --running;
      if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        ok = false;
        failure = WIFEXITED(status) ? "exit " + std::to_string(WEXITSTATUS(status))
                                    : "signal " + std::to_string(WTERMSIG(status));
      }
    }
    if (g_stop_signal != 0 && !stopping) {
      stopping = true;
      stop_deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
      if (!quiet) std::fprintf(stderr, "%ssweep %s: stopping its cases\n", tty ? "\n" : "", name.c_str());
      stop();
    }
    if (stopping && std::chrono::steady_clock::now() > stop_deadline)
      for (size_t k = 0; k < pids.size(); ++k)
        if (alive[k]) ::kill(-pids[k], SIGKILL);
    // Cases done are read once; those not done every 2 s (every 0.5 s for
    // the first 10 s), so that a large sweep on a network file system is not
    // polled case by case all the time.
    if (running == 0 || poll < 20 || poll % 4 == 0) {
      for (size_t k = 0; k < pending_dirs.size(); ++k) {
        if (recorded[k]) continue;
        const Status s = caseStatus(pending_dirs[k], timeout_s);
        if (s == Status::pending) continue;
        recorded[k] = true;
        ++done;
        failed += s != Status::ok;
      }
    }
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const size_t total = pending_dirs.size();
    if (!quiet && total > 0 && !stopping) {
      std::string eta = "-";
      if (done > 0 && done < total) eta = clockText(elapsed / done * (total - done));
      char line[256];
      std::snprintf(line, sizeof line, "sweep %s: %zu/%zu cases done, %zu failed, %zu running, %s elapsed, ETA %s",
                    name.c_str(), done, total, failed,
                    std::min(total - done, static_cast<size_t>(std::max(jobs, 1))), clockText(elapsed).c_str(),
                    eta.c_str());
      const int decile = static_cast<int>(10 * done / total);
      if (tty) {
        std::fprintf(stderr, "\r%-100s", line);
      } else if (decile != last_decile) {
        std::fprintf(stderr, "%s\n", line);
      }
      last_decile = decile;
    }
    if (running == 0) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
  }
  if (!quiet && tty && !stopping) std::fprintf(stderr, "\n");
  if (stopping) return Outcome::interrupted;
  return ok ? Outcome::done : Outcome::backend_failed;
}

std::string selfExecutable() {
  std::error_code ec;
  const fs::path p = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string("hyq_sim") : p.string();
}

bool hasControlCharacter(const std::string& s) {
  return std::any_of(s.begin(), s.end(), [](char c) { return static_cast<unsigned char>(c) < 0x20 || c == 0x7f; });
}

// An exclusive lock on the sweep's folder (flock on .sweep.lock) for as long
// as the sweep or any process it started lives: the descriptor is inherited
// (no close-on-exec) by GNU parallel, each case's line and its run, and the
// lock is released only when the last of them has closed it. A sweep killed
// with SIGKILL thus keeps its folder locked until its cases have ended.
class FolderLock {
 public:
  explicit FolderLock(const std::string& dir) : fd_(::open((dir + "/.sweep.lock").c_str(), O_RDWR | O_CREAT, 0644)) {}
  ~FolderLock() {
    if (fd_ >= 0) ::close(fd_);
  }
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;
  bool acquired() const { return fd_ >= 0 && ::flock(fd_, LOCK_EX | LOCK_NB) == 0; }

 private:
  int fd_;
};

// ---------------------------------------------------------------------------
// The command

// `hyq_sim sweep`'s command line.
struct SweepOptions {
  std::string path;                    // the sweep file
  // The sweep's folder ("": out/sweeps/<name>), made absolute once the sweep is read.
  std::string out_dir;
  std::string backend = "parallel";    // "parallel" | "slurm"
  std::string sim = selfExecutable();  // the simulator each case runs
  int jobs = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));  // cases at once
  bool no_wait = false, aggregate_only = false, fresh = false, retry_failed = false, quiet = false, json = false,
       plots = true;
  std::optional<double> timeout;       // [s] per case, instead of the sweep file's timeout_s
};

// A refusal: one line on stderr, exit code 2 (bad input).
int refuse(const std::string& message) {
  std::cerr << "hyq_sim: " << clipForMessage(message, 500) << "\n";
  return 2;
}

// A failure (the folder, the backend): one line on stderr, exit code 1.
int failed(const std::string& message) {
  std::cerr << "hyq_sim: " << clipForMessage(message, 500) << "\n";
  return 1;
}

// The options after SWEEP.yaml into `o`; "" when they are good, else the
// refusal (the first bad option's).
std::string parseSweepOptions(int argc, char** argv, SweepOptions& o) {
  std::vector<std::string> seen;
  for (int i = 3; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.rfind("--", 0) == 0 && std::find(seen.begin(), seen.end(), arg) != seen.end())
      return "command line: " + clipForMessage(arg) + ": given twice";
    seen.push_back(arg);
    // The option's value: the next argument, unless it is empty or an option.
    auto value = [&]() -> std::optional<std::string> {
      if (i + 1 >= argc || std::strncmp(argv[i + 1], "--", 2) == 0 || argv[i + 1][0] == '\0')
        return std::nullopt;
      return std::string(argv[++i]);
    };
    auto missing = [&](const char* what) { return "command line: " + arg + ": missing " + what; };
    if (arg == "--out" || arg == "--sim") {
      const auto v = value();
      if (!v) return missing(arg == "--out" ? "a directory" : "a program");
      if (hasControlCharacter(*v)) return "command line: " + arg + ": a control character in the path";
      (arg == "--out" ? o.out_dir : o.sim) = arg == "--out" ? *v : fs::absolute(*v).string();
    } else if (arg == "--jobs") {
      const auto v = value();
      if (!v) return missing("an integer 1..1024");
      if (v->size() > 4 || v->find_first_not_of("0123456789") != std::string::npos || std::stoi(*v) < 1 ||
          std::stoi(*v) > 1024)
        return "command line: --jobs: expected an integer 1..1024, got '" + clipForMessage(*v) + "'";
      o.jobs = std::stoi(*v);
    } else if (arg == "--backend") {
      const auto v = value();
      if (!v) return missing("parallel|slurm");
      if (*v != "parallel" && *v != "slurm")
        return "command line: --backend: expected parallel or slurm, got '" + clipForMessage(*v) + "'";
      o.backend = *v;
    } else if (arg == "--timeout") {
      const auto v = value();
      if (!v) return missing("seconds");
      const std::optional<double> t = parseDecimal(*v);
      if (!t || !(*t >= 1 && *t <= 86400))
        return "command line: --timeout: expected seconds in [1, 86400] (a decimal number), got '" +
               clipForMessage(*v) + "'";
      o.timeout = *t;
    } else if (arg == "--no-wait") {
      o.no_wait = true;
    } else if (arg == "--aggregate") {
      o.aggregate_only = true;
    } else if (arg == "--fresh") {
      o.fresh = true;
    } else if (arg == "--retry-failed") {
      o.retry_failed = true;
    } else if (arg == "--quiet") {
      o.quiet = true;
    } else if (arg == "--json") {
      o.json = true;
    } else if (arg == "--no-plots") {
      o.plots = false;
    } else {
      return "command line: " + clipForMessage(arg) + ": unknown option (hyq_sim sweep --help lists them)";
    }
  }
  return "";
}

// Options that do not go together; "" when none, else the refusal.
std::string checkSweepOptions(const SweepOptions& o) {
  if (o.no_wait && o.backend != "slurm") return "command line: --no-wait: only with --backend slurm";
  return "";
}

// The cases that run this time, with their shell lines (jobs.txt).
struct PendingCases {
  std::vector<std::string> dirs;
  std::string lines;
};

// Which cases run: those not done, those whose scenario changed, and with
// --retry-failed those that did not run to their end; their folders are
// emptied of an earlier run and given their scenario. With --aggregate none
// runs, and a case done with another scenario than the sweep's is refused.
// "" or the refusal; throws when a file cannot be read or written.
std::string selectCases(const Sweep& sweep, const SweepOptions& o, PendingCases& pending) {
  // Every case's state first: a damaged one is refused before any folder
  // is touched.
  std::vector<Status> statuses;
  std::vector<bool> same;
  for (const SweepCase& c : sweep.cases) {
    const std::string dir = o.out_dir + "/cases/" + c.id;
    std::string damage;
    statuses.push_back(caseStatus(dir, sweep.timeout_s, &damage));
    if (statuses.back() == Status::damaged) return damage;
    std::error_code ec;
    same.push_back(fs::exists(dir + "/scenario.yaml", ec) && readBounded(dir + "/scenario.yaml") == c.scenario_yaml);
  }
  size_t stale = 0;
  std::string stale_id;
  // Parallel's lines end at once if the sweep is gone before they start.
  const pid_t guard = o.backend == "parallel" ? ::getpid() : 0;
  for (size_t k = 0; k < sweep.cases.size(); ++k) {
    const SweepCase& c = sweep.cases[k];
    const std::string dir = o.out_dir + "/cases/" + c.id;
    const Status status = statuses[k];
    if (o.aggregate_only) {
      if (!same[k] && status != Status::pending && stale++ == 0) stale_id = c.id;
      continue;
    }
    if (!(o.fresh || !same[k] || status == Status::pending || (o.retry_failed && status != Status::ok))) continue;
    fs::create_directories(dir);
    for (const char* f : {"exit_code", "summary.json", "events.csv", "run.log"}) fs::remove(dir + "/" + f);
    if (!same[k]) writeFile(dir + "/scenario.yaml", c.scenario_yaml);
    pending.dirs.push_back(dir);
    pending.lines += caseLine(dir, o.sim, sweep.timeout_s, guard) + "\n";
  }
  if (stale > 0)
    return o.out_dir + ": " + std::to_string(stale) + " cases (" + stale_id +
           " the first) ran with another scenario than the sweep file gives now: start the sweep "
           "without --aggregate to run them again";
  return "";
}

// The sweep's own files in its folder: sweep.yaml (the file as read),
// cases.csv (what each case is) and sweep_meta.json; the report reads them.
void writeSweepRecords(const Sweep& sweep, const std::string& out_dir) {
  writeFile(out_dir + "/sweep.yaml", sweep.source_text);
  auto csvCell = [](const std::string& v) {
    std::string quoted;
    for (char ch : v) quoted += ch == '"' ? std::string("\"\"") : std::string(1, ch);
    return "\"" + quoted + "\"";
  };
  std::string csv = "id,point,engine,recovery,seed";
  for (const std::string& k : sweep.set_keys) csv += "," + csvCell(k);
  csv += "\n";
  for (const SweepCase& c : sweep.cases) {
    csv += c.id + "," + std::to_string(c.point) + "," + c.engine + "," + (c.recovery ? "on" : "off") + "," +
           std::to_string(c.seed);
    for (const auto& kv : c.values) csv += "," + csvCell(kv.second);
    csv += "\n";
  }
  writeFile(out_dir + "/cases.csv", csv);
  std::string meta = "{\"name\": " + jsonString(sweep.name) + ", \"scenario\": " +
                     jsonString(sweep.scenario_file) + ", \"cases\": " + std::to_string(sweep.cases.size()) +
                     ", \"timeout_s\": " + number(sweep.timeout_s) + ", \"goal_distance_m\": " +
                     (sweep.goal_distance_m < 0 ? std::string("null") : number(sweep.goal_distance_m)) +
                     ", \"set_keys\": [";
  for (size_t k = 0; k < sweep.set_keys.size(); ++k) meta += (k ? ", " : "") + jsonString(sweep.set_keys[k]);
  meta += "]}\n";
  writeFile(out_dir + "/sweep_meta.json", meta);
}

// The backend's processes while they run: their pids, how to stop them and
// the log that says why they failed.
struct Backend {
  std::vector<pid_t> pids;
  std::function<void()> stop;
  std::string log;
  // Slurm: each array's first line in the jobs file (0-based) and its
  // sbatch log (the job id).
  std::vector<std::pair<size_t, std::string>> arrays;
};

// GNU parallel on this machine, running the pending cases' lines.
std::optional<int> startParallel(const SweepOptions& o, const PendingCases& pending, Backend& backend) {
  if (!onPath("parallel")) return refuse("GNU parallel not found: install Debian's 'parallel' (make deps does)");
  writeFile(o.out_dir + "/jobs.txt", pending.lines);
  backend.log = o.out_dir + "/parallel.log";
  // The job lines are bash, whatever the user's shell.
  ::setenv("PARALLEL_SHELL", "/bin/bash", 1);
  // Stopped (or left by a sweep that died), parallel sends each case's
  // line TERM and gives it 15 s to stop its run (timeout(1) kills the run
  // 10 s after passing TERM on) before it kills it.
  backend.pids.push_back(spawn({"parallel", "--will-cite", "--jobs", std::to_string(o.jobs), "--termseq",
                                "TERM,15000,KILL,25", "--joblog", o.out_dir + "/joblog.tsv", "-a",
                                o.out_dir + "/jobs.txt"},
                               backend.log));
  const pid_t group = backend.pids.back();
  backend.stop = [group] { ::kill(-group, SIGTERM); };
  return std::nullopt;
}

// Slurm job arrays (sbatch --array) running the pending cases' lines. With
// --no-wait the sweep ends here, submitted.
std::optional<int> startSlurm(const SweepOptions& o, const Sweep& sweep, const PendingCases& pending,
                              Backend& backend) {
  // A submission's own jobs file: tasks still queued from an earlier
  // submission read theirs.
  const std::string stamp = std::to_string(std::time(nullptr)) + "-" + std::to_string(::getpid());
  if (!onPath("sbatch")) return refuse("sbatch not found: the slurm backend needs Slurm's clients");
  const std::string& out_dir = o.out_dir;
  fs::create_directories(out_dir + "/slurm");
  const std::string jobs_file = out_dir + "/slurm/jobs-" + stamp + ".txt";
  writeFile(jobs_file, pending.lines);
  const std::string script_file = out_dir + "/slurm/array-" + stamp + ".sh";
  writeFile(script_file,
            "#!/bin/bash\n"
            "# One case of the sweep per array task: line HYQ_SWEEP_OFFSET + task id of its jobs file.\n"
            "set -u\n"
            "line=$(sed -n \"$((HYQ_SWEEP_OFFSET + SLURM_ARRAY_TASK_ID))p\" " + shellQuote(jobs_file) + ")\n"
            "exec bash -c \"$line\"\n");
  const size_t chunks = (pending.dirs.size() + kSlurmArrayChunk - 1) / kSlurmArrayChunk;
  // --jobs in all: shared out among the arrays.
  const int per_array = std::max(1, o.jobs / static_cast<int>(chunks));
  const long minutes = static_cast<long>(std::ceil(sweep.timeout_s / 60.0)) + 2;
  for (size_t offset = 0; offset < pending.dirs.size(); offset += kSlurmArrayChunk) {
    const size_t n = std::min(kSlurmArrayChunk, pending.dirs.size() - offset);
    // Each array's own log: its job id names its tasks' output files.
    const std::string log = out_dir + "/slurm/sbatch-" + stamp + "-" + std::to_string(offset / kSlurmArrayChunk) +
                            ".log";
    backend.arrays.emplace_back(offset, log);
    if (backend.log.empty()) backend.log = log;
    // The folder has no '%' nor a backslash (refused): it stands for itself
    // in Slurm's file name pattern.
    std::vector<std::string> args{"sbatch", "--parsable", "--job-name=hyq-" + sweep.name,
                                  "--output=" + out_dir + "/slurm/%A_%a.out",
                                  "--time=" + std::to_string(minutes), "--ntasks=1", "--cpus-per-task=1",
                                  "--array=1-" + std::to_string(n) + "%" + std::to_string(per_array),
                                  "--export=ALL,HYQ_SWEEP_OFFSET=" + std::to_string(offset)};
    if (!o.no_wait) args.push_back("--wait");
    args.push_back(script_file);
    if (o.no_wait) {
      if (runAndWait(args, log) != 0) {
        std::cerr << "hyq_sim: sbatch failed (" << log << " says why)\n";
        return 1;
      }
    } else {
      backend.pids.push_back(spawn(args, log));
    }
  }
  if (o.no_wait) {
    std::printf("submitted %zu cases to Slurm (job ids in %s/slurm/sbatch-%s-*.log); when they are done:\n"
                "  hyq_sim sweep %s --out %s --aggregate\n",
                pending.dirs.size(), out_dir.c_str(), stamp.c_str(), o.path.c_str(), out_dir.c_str());
    return 0;
  }
  const std::vector<pid_t> waiting = backend.pids;
  const std::string dir = out_dir;
  backend.stop = [waiting, dir] {
    // Cancelling the arrays sends their tasks TERM, which each case's
    // line passes on to its run.
    std::vector<std::string> args{"scancel"};
    for (const std::string& id : submittedJobs(dir)) args.push_back(id);
    if (args.size() > 1) runAndWait(args, dir + "/slurm/scancel.log");
    for (pid_t p : waiting) ::kill(-p, SIGTERM);
  };
  return std::nullopt;
}

// Starts the backend on the pending cases; an exit code when the sweep ends
// here (a refusal, a backend that cannot start, a submission with --no-wait).
std::optional<int> startBackend(const SweepOptions& o, const Sweep& sweep, const PendingCases& pending,
                                Backend& backend) {
  try {
    if (o.backend == "parallel") return startParallel(o, pending, backend);
    return startSlurm(o, sweep, pending, backend);
  } catch (const std::exception& e) {
    return failed(e.what());
  }
}

// The cases that a Slurm array left without an exit status: how many, the
// first one's case, task and reason, and the sbatch log that lists them.
struct UnrunTasks {
  size_t count = 0;
  std::string first;
  std::string log;
};

// The last non-empty line of a small text file ("" if none or unreadable).
std::string lastLineOf(const std::string& path) {
  std::string text;
  try {
    text = readRegularFile(path, 1 << 16);
  } catch (const ScenarioError&) {
    return "";
  }
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r' || text.back() == ' ')) text.pop_back();
  return clipForMessage(text.substr(text.find_last_of('\n') == std::string::npos ? 0 : text.find_last_of('\n') + 1),
                        200);
}

// The job id in an sbatch log: its first line of the form sbatch
// --parsable prints, "<job id>" or "<job id>;<cluster>" ("" if none).
std::string jobIdIn(const std::string& log) {
  std::string text;
  try {
    text = readRegularFile(log, 1 << 16);
  } catch (const ScenarioError&) {
    return "";
  }
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    const std::string id = line.substr(0, line.find(';'));
    if (!id.empty() && id.size() < 20 && id.find_first_not_of("0123456789") == std::string::npos) return id;
  }
  return "";
}

// Why the Slurm arrays left cases without an exit status, case by case: the
// task's output file says what it did, and a task without one never ran its
// script (Slurm could not open that file, or did not start the task). The
// reasons are appended to each array's sbatch log.
UnrunTasks explainSlurmTasks(const SweepOptions& o, const Sweep& sweep, const PendingCases& pending,
                             const Backend& backend) {
  UnrunTasks unrun;
  for (size_t a = 0; a < backend.arrays.size(); ++a) {
    const auto& [offset, log] = backend.arrays[a];
    const std::string job = jobIdIn(log);
    const size_t end = a + 1 < backend.arrays.size() ? backend.arrays[a + 1].first : pending.dirs.size();
    std::string notes;
    for (size_t k = offset; k < end; ++k) {
      if (caseStatus(pending.dirs[k], sweep.timeout_s) != Status::pending) continue;
      const std::string task = (job.empty() ? std::string("<job>") : job) + "_" + std::to_string(k - offset + 1);
      const std::string out = "slurm/" + task + ".out";
      std::string why;
      if (job.empty())
        why = "sbatch gave no job id";
      else if (!fs::exists(o.out_dir + "/" + out))
        why = "no output file " + out + ": Slurm could not open it (a folder the node cannot write?) or never "
              "started the task";
      else
        why = "its output " + out + " ends: " + lastLineOf(o.out_dir + "/" + out);
      const std::string line = "case " + fs::path(pending.dirs[k]).filename().string() + " (task " + task + "): " + why;
      notes += line + "\n";
      if (unrun.count++ == 0) {
        unrun.first = line;
        unrun.log = log;
      }
    }
    if (notes.empty()) continue;
    std::ofstream(log, std::ios::app) << "hyq_sim: the array ended with cases that have no exit status:\n" << notes;
  }
  return unrun;
}

// Waits for the backend (progress on stderr); true when a signal stopped
// the sweep. A backend that failed before every case recorded its status
// is reported.
bool awaitBackend(const SweepOptions& o, const Sweep& sweep, const PendingCases& pending, const Backend& backend) {
  std::string failure;
  const Outcome outcome = waitWithProgress(backend.pids, pending.dirs, sweep.timeout_s, sweep.name, o.jobs, o.quiet,
                                           backend.stop, failure);
  if (outcome == Outcome::backend_failed) {
    // GNU parallel exits with the number of failed jobs: the cases' own
    // statuses say which. Any other failure of the backend is reported.
    const bool all_recorded = std::all_of(pending.dirs.begin(), pending.dirs.end(), [&](const std::string& d) {
      return caseStatus(d, sweep.timeout_s) != Status::pending;
    });
    const UnrunTasks unrun = o.backend == "slurm" ? explainSlurmTasks(o, sweep, pending, backend) : UnrunTasks{};
    if (unrun.count > 0)
      std::cerr << "hyq_sim: the slurm backend failed (" << failure << "; " << unrun.log << " says why): "
                << unrun.count << (unrun.count == 1 ? " case has" : " cases have") << " no exit status, the first "
                << unrun.first << "; they run when the sweep is started again\n";
    else if (!all_recorded)
      std::cerr << "hyq_sim: the " << o.backend << " backend failed (" << failure << "; " << backend.log
                << " says why); the cases left pending run when the sweep is started again\n";
  }
  return outcome == Outcome::interrupted;
}

// The aggregate: sweep.json, sweep.csv and the plots, by sweep_report.py;
// the sweep's exit code. Debian's python3 (which has matplotlib) before
// another one on PATH.
int runReport(const SweepOptions& o, const Sweep& sweep, size_t ran, double elapsed, bool interrupted) {
  const std::string python = ::access("/usr/bin/python3", X_OK) == 0 ? "/usr/bin/python3" : "python3";
  std::vector<std::string> report{python, std::string(HYQ_SOURCE_DIR) + "/sim_host/cli/sweep_report.py", o.out_dir,
                                  "--elapsed", number(elapsed), "--ran", std::to_string(ran)};
  if (o.quiet) report.push_back("--quiet");
  if (o.json) report.push_back("--json");
  if (!o.plots) report.push_back("--no-plots");
  std::vector<char*> argv_report;
  for (std::string& a : report) argv_report.push_back(a.data());
  argv_report.push_back(nullptr);
  std::fflush(stdout);
  pid_t pid = -1;
  if (posix_spawnp(&pid, python.c_str(), nullptr, nullptr, argv_report.data(), environ) != 0) {
    std::cerr << "hyq_sim: python3 not found: the sweep's report needs it\n";
    return 1;
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (interrupted) {
    std::cerr << "hyq_sim: sweep " << sweep.name << " stopped; the cases not done run when it is started again\n";
    return 130;
  }
  if (!WIFEXITED(status)) return 1;
  // The report exits 0 when every case ran to its end, 1 when some did not,
  // 2 when a case's files are damaged (its one line names the file).
  if (WEXITSTATUS(status) == 0 || WEXITSTATUS(status) == 2) return WEXITSTATUS(status);
  return 1;
}

}  // namespace

std::string setScenarioKey(const std::string& scenario_yaml, const std::string& key,
                           const std::string& value) {
  if (key.empty() || key.size() > 200) throw ScenarioError("set: expected a key of 1..200 characters");
  std::vector<std::string> parts;
  std::stringstream ss(key);
  std::string part;
  while (std::getline(ss, part, '.')) parts.push_back(part);
  if (parts.empty() || key.back() == '.')
    throw ScenarioError("set: " + clipForMessage(key) + ": empty part in the key");
  YAML::Node root = YAML::Load(scenario_yaml);
  if (!root.IsMap()) throw ScenarioError("set: the scenario is not a map");
  YAML::Node parsed;
  try {
    parsed = YAML::Load(value);
  } catch (const YAML::Exception& e) {
    throw ScenarioError("set: " + clipForMessage(key) + ": malformed value '" + clipForMessage(value) + "'");
  }
  applyAt(root, parts, 0, parsed, key);
  YAML::Emitter e;
  e << root;
  return std::string(e.c_str()) + "\n";
}


Sweep loadSweep(const std::string& path) {
  const std::string text = readBounded(path);
  const std::string file = clipForMessage(path, 200);
  const YAML::Node root = sweepRoot(text, file);
  Sweep sweep;
  sweep.source_file = path;
  sweep.source_text = text;
  readSweepHead(root, path, file, sweep);

  std::string base_yaml = readScenarioFile(sweep.scenario_file);
  const Scenario base = parseScenario(base_yaml, sweep.scenario_file);
  const CaseAxes each = readCaseAxes(root, file, base);
  if (root["duration"]) base_yaml = setScenarioKey(base_yaml, "duration", flowYaml(root["duration"]));

  // The product of the parameter axes' values.
  const std::vector<std::vector<std::string>> axes = readSetAxes(root, file, sweep);
  size_t points = 1;
  for (const auto& a : axes) {
    points *= a.size();
    if (points > kMaxCases) failAt(file, "set", "more than " + std::to_string(kMaxCases) + " combinations");
  }
  const size_t total = points * each.engines.size() * each.recoveries.size() * each.seeds.size();
  if (total > kMaxCases)
    failAt(file, "(top level)", std::to_string(total) + " cases: at most " + std::to_string(kMaxCases));

  const int point_width = points > 1000 ? 5 : 3;
  for (size_t p = 0; p < points; ++p) {
    const auto values = pointValues(axes, sweep.set_keys, p);
    std::string yaml = base_yaml;
    try {
      for (const auto& [key, value] : values) yaml = setScenarioKey(yaml, key, value);
    } catch (const ScenarioError& e) {
      failAt(file, "set", e.what());
    }
    addCases(yaml, values, p, point_width, each, sweep);
    checkCombination(file, sweep.cases.back(),
                     std::find(each.engines.begin(), each.engines.end(), "mujoco") != each.engines.end());
  }
  return sweep;
}

int sweepMain(int argc, char** argv) {
  if (argc >= 3 && (std::strcmp(argv[2], "--help") == 0 || std::strcmp(argv[2], "-h") == 0)) {
    std::cerr << usage();
    return 0;
  }
  if (argc < 3) return refuse("expected 'sweep SWEEP.yaml [options]' (hyq_sim sweep --help lists them)");
  SweepOptions o;
  o.path = argv[2];
  std::string refusal = parseSweepOptions(argc, argv, o);
  if (refusal.empty()) refusal = checkSweepOptions(o);
  if (!refusal.empty()) return refuse(refusal);

  Sweep sweep;
  try {
    sweep = loadSweep(o.path);
  } catch (const ScenarioError& e) {
    return refuse(e.what());
  } catch (const YAML::Exception& e) {
    return refuse(clipForMessage(o.path, 200) + ": malformed YAML: " + clipForMessage(e.what()));
  }
  if (o.timeout) sweep.timeout_s = *o.timeout;
  if (o.out_dir.empty()) o.out_dir = "out/sweeps/" + sweep.name;
  o.out_dir = fs::absolute(o.out_dir).lexically_normal().string();
  if (!o.out_dir.empty() && o.out_dir.back() == '/') o.out_dir.pop_back();
  if (o.backend == "slurm" && o.out_dir.find_first_of("\\%") != std::string::npos)
    return refuse("command line: --out: '" + clipForMessage(o.out_dir, 200) +
                  "': a backslash or '%' in the sweep's folder, which Slurm's file name patterns (sbatch --output) "
                  "read as escapes: choose a folder without them");

  const auto start = std::chrono::steady_clock::now();
  try {
    fs::create_directories(o.out_dir + "/cases");
  } catch (const std::exception& e) {
    return failed(e.what());
  }
  const FolderLock lock(o.out_dir);
  if (!lock.acquired())
    return refuse(o.out_dir + ": locked: another hyq_sim sweep, or cases of one that was killed, still run on "
                  "this folder: start again once they have ended");
  if (!o.aggregate_only) {
    const std::string queued = stillQueued(submittedJobs(o.out_dir));
    if (!queued.empty())
      return refuse(o.out_dir + ": Slurm jobs of an earlier start are still queued or running (" + queued +
                    "): wait for them, or scancel them, then start again");
  }
  PendingCases pending;
  try {
    refusal = selectCases(sweep, o, pending);
    if (!refusal.empty()) return refuse(refusal);
    writeSweepRecords(sweep, o.out_dir);
  } catch (const ScenarioError& e) {  // a case's file that cannot be read as one
    return refuse(e.what());
  } catch (const std::exception& e) {
    return failed(e.what());
  }

  bool interrupted = false;
  if (!pending.dirs.empty()) {
    if (!o.quiet)
      std::fprintf(stderr, "sweep %s: %zu cases, %zu to run (%s, %d at once), folder %s\n", sweep.name.c_str(),
                   sweep.cases.size(), pending.dirs.size(), o.backend.c_str(), o.jobs, o.out_dir.c_str());
    const StopSignals signals;
    Backend backend;
    if (const std::optional<int> code = startBackend(o, sweep, pending, backend)) return *code;
    interrupted = awaitBackend(o, sweep, pending, backend);
  }
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return runReport(o, sweep, pending.dirs.size(), elapsed, interrupted);
}

}  // namespace hyq::sim
