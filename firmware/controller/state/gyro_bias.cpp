#include "firmware/controller/state/gyro_bias.hpp"

#include "firmware/controller/model/sincos.hpp"

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

Vec3 GyroBiasEstimator::update(const Quat& measured, const Vec3& gyro) {
  if (!enabled_) return gyro;
  if (!have_attitude_) {
    attitude_ = measured;
    have_attitude_ = true;
    return gyro - bias_;
  }
  // Error from the filter's attitude to the measured one, in B (shortest
  // way), as a rotation vector: the axis times 2 atan2(|v|, w).
  Quat error = attitude_.conjugate() * measured;
  if (error.w() < 0.0) error.coeffs() = -error.coeffs();
  const double half_sine = error.vec().norm();
  const Vec3 e = half_sine > 0.0 ? Vec3(error.vec() * (2.0 * angleOfSineCosine(half_sine, error.w()) / half_sine))
                                 : Vec3(Vec3::Zero());
  for (int k = 0; k < 3; ++k) bias_[k] = clampAbs(bias_[k] - k_i_ * dt_ * e[k], limit_);
  const Vec3 rate = gyro - bias_;
  // The attitude turned by the step's rotation vector: cos and sin of half
  // its angle from one argument reduction.
  const Vec3 step = dt_ * (rate + k_p_ * e);
  const double angle = step.norm();
  if (angle > 0.0) {
    const SinCos half = sinCos(0.5 * angle);
    const Vec3 v = step * (half.s / angle);
    attitude_ = attitude_ * Quat(half.c, v.x(), v.y(), v.z());
  }
  attitude_.normalize();
  return rate;
}

}  // namespace hyq
