// The ground-reaction-force estimate at the time the joint accelerations
// refer to, for the friction and normal estimates.
//
// The joint-acceleration filter's slope over N samples is the acceleration
// (N - 1) / 2 ticks ago, but this tick's torques and posture are current:
// the leg-inertia term M qdd lags the rest of f = -J^-T (tau - b qd - g - M qdd).
// In a slip's onset the foot accelerates at 5-15 m/s^2 and the force swings
// by 50-100 N in a few ms; the mixed-time estimate then lags the true force
// by 3-5 ms and reads a force inside the friction cone while the foot slides
// on it. This line keeps each tick's parts,
//   f = R_wb J^-T (u + M qdd + K alpha),  u = -(tau - b qd - g - c),
// (c and K the links' share of the base's rotation, legBaseRotation; alpha
// the base's angular acceleration) and the slip velocity of that tick, and
// returns them D ticks later, when the joint and base accelerations centred
// on that tick are known: every term of the force and the slip velocity
// then belong to the same instant. The parts stay in joint space, with the
// tick's attitude kept once: the legs stage forms this tick's force from
// the same parts (forceFromParts), and no 3x3 map is turned to W.
//
// Fixed storage; every loop bounded by kMaxGrfDelay.
#pragma once
#include "firmware/controller/model/types.hpp"

namespace hyq {

constexpr int kMaxGrfDelay = 8;  // [ticks] covers acceleration windows up to 17

// One leg's force parts of one tick, in joint space.
struct GrfParts {
  // M's entries from a leg's mass matrix.
  void setMass(const Mat3& m) {
    mass[0] = m(0, 0);
    mass[1] = m(1, 1);
    mass[2] = m(1, 2);
    mass[3] = m(2, 2);
  }
  // Its column c.
  Vec3 massColumn(int c) const {
    return c == 0 ? Vec3(mass[0], 0.0, 0.0) : (c == 1 ? Vec3(0.0, mass[1], mass[2]) : Vec3(0.0, mass[2], mass[3]));
  }

  Mat3 jt_inverse = Mat3::Zero();    // [1/m] J^-T (zero: a singular leg, no estimate)
  Vec3 u_static = Vec3::Zero();      // [N m] -(tau - b qd - g - c)
  // [kg m^2] M's entries (0, 0), (1, 1), (1, 2) = (2, 1) and (2, 2): its HAA
  // row and column hold only the diagonal (legInertia).
  double mass[4] = {0.0, 0.0, 0.0, 0.0};
  Mat3 alpha_torque = Mat3::Zero();  // [kg m^2] K: joint torque per base angular acceleration (B)
};

// The force [N] in W of a leg's parts with the accelerations qdd_leg
// [rad/s^2] of its joints and alpha_base [rad/s^2] of the base (B), and
// R_wb the attitude of the parts' tick.
HYQ_INLINE Vec3 forceFromParts(const Mat3& R_wb, const GrfParts& p, const Vec3& qdd_leg, const Vec3& alpha_base) {
  const double* m = p.mass;
  const Vec3 inertial(m[0] * qdd_leg[0], m[1] * qdd_leg[1] + m[2] * qdd_leg[2], m[2] * qdd_leg[1] + m[3] * qdd_leg[2]);
  const Vec3 u = p.u_static + inertial + p.alpha_torque * alpha_base;
  return R_wb * (p.jt_inverse * u);
}

class GrfDelayLine {
 public:
  // delay [ticks]: D, clamped to [0, kMaxGrfDelay]. Empties the line.
  void reset(int delay);
  int delay() const { return delay_; }

  // This tick's parts of leg `leg`, written in place by the legs stage.
  GrfParts& parts(int leg) { return slots_[next_].parts[leg]; }
  // This tick's attitude, which turns its forces to W.
  void pushAttitude(const Mat3& R_wb) { slots_[next_].R_wb = R_wb; }
  // This tick's slip velocity (W) [m/s] and whether the detector had one.
  void pushSlipVelocity(int leg, const Vec3& v, bool valid);
  // Closes this tick's slot; the next push fills the next one.
  void advance();

  // True once D + 1 ticks have been pushed (and advanced) since the reset.
  bool ready() const { return count_ > delay_; }
  // The force (W) of the tick D ticks before the last closed one, with that
  // tick's parts and the accelerations centred on it: qdd_leg [rad/s^2] of
  // the leg's joints, alpha_base [rad/s^2] of the base, in B.
  Vec3 force(int leg, const Vec3& qdd_leg, const Vec3& alpha_base) const;
  // [N] that force's error from the accelerations', each joint's and each
  // axis's sigma [rad/s^2] taken independent: the columns of J^-T M and of
  // J^-T K (their lengths, which R_wb keeps) times the sigmas, summed in
  // quadrature.
  double forceSigma(int leg, const Vec3& qdd_sigma_leg, const Vec3& alpha_sigma) const;
  // That tick's slip velocity and its validity.
  Vec3 slipVelocity(int leg) const;
  bool slipVelocityValid(int leg) const;

 private:
  struct Slot {
    Mat3 R_wb = Mat3::Identity();
    GrfParts parts[4];
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
