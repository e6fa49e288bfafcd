#include "firmware/controller/force/joint_commands.hpp"

#include <cmath>

#include "firmware/controller/model/robot_params.hpp"

namespace hyq {
namespace {

// Replaces `to` by alpha * to + (1 - alpha) * the posture hold at q_hold
// with feed-forward tau_hold, in applied torque: tau = tau_ff + kp (q_ref - q)
// + kd (qd_ref - qd) is linear in (tau_ff, kp, kp q_ref, kd, kd qd_ref), so
// blending those blends the applied torque. The hold's velocity reference is
// zero. Works on the joint arrays in place: no second frame is built.
void blendFromPosture(const double q_hold[kNumJoints], const double tau_hold[kNumJoints],
                      const JointParams& gains, double alpha, hal::CommandFrame& to) {
  const double a = alpha < 0.0 ? 0.0 : (alpha > 1.0 ? 1.0 : alpha), b = 1.0 - a;
  const double hold_kp = b * gains.posture_kp, hold_kd = b * gains.posture_kd;
  for (int j = 0; j < kNumJoints; ++j) {
    const double kp = a * to.kp[j] + hold_kp;
    const double kd = a * to.kd[j] + hold_kd;
    const double kp_q = a * to.kp[j] * to.q_ref[j] + hold_kp * q_hold[j];
    const double kd_qd = a * to.kd[j] * to.qd_ref[j];
    to.tau_ff[j] = a * to.tau_ff[j] + b * tau_hold[j];
    to.q_ref[j] = kp > 0.0 ? kp_q / kp : to.q_ref[j];
    to.qd_ref[j] = kd > 0.0 ? kd_qd / kd : to.qd_ref[j];
    to.kp[j] = kp;
    to.kd[j] = kd;
  }
}

bool allFinite(const double* v, int n) {
  for (int i = 0; i < n; ++i)
    if (!std::isfinite(v[i])) return false;
  return true;
}

}  // namespace

void postureCommand(const double q_hold[kNumJoints], const double* tau_ff, const JointParams& gains,
                    hal::CommandFrame& command) {
  for (int j = 0; j < kNumJoints; ++j) {
    command.q_ref[j] = q_hold[j];
    command.qd_ref[j] = 0.0;
    command.kp[j] = gains.posture_kp;
    command.kd[j] = gains.posture_kd;
    command.tau_ff[j] = tau_ff ? tau_ff[j] : 0.0;
  }
}

bool commandFinite(const hal::CommandFrame& c) {
  return allFinite(c.tau_ff, kNumJoints) && allFinite(c.q_ref, kNumJoints) &&
         allFinite(c.qd_ref, kNumJoints) && allFinite(c.kp, kNumJoints) && allFinite(c.kd, kNumJoints);
}

void FreezeMode::reset() {
  frozen_ = false;
  unfreeze_time_ = 1e9;
  for (double& t : last_tau_) t = 0.0;
}

bool FreezeMode::apply(bool requested, bool all_down, const double q[kNumJoints],
                       const RecoveryParams& recovery, const JointParams& gains, double dt,
                       hal::CommandFrame& command) {
  const bool freeze_now = requested && (frozen_ || all_down);
  if (freeze_now && !frozen_) {
    for (int j = 0; j < kNumJoints; ++j) {
      freeze_q_[j] = q[j];
      freeze_tau_[j] = clampAbs(last_tau_[j], robot::kEffortLimit);
    }
  }
  const bool left = !freeze_now && frozen_;
  if (left) unfreeze_time_ = 0.0;
  frozen_ = freeze_now;
  if (frozen_) {
    postureCommand(freeze_q_, freeze_tau_, gains, command);
  } else if (unfreeze_time_ < recovery.unfreeze_blend) {
    blendFromPosture(freeze_q_, freeze_tau_, gains, unfreeze_time_ / recovery.unfreeze_blend, command);
    unfreeze_time_ += dt;
  }
  return left;
}

void FreezeMode::recordApplied(const hal::CommandFrame& c, const double q[kNumJoints],
                               const double qd[kNumJoints]) {
  for (int j = 0; j < kNumJoints; ++j) {
    const double tau = c.tau_ff[j] + c.kp[j] * (c.q_ref[j] - q[j]) + c.kd[j] * (c.qd_ref[j] - qd[j]);
    last_tau_[j] = std::isfinite(tau) ? tau : 0.0;
  }
}

}  // namespace hyq
