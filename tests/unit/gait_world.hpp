// What the gait tests start from: HyQ standing in its stand posture on flat
// ground at z = 0, base above the origin.
#pragma once

#include "firmware/controller/gait/gait.hpp"
#include "firmware/controller/model/kinematics.hpp"
#include "firmware/controller/model/robot_params.hpp"

namespace hyq::test {

// nominal: the stand posture's feet in B; in: the feet on the ground below
// them, base and CoM at body_height [m] above the origin.
inline void standingStart(double body_height, Mat3x4& nominal, GaitInput& in) {
  for (int leg = 0; leg < 4; ++leg) {
    const Vec3 q(robot::standAngle(leg, 0), robot::standAngle(leg, 1), robot::standAngle(leg, 2));
    nominal.col(leg) = footPositionBase(leg, q);
    in.feet_world.col(leg) = Vec3(0.0, 0.0, body_height) + nominal.col(leg);
    in.feet_world(2, leg) = 0.0;
  }
  in.base_world = Vec3(0.0, 0.0, body_height);
  in.foothold_origin = in.base_world;
  in.com_world = in.base_world;
}

}  // namespace hyq::test
