#include "sim_host/physics/simulator.hpp"

#include <algorithm>
#include <cmath>

#include "firmware/controller/model/robot_params.hpp"
#include "sim_host/physics/robot.hpp"

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

Simulator::Simulator(const Scenario& scenario, const SimConfig& config)
    : scenario_(scenario), config_(config) {
  // ODE's contact forces are explicit: a stiffer contact needs shorter
  // steps, sqrt(scale) times shorter to keep omega h where the default is.
  if (scenario.physics.engine == EngineKind::ode && scenario.physics.ode_stiffness_scale > 1.0)
    config_.integration.substeps = std::max(
        config_.integration.substeps,
        static_cast<int>(std::ceil(std::sqrt(scenario.physics.ode_stiffness_scale) - 1e-9)));
  terrain_ = std::make_unique<Terrain>(scenario.terrain);
  engine_ = makePhysicsEngine(scenario, *terrain_, config_);

  // Stand posture, feet pressed into the ground by their static sink under
  // a quarter of the weight each: the robot starts loaded, with no drop.
  const std::array<double, 12> q = standPosture();
  const Mat3 rot = Eigen::AngleAxisd(scenario.start_yaw, Vec3::UnitZ()).toRotationMatrix();
  double base_above_ground = -HUGE_VAL;
  for (int leg = 0; leg < kNumLegs; ++leg) {
    const Vec3 f = rot * simFootPositionBase(leg, Vec3(q[3 * leg], q[3 * leg + 1], q[3 * leg + 2]));
    base_above_ground = std::max(base_above_ground, terrain_->height(scenario.start_x + f.x()) - f.z());
  }
  const Vec3 touching(scenario.start_x, scenario.start_y, base_above_ground + kFootRadius);
  const double sink =
      engine_->staticSink(touching, rot, q, (kTotalMass + scenario.payload_kg) * kGravity / kNumLegs);
  engine_->place(touching - Vec3(0.0, 0.0, sink), rot, q);
  sensor_model_ = std::make_unique<SensorModel>(scenario.sensors, scenario.seed);
  measure(Vec3::Zero());
}

Simulator::~Simulator() = default;

Vec3 Simulator::disturbanceAt(double t) const {
  Vec3 f = Vec3::Zero();
  for (const Disturbance& d : scenario_.disturbances)
    if (t >= d.t && t < d.t + d.duration) f += Vec3(d.force[0], d.force[1], d.force[2]);
  return f;
}

void Simulator::jointLoop(const hal::CommandFrame& c, std::array<double, 12>& tau_applied,
                          std::array<double, 12>& tau_joint) const {
  for (int j = 0; j < hal::kNumJoints; ++j) {
    const double q = engine_->jointAngle(j), qd = engine_->jointRate(j);
    double tau = c.tau_ff[j] + c.kp[j] * (c.q_ref[j] - q) + c.kd[j] * (c.qd_ref[j] - qd);
    // A NaN command must not poison the physics: the drive outputs nothing.
    if (!std::isfinite(tau)) tau = 0.0;
    tau = std::clamp(tau, -kEffortLimit, kEffortLimit);
    tau_applied[j] = tau;
    tau_joint[j] = tau - kJointDamping * qd;
  }
}

void Simulator::step(const hal::CommandFrame& command, TickRecord& rec) {
  const IntegrationParams& integ = config_.integration;
  const double h = integ.tick / integ.substeps;
  const double t0 = time();
  const Vec3 v0 = engine_->baseVelocity();
  const Vec3 disturbance = disturbanceAt(t0);
  std::array<Vec3, 4> mean_force;
  for (Vec3& f : mean_force) f.setZero();
  std::array<FootContactState, 4> feet;  // after the last step: the tick's end

  for (int k = 0; k < integ.substeps; ++k) {
    std::array<double, 12> tau_joint;
    jointLoop(command, tau_applied_, tau_joint);
    terrain_->setTime(t0 + k * h);
    engine_->step(tau_joint, disturbance, h);
    for (int leg = 0; leg < kNumLegs; ++leg) {
      feet[leg] = engine_->foot(leg);
      mean_force[leg] += feet[leg].force / integ.substeps;
    }
  }
  ++tick_;

  rec = TickRecord{};
  rec.tick = tick_ - 1;
  rec.time = time();
  const Vec3 pos = engine_->basePosition();
  const Quat quat = engine_->baseQuaternion();
  const Vec3 vel = engine_->baseVelocity();
  rec.base_pos = arr(pos);
  rec.base_quat = {quat.w(), quat.x(), quat.y(), quat.z()};
  rec.base_vel = arr(vel);
  rec.base_omega = arr(engine_->baseOmega());
  for (int leg = 0; leg < kNumLegs; ++leg) {
    const FootContactState& s = feet[leg];
    FootTruth& foot = rec.feet[leg];
    foot.position = arr(s.centre);
    foot.velocity = arr(s.velocity);
    foot.in_contact = s.in_contact;
    foot.force = arr(mean_force[leg]);
    foot.normal = s.in_contact ? arr(s.normal) : arr(terrain_->normal(s.centre.x()));
    foot.mu = terrain_->mu(s.centre.x(), s.centre.y());
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
    truth.q[j] = engine_->jointAngle(j);
    truth.qd[j] = engine_->jointRate(j);
  }
  truth.tau = tau_applied_;
  truth.base_orientation = engine_->baseQuaternion();
  truth.base_omega = engine_->baseOmega();
  truth.base_acceleration = base_acceleration;
  sensor_model_->measure(tick_, truth, sensors_);
}

bool Simulator::fallen() const {
  const Vec3 p = engine_->basePosition();
  const Mat3 r = engine_->baseRotation();
  const double tilt = std::acos(std::clamp(r(2, 2), -1.0, 1.0));
  return p.z() - terrain_->height(p.x()) < config_.fall.min_height || tilt > config_.fall.max_tilt;
}

}  // namespace hyq::sim
