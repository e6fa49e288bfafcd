#include "firmware/controller/state/state_estimator.hpp"

#include "firmware/controller/model/robot_params.hpp"

namespace hyq {

void StateEstimator::reset(const EstimatorParams& params, double dt) {
  p_ = params;
  dt_ = dt;
  position_.setZero();
  velocity_.setZero();
  leg_velocity_.setZero();
  leg_velocity_valid_ = false;
  acc_bias_.setZero();
  acc_bias_learnt_time_ = 0.0;
}

void StateEstimator::initialise(const Mat3& R_wb, const Mat3x4& feet_base) {
  const Vec3 mean_foot_world = R_wb * feet_base.rowwise().mean();
  position_ = Vec3(0.0, 0.0, -mean_foot_world.z());
  velocity_.setZero();
}

void StateEstimator::update(const Mat3& R_wb, const Vec3& specific_force_base,
                            const Mat3x4& foot_vel_base, uint32_t odometry_mask) {
  // A foot that stays put sees the base move at -u_i.
  Vec3 sum = Vec3::Zero();
  int count = 0;
  for (int i = 0; i < 4; ++i) {
    if (odometry_mask & (1u << i)) {
      sum += foot_vel_base.col(i);
      ++count;
    }
  }
  leg_velocity_valid_ = count > 0;
  if (leg_velocity_valid_) leg_velocity_ = -(R_wb * sum) / count;

  const Vec3 accel_world = R_wb * specific_force_base + Vec3(0.0, 0.0, -robot::kGravity);
  const Vec3 predicted = velocity_ + dt_ * accel_world;
  // Complementary filter: the IMU carries the fast part, the legs anchor it.
  const double blend = dt_ / (p_.vel_filter_tau + dt_);
  velocity_ = leg_velocity_valid_ ? predicted + blend * (leg_velocity_ - predicted) : predicted;
  position_ += dt_ * velocity_;
  if (leg_velocity_valid_ && p_.acc_bias_time > 0.0) {
    // A residual bias db makes the filtered velocity lead the legs' by
    // tau R db; this gain turns that lead back into db' = -db / T, T the
    // time learnt so far within [acc_bias_start_time, acc_bias_time].
    const double time_constant =
        acc_bias_learnt_time_ < p_.acc_bias_start_time
            ? p_.acc_bias_start_time
            : (acc_bias_learnt_time_ < p_.acc_bias_time ? acc_bias_learnt_time_ : p_.acc_bias_time);
    const double gain = 1.0 / (p_.vel_filter_tau * time_constant);  // [1/s^2]
    const Vec3 lead_base = R_wb.transpose() * (velocity_ - leg_velocity_);
    for (int k = 0; k < 3; ++k)
      acc_bias_[k] = clampAbs(acc_bias_[k] + gain * dt_ * lead_base[k], p_.acc_bias_limit);
    if (acc_bias_learnt_time_ < p_.acc_bias_time) acc_bias_learnt_time_ += dt_;
  }
}

}  // namespace hyq
