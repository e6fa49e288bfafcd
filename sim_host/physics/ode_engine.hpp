// HyQ in ODE: the rigid bodies and hinges of robot.hpp, stepped by ODE
// (dWorldStep, exact), with the project's own contact model (contact.hpp)
// applying the ground forces on the foot spheres and the trunk's corners.
#pragma once
#include <ode/ode.h>

#include <memory>

#include "sim_host/physics/contact.hpp"
#include "sim_host/physics/physics_engine.hpp"
#include "sim_host/physics/robot.hpp"

namespace hyq::sim {

// ODE's one-time global set-up; safe to call any number of times.
void ensureOdeInitialised();

class OdeEngine final : public PhysicsEngine {
 public:
  OdeEngine(const Scenario& scenario, const Terrain& terrain, const SimConfig& config);
  ~OdeEngine() override;
  OdeEngine(const OdeEngine&) = delete;
  OdeEngine& operator=(const OdeEngine&) = delete;

  const char* name() const override { return "ode"; }
  void place(const Vec3& base_pos, const Mat3& base_rot, const std::array<double, 12>& q) override;
  double staticSink(const Vec3& base_pos, const Mat3& base_rot, const std::array<double, 12>& q,
                    double weight_per_foot) override;
  void step(const std::array<double, 12>& joint_torque, const Vec3& trunk_force,
            double h) override;
  double jointAngle(int j) const override { return robot_->jointAngle(j); }
  double jointRate(int j) const override { return robot_->jointRate(j); }
  Vec3 basePosition() const override { return robot_->basePosition(); }
  Mat3 baseRotation() const override { return robot_->baseRotation(); }
  Quat baseQuaternion() const override { return robot_->baseQuaternion(); }
  Vec3 baseVelocity() const override { return robot_->baseVelocity(); }
  Vec3 baseOmega() const override { return robot_->baseOmega(); }
  FootContactState foot(int leg) const override;
  double totalMass() const override { return robot_->totalMass(); }

 private:
  ContactParams contact_params_;
  IntegrationParams integration_;
  dWorldID world_ = nullptr;
  std::unique_ptr<HyqRobot> robot_;
  std::unique_ptr<ContactModel> contacts_;
  std::array<int, 4> foot_contact_{};
};

}  // namespace hyq::sim
