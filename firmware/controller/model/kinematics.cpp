#include "firmware/controller/model/kinematics.hpp"

#include "firmware/controller/model/sincos.hpp"

#include <cmath>

#include "firmware/controller/model/robot_params.hpp"

namespace hyq {
namespace {

using namespace robot;

// A point on the leg is described by how far along each link it lies
// (0 = link start, 1 = link end). The foot is (1, 1, 1); a link's midpoint
// CoM is 0.5 on that link, 1 on the links before it and 0 after it. One
// routine then gives the positions and Jacobians of feet and CoMs alike.
struct LegPoint {
  double hip, upper, lower;  // [-] fractions of kHipLength, kUpperLength, kLowerLength
};

constexpr LegPoint kFootPoint{1.0, 1.0, 1.0};

constexpr LegPoint linkMidpoint(int link) {
  switch (link) {
    case kHipLink: return {0.5, 0.0, 0.0};
    case kUpperLink: return {1.0, 0.5, 0.0};
    default: return {1.0, 1.0, 0.5};
  }
}

constexpr double linkMass(int link) {
  switch (link) {
    case kHipLink: return kHipMass;
    case kUpperLink: return kUpperMass;
    default: return kLowerMass;
  }
}

// The links' midpoints weighted by their masses, as one point [kg]: a point's
// Jacobian is linear in its fractions, so this point's is sum m Jc over the
// links (the holding torques' -(sum m Jc)' g) from one evaluation.
constexpr LegPoint kMassWeightedMidpoints{0.5 * kHipMass + kUpperMass + kLowerMass,
                                          0.5 * kUpperMass + kLowerMass, 0.5 * kLowerMass};

// Rotation of the leg plane about x_B: the HAA axis is sign * x_B, so a joint
// angle q turns the plane by sign * q about +x_B.
double haaPlaneAngle(int leg, double q_haa) { return kHaaAxisSign[leg] * q_haa; }

// Point in the HAA-rotated frame, x forward and z along the hanging leg.
// HFE and KFE rotate about +y of that frame, so a positive angle moves the
// far end backwards: a link of length L at sagittal angle a ends at
// (-L sin a, 0, -L cos a).
HYQ_INLINE Vec3 sagittalPoint(const LegTrig& t, const LegPoint& p) {
  const double l1 = p.upper * kUpperLength, l2 = p.lower * kLowerLength;
  return Vec3(-l1 * t.s1 - l2 * t.s12, 0.0, -p.hip * kHipLength - l1 * t.c1 - l2 * t.c12);
}

// v turned by the HAA plane angle about +x_B.
HYQ_INLINE Vec3 rotateAboutX(const LegTrig& t, const Vec3& v) {
  return Vec3(v.x(), t.c0 * v.y() - t.s0 * v.z(), t.s0 * v.y() + t.c0 * v.z());
}

HYQ_INLINE Vec3 haaPosition(int leg) { return Vec3(kHaaPos[leg][0], kHaaPos[leg][1], kHaaPos[leg][2]); }

// A point of the leg from the HAA joint, in B.
HYQ_INLINE Vec3 pointFromHaa(const LegTrig& t, const LegPoint& p) { return rotateAboutX(t, sagittalPoint(t, p)); }

// Forced inline, as the helpers above, in every caller: the point's
// fractions are then constants, and a caller that takes a point's position
// and Jacobian computes what they share once.
HYQ_INLINE Vec3 pointPosition(int leg, const LegTrig& t, const LegPoint& p) {
  return haaPosition(leg) + pointFromHaa(t, p);
}

HYQ_INLINE Mat3 pointJacobian(int leg, const LegTrig& t, const LegPoint& p) {
  const Vec3 r = pointFromHaa(t, p);
  const double l1 = p.upper * kUpperLength, l2 = p.lower * kLowerLength;
  // Sagittal derivatives w.r.t. HFE and KFE, then turned by the HAA rotation.
  const Vec3 d_hfe(-l1 * t.c1 - l2 * t.c12, 0.0, l1 * t.s1 + l2 * t.s12);
  const Vec3 d_kfe(-l2 * t.c12, 0.0, l2 * t.s12);
  Mat3 jac;
  jac.col(0) = kHaaAxisSign[leg] * Vec3::UnitX().cross(r);
  jac.col(1) = rotateAboutX(t, d_hfe);
  jac.col(2) = rotateAboutX(t, d_kfe);
  return jac;
}

double clampTo(double v, double lo, double hi, bool& clamped) {
  const double c = v < lo ? lo : (v > hi ? hi : v);
  if (c != v) clamped = true;
  return c;
}

}  // namespace

LegTrig legTrig(int leg, const Vec3& q_leg) {
  const double angle = haaPlaneAngle(leg, q_leg[0]);
  const double a1 = q_leg[1], a12 = q_leg[1] + q_leg[2];
  const SinCos t0 = sinCos(angle), t1 = sinCos(a1), t12 = sinCos(a12);
  return {t0.c, t0.s, t1.c, t1.s, t12.c, t12.s};
}

Vec3 footPositionBase(int leg, const LegTrig& t) { return pointPosition(leg, t, kFootPoint); }

Mat3 footJacobianBase(int leg, const LegTrig& t) { return pointJacobian(leg, t, kFootPoint); }

Vec3 footPositionBase(int leg, const Vec3& q_leg) {
  return pointPosition(leg, legTrig(leg, q_leg), kFootPoint);
}

Mat3 footJacobianBase(int leg, const Vec3& q_leg) {
  return pointJacobian(leg, legTrig(leg, q_leg), kFootPoint);
}

namespace {

HYQ_INLINE Mat3 contactJacobian(int leg, const LegTrig& t, const Mat3& centre_jacobian, const Vec3& normal_base) {
  // A point d from the centre, fixed on the lower link, moves with
  // J_centre qd + w x d, w = Jw qd the lower link's angular velocity: the HAA
  // axis, then HFE and KFE both about the leg plane's y.
  const Vec3 d = -kFootRadius * normal_base;
  const Vec3 w_haa = kHaaAxisSign[leg] * Vec3::UnitX();
  const Vec3 w_sagittal = rotateAboutX(t, Vec3::UnitY());
  Mat3 jac = centre_jacobian;
  jac.col(0) += w_haa.cross(d);
  jac.col(1) += w_sagittal.cross(d);
  jac.col(2) += w_sagittal.cross(d);
  return jac;
}

}  // namespace

Mat3 contactJacobianFromCentre(int leg, const LegTrig& t, const Mat3& centre_jacobian,
                               const Vec3& normal_base) {
  return contactJacobian(leg, t, centre_jacobian, normal_base);
}

HYQ_FLATTEN FootKinematics footKinematics(int leg, const LegTrig& t, bool at_contact, const Vec3& normal_base) {
  FootKinematics out;
  out.position = pointPosition(leg, t, kFootPoint);
  out.centre_jacobian = pointJacobian(leg, t, kFootPoint);
  out.jacobian = at_contact ? contactJacobian(leg, t, out.centre_jacobian, normal_base) : out.centre_jacobian;
  return out;
}

Mat3 footContactJacobianBase(int leg, const Vec3& q_leg, const Vec3& normal_base) {
  const LegTrig t = legTrig(leg, q_leg);
  return contactJacobianFromCentre(leg, t, footJacobianBase(leg, t), normal_base);
}

Vec3 hfePositionBase(int leg, const Vec3& q_leg) {
  return pointPosition(leg, legTrig(leg, q_leg), LegPoint{1.0, 0.0, 0.0});
}

Vec3 kfePositionBase(int leg, const Vec3& q_leg) {
  return pointPosition(leg, legTrig(leg, q_leg), LegPoint{1.0, 1.0, 0.0});
}

Vec3 linkComPositionBase(int leg, int link, const Vec3& q_leg) {
  return pointPosition(leg, legTrig(leg, q_leg), linkMidpoint(link));
}

Vec3 legMassMoment(int leg, const LegTrig& t) {
  // Positions are linear in a point's fractions: the mass-weighted sum of
  // the midpoints is one point.
  return kLegMass * haaPosition(leg) + pointFromHaa(t, kMassWeightedMidpoints);
}

Mat3 linkComJacobianBase(int leg, int link, const Vec3& q_leg) {
  return pointJacobian(leg, legTrig(leg, q_leg), linkMidpoint(link));
}

Vec3 legGravityTorque(int leg, const Vec3& q_leg, const Vec3& gravity_base) {
  return legGravityTorque(leg, legTrig(leg, q_leg), gravity_base);
}

HYQ_FLATTEN Vec3 legGravityTorque(int leg, const LegTrig& t, const Vec3& gravity_base) {
  // Holding torque = gradient of the links' potential energy -sum m g.p_com:
  // -(sum m Jc)' g, from the mass-weighted midpoints as legInertia takes it
  // (the same bits).
  const Mat3 weighted_jacobian = pointJacobian(leg, t, kMassWeightedMidpoints);
  return -(weighted_jacobian.transpose() * gravity_base);
}

LegInertia legInertia(int leg, const Vec3& q_leg, const Vec3& gravity_a, const Vec3& gravity_b) {
  return legInertia(leg, legTrig(leg, q_leg), gravity_a, gravity_b);
}

HYQ_FLATTEN LegInertia legInertia(int leg, const LegTrig& t, const Vec3& gravity_a, const Vec3& gravity_b) {
  // Each link's direction along x_B (the leg plane holds every link; the
  // hip link hangs across x_B, the upper and lower links at a1 and a12).
  const double direction_x[kLinksPerLeg] = {0.0, -t.s1, -t.s12};
  const double lengths[kLinksPerLeg] = {kHipLength, kUpperLength, kLowerLength};
  // Translation, sum m Jc' Jc: Jc's HAA column is +/- x_B x r (r from the HAA
  // joint to the CoM), its HFE and KFE columns the CoM's derivatives in the
  // leg plane, (dx, 0, dz), turned about x_B like r. The turn keeps lengths
  // and angles, and x_B x r is normal to the leg plane: the HAA column is
  // orthogonal to the other two, |x_B x r|^2 = p_z^2 (p the CoM in the leg
  // plane, p_y = 0), and the rest are 2-D dot products.
  double m00 = 0.0, m11 = 0.0, m12 = 0.0, m22 = 0.0;  // [kg m^2]
#pragma GCC unroll 3
  for (int link = 0; link < kLinksPerLeg; ++link) {
    const double m = linkMass(link);
    const LegPoint p = linkMidpoint(link);
    const double l1 = p.upper * kUpperLength, l2 = p.lower * kLowerLength;
    const double p_z = -p.hip * kHipLength - l1 * t.c1 - l2 * t.c12;
    const double hfe_x = -l1 * t.c1 - l2 * t.c12, hfe_z = l1 * t.s1 + l2 * t.s12;
    const double kfe_x = -l2 * t.c12, kfe_z = l2 * t.s12;
    // Rotation: Jw' I Jw with I = k (Id - d d') the rod's inertia about its
    // CoM and Jw's columns the link's joint axes: HAA (x_B) turns every
    // link, HFE the upper and lower links, KFE the lower one, both about the
    // leg plane's normal. The plane holds d, so the pitch axis is normal to
    // d and to x_B: entry (0, 0) is k (1 - d_x^2), an entry between two
    // pitch columns k, and the rest 0.
    const double k = m * lengths[link] * lengths[link] / 12.0;
    const double k_hfe = link >= kUpperLink ? k : 0.0, k_kfe = link >= kLowerLink ? k : 0.0;
    m00 += m * (p_z * p_z) + k * (1.0 - direction_x[link] * direction_x[link]);
    m11 += m * (hfe_x * hfe_x + hfe_z * hfe_z) + k_hfe;
    m12 += m * (hfe_x * kfe_x + hfe_z * kfe_z) + k_kfe;
    m22 += m * (kfe_x * kfe_x + kfe_z * kfe_z) + k_kfe;
  }
  LegInertia out;
  out.mass << m00, 0.0, 0.0, 0.0, m11, m12, 0.0, m12, m22;
  // Holding torques, the gradient of -sum m g.p_com: -(sum m Jc)' g.
  const Mat3 weighted_jacobian = pointJacobian(leg, t, kMassWeightedMidpoints);
  out.holding_a = -(weighted_jacobian.transpose() * gravity_a);
  out.holding_b = -(weighted_jacobian.transpose() * gravity_b);
  return out;
}

namespace {

// legBaseRotation's body; kRate false leaves the rate terms out (their
// inputs unused) and gives the same alpha_map, bit for bit.
template <bool kRate>
inline LegBaseRotation baseRotation(int leg, const LegTrig& t, const Vec3& qd_leg, const Vec3& omega_base,
                                    bool leg_motion) {
  // In the leg's frame (B turned by the HAA plane angle about x_B) every
  // CoM and every HFE or KFE Jacobian column lies in the x-z plane and the
  // HAA column along y: the products below are 2-D. Dot products are the
  // same in either frame; the torque per angular acceleration is turned
  // back to B at the end.
  const double sign = kHaaAxisSign[leg];
  const Vec3 haa_b = haaPosition(leg);
  const double haa_y = t.c0 * haa_b.y() + t.s0 * haa_b.z();  // the HAA joint's y in the leg frame
  const double haa_z = -t.s0 * haa_b.y() + t.c0 * haa_b.z();
  const Vec3 w(omega_base.x(), t.c0 * omega_base.y() + t.s0 * omega_base.z(),
               -t.s0 * omega_base.y() + t.c0 * omega_base.z());  // omega in the leg frame
  const double omega_sq = omega_base.squaredNorm();
  const double qd0 = qd_leg[0], qd1 = qd_leg[1], qd2 = qd_leg[2];
  const double w_haa = sign * qd0;  // the plane's rate about x_B
  const double rate1_sq = qd1 * qd1, rate12 = qd1 + qd2, rate12_sq = rate12 * rate12;
  Vec3 rows[3] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};  // alpha_map's rows, leg frame
  Vec3 rate = Vec3::Zero();
#pragma GCC unroll 3
  for (int link = 0; link < kLinksPerLeg; ++link) {
    const double m = linkMass(link);
    const LegPoint p = linkMidpoint(link);
    const double l1 = p.upper * kUpperLength, l2 = p.lower * kLowerLength;
    // The CoM from the HAA joint (x, 0, z), and the HFE and KFE columns
    // (derivatives of it), in the plane; the HAA column is (0, -sign z, 0).
    const double x = -l1 * t.s1 - l2 * t.s12, z = -p.hip * kHipLength - l1 * t.c1 - l2 * t.c12;
    const double hfe_x = -l1 * t.c1 - l2 * t.c12, hfe_z = l1 * t.s1 + l2 * t.s12;
    const double kfe_x = -l2 * t.c12, kfe_z = l2 * t.s12;
    const double haa_col = -sign * z;
    // r from B's origin: (haa.x + x, haa_y, haa_z + z).
    const double rx = haa_b.x() + x, ry = haa_y, rz = haa_z + z;
    // Rows of m Jc^T [alpha x r] per alpha: Jc_j . (e_c x r) = e_c . (r x Jc_j).
    rows[0] += m * Vec3(-rz * haa_col, 0.0, rx * haa_col);
    if (link >= kUpperLink) rows[1] += m * Vec3(ry * hfe_z, rz * hfe_x - rx * hfe_z, -ry * hfe_x);
    if (link >= kLowerLink) rows[2] += m * Vec3(ry * kfe_z, rz * kfe_x - rx * kfe_z, -ry * kfe_x);
    if constexpr (!kRate) continue;
    // Jc qd, in the leg frame.
    const double vx = hfe_x * qd1 + kfe_x * qd2, vy = haa_col * qd0, vz = hfe_z * qd1 + kfe_z * qd2;
    // omega x (omega x r) + 2 omega x (Jc qd).
    const double w_dot_r = w.x() * rx + w.y() * ry + w.z() * rz;
    double ax = w.x() * w_dot_r - omega_sq * rx + 2.0 * (w.y() * vz - w.z() * vy);
    double ay = w.y() * w_dot_r - omega_sq * ry + 2.0 * (w.z() * vx - w.x() * vz);
    double az = w.z() * w_dot_r - omega_sq * rz + 2.0 * (w.x() * vy - w.y() * vx);
    if (leg_motion) {
      // The leg's own motion: HAA turns the plane at w_haa about x_B,
      // w x (w x u) + 2 w x v_s = (0, -2 w_haa v_z, -w_haa^2 z) with v_s the
      // in-plane velocity; HFE and KFE swing the two segments round (the
      // centripetal part of the sagittal chain).
      ax += rate1_sq * l1 * t.s1 + rate12_sq * l2 * t.s12;
      ay += -2.0 * w_haa * vz;
      az += rate1_sq * l1 * t.c1 + rate12_sq * l2 * t.c12 - w_haa * w_haa * z;
    }
    rate[0] += m * haa_col * ay;
    if (link >= kUpperLink) rate[1] += m * (hfe_x * ax + hfe_z * az);
    if (link >= kLowerLink) rate[2] += m * (kfe_x * ax + kfe_z * az);
  }
  LegBaseRotation out;
  for (int j = 0; j < 3; ++j) out.alpha_map.row(j) = rotateAboutX(t, rows[j]).transpose();
  out.rate_torque = rate;
  return out;
}

}  // namespace

HYQ_FLATTEN LegBaseRotation legBaseRotation(int leg, const LegTrig& t, const Vec3& qd_leg, const Vec3& omega_base,
                                            bool leg_motion) {
  return baseRotation<true>(leg, t, qd_leg, omega_base, leg_motion);
}

HYQ_FLATTEN Mat3 legBaseAlphaMap(int leg, const LegTrig& t) {
  return baseRotation<false>(leg, t, Vec3::Zero(), Vec3::Zero(), false).alpha_map;
}

Mat3 legMassMatrix(int leg, const Vec3& q_leg) {
  return legInertia(leg, q_leg, Vec3::Zero(), Vec3::Zero()).mass;
}

bool legInverseKinematics(int leg, const Vec3& foot_base, Vec3& q_leg) {
  if (!foot_base.allFinite()) {
    for (int j = 0; j < 3; ++j) q_leg[j] = standAngle(leg, j);
    return false;
  }
  const Vec3 d = foot_base - haaPosition(leg);
  bool clamped = false;
  double lo, hi;

  // HAA: the leg plane contains x_B and the foot. Normally the foot hangs
  // below the HAA axis (plane angle measured from -z_B towards +y_B); with a
  // knee folded far up it can sit above it, the other branch. Take the one
  // whose HAA angle is inside the limits (the hanging one if both or neither).
  jointLimits(leg, 0, lo, hi);
  const double radius = std::sqrt(d.y() * d.y() + d.z() * d.z());
  const double haa_down = kHaaAxisSign[leg] * std::atan2(d.y(), -d.z());
  const double haa_up = kHaaAxisSign[leg] * std::atan2(-d.y(), d.z());
  const bool up_branch = (haa_down < lo || haa_down > hi) && haa_up >= lo && haa_up <= hi;
  q_leg[0] = clampTo(up_branch ? haa_up : haa_down, lo, hi, clamped);

  // Sagittal problem in the HAA-rotated frame, from the HFE joint:
  // reach = (L1 sin a1 + L2 sin a12, L1 cos a1 + L2 cos a12).
  const double z_plane = up_branch ? radius : -radius;
  const double reach_x = -d.x();
  const double reach_z = -(z_plane + kHipLength);
  const double dist_sq = reach_x * reach_x + reach_z * reach_z;
  double cos_knee = (dist_sq - kUpperLength * kUpperLength - kLowerLength * kLowerLength) /
                    (2.0 * kUpperLength * kLowerLength);
  cos_knee = clampTo(cos_knee, -1.0, 1.0, clamped);
  const double knee_sign = isFront(leg) ? -1.0 : 1.0;
  jointLimits(leg, 2, lo, hi);
  q_leg[2] = clampTo(knee_sign * std::acos(cos_knee), lo, hi, clamped);

  // With the knee fixed, HFE points the leg at the target (closest answer
  // when the knee had to be clamped).
  const double knee_offset = std::atan2(kLowerLength * std::sin(q_leg[2]),
                                        kUpperLength + kLowerLength * std::cos(q_leg[2]));
  jointLimits(leg, 1, lo, hi);
  q_leg[1] = clampTo(std::atan2(reach_x, reach_z) - knee_offset, lo, hi, clamped);
  return !clamped;
}

}  // namespace hyq
