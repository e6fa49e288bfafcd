// Base state from proprioception only. Orientation comes from the IMU;
// velocity from leg odometry over the stance feet the caller trusts, fused with
// the IMU's specific force (complementary filter, with integral action that
// estimates the accelerometer's bias, fast at first, as a running mean, then
// at acc_bias_time); position by integration.
// Positions are relative to where the robot started: x, y = 0 at init, z = the
// base's height above its feet.
#pragma once
#include <cstdint>

#include "firmware/controller/params.hpp"
#include "firmware/controller/model/types.hpp"

namespace hyq {

class StateEstimator {
 public:
  void reset(const EstimatorParams& params, double dt);
  // Start at rest with the feet (B positions) on the ground at z = 0.
  void initialise(const Mat3& R_wb, const Mat3x4& feet_base);
  // foot_vel_base: u_i = bv_fi + bw x bx_fi per leg (B). odometry_mask: the
  // stance feet trusted not to move this tick. specific_force_base: the
  // accelerometer's reading less accBias() (the estimate before this update).
  void update(const Mat3& R_wb, const Vec3& specific_force_base, const Mat3x4& foot_vel_base,
              uint32_t odometry_mask);
  // [m/s^2] in B: the accelerometer's bias as estimated so far.
  const Vec3& accBias() const { return acc_bias_; }

  const Vec3& position() const { return position_; }
  const Vec3& velocity() const { return velocity_; }

 private:
  EstimatorParams p_{};
  double dt_ = kTickPeriod;
  Vec3 position_ = Vec3::Zero();
  Vec3 velocity_ = Vec3::Zero();
  Vec3 leg_velocity_ = Vec3::Zero();
  bool leg_velocity_valid_ = false;
  Vec3 acc_bias_ = Vec3::Zero();
  double acc_bias_learnt_time_ = 0.0;  // [s] ticks with leg odometry, up to acc_bias_time
};

}  // namespace hyq
