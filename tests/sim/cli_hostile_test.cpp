// hyq_sim against a hostile or careless user: failed writes (a file-size
// limit, a full tmpfs, a full stdout), names and paths that would leave the
// output folder, stale files and symlinks in a reused folder, option values
// that are options, out-of-range scenario values, huge or endless files, a
// QEMU controller that cannot boot, and a long run's memory. Every refusal
// is one line on stderr naming the file or key, with exit code 2 (bad
// input) or 1 (could not write, controller failed); never a signal, never
// a hang, never exit 0 with outputs missing.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "sim_host/loop/controller_port.hpp"
#include "sim_host/records/metrics.hpp"
#include "sim_host/loop/run.hpp"
#include "sim_host/records/run_log.hpp"
#include "sim_host/scenario/scenario.hpp"
#include "tests/sim/test_files.hpp"

namespace hyq::sim {
namespace {

namespace fs = std::filesystem;

const std::string kStand = std::string(HYQ_SOURCE_DIR) + "/sim_host/scenarios/stand.yaml";

// A fresh folder per test, removed at the end.
class Hostile : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string(info->test_suite_name()) + "_" + info->name();
    std::replace(name.begin(), name.end(), '/', '_');
    dir_ = fs::temp_directory_path() / ("hyq_hostile_" + std::to_string(::getpid())) / name;
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_.parent_path()); }
  fs::path dir_;
};

void writeFile(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

std::vector<std::string> listing(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

struct Child {
  std::vector<std::string> args;          // args[0]: the program
  std::vector<std::pair<std::string, std::string>> env;
  fs::path cwd;                           // "" : this process's
  rlim_t file_size_limit = RLIM_INFINITY; // [bytes]
  bool stdout_to_dev_full = false;
  int timeout_s = 60;
};

struct Outcome {
  int exit_code = -1;  // -1: killed by a signal or timed out
  int signal = 0;
  bool timed_out = false;
  std::string err;
};

// Runs the program in a child, stderr captured, with a time limit.
Outcome execute(const Child& run, const fs::path& scratch) {
  static int counter = 0;
  const fs::path err_path = scratch / (".stderr_" + std::to_string(++counter));
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (!run.cwd.empty() && ::chdir(run.cwd.c_str()) != 0) ::_exit(120);
    for (const auto& [k, v] : run.env) ::setenv(k.c_str(), v.c_str(), 1);
    if (run.file_size_limit != RLIM_INFINITY) {
      rlimit lim{run.file_size_limit, run.file_size_limit};
      if (::setrlimit(RLIMIT_FSIZE, &lim) != 0) ::_exit(121);
    }
    const int out = ::open(run.stdout_to_dev_full ? "/dev/full" : "/dev/null", O_WRONLY);
    const int err = ::open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (out < 0 || err < 0) ::_exit(122);
    ::dup2(out, STDOUT_FILENO);
    ::dup2(err, STDERR_FILENO);
    std::vector<char*> argv;
    for (const std::string& a : run.args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execvp(argv[0], argv.data());
    ::_exit(127);
  }
  Outcome o;
  int status = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(run.timeout_s);
  while (::waitpid(pid, &status, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() > deadline) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      o.timed_out = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  if (!o.timed_out && WIFEXITED(status)) o.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) o.signal = WTERMSIG(status);
  o.err = readFile(err_path);
  fs::remove(err_path);
  return o;
}

Outcome sim(const std::vector<std::string>& args, const fs::path& scratch, Child run = {}) {
  run.args = {HYQ_SIM_BIN};
  run.args.insert(run.args.end(), args.begin(), args.end());
  return execute(run, scratch);
}

// One line on stderr holding `needle`, and the exit code.
void expectRefusal(const Outcome& o, int exit_code, const std::string& needle) {
  EXPECT_FALSE(o.timed_out);
  EXPECT_EQ(o.signal, 0) << o.err;
  EXPECT_EQ(o.exit_code, exit_code) << o.err;
  EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << o.err;
  EXPECT_EQ(o.err.rfind("hyq_sim: ", 0), 0u) << o.err;
  EXPECT_NE(o.err.find(needle), std::string::npos) << "'" << needle << "' not in: " << o.err;
  EXPECT_LT(o.err.size(), 600u) << o.err.substr(0, 600);
}

const char* const kRunFiles[] = {"summary.json", "log.csv", "events.csv", "fig5_mu.png",
                                 "fig6_odometry.png", "fig7_normal.png", "fig8_slip_flags.png"};

// ---------------------------------------------------------------- writes

TEST_F(Hostile, FileSizeLimitEndsInOneLineAndLeavesNothingThatLooksComplete) {
  const fs::path out = dir_ / "run";
  ASSERT_EQ(sim({"run", kStand, "--duration", "0.2", "--out", out.string()}, dir_).exit_code, 0);
  writeFile(out / "fig5_mu.png", "figure of the earlier run");
  ASSERT_TRUE(fs::exists(out / "log.csv"));
  Child limited;
  limited.file_size_limit = 64 * 1024;  // log.csv of 2 s is ~2.6 MB
  const Outcome o = sim({"run", kStand, "--duration", "2", "--out", out.string()}, dir_, limited);
  expectRefusal(o, 1, (out / "log.csv").string() + ": " + std::strerror(EFBIG));
  EXPECT_TRUE(listing(out).empty()) << "left: " << ::testing::PrintToString(listing(out));
}

// A real full disk: a small tmpfs in a private mount namespace (skipped
// where unprivileged namespaces are not allowed).
TEST_F(Hostile, FullDiskEndsInOneLineAndLeavesNothingThatLooksComplete) {
  const fs::path mnt = dir_ / "mnt";
  fs::create_directories(mnt);
  auto inTmpfs = [&](const std::string& size, const std::string& command) {
    Child r;
    r.args = {"unshare", "-rm", "sh", "-c",
              "mount -t tmpfs -o size=" + size + " tmpfs '" + mnt.string() + "' || exit 99; " +
                  command + "; rc=$?; ls -A '" + mnt.string() + "' > '" +
                  (dir_ / "listing").string() + "'; exit $rc"};
    return execute(r, dir_);
  };
  if (inTmpfs("4k", "true").exit_code != 0) GTEST_SKIP() << "cannot mount a tmpfs here";
  const std::string sim_run = std::string(HYQ_SIM_BIN) + " run '" + kStand +
                              "' --duration 2 --out '" + mnt.string() + "'";
  // log.csv outgrows 64 KiB.
  Outcome o = inTmpfs("64k", sim_run);
  expectRefusal(o, 1, (mnt / "log.csv").string() + ": " + std::strerror(ENOSPC));
  EXPECT_EQ(readFile(dir_ / "listing"), "");
  // One page: events.csv fits, summary.json does not; events.csv goes too.
  o = inTmpfs("4k", sim_run + " --no-log");
  expectRefusal(o, 1, (mnt / "summary.json").string() + ": " + std::strerror(ENOSPC));
  EXPECT_EQ(readFile(dir_ / "listing"), "");
}

TEST_F(Hostile, FullStdoutExitsOne) {
  Child r;
  r.stdout_to_dev_full = true;
  const Outcome o =
      sim({"run", kStand, "--duration", "0.05", "--no-log", "--out", (dir_ / "o").string()}, dir_, r);
  expectRefusal(o, 1, std::string("stdout: ") + std::strerror(ENOSPC));
}

// In-process: a summary that cannot be written throws OutputError naming
// it and leaves neither it nor its temporary.
TEST_F(Hostile, FailedSummaryWriteThrowsAndLeavesNothing) {
  const fs::path path = dir_ / "summary.json";
  const auto old_handler = std::signal(SIGXFSZ, SIG_IGN);
  rlimit old{};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &old), 0);
  rlimit small = old;
  small.rlim_cur = 1000;
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &small), 0);
  std::string message;
  try {
    writeSummaryJson(path.string(), {{"big", jsonString(std::string(5000, 'x'))}});
  } catch (const OutputError& e) {
    message = e.what();
  }
  ::setrlimit(RLIMIT_FSIZE, &old);
  std::signal(SIGXFSZ, old_handler);
  EXPECT_EQ(message, path.string() + ": " + std::strerror(EFBIG));
  EXPECT_TRUE(listing(dir_).empty()) << ::testing::PrintToString(listing(dir_));
}

TEST_F(Hostile, UncommittedOutputLeavesNoFileAndCommitAllIsAllOrNothing) {
  {
    OutputFile f((dir_ / "a.csv").string());
    f.write("partial");
  }  // an exception on the way: dropped without commit
  EXPECT_TRUE(listing(dir_).empty());

  // The second file's final name is a non-empty folder: its rename fails,
  // and the first, already renamed, is removed again.
  fs::create_directories(dir_ / "b.csv" / "inside");
  OutputFile a((dir_ / "a.csv").string()), b((dir_ / "b.csv").string());
  a.write("a");
  b.write("b");
  std::string message;
  try {
    commitAll({&a, &b});
  } catch (const OutputError& e) {
    message = e.what();
  }
  EXPECT_EQ(message.rfind((dir_ / "b.csv").string() + ": ", 0), 0u) << message;
  EXPECT_EQ(listing(dir_), std::vector<std::string>{"b.csv"});
}

// ---------------------------------------------------------------- the output folder

TEST_F(Hostile, ReusedFolderKeepsNothingOfTheEarlierRun) {
  const fs::path out = dir_ / "run";
  fs::create_directories(out);
  for (const char* name : kRunFiles) writeFile(out / name, "stale");
  writeFile(out / "notes.txt", "mine");
  const Outcome o = sim({"run", kStand, "--duration", "0.05", "--no-log", "--out", out.string()}, dir_);
  ASSERT_EQ(o.exit_code, 0) << o.err;
  EXPECT_EQ(listing(out), (std::vector<std::string>{"events.csv", "notes.txt", "summary.json"}));
  EXPECT_NE(readFile(out / "summary.json").find("\"sim_time_s\": 0.05"), std::string::npos);
  EXPECT_EQ(readFile(out / "notes.txt"), "mine");
}

TEST_F(Hostile, SymlinksInTheFolderAreReplacedNeverWrittenThrough) {
  const fs::path out = dir_ / "run", outside = dir_ / "outside";
  fs::create_directories(out);
  fs::create_directories(outside);
  for (const char* name : kRunFiles) {
    writeFile(outside / name, "precious");
    fs::create_symlink(outside / name, out / name);
  }
  // A dangling one: writing through it would create its target.
  fs::remove(out / "events.csv");
  fs::create_symlink(dir_ / "nowhere", out / "events.csv");
  const Outcome o = sim({"run", kStand, "--duration", "0.05", "--out", out.string()}, dir_);
  ASSERT_EQ(o.exit_code, 0) << o.err;
  for (const char* name : kRunFiles) EXPECT_EQ(readFile(outside / name), "precious") << name;
  for (const char* name : {"summary.json", "log.csv", "events.csv"}) {
    EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(out / name))) << name;
    EXPECT_GT(fs::file_size(out / name), 10u) << name;
  }
  EXPECT_FALSE(fs::exists(fs::symlink_status(out / "fig5_mu.png")));
  EXPECT_FALSE(fs::exists(dir_ / "nowhere"));
}

TEST_F(Hostile, OutputThatCannotBeAFolderOrAFileIsOneLine) {
  writeFile(dir_ / "plain", "a file");
  expectRefusal(sim({"run", kStand, "--duration", "0.05", "--out", (dir_ / "plain").string()}, dir_),
                1, (dir_ / "plain").string() + ": ");
  EXPECT_EQ(readFile(dir_ / "plain"), "a file");
  const fs::path out = dir_ / "run";
  fs::create_directories(out / "log.csv" / "keep");
  expectRefusal(sim({"run", kStand, "--duration", "0.05", "--out", out.string()}, dir_), 1,
                (out / "log.csv").string() + ": ");
  EXPECT_TRUE(fs::exists(out / "log.csv" / "keep"));
  EXPECT_FALSE(fs::exists(out / "summary.json"));
}

TEST_F(Hostile, ScenarioNameMustBeAFileNameWhereItNamesTheFolder) {
  const std::pair<std::string, std::string> bad[] = {
      {"../../escaped", "'../../escaped'"},
      {"a/b", "'a/b'"},
      {"..", "'..'"},
      {"with space", "'with space'"},
      {"\"tab\\there\"", "control character"},
      {std::string(65, 'n'), "too long (65 characters)"},
  };
  for (const auto& [name, needle] : bad) {
    const fs::path file = dir_ / "bad.yaml";
    writeFile(file, "name: " + name + "\nduration: 0.05\ncontroller: {kind: posture}\n");
    Child in_dir;
    in_dir.cwd = dir_;
    const Outcome o = sim({"run", file.string()}, dir_, in_dir);
    expectRefusal(o, 2, file.string() + ": name: ");
    EXPECT_NE(o.err.find(needle), std::string::npos) << o.err;
    EXPECT_FALSE(fs::exists(dir_ / "out")) << name;
    EXPECT_FALSE(fs::exists(dir_.parent_path().parent_path() / "escaped"));
  }
  // A plain name makes out/<name>; any printable name goes with --out.
  const fs::path file = dir_ / "good.yaml";
  writeFile(file, "name: ok_name-1.2\nduration: 0.05\ncontroller: {kind: posture}\n");
  Child in_dir;
  in_dir.cwd = dir_;
  ASSERT_EQ(sim({"run", file.string(), "--no-log"}, dir_, in_dir).exit_code, 0);
  EXPECT_TRUE(fs::exists(dir_ / "out" / "ok_name-1.2" / "summary.json"));
  writeFile(file, "name: a name/with ../ in it\nduration: 0.05\ncontroller: {kind: posture}\n");
  ASSERT_EQ(sim({"run", file.string(), "--no-log", "--out", (dir_ / "o").string()}, dir_).exit_code, 0);
  EXPECT_NE(readFile(dir_ / "o" / "summary.json").find("\"scenario\": \"a name/with ../ in it\""),
            std::string::npos);
}

// In-process: runScenario itself keeps a run inside its folder.
TEST_F(Hostile, RunScenarioRefusesAFolderNameAndAnEmptyRun) {
  Scenario s = parseScenario("name: ../x\nduration: 0.05\n", "code");
  auto controller = makeController("posture", s);
  RunOptions options;
  options.progress = false;
  EXPECT_THROW(runScenario(s, *controller, options), ScenarioError);
  s.name = "x";
  s.duration = 1e-6;
  options.out_dir = (dir_ / "o").string();
  EXPECT_THROW(runScenario(s, *controller, options), ScenarioError);
  EXPECT_FALSE(fs::exists(dir_ / "o" / "summary.json"));
}

// ---------------------------------------------------------------- the command line

TEST_F(Hostile, OptionValuesThatAreOptionsAreRefused) {
  for (const char* option : {"--recovery", "--seed", "--duration", "--out", "--controller", "--substeps"}) {
    const Outcome o = sim({"run", kStand, option, "--no-log"}, dir_);
    expectRefusal(o, 2, std::string("command line: ") + option + ": missing");
    EXPECT_NE(o.err.find("'--no-log'"), std::string::npos) << o.err;
    const Outcome empty = sim({"run", kStand, option, ""}, dir_);
    expectRefusal(empty, 2, std::string("command line: ") + option + ": ");
  }
  EXPECT_FALSE(fs::exists("--no-log"));
  expectRefusal(sim({"run", kStand, "--out"}, dir_), 2, "--out: missing a directory");
  expectRefusal(sim({}, dir_), 2, "expected 'run SCENARIO.yaml");
  expectRefusal(sim({"run", kStand, "--frobnicate"}, dir_), 2, "--frobnicate: unknown option");
  expectRefusal(sim({"run", kStand, "--duration", "0.001"}, dir_), 2,
                "--duration: expected seconds in [0.01, 3600] s");
  expectRefusal(sim({"run", kStand, "--duration", "1e9"}, dir_), 2, "--duration");
  expectRefusal(sim({"run", kStand, "--controller", "nonesuch"}, dir_), 2,
                "--controller: unknown controller 'nonesuch'");
}

TEST_F(Hostile, LongStringsAreCutInMessages) {
  const std::string long_text(100000, 'z');
  const std::string cut = std::string(80, 'z') + "...";
  expectRefusal(sim({"run", kStand, "--controller", long_text}, dir_), 2, cut);
  expectRefusal(sim({"run", kStand, "--seed", long_text}, dir_), 2, cut);
  expectRefusal(sim({"run", kStand, long_text}, dir_), 2, cut + ": unknown option");
  const fs::path file = dir_ / "long.yaml";
  writeFile(file, "name: " + long_text + "\nduration: 1\n");
  expectRefusal(sim({"run", file.string()}, dir_), 2, "name: too long (100000 characters)");
  writeFile(file, "name: x\nduration: 1\n? " + long_text + "\n: 1\n");  // an explicit key: no length limit
  expectRefusal(sim({"run", file.string()}, dir_), 2, cut + ": unknown key");
  writeFile(file, "name: x\nduration: \"" + long_text + "\"\n");
  expectRefusal(sim({"run", file.string()}, dir_), 2, "duration: expected a number, got '" + cut + "'");
}

TEST_F(Hostile, HugeEndlessOrUnreadableFilesAreRefused) {
  const fs::path big = dir_ / "big.yaml";
  writeFile(big, "name: x\nduration: 1\n#" + std::string(kMaxScenarioFileBytes, ' ') + "\n");
  expectRefusal(sim({"run", big.string()}, dir_), 2, big.string() + ": too large");
  Child quick;
  quick.timeout_s = 20;
  expectRefusal(sim({"run", "/dev/zero"}, dir_, quick), 2, "/dev/zero: not a regular file (a character device)");
  expectRefusal(sim({"run", dir_.string()}, dir_), 2, dir_.string() + ": not a regular file (a directory)");
  writeFile(big, std::string("name: x\nduration: 1\n\0\xff\xfe garbage", 32));
  const Outcome o = sim({"run", big.string()}, dir_);
  expectRefusal(o, 2, big.string() + ": ");
}

// A scenario or a sweep file that is a FIFO is refused at once: its open
// would wait for a writer for ever.
TEST_F(Hostile, FifoFilesAreRefusedNotWaitedOn) {
  const fs::path fifo = dir_ / "fifo.yaml";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  Child quick;
  quick.timeout_s = 20;
  const std::string needle = fifo.string() + ": not a regular file (a FIFO)";
  expectRefusal(sim({"run", fifo.string(), "--out", (dir_ / "o").string()}, dir_, quick), 2, needle);
  expectRefusal(sim({"sweep", fifo.string(), "--out", (dir_ / "sw").string()}, dir_, quick), 2, needle);
  // A sweep whose scenario is the FIFO.
  writeFile(dir_ / "sweep.yaml", "name: f\nscenario: fifo.yaml\n");
  expectRefusal(sim({"sweep", (dir_ / "sweep.yaml").string(), "--out", (dir_ / "sw").string()}, dir_, quick), 2,
                needle);
  EXPECT_FALSE(fs::exists(dir_ / "o"));
  EXPECT_FALSE(fs::exists(dir_ / "sw"));
}

// Numbers on the command line are decimal, whole and finite; an option
// given twice is refused, never one of its values silently taken.
TEST_F(Hostile, NumbersAreStrictAndAnOptionIsGivenOnce) {
  const std::string out = (dir_ / "o").string();
  for (const char* v : {"0x2", " 2", "2s", "inf", "nan", "1e999", "0x1p1", ".", "1e", "--2"})
    expectRefusal(sim({"run", kStand, "--duration", v, "--out", out}, dir_), 2, "command line: --duration: ");
  const std::vector<std::vector<std::string>> twice = {
      {"--seed", "1", "--seed", "2"},
      {"--engine", "ode", "--engine", "mujoco"},
      {"--duration", "0.05", "--duration", "0.1"},
      {"--recovery", "on", "--recovery", "off"},
      {"--controller", "posture", "--controller", "wbc"},
      {"--substeps", "1", "--substeps", "2"},
      {"--no-log", "--no-log"},
      {"--quiet", "--quiet"},
  };
  for (const auto& options : twice) {
    std::vector<std::string> args = {"run", kStand, "--out", out};
    args.insert(args.end(), options.begin(), options.end());
    expectRefusal(sim(args, dir_), 2, "command line: " + options[0] + ": given twice");
  }
  expectRefusal(sim({"run", kStand, "--out", out, "--out", out}, dir_), 2, "command line: --out: given twice");
  EXPECT_FALSE(fs::exists(out));

  writeFile(dir_ / "sweep.yaml", "name: n\nscenario: " + kStand + "\nduration: 0.05\n");
  const std::string sweep_out = (dir_ / "sw").string();
  const std::vector<std::vector<std::string>> sweep_options = {
      {"--timeout", "0x10"}, {"--timeout", "1e999"}, {"--timeout", " 10"}, {"--jobs", "1", "--jobs", "2"},
      {"--timeout", "10", "--timeout", "20"}, {"--backend", "parallel", "--backend", "parallel"},
      {"--out", sweep_out}, {"--fresh", "--fresh"}};
  for (const auto& options : sweep_options) {
    std::vector<std::string> args = {"sweep", (dir_ / "sweep.yaml").string(), "--out", sweep_out, "--quiet"};
    args.insert(args.end(), options.begin(), options.end());
    expectRefusal(sim(args, dir_), 2, "command line: " + options[0] + ": ");
  }
  EXPECT_FALSE(fs::exists(sweep_out));
}

// ---------------------------------------------------------------- ranges

struct RangeCase {
  const char* label;
  std::string yaml;   // after "name: x\nduration: 1\n" unless it sets them
  std::string key;    // named in the message
};

class HostileRange : public Hostile, public ::testing::WithParamInterface<RangeCase> {};

TEST_P(HostileRange, OutOfRangeExitsTwoNamingTheKey) {
  const RangeCase& c = GetParam();
  const fs::path file = dir_ / "range.yaml";
  const bool whole = c.yaml.rfind("name:", 0) == 0;
  writeFile(file, whole ? c.yaml : "name: x\nduration: 1\n" + c.yaml);
  const Outcome o = sim({"run", file.string(), "--out", (dir_ / "o").string()}, dir_);
  expectRefusal(o, 2, file.string() + ": " + c.key + ": ");
  EXPECT_FALSE(fs::exists(dir_ / "o"));
}

std::string patches(int n) {
  std::string s = "terrain:\n  patches:\n";
  for (int i = 0; i < n; ++i) s += "    - {x: [0, 1], y: [0, 1], mu: 0.5}\n";
  return s;
}

std::string disturbances(int n) {
  std::string s = "disturbances:\n";
  for (int i = 0; i < n; ++i) s += "  - {t: " + std::to_string(i) + ", duration: 0.1, force: [1, 0, 0]}\n";
  return s;
}

INSTANTIATE_TEST_SUITE_P(
    Cli, HostileRange,
    ::testing::Values(
        RangeCase{"payload_huge", "robot: {payload_kg: 1e308}\n", "robot.payload_kg"},
        RangeCase{"payload_above", "robot: {payload_kg: 200.5}\n", "robot.payload_kg"},
        RangeCase{"payload_negative", "robot: {payload_kg: -1}\n", "robot.payload_kg"},
        RangeCase{"force_huge", "disturbances:\n  - {t: 0, duration: 1, force: [0, 1e300, 0]}\n",
                  "disturbances[0].force[1]"},
        RangeCase{"force_above", "disturbances:\n  - {t: 0, duration: 1, force: [0, 0, -5001]}\n",
                  "disturbances[0].force[2]"},
        RangeCase{"forces_add_up",
                  "disturbances:\n  - {t: 0, duration: 2, force: [4000, 0, 0]}\n"
                  "  - {t: 1, duration: 2, force: [0, 4000, 0]}\n",
                  "disturbances"},
        RangeCase{"disturbance_t", "disturbances:\n  - {t: 3601, duration: 1, force: [1, 0, 0]}\n",
                  "disturbances[0].t"},
        RangeCase{"disturbance_t_negative",
                  "disturbances:\n  - {t: -1, duration: 1, force: [1, 0, 0]}\n", "disturbances[0].t"},
        RangeCase{"disturbance_duration_zero",
                  "disturbances:\n  - {t: 0, duration: 0, force: [1, 0, 0]}\n",
                  "disturbances[0].duration"},
        RangeCase{"disturbance_duration_long",
                  "disturbances:\n  - {t: 0, duration: 3601, force: [1, 0, 0]}\n",
                  "disturbances[0].duration"},
        RangeCase{"disturbance_count", disturbances(101), "disturbances"},
        RangeCase{"duration_huge", "name: x\nduration: 1e9\n", "duration"},
        RangeCase{"duration_below_a_tick", "name: x\nduration: 1e-6\n", "duration"},
        RangeCase{"duration_short", "name: x\nduration: 0.005\n", "duration"},
        RangeCase{"duration_infinite", "name: x\nduration: .inf\n", "duration"},
        RangeCase{"patch_count", patches(1001), "terrain.patches"},
        RangeCase{"patch_far", "terrain:\n  patches:\n    - {x: [0, 1e4], y: [0, 1], mu: 0.5}\n",
                  "terrain.patches[0].x[1]"},
        RangeCase{"patch_mu", "terrain:\n  patches:\n    - {x: [0, 1], y: [0, 1], mu: 1e9}\n",
                  "terrain.patches[0].mu"},
        RangeCase{"terrain_mu", "terrain: {mu: 6}\n", "terrain.mu"},
        RangeCase{"ramp_count",
                  [] {
                    std::string s = "terrain:\n  ramps:\n";
                    for (int i = 0; i < 101; ++i)
                      s += "    - {x0: " + std::to_string(i) + ", angle: 0.1, length: 0.5}\n";
                    return s;
                  }(),
                  "terrain.ramps"},
        RangeCase{"ramp_angle", "terrain: {ramps: [{x0: 1, angle: 1.2, length: 1}]}\n",
                  "terrain.ramps[0].angle"},
        RangeCase{"ramp_x0", "terrain: {ramps: [{x0: -1e6, angle: 0.1, length: 1}]}\n",
                  "terrain.ramps[0].x0"},
        RangeCase{"ramp_end", "terrain: {ramps: [{x0: 399, angle: 0.1, length: 2}]}\n",
                  "terrain.ramps[0].length"},
        RangeCase{"start_x", "robot: {start: {x: 1e4}}\n", "robot.start.x"},
        RangeCase{"start_y", "robot: {start: {y: -401}}\n", "robot.start.y"},
        RangeCase{"start_yaw", "robot: {start: {yaw: 4}}\n", "robot.start.yaw"},
        RangeCase{"noise_q", "sensors: {q: 0.011}\n", "sensors.q"},
        RangeCase{"noise_tau", "sensors: {tau: 1e6}\n", "sensors.tau"},
        RangeCase{"noise_gyro_bias", "sensors: {gyro_bias: 0.2}\n", "sensors.gyro_bias"},
        RangeCase{"noise_acc", "sensors: {acc: 3}\n", "sensors.acc"},
        RangeCase{"noise_orientation", "sensors: {orientation: 0.2}\n", "sensors.orientation"},
        RangeCase{"ode_stiffness", "physics: {ode: {stiffness_scale: 20}}\n", "physics.ode.stiffness_scale"},
        RangeCase{"mujoco_timeconst", "physics: {mujoco: {timeconst: 0.001}}\n", "physics.mujoco.timeconst"},
        RangeCase{"mujoco_solimp", "physics: {mujoco: {solimp: [0.9, 1.5, 0.001]}}\n",
                  "physics.mujoco.solimp[1]"},
        RangeCase{"mujoco_impratio", "physics: {mujoco: {impratio: 0.5}}\n", "physics.mujoco.impratio"},
        // Each value in its range, together a contact that cannot carry HyQ.
        RangeCase{"mujoco_contact_soft", "physics: {mujoco: {solimp: [0.01, 0.01, 0.001]}}\n",
                  "physics.mujoco.solimp"},
        RangeCase{"mujoco_contact_unstable", "physics: {mujoco: {solimp: [0.95, 0.01, 0.001]}}\n",
                  "physics.mujoco.solimp"},
        RangeCase{"mujoco_contact_sinks", "physics: {mujoco: {timeconst: 0.1}}\n", "physics.mujoco"},
        RangeCase{"mujoco_contact_sinks_damped", "physics: {mujoco: {timeconst: 0.05, dampratio: 2}}\n",
                  "physics.mujoco"},
        RangeCase{"mujoco_contact_sinks_wide", "physics: {mujoco: {solimp: [0.01, 0.95, 0.1]}}\n",
                  "physics.mujoco"},
        RangeCase{"mujoco_contact_sinks_payload",
                  "robot: {payload_kg: 200}\nphysics: {mujoco: {timeconst: 0.02, dampratio: 3}}\n",
                  "physics.mujoco"},
        RangeCase{"mujoco_noslip", "physics: {mujoco: {noslip_iterations: 1e6}}\n",
                  "physics.mujoco.noslip_iterations"},
        RangeCase{"mujoco_noslip_fraction", "physics: {mujoco: {noslip_iterations: 2.5}}\n",
                  "physics.mujoco.noslip_iterations"},
        RangeCase{"engine_name", "physics: {engine: bullet}\n", "physics.engine"},
        RangeCase{"mujoco_ground_size",
                  [] {
                    // 60 stripes along y over 60 stripes along x: the
                    // crossings alternate friction, some 14,000 regions.
                    std::string s = "physics: {engine: mujoco}\nterrain:\n  patches:\n";
                    for (int i = 0; i < 60; ++i)
                      s += "    - {x: [" + std::to_string(i) + ", " + std::to_string(i) +
                           ".5], y: [-400, 400], mu: 0.3}\n";
                    for (int i = 0; i < 60; ++i)
                      s += "    - {x: [-400, 400], y: [" + std::to_string(i) + ", " + std::to_string(i) +
                           ".5], mu: 0.2}\n";
                    return s;
                  }(),
                  "terrain.patches"},
        RangeCase{"seed_long", "seed: 99999999999999999999\n", "seed"},
        RangeCase{"seed_negative", "seed: -1\n", "seed"},
        RangeCase{"name_long", "name: " + std::string(65, 'a') + "\nduration: 1\n", "name"}),
    [](const ::testing::TestParamInfo<RangeCase>& info) { return std::string(info.param.label); });

// The bounds themselves are inside (parsed in-process).
TEST(HostileRanges, BoundsAreAccepted) {
  std::string yaml = "name: " + std::string(64, 'a') + "\nduration: 3600\nseed: 9999999999999999999\n" +
                     "robot: {payload_kg: 200, start: {x: -400, y: 400, yaw: -3.14159}}\n"
                     "sensors: {q: 0.01, qd: 1, tau: 50, tau_bias: 50, gyro: 0.2, gyro_bias: 0.1,"
                     " acc: 2, acc_bias: 2, orientation: 0.1}\n"
                     "physics: {engine: ode, ode: {stiffness_scale: 10}, mujoco: {timeconst: 0.002,"
                     " dampratio: 10, solimp: [0.9999, 0.9999, 0.1], impratio: 100, noslip_iterations: 100}}\n"
                     "disturbances:\n  - {t: 3600, duration: 3600, force: [3000, 4000, 0]}\n"
                     "  - {t: 0, duration: 1, force: [0, 0, -5000]}\n"
                     "  - {t: 1, duration: 1, force: [0, 0, 5000]}\n";
  yaml += "terrain:\n  mu: 5\n  ramps:\n    - {x0: -400, angle: -1.19, length: 1}\n"
          "    - {x0: 399, angle: 1.19, length: 1}\n  patches:\n";
  for (int i = 0; i < 1000; ++i) yaml += "    - {x: [-400, 400], y: [-400, 400], mu: 5}\n";
  const Scenario s = parseScenario(yaml, "bounds.yaml");
  EXPECT_EQ(s.terrain.patches.size(), 1000u);
  EXPECT_EQ(s.payload_kg, 200.0);
  EXPECT_EQ(s.physics.ode_stiffness_scale, 10.0);
  EXPECT_EQ(s.physics.mujoco.solimp_width, 0.1);
  EXPECT_EQ(s.physics.mujoco.noslip_iterations, 100);
  EXPECT_EQ(parseScenario("name: x\nduration: 0.01\n", "x.yaml").duration, 0.01);
  // The other ends of MuJoCo's ranges, in contacts that carry the robot.
  for (const char* mujoco : {"{timeconst: 0.1, dampratio: 0.1, solimp: [0.01, 0.9999, 0]}",
                             "{timeconst: 0.05, dampratio: 1}", "{dampratio: 10}", "{timeconst: 0.02, dampratio: 3}",
                             "{solimp: [0.01, 0.95, 0.001]}", "{solimp: [0.5, 0.5, 0.001], impratio: 1}",
                             "{solimp: [0.9, 0.5, 0.001]}"})
    EXPECT_NO_THROW(parseScenario(std::string("name: x\nduration: 1\nphysics: {mujoco: ") + mujoco + "}\n", "x"))
        << mujoco;
  // Every range of the table is used by the reader and reads back sensibly.
  for (const KeyRange& r : kScenarioRanges) {
    EXPECT_EQ(&scenarioRange(r.key), &r);
    EXPECT_LE(r.min, r.max) << r.key;
    EXPECT_FALSE(rangeText(r).empty());
  }
  EXPECT_EQ(rangeText(scenarioRange("terrain.ramps[].angle")), "in (-1.2, 1.2) rad");
  EXPECT_EQ(rangeText(scenarioRange("duration")), "in [0.01, 3600] s");
}

// ---------------------------------------------------------------- the QEMU controller

TEST_F(Hostile, QemuControllerFailuresAreOneLine) {
  const std::vector<std::string> args = {"run", kStand, "--controller", "qemu", "--duration", "0.1",
                                         "--out", (dir_ / "o").string()};
  Child no_qemu;
  no_qemu.env = {{"PATH", (dir_ / "empty_path").string()}};
  expectRefusal(sim(args, dir_, no_qemu), 1, "cannot start qemu-system-arm");

  Child missing;
  missing.env = {{"HYQ_FW_MPS2_ELF", (dir_ / "missing.elf").string()}};
  expectRefusal(sim(args, dir_, missing), 1, (dir_ / "missing.elf").string() + ": board image not readable");
  EXPECT_FALSE(fs::exists(dir_ / "o" / "summary.json"));

  if (std::system("command -v qemu-system-arm > /dev/null 2>&1") != 0)
    GTEST_SKIP() << "no qemu-system-arm: the garbage-image case needs it";
  // Not an ELF: QEMU loads it as a raw image, faults at reset and prints a
  // register dump, which must not reach hyq_sim's stderr.
  writeFile(dir_ / "garbage.elf", std::string(4096, '\xff'));
  Child bad;
  bad.env = {{"HYQ_FW_MPS2_ELF", (dir_ / "garbage.elf").string()}};
  expectRefusal(sim(args, dir_, bad), 1, "qemu controller: cannot boot " + (dir_ / "garbage.elf").string());
  EXPECT_FALSE(fs::exists(dir_ / "o" / "summary.json"));
}

// The pids of the processes whose command line holds `marker`. (The
// pattern "[m]arker" does not match the shell that runs pgrep.)
std::vector<int> processesWith(const std::string& marker, const fs::path& scratch) {
  const fs::path out = scratch / ".pgrep";
  const std::string pattern = "[" + marker.substr(0, 1) + "]" + marker.substr(1);
  std::system(("pgrep -f -- '" + pattern + "' > '" + out.string() + "' 2>/dev/null").c_str());
  std::vector<int> pids;
  std::stringstream lines(readFile(out));
  std::string line;
  while (std::getline(lines, line))
    if (!line.empty()) pids.push_back(std::stoi(line));
  fs::remove(out);
  return pids;
}

// A stand-in emulator (qemu-system-arm first on PATH) that hangs with a
// child of its own: the run ends with one line after the boot timeout,
// leaving neither. One that exits at once is noticed at once.
TEST_F(Hostile, EmulatorThatHangsLeavesNothingAndOneThatExitsIsNoticedAtOnce) {
  const fs::path bin = dir_ / "bin";
  fs::create_directories(bin);
  const std::string marker = "hyq_stand_in_qemu_" + std::to_string(::getpid());
  writeFile(bin / "qemu-system-arm",
            "#!/bin/bash\n(exec -a " + marker + "_child sleep 300) &\nexec -a " + marker + " sleep 300\n");
  fs::permissions(bin / "qemu-system-arm", fs::perms::owner_all);
  writeFile(dir_ / "board.elf", "a board image");
  Child run;
  run.env = {{"PATH", bin.string() + ":" + std::getenv("PATH")}, {"HYQ_FW_MPS2_ELF", (dir_ / "board.elf").string()}};
  run.timeout_s = 40;
  const std::vector<std::string> args = {"run",      kStand, "--controller", "qemu", "--duration", "0.1",
                                         "--no-log", "--out", (dir_ / "o").string()};
  expectRefusal(sim(args, dir_, run), 1, "qemu did not connect");
  std::vector<int> left = processesWith(marker, dir_);
  for (int k = 0; k < 20 && !left.empty(); ++k) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    left = processesWith(marker, dir_);
  }
  EXPECT_TRUE(left.empty()) << left.size() << " processes of the emulator left";
  for (int pid : left) ::kill(pid, SIGKILL);

  writeFile(bin / "qemu-system-arm", "#!/bin/bash\necho 'qemu-system-arm: no such machine' >&2\nexit 3\n");
  const auto t0 = std::chrono::steady_clock::now();
  const Outcome o = sim(args, dir_, run);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  expectRefusal(o, 1, "exited with status 3");
  EXPECT_NE(o.err.find("no such machine"), std::string::npos) << o.err;
  EXPECT_LT(seconds, 3.0);
  EXPECT_FALSE(fs::exists(dir_ / "o" / "summary.json"));
}

// ---------------------------------------------------------------- memory

long residentKb() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  return -1;
}

// Resident memory at a quarter, half and the end of a run.
class ResidentMemory final : public TickObserver {
 public:
  explicit ResidentMemory(uint64_t ticks) : ticks_(ticks) {}
  void onTick(const TickRecord&) override {
    ++seen_;
    if (seen_ == ticks_ / 4) quarter_kb = residentKb();
    if (seen_ == ticks_ / 2) half_kb = residentKb();
  }
  void onFinish() override { end_kb = residentKb(); }
  long quarter_kb = -1, half_kb = -1, end_kb = -1;

 private:
  uint64_t ticks_, seen_ = 0;
};

// 600 simulated seconds of stand.yaml (the posture controller, four feet in
// stance: a quiet-spread sample every tick), metrics on, no log: the
// second half adds no memory (a metrics record kept per tick would add
// ~0.1 GB to it).
TEST_F(Hostile, LongRunKeepsResidentMemoryFlat) {
  Scenario s = loadScenario(kStand);
  s.duration = 600.0;
  auto controller = makeController(s.controller_kind, s);
  Metrics metrics;
  ResidentMemory memory(600000);
  RunOptions options;
  options.out_dir = (dir_ / "long").string();
  options.write_log = false;
  options.progress = false;
  const RunResult r = runScenario(s, *controller, options, {&metrics, &memory});
  ASSERT_FALSE(r.fell);
  ASSERT_GT(memory.half_kb, 0);
  std::printf("VmRSS: %ld kB at 150 s, %ld kB at 300 s, %ld kB at 600 s\n", memory.quarter_kb,
              memory.half_kb, memory.end_kb);
  EXPECT_LT(memory.end_kb - memory.half_kb, 1024) << "kB grown over the second half";
  EXPECT_LT(memory.half_kb - memory.quarter_kb, 1024) << "kB grown from 150 s to 300 s";
  EXPECT_GT(metrics.result().quiet_spread_samples, 590000u);
  EXPECT_TRUE(fs::exists(dir_ / "long" / "summary.json"));
}

}  // namespace
}  // namespace hyq::sim
