// HyQ's physical numbers, from the HyQ description (URDF) published by IIT's
// Dynamic Legged Systems lab: the one place for them.
// Used by the controller's model and by the simulator's ground truth, so the
// two agree on geometry; what the controller does not know (a payload, the
// terrain) lives only in the simulator.
//
// Kinematic convention (both the simulator and the controller follow it):
//   HAA joint of leg i at kHaaPos[i] in B; its axis is kHaaAxisSign[i] * x_B,
//   so that a negative HAA angle swings every foot outward.
//   At q = 0 the leg hangs straight down. From HAA, the hip link reaches the
//   HFE joint kHipLength below (in the HAA-rotated frame). HFE and KFE axes
//   are the HAA-rotated y_B. A positive HFE rotates the thigh's far end
//   backwards (-x); the lower-leg direction is set by HFE + KFE.
//   Front knees bend backwards (KFE < 0), hind knees forwards (KFE > 0).
#pragma once
#include "hal/frames.hpp"

namespace hyq::robot {

using hal::kNumLegs;
enum Leg : int { LF = 0, RF = 1, LH = 2, RH = 3 };
constexpr const char* kLegNames[kNumLegs] = {"LF", "RF", "LH", "RH"};
constexpr bool isFront(int leg) { return leg == LF || leg == RF; }
constexpr bool isLeft(int leg) { return leg == LF || leg == LH; }

constexpr double kGravity = 9.81;  // [m/s^2]

// Trunk
constexpr double kTrunkMass = 58.96;                       // [kg]
constexpr double kTrunkCom[3] = {0.01, 0.0, 0.00358};      // [m] in B
// [kg m^2] about the trunk CoM, in B: xx, yy, zz, xy, xz, yz
constexpr double kTrunkInertia[6] = {1.5725937, 8.5015928, 9.1954911,
                                     0.028375, -0.203139, -0.004462};
// Trunk collision/visual box (for the simulator only) [m]
constexpr double kTrunkSize[3] = {0.93, 0.40, 0.14};

// Legs
constexpr double kHaaPos[kNumLegs][3] = {{0.3735, 0.207, 0.0},
                                         {0.3735, -0.207, 0.0},
                                         {-0.3735, 0.207, 0.0},
                                         {-0.3735, -0.207, 0.0}};  // [m] in B
constexpr double kHaaAxisSign[kNumLegs] = {-1.0, 1.0, -1.0, 1.0};  // [-]
constexpr double kHipLength = 0.08;     // [m] HAA -> HFE
constexpr double kUpperLength = 0.35;   // [m] HFE -> KFE
constexpr double kLowerLength = 0.341;  // [m] KFE -> foot centre
constexpr double kFootRadius = 0.02175; // [m]

// Link masses [kg]; centres of mass assumed at each link's midpoint along
// the link (not in the published description: a modelling choice).
constexpr double kHipMass = 2.93;
constexpr double kUpperMass = 2.638;
constexpr double kLowerMass = 0.881;
constexpr double kLegMass = kHipMass + kUpperMass + kLowerMass;
constexpr double kTotalMass = kTrunkMass + kNumLegs * kLegMass;  // 84.748 kg

// Joints: limits [rad], effort [N m], velocity [rad/s], damping [N m s/rad]
constexpr double kHaaMin = -1.2217, kHaaMax = 0.4363;
constexpr double kHfeFrontMin = -0.8727, kHfeFrontMax = 1.2217;
constexpr double kHfeHindMin = -1.2217, kHfeHindMax = 0.8727;
constexpr double kKfeFrontMin = -2.4435, kKfeFrontMax = -0.3491;
constexpr double kKfeHindMin = 0.3491, kKfeHindMax = 2.4435;
constexpr double kEffortLimit = 150.0;
constexpr double kVelocityLimit = 12.0;
constexpr double kJointDamping = 0.1;

inline void jointLimits(int leg, int joint, double& lo, double& hi) {
  if (joint == 0) { lo = kHaaMin; hi = kHaaMax; return; }
  const bool front = isFront(leg);
  if (joint == 1) {
    lo = front ? kHfeFrontMin : kHfeHindMin;
    hi = front ? kHfeFrontMax : kHfeHindMax;
  } else {
    lo = front ? kKfeFrontMin : kKfeHindMin;
    hi = front ? kKfeFrontMax : kKfeHindMax;
  }
}

// Nominal standing posture per leg (HAA, HFE, KFE) [rad]
constexpr double kStandFront[3] = {-0.2, 0.7, -1.4};
constexpr double kStandHind[3] = {-0.2, -0.7, 1.4};
inline double standAngle(int leg, int joint) {
  return isFront(leg) ? kStandFront[joint] : kStandHind[joint];
}

// --- Simulator-only modelling choices (not in the published description; the
// controller does not use them). Each leg link is a solid cylinder of this
// radius along the link, its mass at the midpoint; the trunk's collision
// points sit at the corners of kTrunkSize.
constexpr double kLinkInertiaRadius = 0.03;  // [m]

}  // namespace hyq::robot
