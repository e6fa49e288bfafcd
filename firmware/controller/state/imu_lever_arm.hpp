// The accelerometer's reading moved from where the IMU sits to B's origin.
//
// A point r [m] (B) of a rigid trunk accelerates with
//   a_r = a_0 + alpha x r + omega x (omega x r),
// so an accelerometer there reads the origin's specific force plus the two
// lever-arm terms. The angular acceleration alpha is the gyro's one-tick
// difference through a first-order low-pass (kImuAlphaTime): the difference
// alone is noisy (sigma_w sqrt(2) / dt, 2.8 rad/s^2 for the simulator's
// 2e-3 rad/s), the low-pass (gain g = dt / (T + dt)) keeps g / sqrt(2 - g)
// of that (0.26 at 2 ms), and since the low-pass is linear an integral of
// its alpha x r over a window is still a low-passed difference of the
// window's two ends crossed with r: the IMU-integrated velocity carries no
// more than about one tick's noise of it.
// The first reading after a reset or a restart has no difference: alpha
// starts again from 0.
#pragma once
#include "firmware/controller/model/types.hpp"

namespace hyq {

class ImuLeverArm {
 public:
  // position [m]: the IMU's in B (EstimatorParams::imu_position); all zero:
  // nothing to take out. dt [s]: the tick.
  // alpha_time [s]: the low-pass's time constant (0: the bare difference).
  void reset(const double (&position)[3], double dt, double alpha_time) {
    r_ = Vec3(position[0], position[1], position[2]);
    enabled_ = !r_.isZero(0.0);
    dt_ = dt;
    gain_ = dt / (alpha_time + dt);
    restart();
  }
  // After a gap: the next difference would span more than a tick.
  void restart() {
    have_last_ = false;
    alpha_.setZero();
  }
  bool enabled() const { return enabled_; }

  // specific_force [m/s^2]: the accelerometer's, in B; omega [rad/s]: the
  // (bias-corrected) rate, B. Returns the specific force at B's origin.
  Vec3 atOrigin(const Vec3& specific_force, const Vec3& omega) {
    if (!enabled_) return specific_force;
    if (have_last_) alpha_ += gain_ * ((omega - last_omega_) / dt_ - alpha_);
    last_omega_ = omega;
    have_last_ = true;
    return specific_force - alpha_.cross(r_) - omega.cross(omega.cross(r_));
  }

 private:
  Vec3 r_ = Vec3::Zero();
  bool enabled_ = false;
  double dt_ = kTickPeriod;
  double gain_ = 1.0;            // [-] the low-pass's per-tick gain, dt / (T + dt)
  Vec3 last_omega_ = Vec3::Zero();
  Vec3 alpha_ = Vec3::Zero();     // [rad/s^2]
  bool have_last_ = false;
};

}  // namespace hyq
