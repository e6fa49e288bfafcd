// The whole body's CoM relative to the controller's model, from the ground
// forces while the robot stands on three or four feet.
//
// At rest the ground forces' moment about the real CoM is zero: with the
// feet at p_i and forces f_i (W), the CoM's horizontal place is
//   c_x = (sum p_x f_z - sum (p_z - c_z) f_x) / sum f_z,   c_y alike,
// whatever the controller asks for (an attitude PD's moment about a wrong
// CoM only tilts the trunk until the forces balance about the real one).
// Its difference from the model's CoM, in B, is low-passed: first as a
// running mean of what has been seen, then exponentially over
// com_offset_time; clamped to com_offset_limit per axis. The vertical part
// is not observable this way and stays 0. A CoM that is off by centimetres
// takes that much from the crawl's stability margins and puts a moment of
// m g times it on the trunk; the controller's CoM is the model's plus this.
#pragma once

#include "firmware/controller/params.hpp"
#include "firmware/controller/model/types.hpp"

namespace hyq {

class ComOffsetEstimator {
 public:
  void reset(const EstimatorParams& params, double dt);
  // One tick: feet [m] and their estimated ground forces [N], W; `stance`
  // the feet on the ground that hold (bits); com_model [m] the model's CoM,
  // W; R_wb the trunk's orientation; weight [N] the model's m g; com_vel
  // [m/s] the CoM's velocity, W, and omega [rad/s] the trunk's angular
  // velocity. Learns only when three or more feet stand, the forces are
  // those of a body at rest (their sum within weight_tolerance of the
  // weight, vertical) and the trunk is still (kComOffsetRestSpeed,
  // kComOffsetRestRate).
  void update(const Mat3x4& feet, const Mat3x4& forces, uint32_t stance, const Vec3& com_model, const Mat3& R_wb,
              double weight, const Vec3& com_vel, const Vec3& omega);
  const Vec3& offsetBase() const { return offset_; }  // [m] B, z = 0
  bool enabled() const { return enabled_; }  // com_offset_time > 0

 private:
  bool enabled_ = false;
  double dt_ = 0.001;         // [s]
  double time_ = 0.0;         // [s] the longest time constant
  double start_time_ = 0.0;   // [s] the shortest one
  double learnt_ = 0.0;       // [s] of samples so far
  double limit_ = 0.0;        // [m]
  double tolerance_ = 0.0;    // [-]
  Vec3 offset_ = Vec3::Zero();
};

}  // namespace hyq
