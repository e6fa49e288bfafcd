// A sweep as a Slurm job array, through a real slurmctld and slurmd started
// on this machine (slurm_local.sh), against the same sweep run by GNU
// parallel: the two aggregates agree case for case. Then the cluster way of
// working: submit without waiting, aggregate once the cases are done.
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
#include <thread>
#include <vector>

namespace {

namespace fs = std::filesystem;

const std::string kScript = std::string(HYQ_SOURCE_DIR) + "/tests/sweep/slurm_local.sh";
const std::string kSim = HYQ_SIM_BIN;

int shell(const std::string& command) {
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// sweep.csv without the columns that time the runs (wall and CPU time).
std::vector<std::string> rowsWithoutTimes(const std::string& csv_path) {
  std::vector<std::string> rows;
  std::stringstream in(readFile(csv_path));
  std::string line;
  std::vector<bool> keep;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream ls(line);
    std::string cell;
    while (std::getline(ls, cell, ',')) cells.push_back(cell);
    if (keep.empty())
      for (const std::string& c : cells) keep.push_back(c != "wall_time_s" && c != "cpu_time_s");
    std::string row;
    for (size_t k = 0; k < cells.size() && k < keep.size(); ++k)
      if (keep[k]) row += cells[k] + ",";
    rows.push_back(row);
  }
  return rows;
}

// The cluster lives as long as the test: stopped however the test ends.
class LocalSlurm : public ::testing::Test {
 protected:
  void SetUp() override {
    for (const char* p : {"slurmctld", "slurmd", "sbatch", "munged"})
      if (shell(std::string("command -v ") + p + " >/dev/null") != 0)
        GTEST_SKIP() << p << " not installed (make test installs slurm-wlm and munge)";
    if (::geteuid() != 0) GTEST_SKIP() << "the local cluster runs its daemons as root";
    // Short: the munge socket's path lives in it.
    dir_ = "/tmp/hyq_slurm_" + std::to_string(::getpid());
    ASSERT_EQ(shell(kScript + " start " + dir_ + " > " + dir_ + ".start.log 2>&1"), 0)
        << readFile(dir_ + ".start.log");
    started_ = true;
    ::setenv("SLURM_CONF", (dir_ + "/slurm.conf").c_str(), 1);
    // Per test: ctest runs the tests of this file at the same time.
    work_ = std::string(HYQ_BINARY_DIR) + "/test_sweep_slurm/" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name();
    fs::remove_all(work_);
    fs::create_directories(work_);
    std::ofstream(work_ + "/sweep.yaml")
        << "name: slurm_check\n"
           "scenario: " HYQ_SOURCE_DIR "/sim_host/scenarios/stance_slip.yaml\n"
           "seeds: {from: 1, to: 4}\n"
           "recovery: [on, off]\n"
           "duration: 4\n";
  }
  void TearDown() override {
    if (started_) shell(kScript + " stop " + dir_ + " >/dev/null 2>&1");
    fs::remove_all(dir_);
    fs::remove(dir_ + ".start.log");
  }
  std::string sweep(const std::string& options) const {
    return kSim + " sweep " + work_ + "/sweep.yaml --jobs 2 --quiet --no-plots " + options;
  }
  std::string dir_, work_;
  bool started_ = false;
};

TEST_F(LocalSlurm, AJobArrayGivesTheSameAggregateAsGnuParallel) {
  ASSERT_EQ(shell(sweep("--backend slurm --out " + work_ + "/slurm")), 0)
      << readFile(work_ + "/slurm/slurm/sbatch.log");
  ASSERT_EQ(shell(sweep("--backend parallel --out " + work_ + "/parallel")), 0);

  const YAML::Node a = YAML::LoadFile(work_ + "/slurm/sweep.json");
  const YAML::Node b = YAML::LoadFile(work_ + "/parallel/sweep.json");
  EXPECT_EQ(a["cases"].as<int>(), 8);
  EXPECT_EQ(a["status"]["ok"].as<int>(), 8);
  // Every group's counts and distributions, as JSON text.
  EXPECT_EQ(YAML::Dump(a["groups"]), YAML::Dump(b["groups"]));
  const auto rows_a = rowsWithoutTimes(work_ + "/slurm/sweep.csv");
  EXPECT_EQ(rows_a.size(), 9u);
  EXPECT_EQ(rows_a, rowsWithoutTimes(work_ + "/parallel/sweep.csv"));
  // Each case ran as one array task: its output file is there.
  int task_outputs = 0;
  for (const auto& e : fs::directory_iterator(work_ + "/slurm/slurm"))
    task_outputs += e.path().extension() == ".out";
  EXPECT_EQ(task_outputs, 8);
}

TEST_F(LocalSlurm, SubmittedWithoutWaitingThenAggregated) {
  const std::string out = work_ + "/later";
  ASSERT_EQ(shell(sweep("--backend slurm --no-wait --out " + out + " > " + work_ + "/submit.txt")), 0);
  EXPECT_NE(readFile(work_ + "/submit.txt").find("--aggregate"), std::string::npos);
  // Done when every case has its exit status (bounded wait).
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  int done = 0;
  while (std::chrono::steady_clock::now() < deadline) {
    done = 0;
    for (const auto& e : fs::directory_iterator(out + "/cases")) done += fs::exists(e.path() / "exit_code");
    if (done == 8) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
  }
  ASSERT_EQ(done, 8);
  ASSERT_EQ(shell(sweep("--aggregate --out " + out)), 0);
  const YAML::Node r = YAML::LoadFile(out + "/sweep.json");
  EXPECT_EQ(r["status"]["ok"].as<int>(), 8);
  EXPECT_EQ(r["last_start"]["cases_run"].as<int>(), 0);
}

}  // namespace
