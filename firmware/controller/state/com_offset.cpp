#include "firmware/controller/state/com_offset.hpp"

#include <algorithm>
#include <cmath>

namespace hyq {

void ComOffsetEstimator::reset(const EstimatorParams& params, double dt) {
  enabled_ = params.com_offset_time > 0.0;
  dt_ = dt;
  time_ = params.com_offset_time;
  start_time_ = std::min(params.com_offset_start_time, params.com_offset_time);
  learnt_ = 0.0;
  limit_ = params.com_offset_limit;
  tolerance_ = params.com_offset_weight_tolerance;
  offset_ = Vec3::Zero();
}

void ComOffsetEstimator::update(const Mat3x4& feet, const Mat3x4& forces, uint32_t stance, const Vec3& com_model,
                                const Mat3& R_wb, double weight, const Vec3& com_vel, const Vec3& omega) {
  if (!enabled_ || !(com_vel.norm() < kComOffsetRestSpeed) || !(omega.norm() < kComOffsetRestRate)) return;
  int count = 0;
  Vec3 total = Vec3::Zero();
  double moment_x = 0.0, moment_y = 0.0;  // [N m] sum p_xy f_z - (p_z - c_z) f_xy
  for (int i = 0; i < kNumLegs; ++i) {
    if (!(stance & (1u << i))) continue;
    const Vec3 p = feet.col(i), f = forces.col(i);
    ++count;
    total += f;
    moment_x += p.x() * f.z() - (p.z() - com_model.z()) * f.x();
    moment_y += p.y() * f.z() - (p.z() - com_model.z()) * f.y();
  }
  // At rest: three feet or more, the forces' sum the weight and vertical.
  if (count < 3 || !total.allFinite() || std::abs(total.z() - weight) > tolerance_ * weight ||
      total.head<2>().norm() > tolerance_ * weight)
    return;
  const Vec3 measured_world(moment_x / total.z() - com_model.x(), moment_y / total.z() - com_model.y(), 0.0);
  Vec3 measured = R_wb.transpose() * measured_world;
  measured.z() = 0.0;
  learnt_ += dt_;
  const double alpha = dt_ / std::min(std::max(learnt_, start_time_), time_);
  offset_ += alpha * (measured - offset_);
  for (int k = 0; k < 2; ++k) offset_[k] = std::clamp(offset_[k], -limit_, limit_);
}

}  // namespace hyq
