// Whole-robot joint commands that are not the walking controller's own: the
// posture hold (a bad frame, a lost link, refused parameters) and freezing
// mode ("wooden chair"), with its hand-back to walking.
#pragma once
#include "firmware/controller/params.hpp"
#include "firmware/controller/model/types.hpp"
#include "hal/frames.hpp"

namespace hyq {

// Every joint held at q_hold [rad] with the posture gains, plus tau_ff [N m]
// (nullptr: none); zero velocity reference. Leaves tick, flags and telemetry alone.
void postureCommand(const double q_hold[kNumJoints], const double* tau_ff, const JointParams& gains,
                    hal::CommandFrame& command);

// True when every torque, reference and gain of `command` is finite.
bool commandFinite(const hal::CommandFrame& command);

// Freezing mode. The recovery decides when the robot should freeze; this
// makes the command. On entry every joint stiffens where it is, its
// feed-forward the torque the joint loop was producing, so nothing steps; on
// exit the frozen command hands over to the walking one linearly in applied
// torque. A leg that swings when freezing is called is put down first (the
// gait lowers it while paused), the stance legs still under force control: a
// robot frozen on three legs, one of them slipping, tips over.
class FreezeMode {
 public:
  void reset();
  // requested: the recovery's decision; all_down: all four feet in stance;
  // q [rad]: the joints now. Replaces or blends `command`. Returns true on
  // the tick freezing ends (the gait must re-plan from where the robot is).
  bool apply(bool requested, bool all_down, const double q[kNumJoints], const RecoveryParams& recovery,
             const JointParams& gains, double dt, hal::CommandFrame& command);
  // What the joint loop will apply with `command` at state (q, qd), before
  // saturation: the feed-forward of the next freeze entry.
  void recordApplied(const hal::CommandFrame& command, const double q[kNumJoints],
                     const double qd[kNumJoints]);
  bool frozen() const { return frozen_; }

 private:
  bool frozen_ = false;
  double unfreeze_time_ = 1e9;       // [s] since freezing ended
  double freeze_q_[kNumJoints] = {};  // [rad]
  double freeze_tau_[kNumJoints] = {};  // [N m]
  double last_tau_[kNumJoints] = {};    // [N m] what the joint loop applied last tick
};

}  // namespace hyq
