#include "firmware/controller/controller.hpp"

#include <algorithm>
#include <cmath>

#include "firmware/controller/model/kinematics.hpp"
#include "firmware/controller/params_check.hpp"
#include "firmware/controller/model/robot_params.hpp"

namespace hyq {

namespace {

Vec3 legVec(const double* a, int leg) { return Vec3(a[3 * leg], a[3 * leg + 1], a[3 * leg + 2]); }

// Inverse of a 3x3 matrix from its cofactors (a leg Jacobian: a few dozen
// flops where a pivoting LU costs thousands of instructions on the board).
// False when it is singular to working precision: |det| below 1e-12 of the
// product of its row norms, the largest |det| those rows can have.
bool invert3(const Mat3& m, Mat3& inverse) {
  double scale = 1.0;
  for (int r = 0; r < 3; ++r) scale *= m.row(r).norm();
  bool invertible = false;
  double det = 0.0;
  m.computeInverseAndDetWithCheck(inverse, det, invertible, 1e-12 * scale);
  return invertible && scale > 0.0;
}

// Rotation vector of R (axis * angle), robust near 0 and pi.
Vec3 rotationLog(const Mat3& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.axis() * aa.angle();
}

void copy3(const Vec3& v, double* out) {
  out[0] = v.x();
  out[1] = v.y();
  out[2] = v.z();
}

// [m] The stand posture's foot centres in B: the gaits' foothold pattern.
Mat3x4 standFeetBase() {
  Mat3x4 feet;
  for (int leg = 0; leg < kNumLegs; ++leg) {
    const Vec3 q(robot::standAngle(leg, 0), robot::standAngle(leg, 1), robot::standAngle(leg, 2));
    feet.col(leg) = footPositionBase(leg, q);
  }
  return feet;
}

// Every field of the command but its telemetry to zero: each path through
// step() writes the telemetry whole (fillTelemetry, repeatTelemetry, or
// cleared before init), and its bytes need not be written twice.
void clearJointCommands(hal::CommandFrame& c) {
  static_assert(sizeof(hal::CommandFrame) ==
                    2 * sizeof(uint32_t) + 5 * kNumJoints * sizeof(double) + sizeof(hal::Telemetry),
                "a field added to CommandFrame is cleared here");
  c.flags = 0;
#pragma GCC unroll 12
  for (int j = 0; j < kNumJoints; ++j) {
    c.tau_ff[j] = 0.0;
    c.q_ref[j] = 0.0;
    c.qd_ref[j] = 0.0;
    c.kp[j] = 0.0;
    c.kd[j] = 0.0;
  }
}

// True when a joint of `leg` at angles q [rad] is within margin [rad] of a limit.
bool nearJointStop(int leg, const Vec3& q, double margin) {
  bool near = false;
  for (int j = 0; j < 3; ++j) {
    double lo, hi;
    robot::jointLimits(leg, j, lo, hi);
    if (q[j] < lo + margin || q[j] > hi - margin) near = true;
  }
  return near;
}

// [rad/s] the crossover of the damping loops closed through a leg alone:
// swing_crossover_fraction of the torque loop's bandwidth (JointParams).
double swingCrossover(const JointParams& joint) {
  return 2.0 * 3.14159265358979323846 * joint.swing_crossover_fraction * joint.torque_bandwidth;
}

// A force's part along unit normal n [N], and its tangential part over that
// [-] (0 where the normal part is not positive or not a number).
void splitForce(const Vec3& f, const Vec3& n, double& normal, double& ratio) {
  normal = f.dot(n);
  ratio = normal > 0.0 ? (f - normal * n).norm() / normal : 0.0;
}

}  // namespace

bool sensorFrameValid(const hal::SensorFrame& f, const SafetyParams& lim) {
  // Every test passes only a number within finite bounds (checkParams keeps
  // the limits finite) and fails for NaN, so a non-finite number fails its
  // own range test: no separate finiteness pass.
#pragma GCC unroll 12
  for (int j = 0; j < kNumJoints; ++j) {
    double lo, hi;
    robot::jointLimits(j / 3, j % 3, lo, hi);
    if (!(f.q[j] >= lo - lim.joint_range_margin && f.q[j] <= hi + lim.joint_range_margin)) return false;
    if (!(std::fabs(f.qd[j]) <= lim.max_joint_velocity)) return false;
    if (!(std::fabs(f.tau[j]) <= lim.max_joint_torque)) return false;
  }
  const double qn = std::sqrt(f.imu_quat[0] * f.imu_quat[0] + f.imu_quat[1] * f.imu_quat[1] +
                              f.imu_quat[2] * f.imu_quat[2] + f.imu_quat[3] * f.imu_quat[3]);
  if (!(std::fabs(qn - 1.0) <= lim.quat_norm_tol)) return false;
  for (int k = 0; k < 3; ++k) {
    if (!(std::fabs(f.imu_gyro[k]) <= lim.max_gyro)) return false;
    if (!(std::fabs(f.imu_acc[k]) <= lim.max_acc)) return false;
  }
  return true;
}

bool Controller::init(const Params& params) {
  ParamIssue issue;
  params_refused_ = !checkParams(params, issue);
  initialised_ = !params_refused_;
  if (params_refused_) return false;
  params_ = params;
  settle_ticks_ = static_cast<int>(params_.estimator.torque_bias_settle / params_.dt + 0.5);
  started_ = false;
  have_good_ = false;
  was_bad_ = false;
  have_tick_ = false;
  bad_command_count_ = 0;
  tick_gap_count_ = 0;
  estimator_.reset(params_.estimator, params_.dt);
  gyro_bias_.reset(params_.estimator, params_.dt);
  imu_lever_arm_.reset(params_.estimator.imu_position, params_.dt, kImuAlphaTime);
  torque_bias_.reset(params_.estimator, params_.dt);
  com_offset_.reset(params_.estimator, params_.dt);
  terrain_.reset(0.0);
  refit_pending_ = LegMask();
  stand_feet_ = standFeetBase();
  row_split_ = TerrainEstimator::RowSplit::of(params_.gait.trot.prior_row_split, params_.gait.trot.prior_row_interior);
  imu_velocity_.reset(params_.slip);
  restartFilters();
  slip_detector_.reset(params_.slip);
  for (SurfaceEstimator& s : surface_) {
    s.reset(params_.slip, params_.dt);
    s.setCarryParams(params_.gait.trot.carry_distance, params_.gait.trot.carry_agreement,
                     params_.gait.trot.carry_agreement_above, params_.gait.trot.carry_max_samples);
  }
  recovery_.reset(params_.recovery);
  friction_map_.reset(params_.recovery.map);
  for (int i = 0; i < kNumLegs; ++i) {
    map_estimate_[i] = map_written_[i] = map_mu_[i] = 0.0;
    map_writes_[i] = hal::MapWrite{};
  }
  probe_.reset(params_.recovery.probe);
  probe_cos_normal_ = std::cos(params_.recovery.probe.max_normal_angle);
  probe_out_ = ProbeOutput();
  for (double& m : probe_mu_) m = 0.0;
  for (Vec3& n : probe_normal_) n = Vec3::UnitZ();
  useGait(params_.gait.kind);
  freeze_.reset();
  grf_qp_.init(params_.qp, params_.recovery.pyramid_scale);
  previous_ = PreviousTick{};
  return true;
}

// A bad frame repeats the last good tick's telemetry: filled again from
// what that tick left (no stage runs on a bad frame, so nothing it reads
// has changed). Before the first good frame: standing, no leg in swing, the
// default cones.
void Controller::repeatTelemetry(hal::Telemetry& t) const {
  if (started_) {
    fillTelemetry(legs_, previous_.gait(), previous_.slipping, previous_.grf_des_world, false, t);
    return;
  }
  t = hal::Telemetry{};
  t.stance_mask = LegMask::all().bits();
  t.swing_leg = kNumLegs;
  t.probe_leg = t.probe_partner = kNumLegs;
  for (int i = 0; i < kNumLegs; ++i) {
    t.mu_used[i] = params_.recovery.mu_default;
    t.normal_used[i][2] = 1.0;
  }
}

void Controller::restartFilters() {
  const EstimatorParams& e = params_.estimator;
  joint_accel_.reset(e.grf_accel_window, params_.dt);
  base_alpha_.reset(e.grf_accel_window, params_.dt);
  for (Mat3& map : turn_maps_) map.setZero();
  turn_map_leg_ = 0;
  // The friction and normal estimates wait for the acceleration centred on
  // their tick (none without the leg dynamics); GrfDelayLine clamps it.
  const bool aligned = e.grf_leg_dynamics && e.grf_estimate_aligned;
  grf_delay_.reset(aligned ? joint_accel_.centreLag() : 0);
  // The gyro-bias filter's attitudes must be a tick apart too; and no
  // torque-offset sample until a swing has settled again on fresh estimates.
  gyro_bias_.restart();
  imu_lever_arm_.restart();
  // A friction probe's pair does not survive the safe hold of a bad frame.
  probe_.drop();
  probe_out_ = ProbeOutput();
  for (int& n : previous_.swing_ticks) n = 0;
  // The slip damping's two-tick mean: last tick's slip velocity is not the
  // tick before this one after a gap.
  previous_.slip.slip_velocity_valid = false;
}

void Controller::safeHold(hal::CommandFrame& command, uint32_t flags) const {
  double q_hold[kNumJoints];
  for (int j = 0; j < kNumJoints; ++j)
    q_hold[j] = have_good_ ? last_good_q_[j] : robot::standAngle(j / 3, j % 3);
  postureCommand(q_hold, nullptr, params_.joint, command);
  command.flags = flags;
}

void Controller::step(const hal::SensorFrame& s, hal::CommandFrame& command) {
  stage_timer_.begin();
  clearJointCommands(command);
  command.tick = s.tick;
  const bool good = checkFrame(s, command);
  stage_timer_.mark(Stage::kFrameCheck);
  if (!good) return;

  const Imu imu = readImu(s);
  computeLegs(s, imu, legs_);
  stage_timer_.mark(Stage::kLegs);
  // Starting the estimator, the terrain plane and the gait on the first good
  // frame, and the gait's replan after a bad one, count with the state
  // estimate (its marks add up).
  if (!started_) {
    start(imu, legs_);
    run_ticks_ = 0;
  } else if (run_ticks_ < UINT32_MAX) {
    ++run_ticks_;
  }
  if (was_bad_) {
    gait().replanFrom(previous_.base_position + imu.R_wb * legs_.com_base);
    was_bad_ = false;
  }
  stage_timer_.mark(Stage::kStateEstimate);

  const Contact contact = detectSlip(imu, legs_);
  stage_timer_.mark(Stage::kSlipDetection);
  const Body body = estimateState(imu, legs_, contact);
  stage_timer_.mark(Stage::kStateEstimate);
  const RecoveryInput estimates = estimateSurfaces(imu, legs_, contact, body.feet_world);
  const bool freezing = superviseRecovery(estimates);
  stage_timer_.mark(Stage::kSurfaceAndRecovery);
  const GaitOutput& plan = planMotion(imu, legs_, body, contact, freezing);
  stage_timer_.mark(Stage::kGait);
  const Vec6 wrench = trunkWrench(imu, legs_, body, plan);
  stage_timer_.mark(Stage::kWrench);
  const GrfOutput forces = distributeForces(wrench, legs_, body, plan);  // marks kQpBuild, kQpSolve
  // The forces the legs are asked for: the QP's, with a probe's pair when
  // the probe is on (no copy of them when it is off).
  const Mat3x4* grf_cmd = &forces.forces;
  Mat3x4 probed;
  if (probe_.enabled()) {
    probed = forces.forces;
    probeFriction(legs_, body, contact, plan, probed);
    grf_cmd = &probed;
  }
  stage_timer_.mark(Stage::kProbe);
  jointCommands(imu, legs_, body, contact, plan, *grf_cmd, command);

  if (freeze_.apply(freezing, plan.stance_mask == LegMask::all(), s.q, params_.recovery, params_.joint,
                    params_.dt, command))
    gait().replanFrom(body.com);

  command.flags |= (forces.infeasible ? static_cast<uint32_t>(hal::kFlagQpInfeasible) : 0u) |
                   (forces.hit_iteration_limit ? static_cast<uint32_t>(hal::kFlagQpMaxIter) : 0u) |
                   (freeze_.frozen() ? static_cast<uint32_t>(hal::kFlagFreeze) : 0u);
  if (inject_command_fault_) {
    command.tau_ff[0] = std::nan("");
    inject_command_fault_ = false;
  }
  if (!commandFinite(command)) {
    // No NaN or Inf leaves the controller: hold the posture instead.
    safeHold(command, command.flags | hal::kFlagBadCommand);
    ++bad_command_count_;
  }
  freeze_.recordApplied(command, s.q, s.qd);  // what was sent, for the next freeze entry
  fillTelemetry(legs_, plan, contact.slipping, *grf_cmd, true, command.telemetry);

  endTick(contact, forces.forces);
  stage_timer_.mark(Stage::kCommands);
}

// What the next tick reads of this one (the rule for time, controller.hpp).
void Controller::endTick(const Contact& contact, const Mat3x4& grf_des) {
  previous_.last ^= 1;  // this tick's plan is the next tick's last one
  const GaitOutput& plan = previous_.gait();
  previous_.slip = contact.slip;
  previous_.watched = contact.watched | contact.held;
  previous_.slipping = contact.slipping;
  previous_.grf_des_world = grf_des;
  previous_.ground_normal = terrain_.normal();
  previous_.torque_bias = torque_bias_.biases();
  previous_.acc_bias = estimator_.accBias();
  previous_.base_position = estimator_.position();
  for (int i = 0; i < kNumLegs; ++i) {
    previous_.normal_in_use[i] = recovery_.normalInUse(i);
    const bool swinging = plan.leg_phase[i] == LegPhase::kSwing;
    int& n = previous_.swing_ticks[i];
    n = swinging ? n + (n < settle_ticks_ ? 1 : 0) : 0;
  }
  previous_.freezing = recovery_.freezing();
}

// Frame check: a frame that is not initialised for, corrupt, or that follows
// a gap in the tick counter. Returns false when `command` is already the
// safe hold.
bool Controller::checkFrame(const hal::SensorFrame& s, hal::CommandFrame& command) {
  if (!initialised_) {
    safeHold(command, params_refused_ ? hal::kFlagBadParams : hal::kFlagNotInitialised);
    command.telemetry = hal::Telemetry{};
    return false;
  }
  const bool gap = have_tick_ && s.tick != last_tick_ + 1u;
  have_tick_ = true;
  last_tick_ = s.tick;
  if (gap) {
    ++tick_gap_count_;
    command.flags |= hal::kFlagTickGap;
  }
  const bool valid = sensorFrameValid(s, params_.safety);
  // Samples that assume one tick between them start again after a gap, and
  // after a bad frame (the next good one is two ticks on).
  if (gap || !valid) restartFilters();
  if (!valid) {
    safeHold(command, command.flags | hal::kFlagBadSensorFrame);
    was_bad_ = true;
    repeatTelemetry(command.telemetry);
    return false;
  }
  for (int j = 0; j < kNumJoints; ++j) last_good_q_[j] = s.q[j];
  have_good_ = true;
  return true;
}

Controller::Imu Controller::readImu(const hal::SensorFrame& s) {
  Imu imu;
  const Quat quat = Quat(s.imu_quat[0], s.imu_quat[1], s.imu_quat[2], s.imu_quat[3]).normalized();
  imu.R_wb = quat.toRotationMatrix();
  imu.omega_base = gyro_bias_.update(quat, Vec3(s.imu_gyro[0], s.imu_gyro[1], s.imu_gyro[2]));
  // The accelerometer's bias is learnt at the origin's reading: taken off after the lever arm.
  imu.specific_force =
      imu_lever_arm_.atOrigin(Vec3(s.imu_acc[0], s.imu_acc[1], s.imu_acc[2]), imu.omega_base) - previous_.acc_bias;
  return imu;
}

// Leg state: kinematics, and each foot's GRF from its joint torques.
HYQ_FLATTEN void Controller::computeLegs(const hal::SensorFrame& s, const Imu& imu, Legs& legs) {
  const bool dynamics = params_.estimator.grf_leg_dynamics;
  const Mat3& R_wb = imu.R_wb;
  const Vec3 gravity_base = R_wb.transpose() * Vec3(0.0, 0.0, -robot::kGravity);
  Vec12 qd_all;
  for (int j = 0; j < kNumJoints; ++j) qd_all[j] = s.qd[j];
  legs.qdd = joint_accel_.update(qd_all);
  // With the leg dynamics, the links accelerate with the base as well as
  // fall: gravity minus the base's acceleration is minus the accelerometer's
  // specific force; and, with grf_base_rotation, in the trot, they turn with it
  // (legBaseRotation: the angular acceleration from the gyro's slope, centred
  // like qdd, and the centrifugal and Coriolis terms of this tick, with
  // grf_leg_motion those of the leg's own joint motion too). The crawl takes
  // the angular acceleration's term alone, and only while the trunk turns
  // faster than kCrawlTurnAlphaMin.
  // The filter takes its samples in either gait, so that it is warm at a
  // gait switch; the slope only where it is used.
  const bool rotation = profile_.grf_base_rotation, fast_turn = profile_.grf_fast_turn;
  if (rotation || fast_turn) {
    legs.alpha_base = base_alpha_.update(imu.omega_base);
    if (!rotation && !(legs.alpha_base.norm() > kCrawlTurnAlphaMin)) legs.alpha_base.setZero();
  } else {
    base_alpha_.record(imu.omega_base);
    legs.alpha_base.setZero();
  }
  const Vec3 apparent_gravity =
      dynamics && imu.specific_force.allFinite() ? Vec3(-imu.specific_force) : gravity_base;
  const Vec3 normal_base = R_wb.transpose() * previous_.ground_normal;
  legs.at_stop = LegMask();
  // The whole-body CoM's moment [kg m], B: the trunk's, then each leg's.
  Vec3 com_moment = robot::kTrunkMass * Vec3(robot::kTrunkCom[0], robot::kTrunkCom[1], robot::kTrunkCom[2]);
  for (int leg = 0; leg < kNumLegs; ++leg) {
    const Vec3 q = legVec(s.q, leg), qd = legVec(s.qd, leg);
    legs.trig[leg] = legTrig(leg, q);
    const LegTrig& t = legs.trig[leg];
    const Vec3 tau = legVec(s.tau, leg) - previous_.torque_bias.segment<3>(3 * leg);
    legs.q.col(leg) = q;
    if (nearJointStop(leg, q, params_.stance.joint_stop_margin)) legs.at_stop.set(leg);
    legs.qd.col(leg) = qd;
    legs.tau.col(leg) = tau;
    const bool at_contact = params_.estimator.grf_contact_point;
    const FootKinematics foot = footKinematics(leg, t, at_contact, normal_base);
    legs.foot_base.col(leg) = foot.position;
    legs.jacobian[leg] = foot.jacobian;
    com_moment += legMassMoment(leg, t);
    // The velocity of the lower link's point at the contact: the point that
    // sticks while the foot sphere rolls over the ground (its centre moves
    // kFootRadius per radian the shank turns).
    const Vec3 contact_point =
        at_contact ? Vec3(legs.foot_base.col(leg) - robot::kFootRadius * normal_base)
                   : Vec3(legs.foot_base.col(leg));
    legs.foot_vel_base.col(leg) = legs.jacobian[leg] * qd + imu.omega_base.cross(contact_point);
    // tau - b qd = M qdd + g - J^T f  =>  f = -J^-T (tau - b qd - g - M qdd).
    // Split as f = R_wb J^-T (u + M qdd + K alpha), u = -(tau - b qd - g - c),
    // written in place into the delay line's slot of this tick, which pairs
    // them later with the accelerations centred on it (GrfDelayLine). A
    // singular leg gives no estimate (J^-T zero).
    GrfParts& parts = grf_delay_.parts(leg);
    Vec3 rest;
    Mat3& mass = legs.mass[leg];
    if (dynamics) {
      const LegInertia model = legInertia(leg, t, gravity_base, apparent_gravity);
      legs.gravity_torque[leg] = model.holding_a;
      rest = tau - robot::kJointDamping * qd - model.holding_b;
      mass = model.mass;
      if (rotation) {
        const LegBaseRotation turn =
            legBaseRotation(leg, t, qd, imu.omega_base, params_.estimator.grf_leg_motion);
        rest -= turn.rate_torque;
        parts.alpha_torque = turn.alpha_map;
      } else if (fast_turn) {
        // Every tick's parts hold a map: the delay line pairs them with the
        // slope centred on their tick, whichever side of the threshold it
        // falls. A leg's map is refreshed every fourth tick (its posture
        // moves by under 0.01 rad in that time), a quarter of the cost.
        if (leg == turn_map_leg_) turn_maps_[leg] = legBaseAlphaMap(leg, t);
        parts.alpha_torque = turn_maps_[leg];
      } else {
        parts.alpha_torque.setZero();
      }
    } else {
      legs.gravity_torque[leg] = legGravityTorque(leg, t, gravity_base);
      rest = tau - legs.gravity_torque[leg];
      mass.setZero();
      parts.alpha_torque.setZero();
    }
    parts.u_static = -rest;
    parts.setMass(mass);
    if (!invert3(legs.jacobian[leg].transpose(), parts.jt_inverse)) parts.jt_inverse.setZero();
    legs.grf_world.col(leg) = forceFromParts(R_wb, parts, legs.qdd.segment<3>(3 * leg), legs.alpha_base);
  }
  if (fast_turn) turn_map_leg_ = (turn_map_leg_ + 1) % kNumLegs;
  grf_delay_.pushAttitude(R_wb);
  legs.com_base = com_moment / robot::kTotalMass + com_offset_.offsetBase();
}

// The first good frame: the estimator, the terrain plane and the gait start
// from the robot standing where it is.
void Controller::start(const Imu& imu, const Legs& legs) {
  estimator_.initialise(imu.R_wb, legs.foot_base);
  Mat3x4 feet_world;
  for (int i = 0; i < kNumLegs; ++i) feet_world.col(i) = estimator_.position() + imu.R_wb * legs.foot_base.col(i);
  terrain_.fit(feet_world, LegMask::all().bits());
  recovery_.reset(params_.recovery, terrain_.normal());
  // The first tick's stages after this one read the robot standing here.
  previous_.ground_normal = terrain_.normal();
  previous_.base_position = estimator_.position();
  for (int i = 0; i < kNumLegs; ++i) previous_.normal_in_use[i] = recovery_.normalInUse(i);
  previous_.freezing = recovery_.freezing();
  GaitInput gin;
  gin.feet_world = feet_world;
  gin.base_world = estimator_.position();
  gin.com_world = estimator_.position() + imu.R_wb * legs.com_base;
  gin.foothold_origin = estimator_.position() + imu.R_wb * com_offset_.offsetBase();
  const double yaw = std::atan2(imu.R_wb(1, 0), imu.R_wb(0, 0));
  gait().reset(params_.gait, params_.dt, gin, yaw, stand_feet_);
  started_ = true;
}

void Controller::switchGaitIfDue(const Body& body) {
  const GaitSchedule& schedule = params_.gait.schedule;
  if (!profile_.switches_to_trot || recovery_.freezing()) return;
  if (static_cast<double>(run_ticks_) * params_.dt < schedule.trot_at) return;
  if (body.com_vel.head<2>().norm() > schedule.max_com_speed) return;
  const GaitOutput& plan = previous_.gait();
  if (plan.stance_mask != LegMask::all()) return;
  for (int i = 0; i < kNumLegs; ++i)
    if (plan.unloading[i] || plan.load[i] < 1.0) return;
  GaitParams trot = params_.gait;
  trot.kind = GaitKind::kTrot;
  trot.speed = schedule.trot_speed;
  trot.start_delay = 0.0;  // no standing delay: the start shift, then the first pair's unloading
  GaitInput gin;
  gin.feet_world = body.feet_world;
  gin.base_world = body.base;
  gin.com_world = body.com;
  gin.foothold_origin = body.foothold_origin;
  gin.com_vel_world = body.com_vel;
  trot_.reset(trot, params_.dt, gin, plan.yaw_des, stand_feet_);
  useGait(GaitKind::kTrot);
}

void Controller::useGait(GaitKind kind) {
  profile_ = gaitProfile(kind, params_);
  imu_velocity_.setWindow(profile_.imu_integration_window);
  recovery_.setGuessDelay(profile_.guess_delay);
  recovery_.setGuessHolds(profile_.guess_holds, params_.slip.min_estimate_force);
  recovery_.setGuessLoadLimit(profile_.guess_light_feet_only ? params_.slip.min_estimate_force : kAssumeLoaded);
  recovery_.setGuessFromStanceRatio(profile_.guess_from_stance_ratio);
  for (SurfaceEstimator& s : surface_) s.setGaitMode(profile_.carry_over, profile_.peak_of_loaded_samples);
}

// Contact and slip: slip detection in B, free of any base-velocity estimate
// (Algorithm 1), with the IMU integration as the second opinion when
// several legs slip.
Controller::Contact Controller::detectSlip(const Imu& imu, const Legs& legs) {
  const GaitOutput& plan = previous_.gait();
  Contact contact;
  contact.stance = plan.stance_mask;
  // Feet the detector watches: the stance feet, and a landing foot that
  // already pushes on the ground (a slide at touch-down starts before the
  // stance trigger; caught here, its estimate is ready when stance begins).
  // A landing foot is one in late swing whose reference has stopped moving
  // along the ground (slower than the slip threshold): before that the
  // swing itself carries the foot forward, which would read as a slip, and
  // the foot is still above the ground, where a leg whose torque offsets are
  // not yet learnt reads tens of N.
  // In the crawl, a landing foot whose force dips below the watch after it
  // was watched (a foot dragged lightly over ice reads 7-30 N) is held: its
  // detection neither counts nor restarts until the force is back or below
  // force_watch_release; and a foot still coming down toward the ground
  // (against last tick's holding feet) is in the air, whatever its force
  // estimate reads. The trot's landings slide by design; it watches on the
  // force alone, but for that approach test on joints behind a torque loop.
  // In the crawl, a searching foot on the ground below the watch's force is
  // judged by the drag test alone (no slip flag, no share in the median;
  // kSearchStallDepth).
  const Vec3 normal_base = imu.R_wb.transpose() * previous_.ground_normal;
  contact.watched = contact.stance;
  LegMask drag_only;
  for (int i = 0; i < kNumLegs; ++i) {
    const double reference_speed = plan.foot_vel_des[i].head<2>().norm();  // [m/s] W, horizontal
    if (plan.leg_phase[i] == LegPhase::kStance || !plan.swing_late[i] || reference_speed >= params_.slip.threshold)
      continue;
    const double approach_speed =
        profile_.landing_approach_test && previous_.slip.slip_velocity_valid
            ? -(legs.foot_vel_base.col(i) - previous_.slip.u_reference).dot(normal_base)
            : 0.0;  // [m/s] toward the ground
    if (approach_speed >= params_.stance.watch_approach_speed) continue;
    const double normal_force = legs.grf_world.col(i).dot(previous_.ground_normal);  // [N]
    if (normal_force > params_.stance.force_watch)
      contact.watched.set(i);
    else if (profile_.hold_landing_dips && previous_.watched.has(i) &&
             normal_force > params_.stance.force_watch_release)
      contact.held.set(i);
    else if (profile_.drag_is_touchdown && plan.leg_phase[i] == LegPhase::kSearch &&
             previous_.slip.slip_velocity_valid && std::abs(approach_speed) < kSearchStallSpeed) {
      // Lighter still, a searching foot the ground holds up (its reference
      // sunk below it, the foot neither coming down nor bouncing up) is
      // watched by the drag test alone.
      const Vec3 foot_des_base = imu.R_wb.transpose() * (plan.foot_des[i] - previous_.base_position);
      if ((legs.foot_base.col(i) - foot_des_base).dot(normal_base) > kSearchStallDepth) drag_only.set(i);
    }
  }

  // The IMU integration is anchored to last tick's base velocity from the
  // stance legs, only while those legs agree (a two-foot slip corrupts their
  // mean before any flag).
  imu_velocity_.update(imu.specific_force, imu.R_wb, Vec3(0.0, 0.0, -robot::kGravity), params_.dt,
                       previous_.slip.base_velocity_legs, previous_.slip.legs_agree);
  SlipInput sin;
  sin.stance_mask = (contact.watched | contact.held).bits();
  sin.hold_mask = contact.held.bits();
  sin.landing_mask = ((contact.watched | contact.held) & ~contact.stance).bits();
  sin.drag_only_mask = drag_only.bits();
  for (int i = 0; i < kNumLegs; ++i) sin.u[i] = legs.foot_vel_base.col(i);
  sin.rotation_world_base = imu.R_wb;
  sin.imu_base_velocity = imu_velocity_.velocityBase();
  sin.imu_velocity_valid = imu_velocity_.valid();
  sin.anchor_on_two_feet = profile_.anchor_on_two_feet;
  sin.ground_normal_base = normal_base;
  contact.slip = slip_detector_.update(sin);
  contact.slipping = LegMask(contact.slip.slip_mask) & contact.watched;
  // With recovery off the flags change nothing here either: every stance
  // foot counts, slipping or not, as in the baseline the paper compares
  // against (its Fig. 6: 18 cm of odometry error in 50 cm).
  contact.untrusted = params_.recovery.enabled ? contact.slipping : LegMask();
  return contact;
}

// State estimate: odometry over the stance feet that hold; the terrain plane
// refit after each touch-down through them, with each foot's local plane
// through the feet and the footholds the legs lifted off from (the prior of
// that foot's surface estimate).
Controller::Body Controller::estimateState(const Imu& imu, const Legs& legs, const Contact& contact) {
  estimator_.update(imu.R_wb, imu.specific_force, legs.foot_vel_base, (contact.stance & ~contact.untrusted).bits());
  Body body;
  body.base = estimator_.position();
  for (int i = 0; i < kNumLegs; ++i) body.feet_world.col(i) = body.base + imu.R_wb * legs.foot_base.col(i);
  body.com = body.base + imu.R_wb * legs.com_base;
  body.omega = imu.R_wb * imu.omega_base;
  body.com_vel = estimator_.velocity() + body.omega.cross(body.com - body.base);
  // Off by default: its arguments are not computed then.
  if (com_offset_.enabled())
    com_offset_.update(body.feet_world, legs.grf_world, (contact.stance & ~contact.untrusted).bits(),
                       body.com - imu.R_wb * com_offset_.offsetBase(), imu.R_wb, robot::kTotalMass * robot::kGravity,
                       body.com_vel, imu.omega_base);
  body.foothold_origin = body.base + imu.R_wb * com_offset_.offsetBase();

  const GaitOutput& plan = previous_.gait();
  for (int i = 0; i < kNumLegs; ++i)
    if (plan.liftoff_event.has(i)) terrain_.recordLiftoff(i, body.feet_world.col(i));
  // In the trot the ground is where the feet push: a stance foot that
  // carries less than force_on, or whose leg is at a joint's stop, is not
  // known to be on it. A trot's foot that ends its swing in the air (the
  // trunk rolled by a push, the search given up) is stance to the gait; a
  // plane through it is tilted by its height. (The crawl's feet land slowly
  // and its unloading foot is still on the ground: every stance foot counts.)
  LegMask loaded = LegMask::all();
  if (profile_.plane_through_loaded_feet) {
    loaded = LegMask();
    for (int i = 0; i < kNumLegs; ++i)
      if (legs.grf_world.col(i).dot(previous_.ground_normal) > params_.stance.force_on && !legs.at_stop.has(i))
        loaded.set(i);
  }
  LegMask refit = plan.touchdown_event & loaded;
  // A trot's landing foot is seldom loaded and holding at its touch-down
  // tick (on joints behind a torque loop it skids for a few ms and is not
  // trusted): without it two collinear feet remain and the plane is not
  // refit. Its refit waits, while the foot stands, for the first tick it is
  // loaded and trusted; if fewer than three feet hold then (the other pair
  // already unloaded), that landing gets no refit.
  if (profile_.plane_through_loaded_feet) {
    refit_pending_ = (refit_pending_ | plan.touchdown_event) & plan.stance_mask;
    refit = refit_pending_ & loaded & ~contact.untrusted;
    refit_pending_ = refit_pending_ & ~refit;
  }
  if (refit.any())
    terrain_.fit(body.feet_world, (contact.stance & ~contact.untrusted & loaded).bits(),
                 params_.slip.prior_local_length, params_.slip.prior_inlier_distance, refit.bits(),
                 params_.slip.prior_turn_margin, params_.slip.turn_sets_ground);
  return body;
}

// Surface estimate: n and mu under each slipping foot, from each slip
// sample and the force of the same instant (GrfDelayLine: D ticks old, the
// acceleration centred on it); and the joint-torque offsets, learnt in
// mid-swing.
RecoveryInput Controller::estimateSurfaces(const Imu& imu, const Legs& legs, const Contact& contact,
                                          const Mat3x4& feet_world) {
  const SlipResult& slip = contact.slip;
  for (int i = 0; i < kNumLegs; ++i)
    grf_delay_.pushSlipVelocity(i, slip.slip_velocity_world[i], slip.slip_velocity_valid);
  grf_delay_.advance();
  const bool aligned = grf_delay_.delay() > 0;
  Mat3x4& grf_sample = grf_sample_;
  for (int i = 0; i < kNumLegs; ++i)
    grf_sample.col(i) =
        aligned ? grf_delay_.force(i, legs.qdd.segment<3>(3 * i), legs.alpha_base) : Vec3(legs.grf_world.col(i));

  // Torque offsets: in mid-swing the foot carries nothing, so the model must
  // explain the whole (offset-corrected) torque; -J^T F is what it misses.
  // Not while freezing: the gait then lowers a swinging foot to the ground.
  const GaitOutput& plan = previous_.gait();
  for (int i = 0; i < kNumLegs; ++i) {
    if (plan.leg_phase[i] != LegPhase::kSwing || plan.swing_late[i] || previous_.swing_ticks[i] < settle_ticks_ ||
        previous_.freezing)
      continue;
    torque_bias_.update(i, -(legs.jacobian[i].transpose() * (imu.R_wb.transpose() * grf_sample.col(i))));
  }

  // The base's acceleration error, once a tick and only for a slipping
  // foot's sample (the trot's force estimate has its term). The crawl's
  // samples leave it out: its term is in only while the trunk turns past
  // kCrawlTurnAlphaMin, where the slope's error from the gyro's noise (under
  // 1 rad/s^2) is under a tenth of the term.
  const Vec3 alpha_sigma = aligned && contact.slipping.any() && profile_.grf_base_rotation
                               ? base_alpha_.accelerationSigma(0)
                               : Vec3(Vec3::Zero());
  RecoveryInput rin;
  rin.stance_mask = contact.stance.bits();
  rin.slip_mask = contact.slipping.bits();
  rin.terrain_normal = terrain_.normal();
  const bool feet_now = profile_.prior_from_feet_now;
  for (int i = 0; i < kNumLegs; ++i) {
    const bool slip_i = contact.slipping.has(i);
    SurfaceInput in;
    in.prior = feet_now                          ? terrain_.feetOrRowNormal(i, row_split_)
               : params_.slip.prior_agreed_ground ? terrain_.priorNormal(i)
                                                  : terrain_.localNormal(i);
    // The other row's plane (LF-LH, RF-RH): the ground this foot may stand
    // on where the slope changes between the rows (SlipParams::prior_switch_angle).
    in.alternative_prior = feet_now ? Vec3::Zero() : terrain_.localNormal(i ^ 2);
    in.foot = feet_world.col(i);
    rin.ground_normal[i] = terrain_.groundNormal(i);
    const bool v_valid = aligned ? grf_delay_.slipVelocityValid(i) : slip.slip_velocity_valid;
    Vec3 v = aligned ? grf_delay_.slipVelocity(i) : slip.slip_velocity_world[i];
    // The trot's slips come as the foot is loaded, while the other pair is
    // unloaded: the two pairs' contacts compress and relax along the normal
    // at several cm/s, which is in the slip velocity against them but not a
    // slide (TrotParams::slip_along_ground).
    if (profile_.slip_along_ground) {
      v -= v.dot(in.prior) * in.prior;
    }
    // The sample's force error: the acceleration term's, and the torque
    // offsets' that the leg has not yet learnt in swing, each joint's
    // through its column of J^-T (all alike: sigma |J^-1|_F).
    // Only a sample (the foot slipping, its velocity known) uses it.
    double force_sigma = 0.0;
    if (aligned && slip_i && v_valid) {
      const double accel_sigma = grf_delay_.forceSigma(i, joint_accel_.accelerationSigma(3 * i), alpha_sigma);
      const double remaining = torque_bias_.remainingSigma(i);  // [N m]
      double offset_sigma = 0.0;                                 // [N]
      if (remaining > 0.0) {
        Mat3 j_inverse;
        bool invertible = false;
        legs.jacobian[i].computeInverseWithCheck(j_inverse, invertible, 1e-9);
        offset_sigma = invertible ? remaining * j_inverse.norm() : HUGE_VAL;
      }
      // Both in N, far from overflow; a singular leg's HUGE_VAL stays infinite.
      force_sigma = std::sqrt(accel_sigma * accel_sigma + offset_sigma * offset_sigma);
    }
    in.slipping = slip_i && v_valid;
    in.slip_velocity = v;
    in.grf = grf_sample.col(i);
    in.force_sigma = force_sigma;
    in.history_valid = v_valid;
    surface_[i].update(in);
    rin.estimate_valid[i] = surface_[i].hasEstimate();
    rin.normal_estimate[i] = surface_[i].normal();
    rin.mu_estimate[i] = surface_[i].mu();
    // This event's travel, while the foot slips. A slip velocity taken along
    // the prior (slip_along_ground, the trot's) holds no other plane.
    if (!profile_.slip_along_ground && in.slipping) rin.slip_travel[i] = surface_[i].travel();
    splitForce(legs.grf_world.col(i), previous_.normal_in_use[i], rin.normal_force[i], rin.force_ratio[i]);
  }
  if (probe_.enabled()) takeProbeAnswers(contact, rin);
  if (friction_map_.enabled() && params_.recovery.enabled) useFrictionMap(contact, feet_world, rin);
  return rin;
}

void Controller::takeProbeAnswers(const Contact& contact, RecoveryInput& rin) {
  // A probe's answer of last tick. Its mu is the foot's friction on this
  // foothold, before the estimate from the break-away's own slide: read at
  // a quasi-static break-away under full load, it is the better one (the
  // slide's samples come as the pair is released and the cone narrows).
  // It is a ratio about the normal the probe read it about, and the foot
  // keeps that normal: the slide's own is a millimetre or two along the
  // pair's line, and on MuJoCo (drawn terrain 59) it turned a cone 11 deg
  // off the slope the probe had it on, which the foot then slid down.
  for (int i = 0; i < kNumLegs; ++i) {
    if (!contact.stance.has(i)) probe_mu_[i] = 0.0;
    if (probe_out_.mu_found[i] > 0.0 && contact.stance.has(i)) {
      probe_mu_[i] = probe_out_.mu_found[i];
      probe_normal_[i] = probe_out_.normal_found[i];
    }
    rin.probe_mu[i] = probe_out_.mu_found[i];
    rin.probe_held[i] = probe_out_.mu_held[i];
    if (probe_mu_[i] > 0.0) {
      rin.normal_estimate[i] = probe_normal_[i];
      rin.estimate_valid[i] = true;
      rin.mu_estimate[i] = probe_mu_[i];
    }
  }
}

// The friction map: a slip's last estimate goes into the cell under its
// foot when its flag drops; every foot reads the cell it stands over (the
// recovery takes it at touch-down).
void Controller::useFrictionMap(const Contact& contact, const Mat3x4& feet_world, RecoveryInput& rin) {
  const double time = static_cast<double>(run_ticks_) * params_.dt;  // [s]
  for (int i = 0; i < kNumLegs; ++i) {
    map_writes_[i] = hal::MapWrite{};
    // An estimate the foot has written already is not a new one: a probe's
    // answer holds for its foothold, and a slip's stays until its next
    // sample, on this foothold or the next (not a reading of the next).
    if (contact.slipping.has(i)) {
      if (rin.estimate_valid[i] && rin.mu_estimate[i] != map_written_[i]) map_estimate_[i] = rin.mu_estimate[i];
    } else if (previous_.slipping.has(i)) {
      const FrictionWrite w = friction_map_.add(feet_world(0, i), feet_world(1, i), map_estimate_[i], time);
      if (w.written) {
        map_written_[i] = map_estimate_[i];
        map_writes_[i] = {{w.ix, w.iy}, static_cast<uint32_t>(w.cell.count), w.cell.mu, w.cell.spread};
      }
      map_estimate_[i] = 0.0;
    }
    const FrictionLookup cell = friction_map_.lookup(feet_world(0, i), feet_world(1, i), time);
    rin.map_mu[i] = cell.known ? cell.mu : 0.0;
    map_mu_[i] = rin.map_mu[i];
  }
}

// The friction probe: only in the crawl's four-foot stance at full load,
// with recovery on and not freezing (friction_probe.hpp).
void Controller::probeFriction(const Legs& legs, const Body& body, const Contact& contact, const GaitOutput& plan,
                               Mat3x4& forces) {
  ProbeInput in;
  in.allowed = params_.recovery.enabled && profile_.kind == GaitKind::kCrawl && !recovery_.freezing() &&
               plan.stance_mask == LegMask::all();
  for (int i = 0; i < kNumLegs; ++i)
    if (plan.unloading[i] || plan.load[i] < 1.0) in.allowed = false;
  in.stance = plan.stance_mask;
  in.slipping = contact.slipping;
  for (int i = 0; i < kNumLegs; ++i) {
    in.normal[i] = recovery_.normalInUse(i);
    if (recovery_.knowsFriction(i) || probe_mu_[i] > 0.0) in.known.set(i);
    if (in.normal[i].dot(terrain_.normal()) < probe_cos_normal_ || terrain_.groundStandsIn(i)) in.normal_unsure.set(i);
    in.mu_in_use[i] = recovery_.muInUse(i);
  }
  in.feet = body.feet_world;
  in.grf = legs.grf_world;
  in.grf_sample = grf_sample_;
  in.grf_des = forces;
  in.velocity_valid = contact.slip.slip_velocity_valid;
  for (int i = 0; i < kNumLegs; ++i) in.slip_velocity[i] = contact.slip.slip_velocity_world[i];
  in.fast = LegMask(contact.slip.raw_mask);
  probe_.update(in, params_.dt, probe_out_);
  forces += probe_out_.pair;
}

// Recovery and freeze supervisor: corrects the cones the QP uses toward the
// estimates, and decides whether the robot must freeze.
bool Controller::superviseRecovery(const RecoveryInput& estimates) {
  recovery_.update(estimates, params_.dt);
  return recovery_.freezing();
}

// Motion reference: the gait's plan for this tick.
const GaitOutput& Controller::planMotion(const Imu& imu, const Legs& legs, const Body& body, const Contact& contact,
                                         bool freezing) {
  switchGaitIfDue(body);
  GaitInput gin;
  gin.feet_world = body.feet_world;
  gin.base_world = body.base;
  gin.com_world = body.com;
  gin.foothold_origin = body.foothold_origin;
  gin.com_vel_world = body.com_vel;
  gin.omega_world = body.omega;
  gin.paused = freezing;
  // The trot's cautiousness: its speed follows the lowest mu in use (part
  // of the recovery; without it the commands are the operator's).
  if (params_.recovery.enabled) {
    double friction = kNoFrictionLimit;
    for (int i = 0; i < kNumLegs; ++i)
      if (recovery_.muInUse(i) < friction) friction = recovery_.muInUse(i);
    // A stance braking under the floor (TractionRecovery::floorUnderEstimate)
    // slows the trot no more than the floor does.
    gin.friction = friction > params_.recovery.mu_floor ? friction : params_.recovery.mu_floor;
    gin.traction = friction * params_.recovery.pyramid_scale;
  }
  // Touch-down: the foot pushes along the terrain normal (in the crawl
  // sooner on ground the map knows to be ice, unless the foot rises:
  // kKnownIceTouchdownShare).
  const bool map = friction_map_.enabled() && params_.recovery.enabled && profile_.early_touchdown_on_known_ice;
  for (int i = 0; i < kNumLegs; ++i) {
    gin.normal_force[i] = legs.grf_world.col(i).dot(terrain_.normal());
    // A trot's leg at a joint's stop reads the stop's reaction, not the ground's.
    const bool at_stop = profile_.stop_is_not_touchdown && legs.at_stop.has(i);
    double force_on = params_.stance.force_on;  // [N]
    if (map && !contact.stance.has(i) && map_mu_[i] > 0.0 && map_mu_[i] < params_.recovery.mu_default) {
      // The foot's velocity along the normal (W): the base's estimate (from
      // the trusted stance feet and the IMU, never this landing foot) plus
      // the leg's own.
      const Vec3 v_foot = estimator_.velocity() + imu.R_wb * legs.foot_vel_base.col(i);
      const bool rising = v_foot.dot(terrain_.normal()) > kKnownIceTouchdownRise;
      if (!rising) force_on *= kKnownIceTouchdownShare;
    }
    if (gin.normal_force[i] > force_on && !at_stop) gin.touchdown_mask.set(i);
  }
  // A landing foot flagged as sliding is on the ground: stance now, so the
  // QP (under the corrected cone) takes it over from the swing PD, whose
  // pull toward the swing target is what drags it. Part of the recovery.
  if (params_.recovery.enabled) gin.touchdown_mask |= contact.slipping & ~contact.stance;
  // A landing foot dragged along the ground below the slip threshold is on
  // the ground too: in the crawl, stance now, whether recovery is on or not
  // (the trot's landings slide by design).
  if (profile_.drag_is_touchdown) gin.touchdown_mask |= LegMask(contact.slip.drag_mask) & ~contact.stance;
  // Written in place, in the slot that is not last tick's (PreviousTick::next).
  GaitOutput& plan = previous_.next();
  clearPlan(plan);
  gait().update(gin, terrain_, plan);
  return plan;
}

// Trunk wrench: follow the terrain's inclination, hold the heading, track
// the plan's CoM. The pitch and roll that lay the trunk on the terrain are
// taken in the heading's frame (x along the heading): a slope across the
// walk rolls the trunk, one along it pitches it, whatever the heading.
Vec6 Controller::trunkWrench(const Imu& imu, const Legs& legs, const Body& body, const GaitOutput& plan) const {
  const Mat3 R_des = terrainAttitude(plan.yaw_des, terrain_.normal(), params_.gait.max_tilt);
  Vec3 com_des = plan.com_des;
  com_des.z() = terrain_.heightAt(com_des.x(), com_des.y()) + params_.gait.body_height - plan.crouch +
                (imu.R_wb * legs.com_base).z();
  const Vec3 omega_world = imu.R_wb * imu.omega_base;
  Vec6 wrench;
  wrench.head<3>() = params_.trunk.kp_lin * (com_des - body.com) +
                     params_.trunk.kd_lin * (plan.com_vel_des - body.com_vel) +
                     robot::kTotalMass * (plan.com_acc_des + Vec3(0.0, 0.0, robot::kGravity));
  wrench.tail<3>() = params_.trunk.kp_ang * rotationLog(R_des * imu.R_wb.transpose()) -
                     params_.trunk.kd_ang * omega_world;
  return wrench;
}

// GRF QP: the stance feet's forces under each foot's friction pyramid.
GrfOutput Controller::distributeForces(const Vec6& wrench, const Legs& legs, const Body& body,
                                       const GaitOutput& plan) {
  GrfInput qin;
  qin.wrench_des = wrench;
  for (int i = 0; i < kNumLegs; ++i) {
    qin.stance[i] = plan.stance_mask.has(i);
    qin.foot_from_com.col(i) = body.feet_world.col(i) - body.com;
    qin.normal.col(i) = recovery_.normalInUse(i);
    qin.mu[i] = recovery_.muInUse(i);
    qin.mu_across[i] = recovery_.muAcross(i);
    qin.max_normal_force[i] = plan.max_normal_force[i];
  }
  // Continuity: a stance foot starts from last tick's force; a foot that has
  // just touched down from the force it measurably pushes with.
  qin.smoothing = params_.qp.force_smoothing;
  // The cone offset is measured in the crawl; the trot keeps the plain pyramid.
  qin.cone_offset = profile_.cone_force_offset;
  for (int i = 0; i < kNumLegs; ++i)
    qin.force_previous.col(i) =
        plan.touchdown_event.has(i) ? Vec3(legs.grf_world.col(i)) : Vec3(previous_.grf_des_world.col(i));
  GrfOutput out;
  grf_qp_.solve(qin, out, &stage_timer_);
  return out;
}

// Joint commands: stance legs push their QP force through J^T, swing legs
// track the gait's foot reference.
void Controller::jointCommands(const Imu& imu, const Legs& legs, const Body& body, const Contact& contact,
                               const GaitOutput& plan, const Mat3x4& grf_des, hal::CommandFrame& command) const {
  const SlipResult& slip = contact.slip;
  for (int leg = 0; leg < kNumLegs; ++leg) {
    Vec3 tau, q_ref = legs.q.col(leg), qd_ref = Vec3::Zero();
    Vec3 kp = Vec3::Zero(), kd = Vec3::Constant(params_.joint.stance_kd);
    if (plan.stance_mask.has(leg)) {
      Vec3 f_cmd = grf_des.col(leg);
      // Slip damping: a flagged foot is asked for D v_slip less force
      // against its slip, so kinetic friction decelerates it (RecoveryParams).
      if (params_.recovery.enabled && LegMask(slip.slip_mask).has(leg) && slip.slip_velocity_valid)
        f_cmd += slipDampingGain(leg, legs) * dampedSlipVelocity(leg, slip, plan);
      tau = legs.gravity_torque[leg] - legs.jacobian[leg].transpose() * (imu.R_wb.transpose() * f_cmd);
      stanceHold(leg, legs, slip, kd, qd_ref);
    } else {
      const Vec3 p_des = imu.R_wb.transpose() * (plan.foot_des[leg] - body.base);
      const Vec3 v_des = imu.R_wb.transpose() * (plan.foot_vel_des[leg] - estimator_.velocity()) -
                         imu.omega_base.cross(p_des);
      legInverseKinematics(leg, p_des, q_ref);
      Mat3 jacobian_inverse;
      if (invert3(footJacobianBase(leg, q_ref), jacobian_inverse)) qd_ref = jacobian_inverse * v_des;
      for (int k = 0; k < 3; ++k) qd_ref[k] = clampAbs(qd_ref[k], robot::kVelocityLimit);
      swingGains(leg, legs, kp, kd);
      const bool on_ground = (contact.watched | contact.held).has(leg);  // a landing foot slip detection watches
      if (on_ground) pressAlongNormal(leg, imu, legs, kp, q_ref, qd_ref);
      tau = legs.gravity_torque[leg];
      if (profile_.swing_inertia_feedforward) tau += swingInertiaTorque(leg, imu, legs, plan);
      // A landing foot on the ground pushes with a force, not only through
      // its swing PD (kLandingPressShare).
      if (profile_.landing_force_press && on_ground)
        tau -= legs.jacobian[leg].transpose() *
               (imu.R_wb.transpose() * (terrain_.normal() * (kLandingPressShare * params_.stance.force_on)));
    }
    for (int k = 0; k < 3; ++k) {
      const int j = 3 * leg + k;
      command.tau_ff[j] = clampAbs(tau[k], robot::kEffortLimit);
      command.q_ref[j] = q_ref[k];
      command.qd_ref[j] = qd_ref[k];
      command.kp[j] = kp[k];
      command.kd[j] = kd[k];
    }
  }
}

// A swinging leg's joint gains from its inertia (JointParams): each joint's
// damping loop crosses over at a fraction of the torque loop's bandwidth,
// its stiffness critically damped, both capped by swing_kp and swing_kd.
void Controller::swingGains(int leg, const Legs& legs, Vec3& kp, Vec3& kd) const {
  const JointParams& joint = params_.joint;
  kp = Vec3::Constant(joint.swing_kp);
  kd = Vec3::Constant(joint.swing_kd);
  if (joint.torque_bandwidth <= 0.0) return;
  // The legs stage computed the mass matrix when the GRF estimate uses the leg dynamics.
  const Mat3 mass = params_.estimator.grf_leg_dynamics ? legs.mass[leg] : legMassMatrix(leg, legs.q.col(leg));
  const double wc = swingCrossover(joint);
  for (int k = 0; k < 3; ++k) {
    kd[k] = std::min(kd[k], mass(k, k) * wc);
    kp[k] = std::min(kp[k], 0.25 * mass(k, k) * wc * wc);
  }
}

// With joints behind a torque loop (JointParams::torque_bandwidth)
// (GaitProfile::stance_hold), a stance leg's joints are damped
// toward the velocity of a foot that holds (the slip detector's
// u_reference less the trunk's rotation at that foot, B), with the swing
// joints' damping. The force commands alone leave a lightly loaded foot to
// the model's errors: on the hyq plant the leg's torques that were meant to
// give 10 N dragged such feet at 0.1-0.25 m/s for 100-250 ms while the body
// moved over them. A foot that holds moves at that velocity: the damping
// then costs nothing. hyq plant, seeds 1-4, longest slip after detection
// without the hold / with it: ice_010 141-418 / 46-50 ms, ice_patches
// 180-204 / 35-38, two_feet_ice 121-148 / 34-80, ramp 95-229 / 33-37.
// In the trot only a stance leg that carries less than force_watch: one
// whose foot is in the air (the trunk tipped away from it, or a landing the
// gait took for one) would otherwise be driven with the stance's torques
// against nothing, its knee past 30 rad/s within 10 ms on the hyq plant
// without the valves' limit, and the frame check would take such frames for
// corrupt. Loaded, a trot's
// foot keeps its slides, which its friction estimates are read from (the
// hold on every stance foot leaves trot_ice_patches without an estimate).
void Controller::stanceHold(int leg, const Legs& legs, const SlipResult& slip, Vec3& kd, Vec3& qd_ref) const {
  if (!profile_.stance_hold || !slip.slip_velocity_valid) return;
  if (profile_.stance_hold_unloaded_only &&
      legs.grf_world.col(leg).dot(previous_.ground_normal) > params_.stance.force_watch)
    return;
  Mat3 jacobian_inverse;
  if (!invert3(legs.jacobian[leg], jacobian_inverse)) return;
  Vec3 kp_unused;
  swingGains(leg, legs, kp_unused, kd);
  // u_i = J qd + w x p: the trunk's rotation's part at this foot is not the leg's.
  const Vec3 rotation = legs.foot_vel_base.col(leg) - legs.jacobian[leg] * legs.qd.col(leg);
  qd_ref = jacobian_inverse * (slip.u_reference - rotation);
  for (int k = 0; k < 3; ++k) qd_ref[k] = clampAbs(qd_ref[k], robot::kVelocityLimit);
}

// The slip damping of a flagged stance foot [N s/m]: RecoveryParams::
// slip_damping, and with joints behind a torque loop (JointParams::
// torque_bandwidth) at most m wc, m the leg's own apparent mass at the foot
// and wc the swing joints' crossover. The damping pushes on the foot through
// the leg; while the foot carries little load nothing heavier than the leg
// moves with it, and D / m above the torque loop's bandwidth oscillates (the
// lower leg's 0.2 kg at the foot: D 100 N s/m is 72 Hz; on the hyq plant a
// landing hind foot rang at 30-40 Hz up to 11 m/s). m is bounded from below
// by 1 / trace(J M^-1 J^T), the smallest eigenvalue of the foot's
// operational-space inertia at least that.
double Controller::slipDampingGain(int leg, const Legs& legs) const {
  const double d = params_.recovery.slip_damping;
  const JointParams& joint = params_.joint;
  if (joint.torque_bandwidth <= 0.0) return d;
  const Mat3 mass = params_.estimator.grf_leg_dynamics ? legs.mass[leg] : legMassMatrix(leg, legs.q.col(leg));
  Mat3 mass_inverse;
  if (!invert3(mass, mass_inverse)) return 0.0;
  const Mat3& jacobian = legs.jacobian[leg];
  const double trace = (jacobian * mass_inverse * jacobian.transpose()).trace();  // [1/kg]
  if (!(trace > 0.0)) return 0.0;
  return std::min(d, swingCrossover(joint) / trace);
}

// In the crawl, a landing foot on the ground (watched or held for slips) is
// pressed along the ground's normal only: the swing PD's pull toward its
// target along the ground is what drags a lightly loaded foot before the
// stance trigger. The PD's stiffness torque K (q_ref - q) acts on the
// ground as f = J^-T K (q_ref - q), K = diag(kp); q_ref keeps the part of f
// along the normal: K (q_ref' - q) = J^T n (n . f). Only kp's ratios
// matter (S = kp / max kp): joints of one stiffness get S = I exactly,
// and a knee softer than the hips (JointParams::torque_bandwidth) does not
// turn the hips' pull into one along the ground. The reference velocity
// keeps its part along the normal and, along the ground, is that of a foot
// that holds (last tick's reference foot velocity, B): the damping then
// acts on the foot's slip, not on the body moving over it.
void Controller::pressAlongNormal(int leg, const Imu& imu, const Legs& legs, const Vec3& kp, Vec3& q_ref,
                                  Vec3& qd_ref) const {
  if (!profile_.press_landing_along_normal) return;
  const Mat3& jacobian = legs.jacobian[leg];
  Mat3 jacobian_inverse;
  if (!invert3(jacobian, jacobian_inverse)) return;
  const Vec3 n = imu.R_wb.transpose() * terrain_.normal();
  const double kp_max = kp.maxCoeff();
  if (kp_max > 0.0) {
    const Vec3 ratio = kp / kp_max;  // [-] S
    const Vec3 q = legs.q.col(leg);
    const Vec3 f = jacobian_inverse.transpose() * ratio.cwiseProduct(q_ref - q);
    q_ref = q + (jacobian.transpose() * (n * n.dot(f))).cwiseQuotient(ratio);
  }
  const Vec3 holding = previous_.slip.slip_velocity_valid ? previous_.slip.u_reference : Vec3::Zero();  // [m/s] B
  const Vec3 v = jacobian * qd_ref;
  qd_ref = jacobian_inverse * (n * n.dot(v) + holding - n * n.dot(holding));
  for (int k = 0; k < 3; ++k) qd_ref[k] = clampAbs(qd_ref[k], robot::kVelocityLimit);
}

// slipDampingVelocity's inputs for a leg: this and last tick's slip
// velocity, the cone's normal in use, and whether its load still ramps up
// after touch-down.
Vec3 Controller::dampedSlipVelocity(int leg, const SlipResult& slip, const GaitOutput& plan) const {
  const SlipResult& last = previous_.slip;
  const bool landing = plan.load[leg] < 1.0 && !plan.unloading[leg];
  return slipDampingVelocity(slip.slip_velocity_world[leg], last.slip_velocity_world[leg], last.slip_velocity_valid,
                             recovery_.normalInUse(leg), landing);
}

// The trot's swings accelerate a foot at up to ~50 m/s^2: the leg's inertia
// times the reference's joint acceleration, fed forward (the motion of the
// base and the velocity terms left out).
Vec3 Controller::swingInertiaTorque(int leg, const Imu& imu, const Legs& legs, const GaitOutput& plan) const {
  Mat3 jacobian_inverse;
  if (!invert3(footJacobianBase(leg, legs.trig[leg]), jacobian_inverse)) return Vec3::Zero();
  const Vec3 qdd = jacobian_inverse * (imu.R_wb.transpose() * plan.foot_acc_des[leg]);
  // The legs stage computed the mass matrix when the GRF estimate uses the
  // leg dynamics.
  if (params_.estimator.grf_leg_dynamics) return legs.mass[leg] * qdd;
  return legMassMatrix(leg, legs.q.col(leg)) * qdd;
}

void Controller::fillTelemetry(const Legs& legs, const GaitOutput& plan, LegMask slipping,
                               const Mat3x4& grf_des, bool map_writes, hal::Telemetry& t) const {
  t.stance_mask = plan.stance_mask.bits();
  t.slip_mask = slipping.bits();
  t.swing_leg = static_cast<uint32_t>(plan.swing_leg);
  t.gait_phase = plan.phase;
  t.probe_leg = static_cast<uint32_t>(probe_out_.leg);
  t.probe_partner = static_cast<uint32_t>(probe_out_.partner);
  t.probe_counts[0] = probe_.started();
  t.probe_counts[1] = probe_.found();
  t.probe_counts[2] = probe_.held();
  copy3(estimator_.position(), t.base_pos_est);
  copy3(estimator_.velocity(), t.base_vel_est);
  for (int i = 0; i < kNumLegs; ++i) {
    copy3(legs.foot_vel_base.col(i), t.foot_vel_base[i]);
    copy3(legs.grf_world.col(i), t.grf_est[i]);
    copy3(grf_des.col(i), t.grf_des[i]);
    t.mu_used[i] = recovery_.muInUse(i);
    copy3(recovery_.normalInUse(i), t.normal_used[i]);
    t.mu_hat[i] = probe_mu_[i] > 0.0 ? probe_mu_[i] : surface_[i].hasEstimate() ? surface_[i].mu() : 0.0;
    copy3(surface_[i].hasEstimate() ? surface_[i].normal() : Vec3(Vec3::Zero()), t.normal_hat[i]);
  }
  // The map's writes of this tick (a repeated tick wrote nothing).
  if (map_writes)
    for (int i = 0; i < kNumLegs; ++i) t.map_writes[i] = map_writes_[i];
  else
    for (hal::MapWrite& w : t.map_writes) w = hal::MapWrite{};
}

}  // namespace hyq
