#include "firmware/controller/state/torque_bias.hpp"

namespace hyq {

void TorqueBiasEstimator::reset(const EstimatorParams& params, double dt) {
  // The residual is the offset only if the model includes the leg's
  // dynamics; the static GRF estimate would learn M qdd + b qd as offsets.
  enabled_ = params.torque_bias_time > 0.0 && params.grf_leg_dynamics;
  alpha_min_ = enabled_ ? dt / params.torque_bias_time : 0.0;
  limit_ = params.torque_bias_limit;
  offset_sigma_ = params.torque_offset_sigma > 0.0 ? params.torque_offset_sigma : 0.0;
  start_weight_ = params.torque_bias_start_weight > 0.0 ? params.torque_bias_start_weight : 0.0;
  bias_.setZero();
  for (int& n : samples_) n = 0;
}

double TorqueBiasEstimator::remainingSigma(int leg) const {
  if (leg < 0 || leg > 3) return offset_sigma_;
  if (!enabled_) return offset_sigma_;
  const double k = static_cast<double>(samples_[leg]);
  if (!(k + start_weight_ > 0.0)) return offset_sigma_;
  return offset_sigma_ * start_weight_ / (k + start_weight_);
}

void TorqueBiasEstimator::update(int leg, const Vec3& residual) {
  if (!enabled_ || leg < 0 || leg > 3 || !residual.allFinite()) return;
  // 1/(k + k0) until the window is full: nearly the plain mean of the
  // samples so far. The residual comes from a force estimate a few ticks
  // old (the acceleration window's centre), made with the offset of then;
  // k0 (torque_bias_start_weight) keeps each step small against that lag.
  if (samples_[leg] < 1000000) ++samples_[leg];
  const double k = static_cast<double>(samples_[leg]) + start_weight_;
  const double alpha = 1.0 / k > alpha_min_ ? 1.0 / k : alpha_min_;
  // The residual is of the corrected reading: it is what the offset still misses.
  for (int j = 0; j < 3; ++j) bias_[3 * leg + j] = clampAbs(bias_[3 * leg + j] + alpha * residual[j], limit_);
}

}  // namespace hyq
