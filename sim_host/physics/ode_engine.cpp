#include "sim_host/physics/ode_engine.hpp"

#include "firmware/controller/model/robot_params.hpp"

namespace hyq::sim {
using namespace hyq::robot;

void ensureOdeInitialised() {
  static const bool done = (dInitODE2(0), true);
  (void)done;
}

OdeEngine::OdeEngine(const Scenario& scenario, const Terrain& terrain, const SimConfig& config)
    : contact_params_(config.contact), integration_(config.integration) {
  contact_params_.normal_stiffness *= scenario.physics.ode_stiffness_scale;
  contact_params_.tangent_stiffness *= scenario.physics.ode_stiffness_scale;
  if (scenario.plant.body == BodyModel::published) contact_params_.normal_damping = contact_params_.published_normal_damping;
  ensureOdeInitialised();
  dRandSetSeed(static_cast<unsigned long>(scenario.seed));
  world_ = dWorldCreate();
  dWorldSetGravity(world_, 0.0, 0.0, -kGravity);
  dWorldSetQuickStepNumIterations(world_, integration_.quick_step_iterations);
  robot_ = std::make_unique<HyqRobot>(world_, scenario.payload_kg, integration_.joint_stop_erp,
                                      integration_.joint_stop_cfm, plantBody(scenario.plant));
  contacts_ = std::make_unique<ContactModel>(terrain, contact_params_);
  for (int leg = 0; leg < kNumLegs; ++leg)
    foot_contact_[leg] = contacts_->addSphere(robot_->lowerLeg(leg), robot_->footOffset(leg), kFootRadius);
  // The trunk touches the ground only in a fall: its box corners suffice.
  // The box is centred on the base origin; the trunk body's origin is its CoM.
  const Vec3& com = robot_->trunkCom();
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3 c(((corner & 1) ? 0.5 : -0.5) * kTrunkSize[0] - com.x(),
                 ((corner & 2) ? 0.5 : -0.5) * kTrunkSize[1] - com.y(),
                 ((corner & 4) ? 0.5 : -0.5) * kTrunkSize[2] - com.z());
    contacts_->addSphere(robot_->trunk(), c, contact_params_.trunk_corner_radius);
  }
}

OdeEngine::~OdeEngine() {
  contacts_.reset();
  robot_.reset();
  dWorldDestroy(world_);
}

void OdeEngine::place(const Vec3& base_pos, const Mat3& base_rot, const std::array<double, 12>& q) {
  robot_->place(base_pos, base_rot, q);
}

double OdeEngine::staticSink(const Vec3&, const Mat3&, const std::array<double, 12>&,
                             double weight_per_foot) {
  return weight_per_foot / contact_params_.normal_stiffness;
}

void OdeEngine::step(const std::array<double, 12>& joint_torque, const Vec3& trunk_force,
                     double h) {
  for (int j = 0; j < 12; ++j) robot_->addJointTorque(j, joint_torque[j]);
  contacts_->applyForces(h);
  dBodyAddForce(robot_->trunk(), trunk_force.x(), trunk_force.y(), trunk_force.z());
  if (integration_.quick_step)
    dWorldQuickStep(world_, h);
  else
    dWorldStep(world_, h);
}

FootContactState OdeEngine::foot(int leg) const {
  const SphereContact& s = contacts_->sphere(foot_contact_[leg]);
  FootContactState f;
  const dReal* c = dGeomGetPosition(s.geom);
  f.centre = Vec3(c[0], c[1], c[2]);
  dVector3 v;
  dBodyGetPointVel(s.body, c[0], c[1], c[2], v);
  f.velocity = Vec3(v[0], v[1], v[2]);
  f.in_contact = s.in_contact;
  f.force = s.force;
  f.normal = s.normal;
  f.point = s.point;
  f.slip_velocity = s.in_contact ? s.slip_velocity : Vec3::Zero();
  return f;
}

}  // namespace hyq::sim
