// Sweeps: the scenario key setter, the expansion of a sweep file, and a
// whole sweep through GNU parallel with cases that crash and hang, resumed.
#include "sim_host/cli/sweep.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

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

}  // namespace
}  // namespace hyq::sim
