// The rigid-body world under the simulator: HyQ's 13 bodies and 12 hinges on
// the terrain, stepped by one physics engine. The simulator around it (joint
// loop, disturbances, sensors, ground-truth records) is the same for every
// engine, so that two engines run the same scenario with the same controller,
// sensor model and metrics.
//
// Engines: ODE with the project's own contact model (ode_engine.hpp), and
// MuJoCo with its soft elliptic-cone contacts (mujoco_engine.hpp).
#pragma once
#include <array>
#include <memory>
#include <string>

#include "firmware/controller/model/types.hpp"
#include "sim_host/scenario/scenario.hpp"
#include "sim_host/physics/sim_params.hpp"
#include "sim_host/physics/terrain.hpp"

namespace hyq::sim {

// One foot's contact over the last engine step, W: the contact (point,
// normal, slip velocity) as it was when the step began, the force the step
// applied, the centre and its velocity where the step ended.
struct FootContactState {
  bool in_contact = false;
  Vec3 centre = Vec3::Zero();         // [m] foot sphere centre (end of the step)
  Vec3 velocity = Vec3::Zero();       // [m/s] of the centre (end of the step)
  Vec3 force = Vec3::Zero();          // [N] ground force on the foot during the step
  Vec3 normal = Vec3::UnitZ();        // [-] contact normal, out of the ground
  Vec3 point = Vec3::Zero();          // [m] contact point
  Vec3 slip_velocity = Vec3::Zero();  // [m/s] tangential velocity of the foot's material
                                      // point at the contact (0 while it sticks or rolls)
};

class PhysicsEngine {
 public:
  virtual ~PhysicsEngine() = default;

  virtual const char* name() const = 0;
  // Puts the robot where base pose + joint angles say, at rest.
  virtual void place(const Vec3& base_pos, const Mat3& base_rot,
                     const std::array<double, 12>& q) = 0;
  // How far below the pose whose feet just touch the ground (base_pos,
  // base_rot, q) the robot stands with its feet carrying its weight: the
  // contact's static sink [m]. May move the robot; place() it afterwards.
  virtual double staticSink(const Vec3& base_pos, const Mat3& base_rot,
                            const std::array<double, 12>& q, double weight_per_foot) = 0;

  // One step of `h` seconds with these joint torques (child link about the
  // joint axis) and an external force at the trunk's centre of mass.
  virtual void step(const std::array<double, 12>& joint_torque, const Vec3& trunk_force,
                    double h) = 0;

  virtual double jointAngle(int j) const = 0;    // [rad]
  virtual double jointRate(int j) const = 0;     // [rad/s]
  virtual Vec3 basePosition() const = 0;         // [m] base frame origin, W
  virtual Mat3 baseRotation() const = 0;         // B in W
  virtual Quat baseQuaternion() const = 0;
  virtual Vec3 baseVelocity() const = 0;         // [m/s] base origin, W
  virtual Vec3 baseOmega() const = 0;            // [rad/s] W
  virtual FootContactState foot(int leg) const = 0;
  virtual double totalMass() const = 0;          // [kg] including the payload
};

// The engine `scenario.physics.engine` names, built for the scenario's
// terrain, payload and physics settings.
std::unique_ptr<PhysicsEngine> makePhysicsEngine(const Scenario& scenario,
                                                 const Terrain& terrain,
                                                 const SimConfig& config);

}  // namespace hyq::sim
