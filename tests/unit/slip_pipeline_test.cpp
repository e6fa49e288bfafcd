// The three slip components wired as the controller's tick wires them, on a
// synthetic foot that slips on a tilted low-friction plane while the
// controller believes it is on flat, grippy ground. A stand-in "QP" clips
// the demanded force to the cone in use; a Coulomb contact makes the foot
// slide when that force leaves the true cone. This is the wiring example:
//   1. ImuVelocityIntegrator::update (anchor from last tick's legs)
//   2. SlipDetector::update
//   3. SurfaceEstimator::update per leg (slip flag, slip velocity, GRF)
//   4. TractionRecovery::update -> normal and mu for the QP
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "firmware/controller/slip/slip_detector.hpp"
#include "firmware/controller/slip/surface_estimator.hpp"
#include "firmware/controller/slip/traction_recovery.hpp"

namespace hyq {
namespace {

constexpr double kDt = 0.001;

double angleBetween(const Vec3& a, const Vec3& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// The foot slides along the plane; its effective mass resists the excess of
// tangential push over kinetic friction.
struct SlidingFoot {
  Vec3 normal;
  double mu;
  double effective_mass = 2.0;  // [kg]
  Vec3 velocity = Vec3::Zero();

  // Commanded GRF in, actual GRF on the foot out.
  Vec3 step(const Vec3& commanded) {
    const double fn = commanded.dot(normal);
    const Vec3 push = commanded - fn * normal;  // the tangential force asked for
    const double speed = velocity.norm();
    if (speed < 1e-9 && push.norm() <= mu * fn) return commanded;  // sticks
    const Vec3 direction = speed > 1e-9 ? Vec3(velocity / speed) : Vec3(-push.normalized());
    const Vec3 friction = -mu * fn * direction;
    // The leg pushes the foot by -push; friction acts on it.
    Vec3 v_new = velocity + (-push + friction) / effective_mass * kDt;
    if (v_new.dot(direction) <= 0.0) v_new.setZero();  // friction stops it
    velocity = v_new - v_new.dot(normal) * normal;
    return fn * normal + friction;
  }
};

// The QP's friction constraint alone: the demand clipped to the pyramid in use
// (cone of radius mu_pyramid about n_used).
Vec3 clipToCone(const Vec3& demand, const Vec3& n_used, double mu_pyramid) {
  const double fn = demand.dot(n_used);
  Vec3 t = demand - fn * n_used;
  if (t.norm() > mu_pyramid * fn) t *= mu_pyramid * fn / t.norm();
  return fn * n_used + t;
}

struct Outcome {
  int detected_tick = -1;    // first flagged tick (slip starts at tick 0)
  int slip_over_tick = -1;   // first tick the foot stands still after detection
  int freeze_ticks = 0;
  int other_legs_flagged = 0;
  double largest_mu_step = 0.0;
  double largest_turn = 0.0;  // [rad] normal in use, per tick
  double mu_hat = 0.0, mu_in_use = 0.0;
  double normal_hat_error = 0.0, normal_in_use_error = 0.0;  // [rad]
};

// LF stands on a plane rolled 0.2 rad with mu 0.3; the controller's plane
// fit says flat, its mu is 0.6, and the body asks LF for a 60 N sideways
// push, inside the cone it believes in but outside the real one.
Outcome runSlip(const RecoveryParams& recovery_params, int ticks = 600) {
  SlipParams slip_params;
  ImuVelocityIntegrator imu;
  SlipDetector detector;
  SurfaceEstimator estimators[4];
  TractionRecovery recovery;
  imu.reset(slip_params);
  detector.reset(slip_params);
  for (SurfaceEstimator& e : estimators) e.reset(slip_params, 0.001);
  recovery.reset(recovery_params);

  SlidingFoot foot{Eigen::AngleAxisd(0.2, Vec3::UnitX()) * Vec3::UnitZ(), 0.3};
  const Vec3 demand(0.0, 60.0, 300.0);  // [N] GRF on LF wanted by the body
  const Vec3 g(0.0, 0.0, -9.81);
  SlipResult last;
  Outcome out;
  for (int tick = 0; tick < ticks; ++tick) {
    const Vec3 commanded = clipToCone(demand, recovery.normalInUse(0), recovery.muPyramid(0));
    const Vec3 grf = foot.step(commanded);

    imu.update(-g, Mat3::Identity(), g, kDt, last.base_velocity_legs, last.legs_agree);
    SlipInput in;
    in.stance_mask = 0xF;
    in.u[0] = foot.velocity;  // base still: u_i is the foot's own velocity
    in.imu_base_velocity = imu.velocityBase();
    in.imu_velocity_valid = imu.valid();
    last = detector.update(in);

    RecoveryInput rin;
    rin.stance_mask = 0xF;
    rin.slip_mask = last.slip_mask;
    rin.terrain_normal = Vec3::UnitZ();
    for (int leg = 0; leg < 4; ++leg) {
      const bool flagged = (last.slip_mask >> leg) & 1u;
      const Vec3 leg_grf = leg == 0 ? grf : Vec3(0.0, 0.0, 250.0);
      SurfaceInput sample;
      sample.slipping = flagged;
      sample.slip_velocity = last.slip_velocity_world[leg];
      sample.grf = leg_grf;
      estimators[leg].update(sample);
      rin.estimate_valid[leg] = estimators[leg].hasEstimate();
      rin.normal_estimate[leg] = estimators[leg].normal();
      rin.mu_estimate[leg] = estimators[leg].mu();
    }
    const double mu_before = recovery.muInUse(0);
    const Vec3 normal_before = recovery.normalInUse(0);
    recovery.update(rin, kDt);
    out.largest_mu_step = std::max(out.largest_mu_step, std::fabs(recovery.muInUse(0) - mu_before));
    out.largest_turn = std::max(out.largest_turn, angleBetween(normal_before, recovery.normalInUse(0)));
    if (recovery.freezing()) ++out.freeze_ticks;
    if (last.slip_mask & 0xEu) ++out.other_legs_flagged;
    if (out.detected_tick < 0 && last.slip_mask) out.detected_tick = tick;
    if (out.detected_tick >= 0 && out.slip_over_tick < 0 && foot.velocity.norm() == 0.0)
      out.slip_over_tick = tick;
  }
  out.mu_hat = estimators[0].mu();
  out.mu_in_use = recovery.muInUse(0);
  out.normal_hat_error = angleBetween(estimators[0].normal(), foot.normal);
  out.normal_in_use_error = angleBetween(recovery.normalInUse(0), foot.normal);
  std::printf("K_n %.0f, K_mu %.0f/s, recovery %s: detected at %d ms, slip over %d ms after "
              "detection, mu_hat %.4f, mu in use %.4f, freeze ticks %d\n",
              recovery_params.k_normal, recovery_params.k_mu,
              recovery_params.enabled ? "on" : "off", out.detected_tick,
              out.slip_over_tick < 0 ? -1 : out.slip_over_tick - out.detected_tick, out.mu_hat,
              out.mu_in_use, out.freeze_ticks);
  return out;
}

TEST(SlipPipelineTest, SlipOnAWrongNormalIsDetectedEstimatedAndStopped) {
  const RecoveryParams params;
  const Outcome o = runSlip(params);
  ASSERT_GE(o.detected_tick, 0);
  ASSERT_GE(o.slip_over_tick, 0);
  EXPECT_LE(o.detected_tick, 10);
  EXPECT_EQ(o.other_legs_flagged, 0);
  // Stopped by the correction, before freezing would have stepped in.
  EXPECT_LT((o.slip_over_tick - o.detected_tick) * kDt, params.freeze_after);
  EXPECT_EQ(o.freeze_ticks, 0);
  // Kinetic friction on the true cone: the estimate is exact here.
  EXPECT_NEAR(o.mu_hat, 0.3, 1e-9);
  EXPECT_LT(o.normal_hat_error, 1e-9);
  EXPECT_LT(o.normal_in_use_error, 0.01);  // correction stops when the flag drops
  // The QP aims at estimate_margin of the estimate, but not below the slope
  // floor of the plane the estimate found (the normal in use: 0.2 rad, a
  // floor of 0.34), above it here.
  const double slope_floor = params.slope_floor_factor * std::tan(0.2) / params.pyramid_scale;
  ASSERT_GT(slope_floor, params.estimate_margin * 0.3);
  EXPECT_NEAR(o.mu_in_use, slope_floor, 0.01);
  // Smooth: bounded per-tick changes of what the QP sees (the largest while
  // the flag is up before the first estimate, heading for the floor).
  EXPECT_LE(o.largest_mu_step, params.k_mu * kDt * (params.mu_default - params.mu_floor) + 1e-12);
  EXPECT_LE(o.largest_turn, params.k_normal * kDt * 0.2 + 1e-9);
}

TEST(SlipPipelineTest, SlowerGainsLetTheSlipRunLonger) {
  RecoveryParams slow;
  slow.k_normal = 30.0;
  slow.k_mu = 50.0;
  slow.freeze_after = 1.0;  // watch the correction alone
  RecoveryParams fast = slow;
  fast.k_normal = RecoveryParams{}.k_normal;
  fast.k_mu = RecoveryParams{}.k_mu;
  const Outcome o_slow = runSlip(slow), o_fast = runSlip(fast);
  ASSERT_GE(o_slow.slip_over_tick, 0);
  ASSERT_GE(o_fast.slip_over_tick, 0);
  EXPECT_GT(o_slow.slip_over_tick, o_fast.slip_over_tick + 30);
}

TEST(SlipPipelineTest, RecoveryOffDetectsAndEstimatesButTheFootKeepsSliding) {
  RecoveryParams off;
  off.enabled = false;
  const Outcome o = runSlip(off, 300);
  EXPECT_LE(o.detected_tick, 10);
  EXPECT_LT(o.slip_over_tick, 0);  // never stops
  EXPECT_NEAR(o.mu_hat, 0.3, 1e-9);  // estimated and reportable
  EXPECT_EQ(o.mu_in_use, off.mu_default);
  EXPECT_NEAR(o.normal_in_use_error, 0.2, 1e-9);  // still the flat plane fit
  EXPECT_EQ(o.freeze_ticks, 0);
}

}  // namespace
}  // namespace hyq
