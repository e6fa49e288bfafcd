// HyQ as ODE rigid bodies: trunk + 4 x (hip, upper, lower link), 12 hinges
// with limits, joint frames from robot_params.hpp, following its kinematic
// convention (so the controller's model matches what is built), and the
// masses, centres of mass and inertias of one body description
// (body_model.hpp: the controller's nominal model or the published one).
#pragma once
#include <ode/ode.h>

#include <array>

#include "firmware/controller/model/types.hpp"
#include "hal/frames.hpp"
#include "sim_host/physics/body_model.hpp"

namespace hyq::sim {

class HyqRobot {
 public:
  // payload_kg: extra trunk mass spread over the trunk box.
  HyqRobot(dWorldID world, double payload_kg, double stop_erp, double stop_cfm,
           const RobotBody& body = nominalBody());
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
  dJointID joint(int j) const { return joints_[j]; }
  // Foot sphere centre in the lower-leg body frame (the body origin is the
  // link's CoM): of the nominal body, and of `leg` of this robot's body.
  static Vec3 footOffset();
  Vec3 footOffset(int leg) const;
  // The trunk's centre of mass in B [m] (the trunk body's origin).
  const Vec3& trunkCom() const { return body_.trunk_com; }
  double totalMass() const;          // [kg] including the payload

 private:
  const RobotBody body_;  // a copy: plantBody() returns a temporary
  dBodyID trunk_ = nullptr;
  std::array<std::array<dBodyID, 3>, 4> links_{};
  std::array<dJointID, 12> joints_{};
};

// Foot centre of `leg` in B, from the same frame chain the bodies are built
// with (independent of the controller's kinematics, to cross-check it), for
// a lower leg of `lower_length` [m] (the nominal one by default).
Vec3 simFootPositionBase(int leg, const Vec3& q_leg);
Vec3 simFootPositionBase(int leg, const Vec3& q_leg, double lower_length);

}  // namespace hyq::sim
