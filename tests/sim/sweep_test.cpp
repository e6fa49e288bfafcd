// Sweeps: the scenario key setter, the expansion of a sweep file, and a
// whole sweep through GNU parallel with cases that crash and hang, resumed.
#include "sim_host/cli/sweep.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "sim_host/scenario/scenario.hpp"

namespace hyq::sim {
namespace {

namespace fs = std::filesystem;

const char* const kScenario =
    "name: s\n"
    "duration: 1.0\n"
    "terrain:\n"
    "  mu: 0.8\n"
    "  patches:\n"
    "    - {x: [0.4, 1.1], y: [-2, 2], mu: 0.25}\n"
    "    - {x: [1.1, 1.9], y: [-2, 2], mu: 0.2}\n";

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void writeFile(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
}

// A fresh folder under the build tree for one test.
std::string scratch(const std::string& name) {
  const std::string dir = std::string(HYQ_BINARY_DIR) + "/test_sweep/" + name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

TEST(SetScenarioKey, MapKeysListIndicesAndEveryElement) {
  const YAML::Node every = YAML::Load(setScenarioKey(kScenario, "terrain.patches.*.mu", "0.1"));
  EXPECT_DOUBLE_EQ(every["terrain"]["patches"][0]["mu"].as<double>(), 0.1);
  EXPECT_DOUBLE_EQ(every["terrain"]["patches"][1]["mu"].as<double>(), 0.1);
  EXPECT_DOUBLE_EQ(every["terrain"]["mu"].as<double>(), 0.8);

  const YAML::Node one = YAML::Load(setScenarioKey(kScenario, "terrain.patches.1.x", "[1.0, 2.0]"));
  EXPECT_DOUBLE_EQ(one["terrain"]["patches"][1]["x"][1].as<double>(), 2.0);
  EXPECT_DOUBLE_EQ(one["terrain"]["patches"][0]["x"][1].as<double>(), 1.1);

  // A key the file does not have is created, maps on the way included.
  const YAML::Node created = YAML::Load(setScenarioKey(kScenario, "controller.freeze", "true"));
  EXPECT_TRUE(created["controller"]["freeze"].as<bool>());
  // The result is a scenario the reader takes, with the value in it.
  const Scenario s = parseScenario(setScenarioKey(kScenario, "gait.speed", "0.07"), "set");
  EXPECT_DOUBLE_EQ(s.controller_params.gait.speed, 0.07);
}

TEST(SetScenarioKey, PathsThatDoNotFitTheDocumentAreRefused) {
  EXPECT_THROW(setScenarioKey(kScenario, "terrain.patches.2.mu", "0.1"), ScenarioError);
  EXPECT_THROW(setScenarioKey(kScenario, "terrain.mu.x", "0.1"), ScenarioError);
  EXPECT_THROW(setScenarioKey(kScenario, "terrain.patches.first.mu", "0.1"), ScenarioError);
  EXPECT_THROW(setScenarioKey(kScenario, "terrain..mu", "0.1"), ScenarioError);
  EXPECT_THROW(setScenarioKey(kScenario, "terrain.", "0.1"), ScenarioError);
  EXPECT_THROW(setScenarioKey(kScenario, "duration", "[unclosed"), ScenarioError);
}

TEST(LoadSweep, ExpandsParametersEnginesRecoveryAndSeedsInOrder) {
  const std::string dir = scratch("expand");
  writeFile(dir + "/s.yaml", kScenario);
  writeFile(dir + "/sweep.yaml",
            "name: e\nscenario: s.yaml\nseeds: {from: 3, to: 5}\nrecovery: [on, off]\n"
            "engines: [ode, mujoco]\nset:\n  terrain.patches.*.mu: {from: 0.1, to: 0.3, step: 0.1}\n"
            "  gait.speed: [0.04, 0.06]\n");
  const Sweep sweep = loadSweep(dir + "/sweep.yaml");
  ASSERT_EQ(sweep.cases.size(), 3u * 2u * 2u * 2u * 3u);
  EXPECT_EQ(sweep.set_keys, (std::vector<std::string>{"terrain.patches.*.mu", "gait.speed"}));
  EXPECT_EQ(sweep.cases.front().id, "p000_ode_on_s3");
  EXPECT_EQ(sweep.cases[1].id, "p000_ode_on_s4");
  EXPECT_EQ(sweep.cases[3].id, "p000_ode_off_s3");
  EXPECT_EQ(sweep.cases[6].id, "p000_mujoco_on_s3");
  EXPECT_EQ(sweep.cases.back().id, "p005_mujoco_off_s5");
  // The last axis turns fastest.
  EXPECT_EQ(sweep.cases[12].values, (std::vector<std::pair<std::string, std::string>>{
                                        {"terrain.patches.*.mu", "0.1"}, {"gait.speed", "0.06"}}));
  const Scenario last = parseScenario(sweep.cases.back().scenario_yaml, "case");
  EXPECT_EQ(last.seed, 5u);
  EXPECT_FALSE(last.controller_params.recovery.enabled);
  EXPECT_EQ(last.physics.engine, EngineKind::mujoco);
  EXPECT_DOUBLE_EQ(last.terrain.patches[1].mu, 0.3);
  EXPECT_DOUBLE_EQ(last.controller_params.gait.speed, 0.06);
}

TEST(LoadSweep, BadFilesAreRefusedNamingTheKey) {
  const std::string dir = scratch("bad");
  writeFile(dir + "/s.yaml", kScenario);
  auto refusal = [&](const std::string& body) {
    writeFile(dir + "/sweep.yaml", body);
    try {
      loadSweep(dir + "/sweep.yaml");
    } catch (const ScenarioError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(refusal("name: b\nscenario: s.yaml\nseed: 1\n").find("seed: unknown key"), std::string::npos);
  EXPECT_NE(refusal("scenario: s.yaml\n").find("name: missing"), std::string::npos);
  EXPECT_NE(refusal("name: a/b\nscenario: s.yaml\n").find("name:"), std::string::npos);
  EXPECT_NE(refusal("name: b\nscenario: none.yaml\n").find("cannot open"), std::string::npos);
  EXPECT_NE(refusal("name: b\nscenario: s.yaml\nrecovery: [maybe]\n").find("recovery"), std::string::npos);
  EXPECT_NE(refusal("name: b\nscenario: s.yaml\nset: {gait.speed: {from: 1, to: 0, step: 1}}\n").find("step"),
            std::string::npos);
  // A value the scenario reader refuses stops the sweep before any case.
  EXPECT_NE(refusal("name: b\nscenario: s.yaml\nset: {terrain.patches.*.mu: [0.1, 9]}\n").find("mu"),
            std::string::npos);
  EXPECT_NE(refusal("name: b\nscenario: s.yaml\nset: {seed: [1, 2]}\n").find("use seeds"), std::string::npos);
  EXPECT_NE(refusal("name: b\nscenario: s.yaml\nseeds: {from: 1, to: 200000}\n").find("seeds"),
            std::string::npos);
}

int shell(const std::string& command) {
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// A sweep of 6 cases through GNU parallel: seed 2 crashes (SIGSEGV) and
// seed 3 hangs past the timeout; both are recorded as such, the others run.
// Started again, the sweep runs nothing; with --retry-failed it runs the
// two again.
TEST(SweepCommand, CrashesAndTimeoutsAreRecordedAndTheSweepResumes) {
  if (shell("command -v parallel >/dev/null") != 0) GTEST_SKIP() << "GNU parallel not installed";
  const std::string dir = scratch("run");
  writeFile(dir + "/s.yaml", kScenario);
  writeFile(dir + "/sweep.yaml",
            "name: r\nscenario: s.yaml\nseeds: [1, 2, 3]\nrecovery: [on, off]\nduration: 0.3\n");
  writeFile(dir + "/sim.sh",
            "#!/bin/bash\nseed=$(sed -n 's/^seed: //p' scenario.yaml)\n"
            "echo run >> ../../starts\n"
            "case $seed in 2) kill -SEGV $$ ;; 3) sleep 20 ;; *) exec " HYQ_SIM_BIN " \"$@\" ;; esac\n");
  fs::permissions(dir + "/sim.sh", fs::perms::owner_all);
  const std::string sweep = std::string(HYQ_SIM_BIN) + " sweep " + dir + "/sweep.yaml --out " + dir +
                            "/out --jobs 2 --timeout 1 --sim " + dir + "/sim.sh --quiet --no-plots";
  EXPECT_EQ(shell(sweep), 1);  // not every case ran to its end

  const YAML::Node report = YAML::LoadFile(dir + "/out/sweep.json");
  EXPECT_EQ(report["cases"].as<int>(), 6);
  EXPECT_EQ(report["status"]["ok"].as<int>(), 2);
  EXPECT_EQ(report["status"]["crashed"].as<int>(), 2);
  EXPECT_EQ(report["status"]["timeout"].as<int>(), 2);
  EXPECT_EQ(report["status"]["pending"].as<int>(), 0);
  ASSERT_EQ(report["groups"].size(), 2u);
  EXPECT_EQ(report["groups"][0]["recovery"].as<std::string>(), "on");
  EXPECT_EQ(report["groups"][0]["success"].as<int>(), 1);
  EXPECT_EQ(report["groups"][0]["not_completed"].size(), 2u);
  const std::string csv = readFile(dir + "/out/sweep.csv");
  EXPECT_NE(csv.find("ode_on_s2,0,ode,on,2,crashed,139"), std::string::npos) << csv;
  EXPECT_NE(csv.find("ode_off_s3,0,ode,off,3,timeout,124"), std::string::npos) << csv;
  EXPECT_NE(csv.find("ode_on_s1,0,ode,on,1,ok,0,False"), std::string::npos) << csv;
  EXPECT_EQ(readFile(dir + "/out/starts").size(), 6 * 4u);

  // Again: every case is done, nothing runs.
  EXPECT_EQ(shell(sweep), 1);
  EXPECT_EQ(readFile(dir + "/out/starts").size(), 6 * 4u);
  // --retry-failed runs the four that did not end, and no other.
  EXPECT_EQ(shell(sweep + " --retry-failed"), 1);
  EXPECT_EQ(readFile(dir + "/out/starts").size(), 10 * 4u);
  // A changed sweep file runs only the cases whose scenario changed: all,
  // here, as the duration is in every one.
  writeFile(dir + "/sweep.yaml", "name: r\nscenario: s.yaml\nseeds: [1]\nrecovery: [on]\nduration: 0.2\n");
  EXPECT_EQ(shell(sweep), 0);
  EXPECT_EQ(readFile(dir + "/out/starts").size(), 11 * 4u);
  const YAML::Node again = YAML::LoadFile(dir + "/out/sweep.json");
  EXPECT_EQ(again["cases"].as<int>(), 1);
  EXPECT_EQ(again["status"]["ok"].as<int>(), 1);
}

TEST(SweepCommand, BadOptionsAreOneLineAndExitTwo) {
  const std::string dir = scratch("options");
  writeFile(dir + "/s.yaml", kScenario);
  writeFile(dir + "/sweep.yaml", "name: o\nscenario: s.yaml\n");
  const std::string base = std::string(HYQ_SIM_BIN) + " sweep " + dir + "/sweep.yaml";
  for (const std::string& args :
       {base + " --jobs 0", base + " --jobs x", base + " --backend pbs", base + " --timeout 0", base + " --out",
        base + " --no-wait", base + " --bogus", base + " --out $'a\\nb'",
        std::string(HYQ_SIM_BIN) + " sweep " + dir + "/none.yaml"}) {
    EXPECT_EQ(shell("bash -c \"" + args + " 2>" + dir + "/err\""), 2) << args;
    const std::string err = readFile(dir + "/err");
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << args << ": " << err;
  }
}

TEST(LoadSweep, TheSameCaseTwiceIsRefused) {
  const std::string dir = scratch("twice");
  writeFile(dir + "/s.yaml", kScenario);
  for (const char* body : {"seeds: [1, 1]\n", "recovery: [on, on]\n", "engines: [ode, ode]\n"}) {
    writeFile(dir + "/sweep.yaml", std::string("name: t\nscenario: s.yaml\n") + body);
    EXPECT_THROW(loadSweep(dir + "/sweep.yaml"), ScenarioError) << body;
  }
  // A range that ends at the largest integer ends (and its seeds are beyond
  // the scenario reader's).
  writeFile(dir + "/sweep.yaml",
            "name: t\nscenario: s.yaml\nseeds: {from: 18446744073709551614, to: 18446744073709551615}\n");
  EXPECT_THROW(loadSweep(dir + "/sweep.yaml"), ScenarioError);
}

// Interrupted (INT, as Ctrl-C sends it), the sweep stops its cases and
// waits for them: no run is left behind, no case is recorded as done, and
// the sweep exits 130. Started again it runs them.
TEST(SweepCommand, AnInterruptedSweepLeavesNoRunBehind) {
  if (shell("command -v parallel >/dev/null") != 0) GTEST_SKIP() << "GNU parallel not installed";
  const std::string dir = scratch("interrupt");
  writeFile(dir + "/s.yaml", kScenario);
  writeFile(dir + "/sweep.yaml", "name: i\nscenario: s.yaml\nseeds: [1, 2, 3]\nduration: 0.2\n");
  const std::string marker = "hyq_sweep_interrupt_" + std::to_string(::getpid());
  writeFile(dir + "/sim.sh", "#!/bin/bash\nexec -a " + marker + " sleep 60\n");
  fs::permissions(dir + "/sim.sh", fs::perms::owner_all);
  const std::string sweep = std::string(HYQ_SIM_BIN) + " sweep " + dir + "/sweep.yaml --out " + dir +
                            "/out --jobs 2 --sim " + dir + "/sim.sh --quiet --no-plots";
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(shell("(" + sweep + " & p=$!; sleep 2; kill -INT $p; wait $p)"), 130);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_LT(seconds, 20.0);
  // (The pattern "[h]..." does not match the shell that runs pgrep.)
  EXPECT_NE(shell("pgrep -f '[h]" + marker.substr(1) + "' >/dev/null"), 0) << "a run was left behind";
  for (const char* id : {"ode_on_s1", "ode_on_s2", "ode_on_s3"})
    EXPECT_FALSE(fs::exists(dir + "/out/cases/" + id + "/exit_code")) << id;
  // Started again with the real simulator, it runs the three.
  EXPECT_EQ(shell(std::string(HYQ_SIM_BIN) + " sweep " + dir + "/sweep.yaml --out " + dir +
                  "/out --quiet --no-plots"),
            0);
  EXPECT_EQ(YAML::LoadFile(dir + "/out/sweep.json")["status"]["ok"].as<int>(), 3);
}

// --aggregate never takes a case run with another scenario for a result of
// the sweep as it is now.
TEST(SweepCommand, AggregateRefusesCasesOfAnotherScenario) {
  const std::string dir = scratch("stale");
  writeFile(dir + "/s.yaml", kScenario);
  writeFile(dir + "/sweep.yaml", "name: a\nscenario: s.yaml\nduration: 0.2\n");
  const std::string sweep = std::string(HYQ_SIM_BIN) + " sweep " + dir + "/sweep.yaml --out " + dir +
                            "/out --quiet --no-plots";
  ASSERT_EQ(shell(sweep), 0);
  writeFile(dir + "/sweep.yaml", "name: a\nscenario: s.yaml\nduration: 0.3\n");
  EXPECT_EQ(shell(sweep + " --aggregate 2>/dev/null"), 2);
  ASSERT_EQ(shell(sweep), 0);
  EXPECT_NE(readFile(dir + "/out/cases/ode_on_s1/summary.json").find("\"sim_time_s\": 0.3"), std::string::npos);
}

// A sweep file's key given twice is refused, as the scenario reader does,
// at the top level, under set and in a range.
TEST(LoadSweep, AKeyGivenTwiceIsRefused) {
  const std::string dir = scratch("given_twice");
  writeFile(dir + "/s.yaml", kScenario);
  const std::pair<const char*, const char*> bodies[] = {
      {"name: t\nscenario: s.yaml\nseeds: [1]\nseeds: [2]\n", "seeds: given twice"},
      {"name: t\nname: u\nscenario: s.yaml\n", "name: given twice"},
      {"name: t\nscenario: s.yaml\nset:\n  gait.speed: [0.04]\n  gait.speed: [0.06]\n",
       "set.gait.speed: given twice"},
      {"name: t\nscenario: s.yaml\nset:\n  gait.speed: {from: 0.04, to: 0.06, step: 0.01, step: 0.02}\n",
       "step: given twice"},
  };
  for (const auto& [body, needle] : bodies) {
    writeFile(dir + "/sweep.yaml", body);
    std::string message = "accepted";
    try {
      loadSweep(dir + "/sweep.yaml");
    } catch (const ScenarioError& e) {
      message = e.what();
    }
    EXPECT_NE(message.find(dir + "/sweep.yaml: "), std::string::npos) << body << ": " << message;
    EXPECT_NE(message.find(needle), std::string::npos) << body << ": " << message;
  }
}

// More cases than a sweep may have are refused, with their count, before
// any folder is made.
TEST(LoadSweep, MoreCasesThanTheBoundAreRefusedBeforeAnythingIsWritten) {
  const std::string dir = scratch("too_many");
  writeFile(dir + "/s.yaml", kScenario);
  auto refusal = [&](const std::string& body) {
    writeFile(dir + "/sweep.yaml", "name: t\nscenario: s.yaml\n" + body);
    try {
      loadSweep(dir + "/sweep.yaml");
    } catch (const ScenarioError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(refusal("seeds: {from: 1, to: 10001}\n").find("10001 seeds: a sweep has at most 10000 cases"),
            std::string::npos);
  const std::string product = "seeds: {from: 1, to: 101}\nset: {gait.speed: {from: 0.01, to: 0.1, count: 100}}\n";
  EXPECT_NE(refusal(product).find("10100 cases: at most 10000"), std::string::npos) << refusal(product);
  EXPECT_EQ(refusal("seeds: {from: 1, to: 100}\nset: {gait.speed: {from: 0.01, to: 0.1, count: 100}}\n"),
            "accepted");
  // From the command line: exit 2, one line, and no folder.
  writeFile(dir + "/sweep.yaml", "name: t\nscenario: s.yaml\n" + product);
  EXPECT_EQ(shell(std::string(HYQ_SIM_BIN) + " sweep " + dir + "/sweep.yaml --out " + dir +
                  "/out --aggregate --quiet --no-plots 2> " + dir + "/err"),
            2);
  const std::string err = readFile(dir + "/err");
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_NE(err.find("10100 cases"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir + "/out"));
}

// A set value that no run could take (here a controller the simulator does
// not have) stops the sweep before any case folder, naming key and value.
TEST(SweepCommand, ASetValueNoRunTakesIsRefusedBeforeAnyCase) {
  const std::string dir = scratch("bad_value");
  writeFile(dir + "/s.yaml", kScenario);
  writeFile(dir + "/sweep.yaml",
            "name: v\nscenario: s.yaml\nduration: 0.2\nset:\n  controller.kind: [posture, nonesuch]\n");
  EXPECT_EQ(shell(std::string(HYQ_SIM_BIN) + " sweep " + dir + "/sweep.yaml --out " + dir +
                  "/out --quiet --no-plots 2> " + dir + "/err"),
            2);
  const std::string err = readFile(dir + "/err");
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_NE(err.find("controller.kind"), std::string::npos) << err;
  EXPECT_NE(err.find("nonesuch"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir + "/out"));
}

// The processes whose command line holds `marker` (pgrep -f), as one text.
// (The pattern "[m]arker" does not match the shell that runs pgrep.)
std::string processesWith(const std::string& marker) {
  const std::string out = fs::temp_directory_path() / ("hyq_sweep_ps_" + std::to_string(::getpid()));
  shell("pgrep -a -f -- '[" + marker.substr(0, 1) + "]" + marker.substr(1) + "' > " + out + " 2>/dev/null");
  const std::string text = readFile(out);
  fs::remove(out);
  return text;
}

// The pids of the processes that have `path` open.
std::vector<int> holdersOf(const std::string& path) {
  std::vector<int> pids;
  std::error_code ec;
  for (const auto& proc : fs::directory_iterator("/proc", ec)) {
    const std::string name = proc.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::error_code fd_ec;
    for (const auto& fd : fs::directory_iterator(proc.path() / "fd", fd_ec)) {
      std::error_code link_ec;
      if (fs::read_symlink(fd.path(), link_ec) == path) {
        pids.push_back(std::stoi(name));
        break;
      }
    }
  }
  return pids;
}

// A process's command line, its arguments joined by spaces ("" once it has ended).
std::string commandLine(int pid) {
  std::string text = readFile("/proc/" + std::to_string(pid) + "/cmdline");
  std::replace(text.begin(), text.end(), '\0', ' ');
  return text;
}

// Sends SIGKILL to each pid (processes this test started and left behind).
void killAll(const std::string& marker) {
  std::stringstream lines(processesWith(marker));
  std::string line;
  while (std::getline(lines, line))
    if (!line.empty() && std::isdigit(static_cast<unsigned char>(line[0]))) ::kill(std::stoi(line), SIGKILL);
}

// A sweep killed with SIGKILL takes its backend and its cases with it, and
// the folder stays locked until the last of them has ended: a start in the
// meantime is refused, leaving every file as it was. Then a start runs the
// cases, none of which the killed sweep recorded as done.
TEST(SweepCommand, AKilledSweepLeavesNoProcessAndItsFolderLockedUntilItsCasesEnd) {
  if (shell("command -v parallel >/dev/null") != 0) GTEST_SKIP() << "GNU parallel not installed";
  const std::string dir = scratch("killed_" + std::to_string(::getpid()));
  writeFile(dir + "/s.yaml", kScenario);
  writeFile(dir + "/sweep.yaml", "name: k\nscenario: s.yaml\nseeds: [1, 2, 3]\nduration: 0.2\n");
  // A run that takes 3 s to end once told to.
  writeFile(dir + "/sim.sh",
            "#!/bin/bash\ntouch started\ntrap 'sleep 3; exit 1' TERM\nsleep 60 & wait\n");
  fs::permissions(dir + "/sim.sh", fs::perms::owner_all);
  const std::string out = dir + "/out";
  const std::string start = std::string(HYQ_SIM_BIN) + " sweep " + dir + "/sweep.yaml --out " + out +
                            " --jobs 2 --quiet --no-plots";
  ASSERT_EQ(shell(start + " --sim " + dir + "/sim.sh > /dev/null 2>&1 & echo $! > " + dir + "/pid"), 0);
  const int pid = std::stoi(readFile(dir + "/pid"));
  const auto t0 = std::chrono::steady_clock::now();
  while (!(fs::exists(out + "/cases/ode_on_s1/started") && fs::exists(out + "/cases/ode_on_s2/started")) &&
         std::chrono::steady_clock::now() - t0 < std::chrono::seconds(20))
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  ASSERT_TRUE(fs::exists(out + "/cases/ode_on_s2/started"));
  ASSERT_EQ(::kill(pid, SIGKILL), 0);
  const auto killed = std::chrono::steady_clock::now();

  // At once: the cases are still ending, the folder is locked.
  const std::string records = readFile(out + "/cases.csv");
  EXPECT_EQ(shell(start + " 2> " + dir + "/err"), 2);
  const std::string err = readFile(dir + "/err");
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_NE(err.find(out + ": "), std::string::npos) << err;
  EXPECT_EQ(readFile(out + "/cases.csv"), records);
  EXPECT_TRUE(fs::exists(out + "/cases/ode_on_s1/started"));

  // Within a few seconds nothing of the sweep is left.
  std::string left;
  std::vector<int> holders;
  do {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    left = processesWith(dir);
    holders = holdersOf(out + "/.sweep.lock");
  } while ((!left.empty() || !holders.empty()) && std::chrono::steady_clock::now() - killed < std::chrono::seconds(15));
  EXPECT_EQ(left, "") << "left behind";
  std::string holder_lines;
  for (int holder : holders)
    holder_lines += "\n  " + std::to_string(holder) + ": " + commandLine(holder);
  EXPECT_TRUE(holders.empty()) << holders.size() << " processes hold the folder's lock:" << holder_lines;
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - killed).count(), 12.0);
  killAll(dir);
  for (const char* id : {"ode_on_s1", "ode_on_s2", "ode_on_s3"})
    EXPECT_FALSE(fs::exists(out + "/cases/" + id + "/exit_code")) << id;
  // Then a start runs the three.
  EXPECT_EQ(shell(start), 0);
  EXPECT_EQ(YAML::LoadFile(out + "/sweep.json")["status"]["ok"].as<int>(), 3);
}

// --aggregate over damaged case folders: each damage ends the report in one
// line naming the case's file, exit 2, in bounded time and memory, and the
// aggregate already written is left as it was.
TEST(SweepCommand, AggregateOfDamagedCasesEndsInOneLineNamingTheCase) {
  const std::string dir = scratch("damaged");
  writeFile(dir + "/s.yaml", kScenario);
  writeFile(dir + "/sweep.yaml", "name: d\nscenario: s.yaml\nduration: 0.2\n");
  const std::string out = dir + "/out";
  const std::string sweep = std::string(HYQ_SIM_BIN) + " sweep " + dir + "/sweep.yaml --out " + out +
                            " --quiet --no-plots";
  ASSERT_EQ(shell(sweep), 0);
  const std::string case_dir = out + "/cases/ode_on_s1";
  const std::string good = readFile(case_dir + "/summary.json");
  const std::string aggregate = readFile(out + "/sweep.json");
  ASSERT_NE(good.find("\"fell\": false"), std::string::npos);
  ASSERT_NE(good.find("\"distance_m\": "), std::string::npos);
  auto replaced = [&](const std::string& from, const std::string& to) {
    std::string text = good;
    const size_t at = text.find(from);
    return text.replace(at, from.size(), to);
  };
  auto distance = [&](const std::string& value) {
    const size_t at = good.find("\"distance_m\": ") + 14;
    std::string text = good;
    return text.replace(at, text.find_first_of(",\n}", at) - at, value);
  };
  struct Damage {
    std::string label;
    std::function<void(const std::string& path)> make;
    std::string file;  // the damaged file
  };
  auto text = [](const std::string& t) { return [t](const std::string& path) { writeFile(path, t); }; };
  const std::string summary = case_dir + "/summary.json";
  const std::vector<Damage> damages = {
      {"garbage", text("{\"fell\": tru"), summary},
      {"empty", text(""), summary},
      {"no keys", text("{}"), summary},
      {"a list", text("[1, 2]"), summary},
      {"null", text("null"), summary},
      {"a string", text("\"summary\""), summary},
      {"not utf-8", text("{\"fell\": \"\xff\xfe\"}"), summary},
      {"fell is text", text(replaced("\"fell\": false", "\"fell\": \"yes\"")), summary},
      {"fell is a number", text(replaced("\"fell\": false", "\"fell\": 0")), summary},
      {"distance infinite", text(distance("1e999")), summary},
      {"distance NaN", text(distance("NaN")), summary},
      {"distance text", text(distance("\"far\"")), summary},
      {"too large", [](const std::string& p) { writeFile(p, "{}"); fs::resize_file(p, 64 << 20); }, summary},
      {"a FIFO", [](const std::string& p) { ::mkfifo(p.c_str(), 0644); }, summary},
      {"a link to /dev/zero", [](const std::string& p) { fs::create_symlink("/dev/zero", p); }, summary},
      {"a folder", [](const std::string& p) { fs::create_directories(p); }, summary},
      {"exit_code a FIFO", [](const std::string& p) { ::mkfifo(p.c_str(), 0644); }, case_dir + "/exit_code"},
  };
  for (const Damage& d : damages) {
    const std::string keep = readFile(d.file);
    fs::remove(d.file);
    d.make(d.file);
    const auto t0 = std::chrono::steady_clock::now();
    // 1 GB of address space and 20 s: a report that reads without bound
    // runs out of either.
    const int code = shell("bash -c 'ulimit -v 1000000; timeout -k 1 20 " + sweep + " --aggregate' 2> " + dir +
                           "/err");
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const std::string err = readFile(dir + "/err");
    EXPECT_EQ(code, 2) << d.label << ": " << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << d.label << ": " << err;
    EXPECT_NE(err.find(d.file), std::string::npos) << d.label << ": " << err;
    EXPECT_EQ(err.find("Traceback"), std::string::npos) << d.label << ": " << err;
    EXPECT_LT(seconds, 10.0) << d.label;
    EXPECT_EQ(readFile(out + "/sweep.json"), aggregate) << d.label;
    fs::remove_all(d.file);
    writeFile(d.file, keep);
  }
  EXPECT_EQ(shell(sweep + " --aggregate"), 0);
}

// Slurm's file name patterns give a backslash and '%' a meaning: a sweep's
// folder with either is refused for the Slurm backend before anything is
// written.
TEST(SweepCommand, SlurmFolderWithPatternCharactersIsRefused) {
  const std::string dir = scratch("slurm_out");
  writeFile(dir + "/s.yaml", kScenario);
  writeFile(dir + "/sweep.yaml", "name: o\nscenario: s.yaml\n");
  for (const std::string name : {"a\\b", "100%"}) {
    const int code = shell(std::string(HYQ_SIM_BIN) + " sweep " + dir + "/sweep.yaml --backend slurm --out '" +
                           dir + "/" + name + "' 2> " + dir + "/err");
    const std::string err = readFile(dir + "/err");
    EXPECT_EQ(code, 2) << name << ": " << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    EXPECT_NE(err.find("--out"), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(dir + "/" + name)) << name;
  }
}

// An array whose tasks Slurm never ran (here a stand-in sbatch that fails
// as Slurm does when it cannot open a task's output file): the sweep says
// which cases did not run and why, on stderr and in the log it names.
TEST(SweepCommand, SlurmTasksThatNeverRanAreExplained) {
  const std::string dir = scratch("slurm_failed");
  writeFile(dir + "/s.yaml", kScenario);
  writeFile(dir + "/sweep.yaml", "name: f\nscenario: s.yaml\nseeds: [1, 2]\nduration: 0.2\n");
  fs::create_directories(dir + "/bin");
  writeFile(dir + "/bin/sbatch", "#!/bin/bash\necho 41\nexit 1\n");
  fs::permissions(dir + "/bin/sbatch", fs::perms::owner_all);
  const int code = shell("PATH=" + dir + "/bin:$PATH " + HYQ_SIM_BIN + " sweep " + dir +
                         "/sweep.yaml --backend slurm --out " + dir + "/out --quiet --no-plots 2> " + dir + "/err");
  const std::string err = readFile(dir + "/err");
  EXPECT_EQ(code, 1) << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_NE(err.find("ode_on_s1"), std::string::npos) << err;
  EXPECT_NE(err.find("41_1.out"), std::string::npos) << err;
  // The log it names lists both cases and the reason.
  const size_t at = err.find(dir + "/out/slurm/");
  ASSERT_NE(at, std::string::npos) << err;
  const std::string log = readFile(err.substr(at, err.find_first_of(" ;)\n", at) - at));
  for (const char* id : {"ode_on_s1", "ode_on_s2"}) EXPECT_NE(log.find(id), std::string::npos) << log;
  EXPECT_NE(log.find("output file"), std::string::npos) << log;
}

}  // namespace
}  // namespace hyq::sim
