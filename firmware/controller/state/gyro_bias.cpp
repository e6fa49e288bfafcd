#include "firmware/controller/state/gyro_bias.hpp"

namespace hyq {

void GyroBiasEstimator::reset(const EstimatorParams& params, double dt) {
  enabled_ = params.gyro_bias_time > 0.0;
  k_p_ = enabled_ ? 2.0 / params.gyro_bias_time : 0.0;
  k_i_ = enabled_ ? 1.0 / (params.gyro_bias_time * params.gyro_bias_time) : 0.0;
  limit_ = params.gyro_bias_limit;
  dt_ = dt;
  attitude_ = Quat::Identity();
  bias_.setZero();
  have_attitude_ = false;
}

Vec3 GyroBiasEstimator::update(const Mat3& R_wb, const Vec3& gyro) {
  if (!enabled_) return gyro;
  const Quat measured(R_wb);
  if (!have_attitude_) {
    attitude_ = measured;
    have_attitude_ = true;
    return gyro - bias_;
  }
  // Error from the filter's attitude to the measured one, in B (shortest way).
  Quat error = attitude_.conjugate() * measured;
  if (error.w() < 0.0) error.coeffs() = -error.coeffs();
  const Eigen::AngleAxisd aa(error);
  const Vec3 e = aa.axis() * aa.angle();
  for (int k = 0; k < 3; ++k) bias_[k] = clampAbs(bias_[k] - k_i_ * dt_ * e[k], limit_);
  const Vec3 rate = gyro - bias_;
  const Vec3 step = dt_ * (rate + k_p_ * e);
  const double angle = step.norm();
  if (angle > 0.0) attitude_ = attitude_ * Quat(Eigen::AngleAxisd(angle, step / angle));
  attitude_.normalize();
  return rate;
}

}  // namespace hyq
