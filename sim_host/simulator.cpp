#include "sim_host/simulator.hpp"

#include <algorithm>
#include <cmath>

#include "firmware/controller/robot_params.hpp"

namespace hyq::sim {
namespace {
using namespace hyq::robot;

std::array<double, 12> standPosture() {
  std::array<double, 12> q{};
  for (int leg = 0; leg < kNumLegs; ++leg)
    for (int joint = 0; joint < 3; ++joint) q[3 * leg + joint] = standAngle(leg, joint);
  return q;
}

std::array<double, 3> arr(const Vec3& v) { return {v.x(), v.y(), v.z()}; }
}  // namespace

void ensureOdeInitialised() {
  static const bool done = (dInitODE2(0), true);
  (void)done;
}

Simulator::Simulator(const Scenario& scenario, const SimConfig& config)
    : scenario_(scenario), config_(config) {
  ensureOdeInitialised();
  dRandSetSeed(static_cast<unsigned long>(scenario.seed));
  world_ = dWorldCreate();
  dWorldSetGravity(world_, 0.0, 0.0, -kGravity);
  dWorldSetQuickStepNumIterations(world_, config_.integration.quick_step_iterations);
  terrain_ = std::make_unique<Terrain>(scenario.terrain);
  robot_ = std::make_unique<HyqRobot>(world_, scenario.payload_kg,
                                      config_.integration.joint_stop_erp,
                                      config_.integration.joint_stop_cfm);
  contacts_ = std::make_unique<ContactModel>(*terrain_, config_.contact);
  for (int leg = 0; leg < kNumLegs; ++leg)
    foot_contact_[leg] = contacts_->addSphere(robot_->lowerLeg(leg), HyqRobot::footOffset(), kFootRadius);
  // The trunk touches the ground only in a fall: its box corners suffice.
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3 c(((corner & 1) ? 0.5 : -0.5) * kTrunkSize[0] - kTrunkCom[0],
                 ((corner & 2) ? 0.5 : -0.5) * kTrunkSize[1] - kTrunkCom[1],
                 ((corner & 4) ? 0.5 : -0.5) * kTrunkSize[2] - kTrunkCom[2]);
    contacts_->addSphere(robot_->trunk(), c, config_.contact.trunk_corner_radius);
  }

  // Stand posture, feet pressed into the ground by their static sink under
  // a quarter of the weight each: the robot starts loaded, with no drop.
  const std::array<double, 12> q = standPosture();
  const Mat3 rot = Eigen::AngleAxisd(scenario.start_yaw, Vec3::UnitZ()).toRotationMatrix();
  double base_above_ground = -HUGE_VAL;
  for (int leg = 0; leg < kNumLegs; ++leg) {
    const Vec3 f = rot * simFootPositionBase(leg, Vec3(q[3 * leg], q[3 * leg + 1], q[3 * leg + 2]));
    base_above_ground = std::max(base_above_ground, terrain_->height(scenario.start_x + f.x()) - f.z());
  }
  const double sink =
      (kTotalMass + scenario.payload_kg) * kGravity / kNumLegs / config_.contact.normal_stiffness;
  robot_->place(Vec3(scenario.start_x, scenario.start_y, base_above_ground + kFootRadius - sink),
                rot, q);
  sensor_model_ = std::make_unique<SensorModel>(scenario.sensors, scenario.seed);
  measure(Vec3::Zero());
}

Simulator::~Simulator() {
  contacts_.reset();
  robot_.reset();
  terrain_.reset();
  dWorldDestroy(world_);
}

Vec3 Simulator::disturbanceAt(double t) const {
  Vec3 f = Vec3::Zero();
  for (const Disturbance& d : scenario_.disturbances)
    if (t >= d.t && t < d.t + d.duration) f += Vec3(d.force[0], d.force[1], d.force[2]);
  return f;
}

void Simulator::applyJointLoop(const hal::CommandFrame& c, std::array<double, 12>& tau_applied) {
  for (int j = 0; j < hal::kNumJoints; ++j) {
    const double q = robot_->jointAngle(j), qd = robot_->jointRate(j);
    double tau = c.tau_ff[j] + c.kp[j] * (c.q_ref[j] - q) + c.kd[j] * (c.qd_ref[j] - qd);
    // A NaN command must not poison the physics: the drive outputs nothing.
    if (!std::isfinite(tau)) tau = 0.0;
    tau = std::clamp(tau, -kEffortLimit, kEffortLimit);
    tau_applied[j] = tau;
    robot_->addJointTorque(j, tau - kJointDamping * qd);
  }
}

void Simulator::step(const hal::CommandFrame& command, TickRecord& rec) {
  const IntegrationParams& integ = config_.integration;
  const double h = integ.tick / integ.substeps;
  const double t0 = time();
  const Vec3 v0 = robot_->baseVelocity();
  const Vec3 disturbance = disturbanceAt(t0);
  std::array<Vec3, 4> mean_force;
  for (Vec3& f : mean_force) f.setZero();

  for (int k = 0; k < integ.substeps; ++k) {
    applyJointLoop(command, tau_applied_);
    contacts_->applyForces();
    for (int leg = 0; leg < kNumLegs; ++leg)
      mean_force[leg] += contacts_->sphere(foot_contact_[leg]).force / integ.substeps;
    dBodyAddForce(robot_->trunk(), disturbance.x(), disturbance.y(), disturbance.z());
    if (integ.quick_step)
      dWorldQuickStep(world_, h);
    else
      dWorldStep(world_, h);
  }
  ++tick_;

  rec = TickRecord{};
  rec.tick = tick_ - 1;
  rec.time = time();
  const Vec3 pos = robot_->basePosition();
  const Quat quat = robot_->baseQuaternion();
  const Vec3 vel = robot_->baseVelocity();
  rec.base_pos = arr(pos);
  rec.base_quat = {quat.w(), quat.x(), quat.y(), quat.z()};
  rec.base_vel = arr(vel);
  rec.base_omega = arr(robot_->baseOmega());
  for (int leg = 0; leg < kNumLegs; ++leg) {
    const SphereContact& s = contacts_->sphere(foot_contact_[leg]);
    FootTruth& foot = rec.feet[leg];
    const dReal* c = dGeomGetPosition(s.geom);
    const Vec3 centre(c[0], c[1], c[2]);
    dVector3 v;
    dBodyGetPointVel(s.body, c[0], c[1], c[2], v);
    foot.position = arr(centre);
    foot.velocity = {v[0], v[1], v[2]};
    foot.in_contact = s.in_contact;
    foot.force = arr(mean_force[leg]);
    foot.normal = s.in_contact ? arr(s.normal) : arr(terrain_->normal(centre.x()));
    foot.mu = terrain_->mu(centre.x(), centre.y());
    if (s.in_contact) {
      foot.slip_velocity = arr(s.slip_velocity);
      foot.slip_speed = s.slip_velocity.norm();
    }
  }
  rec.disturbance = arr(disturbance);
  rec.command = command;
  rec.tau_applied = tau_applied_;
  rec.sensors = sensors_;  // the frame the controller answered

  measure((vel - v0) / integ.tick);
}

void Simulator::measure(const Vec3& base_acceleration) {
  TrueProprioception truth;
  for (int j = 0; j < hal::kNumJoints; ++j) {
    truth.q[j] = robot_->jointAngle(j);
    truth.qd[j] = robot_->jointRate(j);
  }
  truth.tau = tau_applied_;
  truth.base_orientation = robot_->baseQuaternion();
  truth.base_omega = robot_->baseOmega();
  truth.base_acceleration = base_acceleration;
  sensor_model_->measure(tick_, truth, sensors_);
}

bool Simulator::fallen() const {
  const Vec3 p = robot_->basePosition();
  const Mat3 r = robot_->baseRotation();
  const double tilt = std::acos(std::clamp(r(2, 2), -1.0, 1.0));
  return p.z() - terrain_->height(p.x()) < config_.fall.min_height || tilt > config_.fall.max_tilt;
}

}  // namespace hyq::sim
