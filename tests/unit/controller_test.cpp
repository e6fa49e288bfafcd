// The controller's tick on hand-made frames: bad input gives a safe command
// and a flag, and the controller recovers when good frames return; the GRF
// estimate with the leg dynamics; a flagged foot in the odometry, on and off.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include "firmware/controller/controller.hpp"
#include "firmware/controller/model/kinematics.hpp"
#include "firmware/controller/params_check.hpp"
#include "firmware/controller/model/robot_params.hpp"

namespace hyq {
namespace {

// Standing still in the stand posture, each foot carrying a quarter of the weight.
hal::SensorFrame standingFrame(uint32_t tick) {
  hal::SensorFrame f{};
  f.tick = tick;
  f.imu_quat[0] = 1.0;
  f.imu_acc[2] = robot::kGravity;
  const Vec3 gravity(0.0, 0.0, -robot::kGravity);
  for (int leg = 0; leg < 4; ++leg) {
    const Vec3 q(robot::standAngle(leg, 0), robot::standAngle(leg, 1), robot::standAngle(leg, 2));
    const Vec3 grf(0.0, 0.0, robot::kTotalMass * robot::kGravity / 4.0);
    const Vec3 tau = legGravityTorque(leg, q, gravity) - footJacobianBase(leg, q).transpose() * grf;
    for (int k = 0; k < 3; ++k) {
      f.q[3 * leg + k] = q[k];
      f.tau[3 * leg + k] = tau[k];
    }
  }
  return f;
}

class ControllerTick : public ::testing::Test {
 protected:
  void SetUp() override {
    Params p;
    p.gait.walk = false;
    controller.init(p);
    for (uint32_t t = 0; t < 200; ++t) controller.step(standingFrame(t), command);
  }
  Controller controller;
  hal::CommandFrame command{};
};

// The GRF estimate with the leg's own dynamics: a standing robot whose left
// front leg swings its knee and hip at constant joint accelerations (the
// torques of the leg's rigid-body model, on a fixed base, with the joint
// damping) is read as carrying the same GRF; the static estimate (which
// leaves M qdd out) is off by the leg's inertia.
// A standing controller after 200 ticks, with or without the leg dynamics.
void startStanding(Controller& c, bool leg_dynamics) {
  Params p;
  p.gait.walk = false;
  p.estimator.grf_leg_dynamics = leg_dynamics;
  // The frames here are exact; a bias estimator would read the synthetic
  // accelerometer step as a bias and take a little of it out (0.7 mN here).
  p.estimator.acc_bias_time = 0.0;
  p.estimator.gyro_bias_time = 0.0;
  c.init(p);
  hal::CommandFrame cmd{};
  for (uint32_t t = 0; t < 200; ++t) c.step(standingFrame(t), cmd);
}

Vec3 estimatedLfGrf(bool leg_dynamics) {
  Controller c;
  startStanding(c, leg_dynamics);
  hal::CommandFrame cmd{};
  const Vec3 qdd(0.0, 8.0, -15.0);  // [rad/s^2]
  const Vec3 q0 = Vec3(robot::standAngle(0, 0), robot::standAngle(0, 1), robot::standAngle(0, 2));
  const Vec3 grf(3.0, -2.0, 180.0);
  const Vec3 gravity(0.0, 0.0, -robot::kGravity);
  for (uint32_t k = 0; k < 30; ++k) {
    hal::SensorFrame f = standingFrame(200 + k);
    const double t = 0.001 * k;
    const Vec3 q = q0 + 0.5 * qdd * t * t, qd = qdd * t;
    const Vec3 tau = legMassMatrix(0, q) * qdd + robot::kJointDamping * qd +
                     legGravityTorque(0, q, gravity) - footJacobianBase(0, q).transpose() * grf;
    for (int j = 0; j < 3; ++j) {
      f.q[j] = q[j];
      f.qd[j] = qd[j];
      f.tau[j] = tau[j];
    }
    c.step(f, cmd);
  }
  return Vec3(cmd.telemetry.grf_est[0][0], cmd.telemetry.grf_est[0][1], cmd.telemetry.grf_est[0][2]);
}

// The base accelerating upward at 3 m/s^2 (accelerometer reading g + 3):
// every leg's links need that much more holding torque; the estimate with
// the dynamics reads the foot forces unchanged, the static one does not.
Vec3 estimatedLfGrfWhileTheBaseAccelerates(bool leg_dynamics) {
  Controller c;
  startStanding(c, leg_dynamics);
  hal::CommandFrame cmd{};
  const double up = 3.0;  // [m/s^2]
  const Vec3 apparent_gravity(0.0, 0.0, -(robot::kGravity + up));
  const Vec3 grf(0.0, 0.0, robot::kTotalMass * (robot::kGravity + up) / 4.0);
  for (uint32_t k = 0; k < 5; ++k) {
    hal::SensorFrame f = standingFrame(200 + k);
    f.imu_acc[2] = robot::kGravity + up;
    const Vec3 q(robot::standAngle(0, 0), robot::standAngle(0, 1), robot::standAngle(0, 2));
    const Vec3 tau = legGravityTorque(0, q, apparent_gravity) - footJacobianBase(0, q).transpose() * grf;
    for (int j = 0; j < 3; ++j) f.tau[j] = tau[j];
    c.step(f, cmd);
  }
  return Vec3(cmd.telemetry.grf_est[0][0], cmd.telemetry.grf_est[0][1], cmd.telemetry.grf_est[0][2]);
}

TEST(ControllerGrfEstimate, TheLegsAccelerateWithTheBase) {
  const Vec3 grf(0.0, 0.0, robot::kTotalMass * (robot::kGravity + 3.0) / 4.0);
  EXPECT_LT((estimatedLfGrfWhileTheBaseAccelerates(true) - grf).norm(), 1e-6);
  // Statically, the links' extra holding torque shows up at the foot as
  // 4.6 N (of the leg's 6.4 kg x 3 m/s^2, the part the joints carry).
  EXPECT_GT((estimatedLfGrfWhileTheBaseAccelerates(false) - grf).norm(), 3.0);
}

TEST(ControllerGrfEstimate, LegInertiaIsTakenOutOfTheGroundForce) {
  const Vec3 grf(3.0, -2.0, 180.0);
  // Left out: Coriolis terms, at most 0.24 rad/s here.
  EXPECT_LT((estimatedLfGrf(true) - grf).norm(), 0.5);
  EXPECT_GT((estimatedLfGrf(false) - grf).norm(), 5.0);
}

// The crawl's GRF estimate while the trunk rolls at a constant angular
// acceleration `alpha_x` [rad/s^2] (the gyro's rate ramping): the left front
// leg's links, turned with it, take torque alpha_map alpha besides their
// weight. Returns the estimate's error [N] after 30 ticks.
Vec3 lfGrfErrorWhileTheTrunkRolls(double alpha_x) {
  Controller c;
  startStanding(c, true);
  hal::CommandFrame cmd{};
  const Vec3 q(robot::standAngle(0, 0), robot::standAngle(0, 1), robot::standAngle(0, 2));
  const Vec3 grf(0.0, 0.0, robot::kTotalMass * robot::kGravity / 4.0);
  const Vec3 gravity(0.0, 0.0, -robot::kGravity);
  const Vec3 alpha(alpha_x, 0.0, 0.0);
  const Mat3 alpha_map = legBaseRotation(0, legTrig(0, q), Vec3::Zero(), Vec3::Zero(), false).alpha_map;
  for (uint32_t k = 0; k < 30; ++k) {
    hal::SensorFrame f = standingFrame(200 + k);
    f.imu_gyro[0] = alpha_x * 0.001 * k;
    const Vec3 tau = legGravityTorque(0, q, gravity) + alpha_map * alpha - footJacobianBase(0, q).transpose() * grf;
    for (int j = 0; j < 3; ++j) f.tau[j] = tau[j];
    c.step(f, cmd);
  }
  return Vec3(cmd.telemetry.grf_est[0][0], cmd.telemetry.grf_est[0][1], cmd.telemetry.grf_est[0][2]) - grf;
}

// A fourth foot's landing on the hyq plant rolls the crawl's trunk at up to
// 46 rad/s^2: the estimate takes the links' turn out above kCrawlTurnAlphaMin
// and leaves it in below (the centrifugal terms, of a gyro rate of up to
// 1.2 rad/s here, are left out of the frames and of the crawl's estimate
// alike).
TEST(ControllerGrfEstimate, TheCrawlTakesOutAFastTurnOfTheTrunk) {
  const Vec3 fast = lfGrfErrorWhileTheTrunkRolls(40.0), slow = lfGrfErrorWhileTheTrunkRolls(0.8 * kCrawlTurnAlphaMin);
  std::printf("error at 40 rad/s^2 %.3f N; at %.0f rad/s^2 (%.2f, %.2f, %.2f) N\n", fast.norm(), 0.8 * kCrawlTurnAlphaMin,
              slow.x(), slow.y(), slow.z());
  EXPECT_LT(fast.norm(), 0.5);
  EXPECT_LT(lfGrfErrorWhileTheTrunkRolls(0.0).norm(), 0.5);
  // Below it the turn is left in: (1.2, -4.2, -3.1) N at 8 rad/s^2.
  EXPECT_GT(slow.norm(), 2.0);
}

TEST(ControllerInit, StepBeforeInitIsFlaggedAndSafe) {
  Controller c;
  hal::CommandFrame cmd{};
  c.step(standingFrame(0), cmd);
  EXPECT_NE(cmd.flags & hal::kFlagNotInitialised, 0u);
  EXPECT_TRUE(commandFinite(cmd));
}

TEST_F(ControllerTick, StandingFrameCarriesTheWeightWithoutFlags) {
  EXPECT_EQ(command.flags, 0u);
  EXPECT_EQ(command.telemetry.stance_mask, 0xFu);
  double fz = 0.0;
  for (int i = 0; i < 4; ++i) fz += command.telemetry.grf_des[i][2];
  EXPECT_NEAR(fz, robot::kTotalMass * robot::kGravity, 0.02 * robot::kTotalMass * robot::kGravity);
  EXPECT_TRUE(commandFinite(command));
  // No slip yet, so no estimate: mu_hat 0 and a zero normal_hat; the cones
  // stand on the ground plane.
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(command.telemetry.mu_hat[i], 0.0) << "leg " << i;
    EXPECT_EQ(Vec3(command.telemetry.normal_hat[i][0], command.telemetry.normal_hat[i][1],
                   command.telemetry.normal_hat[i][2]),
              Vec3::Zero())
        << "leg " << i;
    EXPECT_NEAR(command.telemetry.normal_used[i][2], 1.0, 1e-9) << "leg " << i;
  }
}

TEST_F(ControllerTick, NanFrameGivesDampedHoldOfLastGoodPostureAndRecovers) {
  const hal::SensorFrame good = standingFrame(200);
  controller.step(good, command);
  hal::SensorFrame bad = standingFrame(201);
  bad.q[7] = std::numeric_limits<double>::quiet_NaN();
  bad.imu_gyro[1] = std::numeric_limits<double>::infinity();
  controller.step(bad, command);
  EXPECT_NE(command.flags & hal::kFlagBadSensorFrame, 0u);
  EXPECT_TRUE(commandFinite(command));
  Params defaults;
  for (int j = 0; j < hal::kNumJoints; ++j) {
    EXPECT_DOUBLE_EQ(command.q_ref[j], good.q[j]);
    EXPECT_DOUBLE_EQ(command.qd_ref[j], 0.0);
    EXPECT_DOUBLE_EQ(command.kp[j], defaults.joint.posture_kp);
    EXPECT_DOUBLE_EQ(command.kd[j], defaults.joint.posture_kd);
  }
  // Good frames again: the flag clears and the stance forces come back.
  for (uint32_t t = 202; t < 260; ++t) controller.step(standingFrame(t), command);
  EXPECT_EQ(command.flags & hal::kFlagBadSensorFrame, 0u);
  double fz = 0.0;
  for (int i = 0; i < 4; ++i) fz += command.telemetry.grf_des[i][2];
  EXPECT_NEAR(fz, robot::kTotalMass * robot::kGravity, 0.05 * robot::kTotalMass * robot::kGravity);
}

TEST_F(ControllerTick, OutOfRangeValuesAreRejectedLikeNan) {
  const SafetyParams limits;
  struct Case {
    const char* what;
    void (*corrupt)(hal::SensorFrame&);
  } cases[] = {
      {"joint speed", [](hal::SensorFrame& f) { f.qd[2] = 100.0; }},
      {"torque", [](hal::SensorFrame& f) { f.tau[5] = -1000.0; }},
      {"quaternion norm", [](hal::SensorFrame& f) { f.imu_quat[0] = 2.0; }},
      {"encoder past its limit", [](hal::SensorFrame& f) { f.q[0] = 3.0; }},
      {"accelerometer", [](hal::SensorFrame& f) { f.imu_acc[0] = 1e4; }},
  };
  for (const Case& c : cases) {
    hal::SensorFrame f = standingFrame(300);
    EXPECT_TRUE(sensorFrameValid(f, limits)) << c.what;
    c.corrupt(f);
    EXPECT_FALSE(sensorFrameValid(f, limits)) << c.what;
    controller.step(f, command);
    EXPECT_NE(command.flags & hal::kFlagBadSensorFrame, 0u) << c.what;
    EXPECT_TRUE(commandFinite(command)) << c.what;
  }
}


// Standing on four feet while the left front foot slides forward at 0.2 m/s
// along the ground (its joints move, the base and the other feet stay): the
// detector flags it either way. With recovery on the flagged foot leaves the
// odometry, which then reads the base at rest; with recovery off it stays
// in, as in the paper's baseline, and the odometry reads the base moving
// back at a quarter of the slide (the mean of the four feet's -u_i).
Vec3 odometryWhileLfSlides(bool recovery, uint32_t* slip_mask) {
  Params p;
  p.gait.walk = false;
  p.recovery.enabled = recovery;
  p.estimator.acc_bias_time = 0.0;  // exact frames: keep the comparison to the velocity filter
  p.estimator.gyro_bias_time = 0.0;
  Controller c;
  c.init(p);
  hal::CommandFrame cmd{};
  for (uint32_t t = 0; t < 200; ++t) c.step(standingFrame(t), cmd);
  const Vec3 slide(0.2, 0.0, 0.0);  // [m/s] foot velocity in B
  Vec3 q(robot::standAngle(0, 0), robot::standAngle(0, 1), robot::standAngle(0, 2));
  for (uint32_t k = 0; k < 150; ++k) {
    hal::SensorFrame f = standingFrame(200 + k);
    const Mat3 J = footJacobianBase(0, q);
    const Vec3 qd = J.inverse() * slide;
    for (int j = 0; j < 3; ++j) {
      f.q[j] = q[j];
      f.qd[j] = qd[j];
      // The sliding foot still carries its quarter of the weight.
      f.tau[j] = (legGravityTorque(0, q, Vec3(0.0, 0.0, -robot::kGravity)) -
                  J.transpose() * Vec3(0.0, 0.0, robot::kTotalMass * robot::kGravity / 4.0))[j];
    }
    c.step(f, cmd);
    q += 0.001 * qd;
  }
  *slip_mask = cmd.telemetry.slip_mask;
  return Vec3(cmd.telemetry.base_vel_est[0], cmd.telemetry.base_vel_est[1], cmd.telemetry.base_vel_est[2]);
}

TEST(ControllerOdometry, AFlaggedFootLeavesTheOdometryOnlyWithRecovery) {
  uint32_t mask_on = 0, mask_off = 0;
  const Vec3 v_on = odometryWhileLfSlides(true, &mask_on);
  const Vec3 v_off = odometryWhileLfSlides(false, &mask_off);
  EXPECT_TRUE(mask_on & 1u);
  EXPECT_TRUE(mask_off & 1u);
  EXPECT_LT(v_on.norm(), 0.005);
  EXPECT_NEAR(v_off.x(), -0.05, 0.005);
}

// The output check: a command with a NaN in it never leaves the controller.
// The injected fault makes this tick's torque NaN; the answer is the posture
// hold of the frame's joints, flagged and counted, and the next tick walks on.
TEST_F(ControllerTick, ANanCommandBecomesTheSafeHoldWithAFlag) {
  const hal::SensorFrame frame = standingFrame(200);
  controller.injectCommandFault();
  controller.step(frame, command);
  EXPECT_NE(command.flags & hal::kFlagBadCommand, 0u);
  EXPECT_TRUE(commandFinite(command));
  EXPECT_EQ(controller.badCommandCount(), 1u);
  const Params defaults;
  for (int j = 0; j < hal::kNumJoints; ++j) {
    EXPECT_EQ(command.q_ref[j], frame.q[j]);
    EXPECT_EQ(command.tau_ff[j], 0.0);
    EXPECT_EQ(command.kp[j], defaults.joint.posture_kp);
  }
  EXPECT_EQ(command.telemetry.stance_mask, 0xFu);  // telemetry still reports the tick
  controller.step(standingFrame(201), command);
  EXPECT_EQ(command.flags & hal::kFlagBadCommand, 0u);
  EXPECT_EQ(controller.badCommandCount(), 1u);
}

// Frames that never arrive: the next one's tick jumps. The filters that
// assume one tick between samples (joint accelerations, the GRF delay line,
// the gyro-bias filter) restart exactly as after a bad frame, and the jump
// is flagged and counted.
TEST(ControllerFrames, DroppedFramesRestartTheFilters) {
  auto run = [](int mode, std::vector<hal::CommandFrame>& out) {
    Controller c;
    Params p;
    p.gait.walk = false;
    c.init(p);
    hal::CommandFrame cmd{};
    for (uint32_t t = 1; t <= 260; ++t) {
      hal::SensorFrame f = standingFrame(t);
      // The knees swing, so that the joint accelerations are not zero.
      for (int leg = 0; leg < 4; ++leg) {
        f.q[3 * leg + 2] += 0.05 * std::sin(0.02 * t);
        f.qd[3 * leg + 2] = 0.05 * 0.02 / 0.001 * std::cos(0.02 * t);
      }
      if (t >= 201 && t <= 203) {
        if (mode == 1) continue;                      // dropped
        if (mode == 2) f.tau[4] = std::nan("");       // bad
      }
      c.step(f, cmd);
      out.push_back(cmd);
    }
    return c.tickGapCount();
  };
  std::vector<hal::CommandFrame> continuous, dropped, bad;
  EXPECT_EQ(run(0, continuous), 0u);
  EXPECT_EQ(run(1, dropped), 1u);
  EXPECT_EQ(run(2, bad), 0u);
  ASSERT_EQ(dropped.size(), 257u);
  // Frame 204 is index 203 in the continuous and bad runs, 200 in the dropped one.
  EXPECT_NE(dropped[200].flags & hal::kFlagTickGap, 0u);
  EXPECT_EQ(dropped[201].flags & hal::kFlagTickGap, 0u);
  bool differs_from_continuous = false;
  for (int k = 0; k < 57; ++k) {
    const hal::Telemetry& d = dropped[200 + k].telemetry;
    const hal::Telemetry& b = bad[203 + k].telemetry;
    const hal::Telemetry& c = continuous[203 + k].telemetry;
    for (int leg = 0; leg < 4; ++leg)
      for (int a = 0; a < 3; ++a) {
        EXPECT_EQ(d.grf_est[leg][a], b.grf_est[leg][a]) << "frame " << 204 + k;
        differs_from_continuous |= d.grf_est[leg][a] != c.grf_est[leg][a];
      }
  }
  EXPECT_TRUE(differs_from_continuous);
}

// Parameters out of range are refused: init says so, and every tick answers
// the safe hold with kFlagBadParams until parameters in range come.
TEST(ControllerParams, OutOfRangeParametersAreRefused) {
  struct Case {
    const char* key;
    void (*poison)(Params&);
  } cases[] = {
      {"gait.duty_factor", [](Params& p) { p.gait.duty_factor = 1.5; }},
      {"slip.estimate_samples_mu", [](Params& p) { p.slip.estimate_samples_mu = 33; }},
      {"trunk.kp_lin", [](Params& p) { p.trunk.kp_lin = std::nan(""); }},
      {"recovery.k_mu", [](Params& p) { p.recovery.k_mu = -1.0; }},
      {"dt", [](Params& p) { p.dt = 0.0; }},
      {"gait.liftoff_margin", [](Params& p) { p.gait.liftoff_margin = p.gait.stability_margin; }},
      {"gait.liftoff_wait_max", [](Params& p) { p.gait.liftoff_wait_max = -1.0; }},
      {"qp.f_normal_max", [](Params& p) { p.qp.f_normal_max = 1e9; }},
      {"gait.phase_offset", [](Params& p) { p.gait.phase_offset[2] = -0.1; }},
      {"gait.kind", [](Params& p) { p.gait.kind = static_cast<GaitKind>(2); }},
      {"gait.yaw_rate", [](Params& p) { p.gait.yaw_rate = 0.1; }},  // the crawl walks straight
      {"gait.trot.cycle_time", [](Params& p) { p.gait.trot.cycle_time = 0.2; }},
      {"gait.trot.unload_time", [](Params& p) { p.gait.trot.unload_time = 0.5; }},  // past the stance
      {"gait.schedule.trot_at", [](Params& p) {  // the switch starts from the crawl
         p.gait.kind = GaitKind::kTrot;
         p.gait.schedule.trot_at = 5.0;
       }},
      {"gait.schedule.trot_speed", [](Params& p) { p.gait.schedule.trot_speed = 1.5; }},
      {"gait.trot.guess_delay", [](Params& p) { p.gait.trot.guess_delay = -0.01; }},
      {"stance.force_watch_release", [](Params& p) { p.stance.force_watch_release = p.stance.force_watch + 1.0; }},
      {"slip.slide_window", [](Params& p) { p.slip.slide_window = 17; }},  // past the history's capacity
      {"slip.max_slide_stiffness", [](Params& p) { p.slip.max_slide_stiffness = -1.0; }},
      {"slip.slide_travel", [](Params& p) { p.slip.slide_travel = -0.001; }},
      {"gait.trot.carry_agreement_above", [](Params& p) { p.gait.trot.carry_agreement_above = -0.1; }},
      {"gait.trot.carry_max_samples", [](Params& p) { p.gait.trot.carry_max_samples = 33; }},
  };
  for (const Case& c : cases) {
    Params p;
    c.poison(p);
    ParamIssue issue;
    EXPECT_FALSE(checkParams(p, issue)) << c.key;
    EXPECT_STREQ(issue.name, c.key);
    Controller controller;
    EXPECT_FALSE(controller.init(p)) << c.key;
    hal::CommandFrame cmd{};
    controller.step(standingFrame(1), cmd);
    EXPECT_EQ(cmd.flags, static_cast<uint32_t>(hal::kFlagBadParams)) << c.key;
    EXPECT_TRUE(commandFinite(cmd));
    EXPECT_EQ(cmd.kp[0], Params{}.joint.posture_kp);
    // Valid parameters afterwards are taken.
    EXPECT_TRUE(controller.init(Params{}));
    controller.step(standingFrame(2), cmd);
    EXPECT_EQ(cmd.flags & hal::kFlagBadParams, 0u);
  }
  ParamIssue issue;
  EXPECT_TRUE(checkParams(Params{}, issue)) << issue.name << " " << issue.rule;
}

// A bad frame before any good one: the safe hold, with telemetry that says
// what the controller holds (standing, no leg in swing, the default cones).
TEST(ControllerFrames, ABadFirstFrameReportsTheStandingDefaults) {
  Controller c;
  const Params p;
  ASSERT_TRUE(c.init(p));
  hal::SensorFrame bad = standingFrame(1);
  bad.imu_acc[2] = std::nan("");
  hal::CommandFrame cmd{};
  c.step(bad, cmd);
  EXPECT_NE(cmd.flags & hal::kFlagBadSensorFrame, 0u);
  EXPECT_EQ(cmd.telemetry.stance_mask, 0xFu);
  EXPECT_EQ(cmd.telemetry.swing_leg, static_cast<uint32_t>(kNumLegs));
  for (int leg = 0; leg < 4; ++leg) {
    EXPECT_EQ(cmd.telemetry.mu_used[leg], p.recovery.mu_default);
    EXPECT_EQ(cmd.telemetry.normal_used[leg][2], 1.0);
  }
}

}  // namespace
}  // namespace hyq
