// Joint-torque sensor offsets, learnt while a foot is in the air.
//
// The ground force comes from the joint torques, F = -J^-T (tau - b qd - g -
// M qdd): an offset of the torque reading goes straight into it. The
// simulator draws 0.5 N m per joint (docs/scenarios.md), 1-2.5 N at the foot,
// and a mu sample is that over the normal force. In mid-swing the foot
// carries no force, so the leg's model must explain the whole torque:
// whatever it leaves, -J^T F in joint space, is offset plus noise and model
// error (mean 0.1-0.4 N at the foot without offsets, ice_patches seed 1).
// Each joint's offset is a running average of those residuals, first over
// all samples so far, then exponentially over the last `torque_bias_time`
// seconds of swing.
#pragma once

#include "firmware/controller/params.hpp"
#include "firmware/controller/model/types.hpp"

namespace hyq {

class TorqueBiasEstimator {
 public:
  void reset(const EstimatorParams& params, double dt);
  // One tick of leg `leg` in mid-swing: residual [N m] = -J^T F of the
  // offset-corrected reading (what the model leaves unexplained).
  void update(int leg, const Vec3& residual);
  Vec3 bias(int leg) const { return bias_.segment<3>(3 * leg); }  // [N m]
  const Vec12& biases() const { return bias_; }                     // [N m] every joint's, leg by leg
  // [N m] per joint, 1 sigma: how far the offset may still be off. While the
  // running mean's step 1 / (k + k0) is above the window's (k <= 900 by
  // default), the estimate after k samples holds k / (k + k0) of the offset
  // (k0 the start weight), so torque_offset_sigma * k0 / (k + k0); later the
  // window learns faster and this is an upper bound. The residuals' own
  // noise is left out. With the estimate off, all of it.
  double remainingSigma(int leg) const;

 private:
  bool enabled_ = false;
  double alpha_min_ = 0.0;  // [-] dt / torque_bias_time
  double start_weight_ = 0.0;  // [samples]
  double limit_ = 0.0;      // [N m]
  double offset_sigma_ = 0.0;  // [N m] before any sample
  Vec12 bias_ = Vec12::Zero();
  int samples_[4] = {0, 0, 0, 0};
};

}  // namespace hyq
