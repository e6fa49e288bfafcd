// The ground-reaction-force estimate at the time the joint accelerations
// refer to, for the friction and normal estimates.
//
// The joint-acceleration filter's slope over N samples is the acceleration
// (N - 1) / 2 ticks ago, but this tick's torques and posture are current:
// the leg-inertia term M qdd lags the rest of f = -J^-T (tau - b qd - g - M qdd).
// In a slip's onset the foot accelerates at 5-15 m/s^2 and the force swings
// by 50-100 N in a few ms; the mixed-time estimate then lags the true force
// by 3-5 ms and reads a force inside the friction cone while the foot slides
// on it. This line keeps each tick's parts in W,
//   f = f_static + A qdd + B alpha,  f_static = -J^-T (tau - b qd - g - c),
//   A = J^-T M,  B = J^-T K,
// (c and K the links' share of the base's rotation, legBaseRotation; alpha
// the base's angular acceleration) and the slip velocity of that tick, and
// returns them D ticks later, when the joint and base accelerations centred
// on that tick are known: every term of the force and the slip velocity
// then belong to the same instant.
//
// Fixed storage; every loop bounded by kMaxGrfDelay.
#pragma once
#include "firmware/controller/model/types.hpp"

namespace hyq {

constexpr int kMaxGrfDelay = 8;  // [ticks] covers acceleration windows up to 17

class GrfDelayLine {
 public:
  // delay [ticks]: D, clamped to [0, kMaxGrfDelay]. Empties the line.
  void reset(int delay);
  int delay() const { return delay_; }

  // This tick's parts of leg `leg`'s force (W): f_static [N], A [N s^2/rad],
  // B [N s^2/rad] (it takes alpha in B).
  void pushForce(int leg, const Vec3& f_static, const Mat3& accel_map, const Mat3& alpha_map);
  // This tick's slip velocity (W) [m/s] and whether the detector had one.
  void pushSlipVelocity(int leg, const Vec3& v, bool valid);
  // Closes this tick's slot; the next push fills the next one.
  void advance();

  // True once D + 1 ticks have been pushed (and advanced) since the reset.
  bool ready() const { return count_ > delay_; }
  // The force of the tick D ticks before the last closed one, with that
  // tick's parts and the accelerations centred on it: qdd_leg [rad/s^2] of
  // the leg's joints, alpha_base [rad/s^2] of the base, in B.
  Vec3 force(int leg, const Vec3& qdd_leg, const Vec3& alpha_base) const;
  // [N] that force's error from the accelerations', each joint's and each
  // axis's sigma [rad/s^2] taken independent: |A diag(qdd_sigma)| and
  // |B diag(alpha_sigma)|, column norms summed in quadrature.
  double forceSigma(int leg, const Vec3& qdd_sigma_leg, const Vec3& alpha_sigma) const;
  // That tick's slip velocity and its validity.
  Vec3 slipVelocity(int leg) const;
  bool slipVelocityValid(int leg) const;

 private:
  struct Slot {
    Vec3 f_static[4];
    Mat3 accel_map[4];
    Mat3 alpha_map[4];
    Vec3 slip_velocity[4];
    bool slip_valid[4];
  };
  int oldest() const;  // index of the slot D ticks before the last closed one

  Slot slots_[kMaxGrfDelay + 1];
  int delay_ = 0;
  int next_ = 0;   // slot being filled
  int count_ = 0;  // closed slots since reset, saturating at kMaxGrfDelay + 1
};

}  // namespace hyq
