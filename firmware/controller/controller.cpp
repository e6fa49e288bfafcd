#include "firmware/controller/controller.hpp"

#include <cmath>

#include "firmware/controller/kinematics.hpp"
#include "firmware/controller/robot_params.hpp"

namespace hyq {

namespace {

bool finite(const double* v, int n) {
  for (int i = 0; i < n; ++i)
    if (!std::isfinite(v[i])) return false;
  return true;
}

Vec3 legVec(const double* a, int leg) { return Vec3(a[3 * leg], a[3 * leg + 1], a[3 * leg + 2]); }

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

}  // namespace

bool sensorFrameValid(const hal::SensorFrame& f, const SafetyParams& lim) {
  if (!finite(f.q, hal::kNumJoints) || !finite(f.qd, hal::kNumJoints) ||
      !finite(f.tau, hal::kNumJoints) || !finite(f.imu_quat, 4) || !finite(f.imu_gyro, 3) ||
      !finite(f.imu_acc, 3))
    return false;
  for (int j = 0; j < hal::kNumJoints; ++j) {
    double lo, hi;
    robot::jointLimits(j / 3, j % 3, lo, hi);
    if (f.q[j] < lo - lim.joint_range_margin || f.q[j] > hi + lim.joint_range_margin) return false;
    if (std::fabs(f.qd[j]) > lim.max_joint_velocity) return false;
    if (std::fabs(f.tau[j]) > lim.max_joint_torque) return false;
  }
  const double qn = std::sqrt(f.imu_quat[0] * f.imu_quat[0] + f.imu_quat[1] * f.imu_quat[1] +
                              f.imu_quat[2] * f.imu_quat[2] + f.imu_quat[3] * f.imu_quat[3]);
  if (std::fabs(qn - 1.0) > lim.quat_norm_tol) return false;
  for (int k = 0; k < 3; ++k) {
    if (std::fabs(f.imu_gyro[k]) > lim.max_gyro) return false;
    if (std::fabs(f.imu_acc[k]) > lim.max_acc) return false;
  }
  return true;
}

void Controller::init(const Params& params) {
  params_ = params;
  initialised_ = true;
  started_ = false;
  have_good_ = false;
  was_bad_ = false;
  frozen_ = false;
  unfreeze_time_ = 1e9;
  last_tau_.setZero();
  estimator_.reset(params_.estimator, params_.dt);
  gyro_bias_.reset(params_.estimator, params_.dt);
  torque_bias_.reset(params_.estimator, params_.dt);
  for (int& n : swing_ticks_) n = 0;
  terrain_.reset(0.0);
  imu_velocity_.reset(params_.slip);
  restartAccelerations();
  slip_detector_.reset(params_.slip);
  slip_ = SlipResult{};
  for (int i = 0; i < 4; ++i) surface_[i].reset(params_.slip);
  recovery_.reset(params_.recovery);
  grf_qp_.init(params_.qp, params_.recovery.pyramid_scale);
  grf_des_world_.setZero();
  last_tau_.setZero();
  qp_flags_ = 0;
}

void Controller::restartAccelerations() {
  const EstimatorParams& e = params_.estimator;
  joint_accel_.reset(e.grf_accel_window, params_.dt);
  // The friction and normal estimates wait for the acceleration centred on
  // their tick (none without the leg dynamics); GrfDelayLine clamps it.
  const bool aligned = e.grf_leg_dynamics && e.grf_estimate_aligned;
  grf_delay_.reset(aligned ? joint_accel_.centreLag() : 0);
}

Vec3 Controller::comBase() const {
  Vec3 com = robot::kTrunkMass * Vec3(robot::kTrunkCom[0], robot::kTrunkCom[1], robot::kTrunkCom[2]);
  const double masses[3] = {robot::kHipMass, robot::kUpperMass, robot::kLowerMass};
  for (int leg = 0; leg < 4; ++leg)
    for (int link = 0; link < kLinksPerLeg; ++link)
      com += masses[link] * linkComPositionBase(leg, link, legs_.q.col(leg));
  return com / robot::kTotalMass;
}

void Controller::computeLegs(const hal::SensorFrame& s, const Mat3& R_wb,
                             const Vec3& specific_force) {
  const bool dynamics = params_.estimator.grf_leg_dynamics;
  const Vec3 gravity_base = R_wb.transpose() * Vec3(0.0, 0.0, -robot::kGravity);
  Vec12 qd_all;
  for (int j = 0; j < hal::kNumJoints; ++j) qd_all[j] = s.qd[j];
  const Vec12 qdd_all = joint_accel_.update(qd_all);
  legs_.qdd = qdd_all;
  // With the leg dynamics, the links accelerate with the base as well as
  // fall: gravity minus the base's acceleration is minus the accelerometer's
  // specific force (base angular acceleration and Coriolis terms left out).
  const Vec3 apparent_gravity = dynamics && specific_force.allFinite() ? Vec3(-specific_force) : gravity_base;
  const Vec3 normal_base = R_wb.transpose() * terrain_.normal();
  for (int leg = 0; leg < 4; ++leg) {
    const Vec3 q = legVec(s.q, leg), qd = legVec(s.qd, leg);
    const Vec3 tau = legVec(s.tau, leg) - torque_bias_.bias(leg);
    legs_.q.col(leg) = q;
    legs_.qd.col(leg) = qd;
    legs_.tau.col(leg) = tau;
    legs_.foot_base.col(leg) = footPositionBase(leg, q);
    const Mat3 centre_jacobian = footJacobianBase(leg, q);
    legs_.foot_vel_base.col(leg) = centre_jacobian * qd + omega_base_.cross(legs_.foot_base.col(leg));
    legs_.jacobian[leg] = params_.estimator.grf_contact_point
                              ? contactJacobianFromCentre(leg, q[0], centre_jacobian, normal_base)
                              : centre_jacobian;
    // tau - b qd = M qdd + g - J^T f  =>  f = -J^-T (tau - b qd - g - M qdd).
    // A singular leg gives no estimate.
    // Split as f = f_static + A qdd with A = J^-T M, so that the delay line
    // can pair a tick's f_static with the acceleration centred on it.
    Vec3 rest;
    Mat3 mass = Mat3::Zero();
    if (dynamics) {
      const LegInertia model = legInertia(leg, q, gravity_base, apparent_gravity);
      legs_.gravity_torque[leg] = model.holding_a;
      rest = tau - robot::kJointDamping * qd - model.holding_b;
      mass = model.mass;
    } else {
      legs_.gravity_torque[leg] = legGravityTorque(leg, q, gravity_base);
      rest = tau - legs_.gravity_torque[leg];
    }
    const Eigen::FullPivLU<Mat3> lu(legs_.jacobian[leg].transpose());
    Vec3 f_static = Vec3::Zero();
    Mat3 accel_map = Mat3::Zero();
    if (lu.isInvertible()) {
      f_static = -lu.solve(rest);
      // Column by column: Eigen's matrix right-hand side goes through its
      // blocked triangular solver, which allocates a workspace.
      if (dynamics)
        for (int c = 0; c < 3; ++c) accel_map.col(c) = lu.solve(Vec3(mass.col(c)));
    }
    const Vec3 f_static_world = R_wb * f_static;
    const Mat3 accel_map_world = R_wb * accel_map;
    legs_.grf_world.col(leg) = f_static_world + accel_map_world * qdd_all.segment<3>(3 * leg);
    grf_delay_.pushForce(leg, f_static_world, accel_map_world);
  }
}

void Controller::start() {
  estimator_.initialise(R_wb_, legs_.foot_base);
  Mat3x4 feet_world;
  for (int i = 0; i < 4; ++i)
    feet_world.col(i) = estimator_.position() + R_wb_ * legs_.foot_base.col(i);
  terrain_.fit(feet_world, 0xF);
  recovery_.reset(params_.recovery, terrain_.normal());
  Mat3x4 nominal;
  for (int leg = 0; leg < 4; ++leg) {
    const Vec3 q(robot::standAngle(leg, 0), robot::standAngle(leg, 1), robot::standAngle(leg, 2));
    nominal.col(leg) = footPositionBase(leg, q);
  }
  GaitInput gin;
  gin.feet_world = feet_world;
  gin.base_world = estimator_.position();
  gin.com_world = estimator_.position() + R_wb_ * com_base_;
  const double yaw = std::atan2(R_wb_(1, 0), R_wb_(0, 0));
  gait_.reset(params_.gait, params_.dt, gin, yaw, nominal);
  started_ = true;
}

void Controller::safeHold(hal::CommandFrame& cmd, uint32_t flags) const {
  for (int j = 0; j < hal::kNumJoints; ++j) {
    cmd.q_ref[j] = have_good_ ? last_good_.q[j] : robot::standAngle(j / 3, j % 3);
    cmd.qd_ref[j] = 0.0;
    cmd.kp[j] = params_.joint.posture_kp;
    cmd.kd[j] = params_.joint.posture_kd;
    cmd.tau_ff[j] = 0.0;
  }
  cmd.flags = flags;
}

void Controller::freezeCommand(hal::CommandFrame& cmd) {
  for (int j = 0; j < hal::kNumJoints; ++j) {
    cmd.q_ref[j] = freeze_q_[j];
    cmd.qd_ref[j] = 0.0;
    cmd.kp[j] = params_.joint.posture_kp;
    cmd.kd[j] = params_.joint.posture_kd;
    cmd.tau_ff[j] = freeze_tau_[j];
  }
}

void Controller::blendCommands(const hal::CommandFrame& from, double alpha, hal::CommandFrame& to) {
  // tau = tau_ff + kp (q_ref - q) + kd (qd_ref - qd) is linear in (tau_ff,
  // kp, kp q_ref, kd, kd qd_ref): blending those blends the applied torque.
  const double a = alpha < 0.0 ? 0.0 : (alpha > 1.0 ? 1.0 : alpha), b = 1.0 - a;
  for (int j = 0; j < hal::kNumJoints; ++j) {
    const double kp = a * to.kp[j] + b * from.kp[j];
    const double kd = a * to.kd[j] + b * from.kd[j];
    const double kp_q = a * to.kp[j] * to.q_ref[j] + b * from.kp[j] * from.q_ref[j];
    const double kd_qd = a * to.kd[j] * to.qd_ref[j] + b * from.kd[j] * from.qd_ref[j];
    to.tau_ff[j] = a * to.tau_ff[j] + b * from.tau_ff[j];
    to.q_ref[j] = kp > 0.0 ? kp_q / kp : to.q_ref[j];
    to.qd_ref[j] = kd > 0.0 ? kd_qd / kd : to.qd_ref[j];
    to.kp[j] = kp;
    to.kd[j] = kd;
  }
}

void Controller::step(const hal::SensorFrame& s, hal::CommandFrame& cmd) {
  cmd = hal::CommandFrame{};
  cmd.tick = s.tick;
  if (!initialised_) {
    safeHold(cmd, hal::kFlagNotInitialised);
    return;
  }
  if (!sensorFrameValid(s, params_.safety)) {
    safeHold(cmd, hal::kFlagBadSensorFrame);
    was_bad_ = true;
    // The acceleration filter's samples must be a tick apart, and so must
    // the gyro-bias filter's attitudes: start again.
    restartAccelerations();
    gyro_bias_.restart();
    // The delay line refills: no torque-offset sample until a swing has
    // settled again on fresh estimates.
    for (int& n : swing_ticks_) n = 0;
    fillTelemetry(cmd, slip_.slip_mask);
    return;
  }
  last_good_ = s;
  have_good_ = true;

  const Quat quat(s.imu_quat[0], s.imu_quat[1], s.imu_quat[2], s.imu_quat[3]);
  R_wb_ = quat.normalized().toRotationMatrix();
  // IMU readings less their estimated biases, for everything downstream.
  omega_base_ = gyro_bias_.update(R_wb_, Vec3(s.imu_gyro[0], s.imu_gyro[1], s.imu_gyro[2]));
  const Vec3 specific_force = Vec3(s.imu_acc[0], s.imu_acc[1], s.imu_acc[2]) - estimator_.accBias();
  computeLegs(s, R_wb_, specific_force);
  com_base_ = comBase();
  if (!started_) start();
  if (was_bad_) {
    gait_.replanFrom(estimator_.position() + R_wb_ * com_base_);
    was_bad_ = false;
  }

  const double dt = params_.dt;
  const uint32_t stance = gait_out_.stance_mask;
  // Feet the detector watches: the stance feet, and a landing foot that
  // already pushes on the ground (a slide at touch-down starts before the
  // stance trigger; caught here, its estimate is ready when stance begins).
  uint32_t watched = stance;
  for (int i = 0; i < 4; ++i)
    if (gait_.legPhase(i) != LegPhase::kStance && gait_out_.swing_late[i] &&
        legs_.grf_world.col(i).dot(terrain_.normal()) > params_.stance.force_watch)
      watched |= 1u << i;

  // Slip detection in B, free of any base-velocity estimate (Algorithm 1),
  // with the IMU integration as the second opinion when several legs slip.
  // Anchored to last tick's base velocity from the stance legs, only while
  // those legs agree (a two-foot slip corrupts their mean before any flag).
  imu_velocity_.update(specific_force, R_wb_, Vec3(0.0, 0.0, -robot::kGravity), dt,
                       slip_.base_velocity_legs, slip_.legs_agree);
  SlipInput sin;
  sin.stance_mask = watched;
  sin.landing_mask = watched & ~stance;
  for (int i = 0; i < 4; ++i) sin.u[i] = legs_.foot_vel_base.col(i);
  sin.rotation_world_base = R_wb_;
  sin.imu_base_velocity = imu_velocity_.velocityBase();
  sin.imu_velocity_valid = imu_velocity_.valid();
  sin.ground_normal_base = R_wb_.transpose() * terrain_.normal();
  slip_ = slip_detector_.update(sin);
  const uint32_t slipping = slip_.slip_mask & watched;
  // Feet the odometry and the plane fit leave out: the flagged ones, with
  // recovery on. With it off the flags change nothing, here either: every
  // stance foot counts, slipping or not, as in the baseline the paper
  // compares against (its Fig. 6: 18 cm of odometry error in 50 cm).
  const uint32_t untrusted = params_.recovery.enabled ? slipping : 0u;

  // Odometry over the stance feet that hold (all stance feet, recovery off).
  estimator_.update(R_wb_, specific_force, legs_.foot_vel_base, stance & ~untrusted);
  const Vec3 base = estimator_.position();
  Mat3x4 feet_world;
  for (int i = 0; i < 4; ++i) feet_world.col(i) = base + R_wb_ * legs_.foot_base.col(i);
  const Vec3 com = base + R_wb_ * com_base_;
  const Vec3 com_vel = estimator_.velocity() + (R_wb_ * omega_base_).cross(com - base);

  // Terrain plane at each touch-down, through the feet that hold (all, recovery off);
  // with it each foot's local plane through the feet and the footholds the
  // legs lifted off from, the prior of that foot's surface estimate.
  for (int i = 0; i < 4; ++i)
    if (gait_out_.liftoff_event & (1u << i)) terrain_.recordLiftoff(i, feet_world.col(i));
  if (gait_out_.touchdown_event)
    terrain_.fit(feet_world, stance & ~untrusted, params_.slip.prior_local_length);

  // Estimate n and mu under slipping feet; correct what the QP uses.
  RecoveryInput rin;
  rin.stance_mask = stance;
  rin.slip_mask = slipping;
  rin.terrain_normal = terrain_.normal();
  // The estimates take each slip sample with the force of the same instant
  // (GrfDelayLine): D ticks old, the acceleration centred on it.
  for (int i = 0; i < 4; ++i)
    grf_delay_.pushSlipVelocity(i, slip_.slip_velocity_world[i], slip_.slip_velocity_valid);
  grf_delay_.advance();
  const bool aligned = grf_delay_.delay() > 0;
  // Each leg's force at the instant its samples refer to: D ticks back with
  // the acceleration centred there, or this tick's estimate.
  Mat3x4 grf_sample;
  const Vec12 qdd_sigma = joint_accel_.accelerationSigma();
  for (int i = 0; i < 4; ++i)
    grf_sample.col(i) = aligned ? grf_delay_.force(i, legs_.qdd.segment<3>(3 * i)) : Vec3(legs_.grf_world.col(i));
  // Torque offsets: in mid-swing the foot carries nothing, so the model must
  // explain the whole (offset-corrected) torque; -J^T F is what it misses.
  // Not while freezing: the gait then lowers a swinging foot to the ground.
  const int settle = static_cast<int>(params_.estimator.torque_bias_settle / dt + 0.5);
  for (int i = 0; i < 4; ++i) {
    if (gait_.legPhase(i) != LegPhase::kSwing || gait_out_.swing_late[i] || swing_ticks_[i] < settle ||
        recovery_.freezing())
      continue;
    torque_bias_.update(i, -(legs_.jacobian[i].transpose() * (R_wb_.transpose() * grf_sample.col(i))));
  }
  for (int i = 0; i < 4; ++i) {
    const bool slip_i = (slipping >> i) & 1u;
    surface_[i].setPrior(terrain_.localNormal(i));
    const bool v_valid = aligned ? grf_delay_.slipVelocityValid(i) : slip_.slip_velocity_valid;
    const Vec3 v = aligned ? grf_delay_.slipVelocity(i) : slip_.slip_velocity_world[i];
    // The sample's force error: the acceleration term's, and the torque
    // offsets' that the leg has not yet learnt in swing, each joint's
    // through its column of J^-T (all alike: sigma |J^-1|_F).
    double force_sigma = 0.0;
    if (aligned && slip_i) {
      const double accel_sigma = grf_delay_.forceSigma(i, qdd_sigma.segment<3>(3 * i));
      const double remaining = torque_bias_.remainingSigma(i);  // [N m]
      double offset_sigma = 0.0;                                 // [N]
      if (remaining > 0.0) {
        Mat3 j_inverse;
        bool invertible = false;
        legs_.jacobian[i].computeInverseWithCheck(j_inverse, invertible, 1e-9);
        offset_sigma = invertible ? remaining * j_inverse.norm() : HUGE_VAL;
      }
      force_sigma = std::hypot(accel_sigma, offset_sigma);
    }
    surface_[i].update(slip_i && v_valid, v, grf_sample.col(i), force_sigma);
    rin.estimate_valid[i] = surface_[i].hasEstimate();
    rin.normal_estimate[i] = surface_[i].normal();
    rin.mu_estimate[i] = surface_[i].mu();
    rin.normal_force[i] = legs_.grf_world.col(i).dot(recovery_.normalInUse(i));
  }
  recovery_.update(rin, dt);
  const bool freezing = recovery_.freezing();

  // Touch-down: the foot pushes along the terrain normal.
  GaitInput gin;
  gin.feet_world = feet_world;
  gin.base_world = base;
  gin.com_world = com;
  gin.paused = freezing;
  for (int i = 0; i < 4; ++i)
    if (legs_.grf_world.col(i).dot(terrain_.normal()) > params_.stance.force_on)
      gin.touchdown_mask |= 1u << i;
  // A landing foot flagged as sliding is on the ground: stance now, so the
  // QP (under the corrected cone) takes it over from the swing PD, whose
  // pull toward the swing target is what drags it. Part of the recovery.
  if (params_.recovery.enabled) gin.touchdown_mask |= slipping & ~stance;
  gait_.update(gin, terrain_, gait_out_);
  const uint32_t stance_now = gait_out_.stance_mask;
  for (int i = 0; i < 4; ++i) {
    const bool swinging = gait_.legPhase(i) == LegPhase::kSwing;
    swing_ticks_[i] = swinging ? swing_ticks_[i] + (swing_ticks_[i] < settle ? 1 : 0) : 0;
  }
  for (int i = 0; i < 4; ++i) {
    if ((gait_out_.touchdown_event >> i) & 1u) {
      const double fn = legs_.grf_world.col(i).dot(terrain_.normal());
      touchdown_force_[i] = fn < 0.0 ? 0.0 : (fn > params_.gait.ramp_force ? params_.gait.ramp_force : fn);
    }
  }

  // Trunk: follow the terrain's inclination, hold the heading.
  const Vec3 n = terrain_.normal();
  const double pitch_des = clampAbs(std::atan2(n.x(), n.z()), params_.gait.max_tilt);
  const double roll_des = clampAbs(std::atan2(-n.y(), n.z()), params_.gait.max_tilt);
  const Mat3 R_des = (Eigen::AngleAxisd(gait_out_.yaw_des, Vec3::UnitZ()) *
                      Eigen::AngleAxisd(pitch_des, Vec3::UnitY()) *
                      Eigen::AngleAxisd(roll_des, Vec3::UnitX()))
                         .toRotationMatrix();
  Vec3 com_des = gait_out_.com_des;
  com_des.z() = terrain_.heightAt(com_des.x(), com_des.y()) + params_.gait.body_height +
                (R_wb_ * com_base_).z();
  const Vec3 omega_world = R_wb_ * omega_base_;
  Vec6 wrench;
  wrench.head<3>() = params_.trunk.kp_lin * (com_des - com) +
                     params_.trunk.kd_lin * (gait_out_.com_vel_des - com_vel) +
                     robot::kTotalMass * (gait_out_.com_acc_des + Vec3(0.0, 0.0, robot::kGravity));
  wrench.tail<3>() = params_.trunk.kp_ang * rotationLog(R_des * R_wb_.transpose()) -
                     params_.trunk.kd_ang * omega_world;

  // Ground reaction forces under each foot's friction pyramid.
  GrfInput qin;
  qin.wrench_des = wrench;
  for (int i = 0; i < 4; ++i) {
    qin.stance[i] = (stance_now >> i) & 1u;
    qin.foot_from_com.col(i) = feet_world.col(i) - com;
    qin.normal.col(i) = recovery_.normalInUse(i);
    qin.mu[i] = recovery_.muInUse(i);
    // Hand a foot's load over smoothly: from what the swing PD pushed with at
    // touch-down up to no cap, and down to zero before lift-off.
    const double load = gait_out_.load[i];
    if (load < 1.0) {
      const double ramp = params_.gait.ramp_force;
      qin.max_normal_force[i] = gait_out_.unloading[i]
                                    ? load * ramp
                                    : touchdown_force_[i] + load * (ramp - touchdown_force_[i]);
    }
  }
  // Continuity: a stance foot starts from last tick's force; a foot that has
  // just touched down from the force it measurably pushes with.
  qin.smoothing = params_.qp.force_smoothing;
  for (int i = 0; i < 4; ++i) {
    const bool joined = (gait_out_.touchdown_event >> i) & 1u;
    qin.force_previous.col(i) = joined ? Vec3(legs_.grf_world.col(i)) : Vec3(grf_des_world_.col(i));
  }
  GrfOutput qout;
  grf_qp_.solve(qin, qout);
  grf_des_world_ = qout.forces;
  qp_flags_ = 0;
  if (qout.infeasible) qp_flags_ |= hal::kFlagQpInfeasible;
  if (qout.hit_iteration_limit) qp_flags_ |= hal::kFlagQpMaxIter;

  // Joint commands.
  for (int leg = 0; leg < 4; ++leg) {
    Vec3 tau, q_ref = legs_.q.col(leg), qd_ref = Vec3::Zero();
    double kp = 0.0, kd = params_.joint.stance_kd;
    if ((stance_now >> leg) & 1u) {
      Vec3 f_cmd = grf_des_world_.col(leg);
      // Slip damping: a flagged foot is asked for D v_slip less force
      // against its slip, so kinetic friction decelerates it (RecoveryParams).
      if (params_.recovery.enabled && ((slip_.slip_mask >> leg) & 1u) && slip_.slip_velocity_valid)
        f_cmd += params_.recovery.slip_damping * slip_.slip_velocity_world[leg];
      tau = legs_.gravity_torque[leg] - legs_.jacobian[leg].transpose() * (R_wb_.transpose() * f_cmd);
      q_ref = legs_.q.col(leg);
      qd_ref.setZero();
    } else {
      const Vec3 p_des = R_wb_.transpose() * (gait_out_.foot_des[leg] - base);
      const Vec3 v_des = R_wb_.transpose() * (gait_out_.foot_vel_des[leg] - estimator_.velocity()) -
                         omega_base_.cross(p_des);
      legInverseKinematics(leg, p_des, q_ref);
      const Eigen::FullPivLU<Mat3> lu(footJacobianBase(leg, q_ref));
      if (lu.isInvertible()) qd_ref = lu.solve(v_des);
      for (int k = 0; k < 3; ++k) qd_ref[k] = clampAbs(qd_ref[k], robot::kVelocityLimit);
      tau = legs_.gravity_torque[leg];
      kp = params_.joint.swing_kp;
      kd = params_.joint.swing_kd;
    }
    for (int k = 0; k < 3; ++k) {
      const int j = 3 * leg + k;
      cmd.tau_ff[j] = clampAbs(tau[k], robot::kEffortLimit);
      cmd.q_ref[j] = q_ref[k];
      cmd.qd_ref[j] = qd_ref[k];
      cmd.kp[j] = kp;
      cmd.kd[j] = kd;
    }
  }

  // Freezing mode: stiffen every joint where it is ("wooden chair"). On entry
  // the feed-forward is the torque the joint loop was producing, so nothing
  // steps; on exit the frozen command hands over to the walking one linearly.
  // A leg that swings when the freeze is called is put down first (the gait
  // lowers it while paused), the stance legs still under force control: a
  // robot frozen on three legs, one of them slipping, tips over.
  const bool freeze_now = freezing && (frozen_ || stance_now == 0xFu);
  if (freeze_now && !frozen_) {
    for (int j = 0; j < hal::kNumJoints; ++j) {
      const int leg = j / 3, k = j % 3;
      freeze_q_[j] = legs_.q(k, leg);
      freeze_tau_[j] = clampAbs(last_tau_[j], robot::kEffortLimit);
    }
  }
  if (!freeze_now && frozen_) {
    gait_.replanFrom(com);
    unfreeze_time_ = 0.0;
  }
  frozen_ = freeze_now;
  if (frozen_) {
    freezeCommand(cmd);
  } else if (unfreeze_time_ < params_.recovery.unfreeze_blend) {
    hal::CommandFrame frozen = cmd;
    freezeCommand(frozen);
    blendCommands(frozen, unfreeze_time_ / params_.recovery.unfreeze_blend, cmd);
    unfreeze_time_ += dt;
  }
  // What the joint loop will apply this tick (before saturation), for the
  // next freeze entry.
  for (int j = 0; j < hal::kNumJoints; ++j)
    last_tau_[j] = cmd.tau_ff[j] + cmd.kp[j] * (cmd.q_ref[j] - s.q[j]) + cmd.kd[j] * (cmd.qd_ref[j] - s.qd[j]);

  cmd.flags = qp_flags_ | (frozen_ ? static_cast<uint32_t>(hal::kFlagFreeze) : 0u);
  fillTelemetry(cmd, slipping);
}

void Controller::fillTelemetry(hal::CommandFrame& cmd, uint32_t slip_mask) const {
  hal::Telemetry& t = cmd.telemetry;
  t.stance_mask = gait_out_.stance_mask;
  t.slip_mask = slip_mask;
  t.swing_leg = static_cast<uint32_t>(gait_out_.swing_leg);
  t.gait_phase = gait_out_.phase;
  copy3(estimator_.position(), t.base_pos_est);
  copy3(estimator_.velocity(), t.base_vel_est);
  for (int i = 0; i < 4; ++i) {
    copy3(legs_.foot_vel_base.col(i), t.foot_vel_base[i]);
    copy3(legs_.grf_world.col(i), t.grf_est[i]);
    copy3(grf_des_world_.col(i), t.grf_des[i]);
    t.mu_used[i] = recovery_.muInUse(i);
    copy3(recovery_.normalInUse(i), t.normal_used[i]);
    t.mu_hat[i] = surface_[i].hasEstimate() ? surface_[i].mu() : 0.0;
    copy3(surface_[i].normal(), t.normal_hat[i]);
  }
}

}  // namespace hyq
