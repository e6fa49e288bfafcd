// Sweeps: one scenario expanded over seeds, recovery on/off, engines and
// parameter ranges, each case run as its own `hyq_sim run` by GNU parallel
// on this machine or by a Slurm job array, then aggregated into
// sweep.json, sweep.csv and plots (sim_host/cli/sweep_report.py).
//
// A sweep file (see sim_host/sweeps/ and docs/sweeps.md):
//
//   name: ice_patches_100            # the default output folder out/sweeps/<name>
//   scenario: ../scenarios/ice_patches.yaml   # relative to this file
//   seeds: {from: 1, to: 100}        # or a list [1, 5, 9]
//   recovery: [on, off]              # optional; default the scenario's
//   engines: [ode, mujoco]           # optional; default the scenario's
//   duration: 30                     # optional [s]
//   timeout_s: 600                   # optional [s] per case (default 900)
//   goal_distance_m: 3.77            # optional: a run succeeds only beyond
//   set:                             # optional parameter axes (product)
//     terrain.patches.*.mu: [0.1, 0.15]
//     gait.speed: {from: 0.04, to: 0.06, step: 0.01}
//     disturbances.0.force: [[0, 100, 0], [0, 150, 0]]
//
// A sweep has at most 10,000 cases; each combination's scenario is checked
// as a run would check it before any folder is written.
//
// Every case gets a folder cases/<id>/ with its whole scenario
// (scenario.yaml), its run's output (summary.json, events.csv, run.log)
// and its exit status (exit_code). A case with an exit status is done,
// whatever the status (a crash or a timeout is a result); a sweep run again
// on the same folder runs only the cases that are not done, or whose
// scenario changed. The folder is locked while the sweep, or any process it
// started, runs.
#pragma once

#include <string>
#include <vector>

namespace hyq::sim {

struct SweepCase {
  std::string id;            // folder name under cases/
  int point = 0;             // index of the parameter combination
  std::vector<std::pair<std::string, std::string>> values;  // set key -> value (flow YAML)
  std::string engine;        // "ode" | "mujoco"
  bool recovery = true;
  unsigned long long seed = 1;
  std::string scenario_yaml; // the whole scenario of the case
};

struct Sweep {
  std::string name;
  std::string source_file;
  std::string source_text;  // the sweep file as read
  std::string scenario_file;
  std::vector<std::string> set_keys;
  double timeout_s = 900.0;
  double goal_distance_m = -1.0;  // < 0: none
  std::vector<SweepCase> cases;
};

// Reads and expands a sweep file; every combination's scenario is checked
// by the scenario reader and for its controller's name (and MuJoCo's ground
// when MuJoCo is among the engines). Throws ScenarioError with one line
// naming the file and key.
Sweep loadSweep(const std::string& path);

// Applies `value` (YAML text) at the dotted `key` of a scenario's YAML text:
// "a.b" a map key (created when missing), "list.2" an index, "list.*" every
// element. Throws ScenarioError when the path does not fit the document.
std::string setScenarioKey(const std::string& scenario_yaml, const std::string& key,
                           const std::string& value);

// `hyq_sim sweep SWEEP.yaml [options]` (see usage in sweep.cpp). Returns the
// exit code: 0 every case ran (fallen or not), 1 some case failed, crashed or
// timed out, or the backend failed; 2 bad input, a locked folder or a
// damaged case file.
int sweepMain(int argc, char** argv);

}  // namespace hyq::sim
