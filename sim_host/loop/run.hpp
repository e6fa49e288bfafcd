// One simulation run: scenario + controller in lock-step, observers fed each
// tick, files written. And the `hyq_sim` command line around it.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "hal/frames.hpp"
#include "sim_host/loop/controller_port.hpp"
#include "sim_host/scenario/scenario.hpp"
#include "sim_host/physics/simulator.hpp"
#include "sim_host/records/tick_observer.hpp"

namespace hyq::sim {

struct RunOptions {
  std::string out_dir;          // "" -> out/<scenario name>
  bool write_log = true;        // log.csv (events.csv and summary.json always)
  bool progress = true;         // a live status line, only when stderr is a terminal
  // replay.html's page template (readReplayTemplate); "" writes no replay.html.
  std::string replay_template;
  SimConfig sim;
};

struct RunResult {
  bool fell = false;
  double fall_time = 0.0;       // [s] when `fell`
  double sim_time = 0.0;        // [s] simulated
  double wall_time = 0.0;       // [s]
  double cpu_time = 0.0;        // [s] this process, during the run
  double distance = 0.0;        // [m] base progress along the start heading (x at yaw 0), ground truth
  double real_time_factor = 0.0;
  std::string out_dir;
};

// Runs to the scenario's duration or shortly after a fall. `extra` observers
// (e.g. metrics) see every tick and may add summary.json fields.
// The folder's files of an earlier run (summary.json, log.csv, events.csv,
// replay.html and docs/plots.py's figures) are removed first; the new files are
// written under temporary names and renamed at the end, summary.json last,
// so that none of them appears unless all are complete. Throws OutputError
// ("<file>: <OS error text>") if a file cannot be written, leaving none of
// them; ScenarioError if the run would have no tick, or if its name cannot
// name the default folder out/<name> (isPlainFileName). Exceptions of the
// controller and the observers pass through, the outputs removed.
RunResult runScenario(const Scenario& scenario, ControllerPort& controller,
                      const RunOptions& options, const std::vector<TickObserver*>& extra = {});

// Faults a recording puts between the simulator and the controller.
struct FrameFaults {
  // Frames lost before the frame of this index: the simulator runs on with
  // the last command and the tick counter jumps (0: none).
  std::function<int(int index)> dropped_before;
  // Changes a frame before the controller sees it (and it is recorded).
  std::function<void(int index, hal::SensorFrame& frame)> corrupt;
};

// Sensor frames of a closed-loop run with the host controller, nothing
// written and no observers: `ticks` frames, fewer if the robot falls. The
// input of the firmware replay tests, the golden replay and the controller
// benchmark.
std::vector<hal::SensorFrame> recordSensorFrames(const Scenario& scenario, int ticks,
                                                 const FrameFaults& faults = {});

// `hyq_sim run SCENARIO.yaml [--recovery on|off] [--seed N] [--duration S]
// [--out DIR] [--controller NAME] [--no-log] [--replay] [--substeps N]
// [--engine ode|mujoco]`. Returns the exit code:
// 0 done (fallen or not), 2 bad input, 1 could not write outputs (or
// stdout) or the controller failed (e.g. the board in QEMU). Every refusal
// is one line on stderr naming the file or key, long values cut.
int cliMain(int argc, char** argv);

}  // namespace hyq::sim
