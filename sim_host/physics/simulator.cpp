#include "sim_host/physics/simulator.hpp"

#include <algorithm>
#include <cmath>

#include "firmware/controller/model/robot_params.hpp"
#include "firmware/controller/state/terrain_estimator.hpp"
#include "sim_host/physics/body_model.hpp"
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

// The trunk's start attitude: laid on a ground of normal n as the
// controller's terrain following lays it (terrainAttitude); on level ground
// exactly the heading.
Mat3 startAttitude(const Scenario& scenario, const Vec3& n) {
  if (n.x() == 0.0 && n.y() == 0.0) return Eigen::AngleAxisd(scenario.start_yaw, Vec3::UnitZ()).toRotationMatrix();
  return terrainAttitude(scenario.start_yaw, n, scenario.controller_params.gait.max_tilt);
}
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
  // a quarter of the weight each: the robot starts loaded, with no drop. On
  // a sloped start the trunk lies on the ground as the controller lays it
  // (pitch and roll in the heading's frame, each at most GaitParams::max_tilt), so
  // the four feet stand on the slope instead of two hanging above it.
  const std::array<double, 12> q = standPosture();
  const Mat3 rot = startAttitude(scenario, terrain_->normal(scenario.start_x));
  const RobotBody body = plantBody(scenario.plant);
  double base_above_ground = -HUGE_VAL;
  for (int leg = 0; leg < kNumLegs; ++leg) {
    const Vec3 q_leg(q[3 * leg], q[3 * leg + 1], q[3 * leg + 2]);
    const Vec3 f = rot * simFootPositionBase(leg, q_leg, body.lower_length);
    const double x = scenario.start_x + f.x();
    // The sphere touches a plane of normal n with its centre r / n_z above it.
    base_above_ground = std::max(base_above_ground,
                                 terrain_->height(x) - f.z() + kFootRadius / terrain_->normal(x).z());
  }
  const Vec3 touching(scenario.start_x, scenario.start_y, base_above_ground);
  const double sink =
      engine_->staticSink(touching, rot, q, (body.total_mass + scenario.payload_kg) * kGravity / kNumLegs);
  engine_->place(touching - Vec3(0.0, 0.0, sink), rot, q);
  sensor_model_ = std::make_unique<SensorModel>(scenario.sensors, scenario.seed, scenario.plant);
  ideal_plant_ = scenario.plant.isIdeal();
  readJoints();
  for (int j = 0; j < hal::kNumJoints; ++j) {
    actuators_[j] = JointActuator(scenario.plant.actuator, scenario.plant.encoder, kEffortLimit);
    actuators_[j].reset(q[j]);
    tick_encoders_[j] = JointEncoder(scenario.plant.encoder);
    tick_encoders_[j].reset(q[j]);
  }
  measure(Vec3::Zero(), Vec3::Zero());
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

void Simulator::actuatorLoop(const hal::CommandFrame& c, double h, std::array<double, 12>& tau_applied,
                             std::array<double, 12>& tau_joint) {
  for (int j = 0; j < hal::kNumJoints; ++j) {
    const double q = joint_q_[j], qd = joint_qd_[j];
    const JointCommand command{c.tau_ff[j], c.q_ref[j], c.qd_ref[j], c.kp[j], c.kd[j]};
    const double tau = actuators_[j].step(command, q, qd, h);
    tau_applied[j] = tau;
    tau_joint[j] = tau - kJointDamping * qd;
  }
}

const hal::CommandFrame& Simulator::delayedCommand(const hal::CommandFrame& command) {
  const int delay = scenario_.plant.delay.command_ticks;
  if (delay == 0) return command;
  commands_[commands_received_ % kCommandRing] = command;
  ++commands_received_;
  const uint32_t age = std::min<uint32_t>(static_cast<uint32_t>(delay), commands_received_ - 1);
  return commands_[(commands_received_ - 1 - age) % kCommandRing];
}

void Simulator::primeActuators(const hal::CommandFrame& c) {
  for (int j = 0; j < hal::kNumJoints; ++j) {
    const JointCommand command{c.tau_ff[j], c.q_ref[j], c.qd_ref[j], c.kp[j], c.kd[j]};
    actuators_[j].reset(joint_q_[j], 0.0);  // the encoder's reading, which the PD takes
    actuators_[j].reset(joint_q_[j], actuators_[j].pd(command));
  }
}

void Simulator::readJoints() {
  for (int j = 0; j < hal::kNumJoints; ++j) {
    joint_q_[j] = engine_->jointAngle(j);
    joint_qd_[j] = engine_->jointRate(j);
  }
}

void Simulator::sampleEncoders(bool tick_end) {
  const PlantSpec& plant = scenario_.plant;
  for (int j = 0; j < hal::kNumJoints; ++j) {
    const double q = joint_q_[j], qd = joint_qd_[j];
    if (plant.actuator.model)
      actuators_[j].finishStep(q, qd);
    else if (tick_end)
      tick_encoders_[j].sample(q, qd, config_.integration.tick);
  }
}

void Simulator::step(const hal::CommandFrame& command, TickRecord& rec) {
  const IntegrationParams& integ = config_.integration;
  const double h = integ.tick / integ.substeps;
  const double t0 = time();
  const Vec3 v0 = engine_->baseVelocity(), w0 = engine_->baseOmega();
  const Vec3 disturbance = disturbanceAt(t0);
  std::array<Vec3, 4> mean_force;
  for (Vec3& f : mean_force) f.setZero();
  std::array<FootContactState, 4> feet;  // after the last step: the tick's end
  const hal::CommandFrame& applied = delayedCommand(command);
  const bool actuators = scenario_.plant.actuator.model;
  if (actuators && tick_ == 0) primeActuators(applied);

  for (int k = 0; k < integ.substeps; ++k) {
    std::array<double, 12> tau_joint;
    if (actuators)
      actuatorLoop(applied, h, tau_applied_, tau_joint);
    else
      jointLoop(applied, tau_applied_, tau_joint);
    terrain_->setTime(t0 + k * h);
    engine_->step(tau_joint, disturbance, h);
    if (!ideal_plant_) {
      readJoints();
      sampleEncoders(k + 1 == integ.substeps);
    }
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
    // The ground's friction where the contact is, as the contact takes it
    // (its point, not the sphere's centre: on a 3.3 deg slope the two are
    // 1.1 mm apart, and a foot whose centre stood 1 mm inside a patch of mu
    // 0.157 held 0.43 on the 0.506 beyond its edge, drawn terrain 34).
    const Vec3 at = s.in_contact ? s.point : s.centre;  // [m]
    foot.mu = terrain_->mu(at.x(), at.y());
    if (s.in_contact) {
      foot.slip_velocity = arr(s.slip_velocity);
      foot.slip_speed = s.slip_velocity.norm();
    }
  }
  rec.disturbance = arr(disturbance);
  rec.command = command;
  rec.tau_applied = tau_applied_;
  rec.sensors = sensors_;  // the frame the controller answered
  rec.plant = &scenario_.plant;

  measure((vel - v0) / integ.tick, (engine_->baseOmega() - w0) / integ.tick);
}

void Simulator::measure(const Vec3& base_acceleration, const Vec3& base_alpha) {
  TrueProprioception truth;
  truth.tau = tau_applied_;
  truth.base_orientation = engine_->baseQuaternion();
  truth.base_omega = engine_->baseOmega();
  truth.base_acceleration = base_acceleration;
  if (ideal_plant_) {
    for (int j = 0; j < hal::kNumJoints; ++j) {
      truth.q[j] = engine_->jointAngle(j);
      truth.qd[j] = engine_->jointRate(j);
    }
    sensor_model_->measure(tick_, truth, sensors_);
    return;
  }
  // The joints' state as the last engine step left it (readJoints).
  for (int j = 0; j < hal::kNumJoints; ++j) {
    truth.q[j] = joint_q_[j];
    truth.qd[j] = joint_qd_[j];
  }
  // The readings as the robot has them: the boards' encoders and torque
  // sensors (or the tick's encoders when no actuator is modelled).
  const PlantSpec& plant = scenario_.plant;
  const bool encoders = plant.encoder.resolution > 0.0 || plant.encoder.velocity == VelocitySource::differentiated;
  for (int j = 0; j < hal::kNumJoints; ++j) {
    if (plant.actuator.model) {
      truth.tau[j] = actuators_[j].measured();
      truth.q[j] = actuators_[j].encoder().position();
      truth.qd[j] = actuators_[j].encoder().velocity();
    } else if (encoders) {
      truth.q[j] = tick_encoders_[j].position();
      truth.qd[j] = tick_encoders_[j].velocity();
    }
  }
  truth.base_alpha = base_alpha;
  hal::SensorFrame fresh;
  sensor_model_->measure(tick_, truth, fresh);
  deliver(fresh);
}

void Simulator::deliver(const hal::SensorFrame& fresh) {
  // Before there is a measurement as old as a delay asks, the first one.
  if (tick_ == 0) frames_.fill(fresh);
  frames_[tick_ % kFrameRing] = fresh;
  const DelayParams& d = scenario_.plant.delay;
  auto older = [&](int ticks) -> const hal::SensorFrame& {
    const uint32_t age = std::min<uint32_t>(static_cast<uint32_t>(ticks), tick_);
    return frames_[(tick_ - age) % kFrameRing];
  };
  const hal::SensorFrame& joints = older(d.sensor_ticks);
  const hal::SensorFrame& imu = older(d.sensor_ticks + d.imu_ticks);
  sensors_ = joints;
  std::copy(std::begin(imu.imu_quat), std::end(imu.imu_quat), sensors_.imu_quat);
  std::copy(std::begin(imu.imu_gyro), std::end(imu.imu_gyro), sensors_.imu_gyro);
  std::copy(std::begin(imu.imu_acc), std::end(imu.imu_acc), sensors_.imu_acc);
  sensors_.tick = tick_;
}

bool Simulator::fallen() const {
  const Vec3 p = engine_->basePosition();
  const Mat3 r = engine_->baseRotation();
  const double tilt = std::acos(std::clamp(r(2, 2), -1.0, 1.0));
  return p.z() - terrain_->height(p.x()) < config_.fall.min_height || tilt > config_.fall.max_tilt;
}

}  // namespace hyq::sim
