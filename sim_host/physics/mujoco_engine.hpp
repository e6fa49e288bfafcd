// HyQ in MuJoCo: the model of mujoco_model.hpp stepped by MuJoCo (Euler,
// Newton solver, elliptic cones, soft contacts). The foot spheres roll: the
// contact point, not the sphere's centre, is what sticks.
#pragma once
#include <mujoco/mujoco.h>

#include <array>
#include <string>
#include <vector>

#include "sim_host/physics/physics_engine.hpp"

namespace hyq::sim {

class MujocoEngine final : public PhysicsEngine {
 public:
  // Throws ScenarioError if the terrain needs more ground boxes than the
  // model may have, std::runtime_error with MuJoCo's message if the model
  // does not compile.
  MujocoEngine(const Scenario& scenario, const Terrain& terrain, const SimConfig& config);
  ~MujocoEngine() override;
  MujocoEngine(const MujocoEngine&) = delete;
  MujocoEngine& operator=(const MujocoEngine&) = delete;

  const char* name() const override { return "mujoco"; }
  void place(const Vec3& base_pos, const Mat3& base_rot, const std::array<double, 12>& q) override;
  double staticSink(const Vec3& base_pos, const Mat3& base_rot, const std::array<double, 12>& q,
                    double weight_per_foot) override;
  void step(const std::array<double, 12>& joint_torque, const Vec3& trunk_force,
            double h) override;
  double jointAngle(int j) const override;
  double jointRate(int j) const override;
  Vec3 basePosition() const override;
  Mat3 baseRotation() const override;
  Quat baseQuaternion() const override;
  Vec3 baseVelocity() const override;
  Vec3 baseOmega() const override;
  FootContactState foot(int leg) const override;
  double totalMass() const override;

  const mjModel& model() const { return *m_; }
  const mjData& data() const { return *d_; }

 private:
  void setUp();  // ids and addresses of the model's bodies, joints, feet
  void readContacts();
  void readFeetMotion();

  // Ground boxes under timed patches: geom id and where their friction is asked.
  struct TimedGeom {
    int geom;
    double x, y;  // [m]
  };
  const Terrain& terrain_;
  std::vector<TimedGeom> timed_ground_;
  mjModel* m_ = nullptr;
  mjData* d_ = nullptr;
  int trunk_ = -1;
  std::array<int, 12> qpos_{}, dof_{};
  std::array<int, 4> foot_geom_{};
  std::array<FootContactState, 4> feet_{};
};

}  // namespace hyq::sim
