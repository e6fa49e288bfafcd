// HyQ leg model for the controller: forward kinematics, analytic foot
// Jacobians, leg gravity torques and analytic inverse kinematics, all in the
// base frame B, following the convention documented in robot_params.hpp.
// Stateless free functions; every input in, every output out. Joint angles
// are taken as given (no NaN check here: the controller rejects bad frames
// before any model call); only the IK guards its input.
#pragma once
#include "firmware/controller/model/types.hpp"

namespace hyq {

// Rigid links of one leg, in order from the trunk outwards.
enum LegLink : int { kHipLink = 0, kUpperLink = 1, kLowerLink = 2 };
constexpr int kLinksPerLeg = 3;

// The sines and cosines of one leg's joint angles that every function below
// needs. The functions come in two forms: from q_leg, and from a LegTrig
// computed once for several calls (the same numbers, bit for bit; on the
// board the trigonometric functions are most of the model's cost).
struct LegTrig {
  double c0, s0;    // [-] HAA plane angle (kHaaAxisSign * q_haa)
  double c1, s1;    // [-] HFE angle a1
  double c12, s12;  // [-] a12 = HFE + KFE
};
LegTrig legTrig(int leg, const Vec3& q_leg);

// Foot centre in B [m] (point-foot model: the sphere's centre).
Vec3 footPositionBase(int leg, const Vec3& q_leg);
Vec3 footPositionBase(int leg, const LegTrig& t);

// d(foot position in B)/d(q_leg) [m/rad], analytic.
Mat3 footJacobianBase(int leg, const Vec3& q_leg);
Mat3 footJacobianBase(int leg, const LegTrig& t);

// d(contact point in B)/d(q_leg) [m/rad]: the point of the foot sphere that
// touches ground of normal normal_base (unit, in B), the centre minus
// kFootRadius * normal_base, taken as a point of the lower link. A ground
// force acts there, not at the centre: with J of the centre its tangential
// part's moment r x F_t (0.6-1 N m on ice) is read as a force of 1-2 N.
Mat3 footContactJacobianBase(int leg, const Vec3& q_leg, const Vec3& normal_base);
// The same from the centre's Jacobian already at hand (footJacobianBase
// of the same angles).
Mat3 contactJacobianFromCentre(int leg, const LegTrig& t, const Mat3& centre_jacobian,
                               const Vec3& normal_base);

// The foot as the GRF estimate needs it: footPositionBase, footJacobianBase
// and the Jacobian forces go through (contactJacobianFromCentre with
// normal_base when at_contact, else the centre's), from one LegTrig, each
// bit for bit as the separate calls give it.
struct FootKinematics {
  Vec3 position;         // [m] foot centre in B
  Mat3 centre_jacobian;  // [m/rad] the centre's
  Mat3 jacobian;         // [m/rad] the contact point's (at_contact) or the centre's
};
FootKinematics footKinematics(int leg, const LegTrig& t, bool at_contact, const Vec3& normal_base);

// HFE joint centre in B [m] (the hip link's far end).
Vec3 hfePositionBase(int leg, const Vec3& q_leg);

// KFE joint centre in B [m] (the upper link's far end).
Vec3 kfePositionBase(int leg, const Vec3& q_leg);

// Centre of mass of one link in B [m]: the link's midpoint (robot_params.hpp).
Vec3 linkComPositionBase(int leg, int link, const Vec3& q_leg);

// The leg's mass moment, sum of link mass times link CoM, in B [kg m].
Vec3 legMassMoment(int leg, const LegTrig& t);

// d(link CoM in B)/d(q_leg) [m/rad], analytic.
Mat3 linkComJacobianBase(int leg, int link, const Vec3& q_leg);

// Joint torques [N m] that hold the leg's own link weights still.
// gravity_base: gravitational acceleration expressed in B [m/s^2], e.g.
// R_wb^T * (0, 0, -9.81). With f the ground reaction force on the foot (in B),
// the stance torque is tau = legGravityTorque(...) - J^T f.
Vec3 legGravityTorque(int leg, const Vec3& q_leg, const Vec3& gravity_base);
Vec3 legGravityTorque(int leg, const LegTrig& t, const Vec3& gravity_base);

// Joint-space inertia of one leg on a fixed base [kg m^2]: each link a thin
// rod of its mass along the link (the CoM model above), so
// M = sum_k m_k Jc_k^T Jc_k + Jw_k^T (m_k L_k^2 / 12)(I - d_k d_k^T) Jw_k,
// with Jw_k the link's angular-velocity Jacobian and d_k its direction.
// Symmetric positive definite for any q.
Mat3 legMassMatrix(int leg, const Vec3& q_leg);

// legMassMatrix and, from one Jacobian (that of the links' mass-weighted
// midpoints, sum_k m_k Jc_k), legGravityTorque for two gravity vectors: what
// the GRF estimate needs each tick (true gravity for the stance torques,
// gravity minus the base's acceleration for the estimate). Equal to the
// separate calls.
struct LegInertia {
  Mat3 mass;       // [kg m^2] legMassMatrix
  Vec3 holding_a;  // [N m] legGravityTorque(leg, q_leg, gravity_a)
  Vec3 holding_b;  // [N m] legGravityTorque(leg, q_leg, gravity_b)
};
LegInertia legInertia(int leg, const Vec3& q_leg, const Vec3& gravity_a, const Vec3& gravity_b);
LegInertia legInertia(int leg, const LegTrig& t, const Vec3& gravity_a, const Vec3& gravity_b);

// The joint torques [N m] that make the leg's links turn with the base, on
// top of the fixed-base dynamics (legInertia): a link's CoM at r (from B's
// origin, in B) moving at Jc qd relative to B accelerates with the base's
// rotation by alpha x r + omega x (omega x r) + 2 omega x (Jc qd), and the
// joints supply sum_k m_k Jc_k^T of that, so
//   tau = alpha_map alpha + rate_torque,
//   alpha_map = -sum_k m_k Jc_k^T [r_k]x,
//   rate_torque = sum_k m_k Jc_k^T (omega x (omega x r_k) + 2 omega x (Jc_k qd)).
// omega_base [rad/s] and alpha [rad/s^2] in B. The links' own rotational
// inertia about their CoM is left out: as thin rods it adds under 0.05 kg m^2
// times alpha, about 1 N at the foot at 20 rad/s^2.
//
// With leg_motion, rate_torque also holds the velocity terms of the leg's
// own joint motion on a still base, C(q, qd) qd of the fixed-base dynamics:
// each CoM's acceleration at qdd = 0, sum_ij d2r/dq_i dq_j qd_i qd_j, is
//   w x (w x u) + 2 w x v_s + R_x s''
// with u the CoM from the HAA joint, w = qd_HAA about the HAA axis, v_s the
// velocity HFE and KFE give it, and s'' = -qd_HFE^2 a_1 - (qd_HFE + qd_KFE)^2 a_2
// the centripetal part of the sagittal chain (a_1, a_2 its upper and lower
// segments). The thin rods' rotational part is left out here too: the
// HAA rate times itself and the other two, times about 0.02 kg m^2, under
// 0.03 N m in a trot's stance.
struct LegBaseRotation {
  Mat3 alpha_map;    // [kg m^2] torque per base angular acceleration
  Vec3 rate_torque;  // [N m] centrifugal and Coriolis torques of the base's rotation (and, with leg_motion, of the leg's own)
};
LegBaseRotation legBaseRotation(int leg, const LegTrig& t, const Vec3& qd_leg, const Vec3& omega_base,
                                bool leg_motion);
// legBaseRotation's alpha_map alone (the same, bit for bit), without the
// rate terms' work: the crawl's fast-turn term.
Mat3 legBaseAlphaMap(int leg, const LegTrig& t);

// Analytic inverse kinematics on the robot's knee branch (front KFE < 0,
// hind KFE > 0). q_leg always receives angles within the joint limits.
// Returns false when the target is not finite or not reachable within the
// limits; q_leg then holds the clamped closest answer the branch gives
// (the stand posture for a non-finite target).
bool legInverseKinematics(int leg, const Vec3& foot_base, Vec3& q_leg);

}  // namespace hyq
