// HyQ as ODE rigid bodies: trunk + 4 x (hip, upper, lower link), 12 hinges
// with limits, geometry and masses from robot_params.hpp, following its
// kinematic convention (so the controller's model matches what is built).
#pragma once
#include <ode/ode.h>

#include <array>

#include "firmware/controller/model/types.hpp"
#include "hal/frames.hpp"

namespace hyq::sim {

class HyqRobot {
 public:
  // payload_kg: extra trunk mass spread over the trunk box.
  HyqRobot(dWorldID world, double payload_kg, double stop_erp, double stop_cfm);
  ~HyqRobot();
  HyqRobot(const HyqRobot&) = delete;
  HyqRobot& operator=(const HyqRobot&) = delete;

  // Puts every body where base pose + joint angles say, at rest.
  void place(const Vec3& base_pos, const Mat3& base_rot, const std::array<double, 12>& q);

  double jointAngle(int j) const;    // [rad]
  double jointRate(int j) const;     // [rad/s]
  void addJointTorque(int j, double tau);  // [N m] child link about the joint axis

  Vec3 basePosition() const;         // [m] base frame origin, W
  Mat3 baseRotation() const;         // B in W
  Quat baseQuaternion() const;
  Vec3 baseVelocity() const;         // [m/s] base origin, W
  Vec3 baseOmega() const;            // [rad/s] W

  dBodyID trunk() const { return trunk_; }
  dBodyID lowerLeg(int leg) const { return links_[leg][2]; }
  // Foot sphere centre in the lower-leg body frame (the body origin is the link's CoM).
  static Vec3 footOffset();
  double totalMass() const;          // [kg] including the payload

 private:
  dBodyID trunk_ = nullptr;
  std::array<std::array<dBodyID, 3>, 4> links_{};
  std::array<dJointID, 12> joints_{};
};

// Foot centre of `leg` in B, from the same frame chain the bodies are built
// with (independent of the controller's kinematics, to cross-check it).
Vec3 simFootPositionBase(int leg, const Vec3& q_leg);

}  // namespace hyq::sim
