// Slip detection: the median test on one slipping foot, debounce timing,
// a slow creep the norms miss, noise immunity, two feet slipping at once via
// the IMU integration, slip velocities in W, and NaN handling.
#include "firmware/controller/slip/slip_detector.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace hyq {
namespace {

constexpr uint32_t kAllStance = 0xF;

Mat3 yaw(double angle) {
  return Eigen::AngleAxisd(angle, Vec3::UnitZ()).toRotationMatrix();
}

// Every stance foot still: u_i = -bv_b. `extra` is added to the slipping legs.
SlipInput standingInput(const Vec3& base_velocity_base, uint32_t stance, uint32_t slipping,
                        const Vec3& extra) {
  SlipInput in;
  in.stance_mask = stance;
  for (int leg = 0; leg < kSlipLegs; ++leg) {
    in.u[leg] = -base_velocity_base;
    if ((slipping >> leg) & 1u) in.u[leg] += extra;
  }
  return in;
}

// Ticks a foot dragged at `speed` [m/s] against standing feet takes to pass
// landing_drag_travel, its travel counted in excess of the allowance.
int dragTicks(const SlipParams& params, double speed) {
  const double excess = speed - params.landing_drag_allowance;  // [m/s]
  return static_cast<int>(std::floor(params.landing_drag_travel / (excess * kTickPeriod))) + 1;
}

class SlipDetectorTest : public ::testing::Test {
 protected:
  void SetUp() override { detector.reset(params); }
  // Runs `in` for `ticks` ticks: no slip flag and no raw detection on any,
  // leg 0 alone in drag_mask from its first tick there on. That tick (-1: never).
  int firstDragTick(const SlipInput& in, int ticks) {
    int first = -1;
    for (int k = 1; k <= ticks; ++k) {
      const SlipResult r = detector.update(in);
      EXPECT_EQ(r.slip_mask, 0u) << "tick " << k;
      EXPECT_EQ(r.raw_mask, 0u) << "tick " << k;
      if (first < 0 && r.drag_mask != 0) first = k;
      if (first > 0) {
        EXPECT_EQ(r.drag_mask, 0b0001u) << "tick " << k;
      }
    }
    return first;
  }
  SlipParams params;
  SlipDetector detector;
};

TEST_F(SlipDetectorTest, OneLegSlippingAmongFourIsFlaggedWithItsSlipVelocity) {
  const Vec3 base_velocity(0.05, 0.01, 0.0);
  SlipInput in = standingInput(base_velocity, kAllStance, 0b0100, Vec3(0.3, -0.1, 0.0));
  in.rotation_world_base = yaw(0.5);
  SlipResult r = detector.update(in);
  EXPECT_EQ(r.test, SlipTest::kMedian);
  EXPECT_EQ(r.raw_mask, 0b0100u);
  EXPECT_EQ(r.slip_mask, 0u);  // debounce not yet satisfied
  ASSERT_TRUE(r.slip_velocity_valid);
  const Vec3 expected = yaw(0.5) * Vec3(0.3, -0.1, 0.0);
  EXPECT_NEAR((r.slip_velocity_world[2] - expected).norm(), 0.0, 1e-12);
  EXPECT_NEAR(r.slip_velocity_world[0].norm(), 0.0, 1e-12);
  EXPECT_NEAR((r.base_velocity_legs - base_velocity).norm(), 0.0, 1e-12);
  EXPECT_NEAR(r.median_speed, base_velocity.norm(), 1e-12);
  EXPECT_TRUE(r.legs_agree);  // three feet hold and agree: a valid anchor
}

TEST_F(SlipDetectorTest, SlipJustBelowAndAboveThreshold) {
  // With the base still, s_i - median is exactly the slip speed.
  const Vec3 still = Vec3::Zero();
  SlipResult below =
      detector.update(standingInput(still, kAllStance, 0b0001, Vec3(0.99 * params.threshold, 0, 0)));
  EXPECT_EQ(below.raw_mask, 0u);
  SlipResult above =
      detector.update(standingInput(still, kAllStance, 0b0001, Vec3(1.01 * params.threshold, 0, 0)));
  EXPECT_EQ(above.raw_mask, 0b0001u);
}

TEST_F(SlipDetectorTest, MotionAlongTheGroundNormalIsNotASlip) {
  // Ground rolled 0.3 rad: a foot still settling moves along the normal at
  // three times the threshold and is not flagged; the same speed along the
  // ground is, and its slip velocity keeps every component.
  const Vec3 normal = Eigen::AngleAxisd(0.3, Vec3::UnitX()) * Vec3::UnitZ();
  const Vec3 along = normal.cross(Vec3::UnitX()).normalized();
  const double speed = 3.0 * params.threshold;
  SlipInput settling = standingInput(Vec3(0.05, 0.0, 0.0), kAllStance, 0b0010, speed * normal);
  settling.ground_normal_base = normal;
  for (int k = 0; k < params.debounce_ticks + 2; ++k) {
    const SlipResult r = detector.update(settling);
    EXPECT_EQ(r.raw_mask, 0u);
    EXPECT_EQ(r.slip_mask, 0u);
  }
  // Without the ground normal the whole vectors are compared: flagged.
  settling.ground_normal_base = Vec3::Zero();
  EXPECT_EQ(detector.update(settling).raw_mask, 0b0010u);

  SlipInput sliding = standingInput(Vec3(0.05, 0.0, 0.0), kAllStance, 0b0010, speed * along);
  sliding.ground_normal_base = normal;
  SlipResult r;
  for (int k = 0; k < params.debounce_ticks; ++k) r = detector.update(sliding);
  EXPECT_EQ(r.slip_mask, 0b0010u);
  ASSERT_TRUE(r.slip_velocity_valid);
  EXPECT_NEAR((r.slip_velocity_world[1] - speed * along).norm(), 0.0, 1e-12);
}

TEST_F(SlipDetectorTest, DebounceRaisesAfterExactlyDebounceTicksAndDropsAfterRelease) {
  const Vec3 v(0.05, 0.0, 0.0);
  const SlipInput slipping = standingInput(v, kAllStance, 0b0010, Vec3(0.4, 0, 0));
  const SlipInput clear = standingInput(v, kAllStance, 0, Vec3::Zero());
  for (int k = 1; k <= params.debounce_ticks; ++k) {
    const SlipResult r = detector.update(slipping);
    EXPECT_EQ(r.slip_mask, k < params.debounce_ticks ? 0u : 0b0010u) << "tick " << k;
  }
  for (int k = 1; k <= params.release_ticks; ++k) {
    const SlipResult r = detector.update(clear);
    EXPECT_EQ(r.slip_mask, k < params.release_ticks ? 0b0010u : 0u) << "clear tick " << k;
  }
  // An interrupted detection (debounce_ticks - 1 on, one off) never raises.
  for (int round = 0; round < 5; ++round) {
    for (int k = 0; k < params.debounce_ticks - 1; ++k)
      EXPECT_EQ(detector.update(slipping).slip_mask, 0u);
    EXPECT_EQ(detector.update(clear).slip_mask, 0u);
  }
}

// A held foot (a landing foot whose force dipped) neither counts toward its
// debounce nor restarts it, and takes no part in the median; leaving the
// watched set restarts it.
TEST_F(SlipDetectorTest, AHeldFootKeepsItsDebounceCount) {
  SlipInput slipping = standingInput(Vec3::Zero(), kAllStance, 0b0001, Vec3(0.4, 0, 0));
  SlipInput held = slipping;
  held.hold_mask = 0b0001;
  for (int round = 0; round < params.debounce_ticks - 1; ++round) {
    EXPECT_EQ(detector.update(slipping).slip_mask, 0u) << "round " << round;
    const SlipResult r = detector.update(held);
    EXPECT_EQ(r.raw_mask, 0u);
    EXPECT_EQ(r.slip_mask, 0u);
    EXPECT_NEAR(r.slip_velocity_world[0].norm(), 0.0, 1e-12);  // no slip velocity for a held foot
  }
  EXPECT_EQ(detector.update(slipping).slip_mask, 0b0001u);  // debounce_ticks counted across the holds
  // A flag up stays up through a hold.
  for (int k = 0; k < 2 * params.release_ticks; ++k) EXPECT_EQ(detector.update(held).slip_mask, 0b0001u);

  detector.reset(params);
  SlipInput gone = slipping;
  gone.stance_mask = 0b1110;
  for (int k = 0; k < params.debounce_ticks - 1; ++k) detector.update(slipping);
  detector.update(gone);
  for (int k = 0; k < params.debounce_ticks - 1; ++k) EXPECT_EQ(detector.update(slipping).slip_mask, 0u);
  EXPECT_EQ(detector.update(slipping).slip_mask, 0b0001u);
}

// A foot creeping across the body's motion: the body moves forward at
// 0.04 m/s, RF slides forward and to the left at 0.07 m/s, so |u_RF|
// (0.051 m/s) is 0.011 m/s off the median, far under the threshold. The
// vectors differ by 0.07 m/s:
// the creep filter flags RF, and only RF, within ln(0.071 / (0.071 -
// 0.04)) = 0.83 time constants plus the debounce; the flag drops once the
// creep stops. With the creep test off the same input is never flagged.
TEST_F(SlipDetectorTest, ASlowCreepAgainstTheBodysMotionIsFlaggedByItsVector) {
  const Vec3 body(0.04, 0.0, 0.0);
  const uint32_t three = 0b1011;  // LH in swing
  const SlipInput creeping = standingInput(body, three, 0b0010, Vec3(0.05, 0.05, 0.0));
  const SlipInput still = standingInput(body, three, 0, Vec3::Zero());
  ASSERT_LT(std::abs(creeping.u[1].norm() - body.norm()), 0.25 * params.threshold);
  const int expected = static_cast<int>(std::ceil(params.creep_filter_ticks * 0.83)) + params.debounce_ticks;
  int first = -1;
  for (int k = 1; k <= 3 * params.creep_filter_ticks; ++k) {
    const SlipResult r = detector.update(creeping);
    EXPECT_EQ(r.raw_mask & ~0b0010u, 0u) << "tick " << k;
    // Flagged, RF leaves the two others, which agree: the median is trusted
    // (with RF's vector among them the three would not agree, and no IMU
    // velocity is there to ask).
    if (r.raw_mask != 0) {
      EXPECT_EQ(r.test, SlipTest::kMedian) << "tick " << k;
    }
    if (first < 0 && r.slip_mask != 0) first = k;
  }
  EXPECT_NEAR(first, expected, 3);
  EXPECT_EQ(detector.slipMask(), 0b0010u);
  int dropped = -1;
  for (int k = 1; k <= 3 * params.creep_filter_ticks && dropped < 0; ++k)
    if (detector.update(still).slip_mask == 0) dropped = k;
  EXPECT_GT(dropped, params.release_ticks);
  EXPECT_LT(dropped, params.creep_filter_ticks + params.release_ticks);

  SlipParams off = params;
  off.creep_threshold = 0.0;
  detector.reset(off);
  for (int k = 0; k < 10 * params.creep_filter_ticks; ++k)
    ASSERT_EQ(detector.update(creeping).raw_mask, 0u) << "tick " << k;
}

// A foot sliding with the body's motion, its norm flickering about the
// threshold (a loaded foot creeping down a slope as the crawl shifts the
// body over it): the body moves forward at 0.04 m/s, LF slides forward at
// 0.12-0.14 m/s, so |u_LF| - median is 0.04 and 0.06 m/s in turn, two
// ticks each: the norms flag it for two ticks at a time, under the
// debounce, and between them the three feet do not agree, so the median is
// not trusted. Its vector is 0.12-0.14 m/s off the median: the creep filter,
// held while the norms flag, flags LF alone within a time constant and the
// debounce. (A filter restarted on every norm flag never gets there: LF is
// never flagged.)
TEST_F(SlipDetectorTest, ASlowSlideWhoseNormFlickersIsFlaggedByItsCreep) {
  const Vec3 body(0.04, 0.0, 0.0);
  const uint32_t three = 0b1011;  // LH in swing
  const SlipInput below = standingInput(body, three, 0b0001, Vec3(0.12, 0.0, 0.0));
  const SlipInput above = standingInput(body, three, 0b0001, Vec3(0.14, 0.0, 0.0));
  ASSERT_LT(std::abs(below.u[0].norm() - body.norm()), params.threshold);
  ASSERT_GT(std::abs(above.u[0].norm() - body.norm()), params.threshold);
  int first = -1;
  for (int k = 0; k < 10 * params.creep_filter_ticks && first < 0; ++k) {
    const SlipResult r = detector.update((k / 2) % 2 == 0 ? above : below);
    EXPECT_EQ(r.slip_mask & ~0b0001u, 0u) << "tick " << k;
    if (r.slip_mask != 0) first = k + 1;
  }
  ASSERT_GT(first, 0) << "never flagged";
  EXPECT_LE(first, params.creep_filter_ticks + params.debounce_ticks);
}

// A creep that turns into a fast slip, then the foot holds: the creep
// filter, filled by the creep (0.054 m/s off three still feet, under the
// threshold), restarts once the norms flag the fast slip under the raised
// flag, so the flag drops after release_ticks clear ticks, with no tail
// from the creep's filter (held instead, it would keep the flag up while it
// decays under creep_threshold).
TEST_F(SlipDetectorTest, AFastSlipLeavesNoCreepTailBehindItsFlag) {
  const Vec3 body = Vec3::Zero();
  const SlipInput creeping = standingInput(body, kAllStance, 0b0100, Vec3(0.054, 0.0, 0.0));
  const SlipInput slipping = standingInput(body, kAllStance, 0b0100, Vec3(0.3, 0.1, 0.0));
  const SlipInput still = standingInput(body, kAllStance, 0, Vec3::Zero());
  for (int k = 0; k < 3 * params.creep_filter_ticks; ++k) detector.update(creeping);
  ASSERT_EQ(detector.slipMask(), 0b0100u);
  for (int k = 0; k < params.creep_filter_ticks; ++k) detector.update(slipping);
  ASSERT_EQ(detector.slipMask(), 0b0100u);
  int dropped = -1;
  for (int k = 1; k <= 3 * params.creep_filter_ticks && dropped < 0; ++k)
    if (detector.update(still).slip_mask == 0) dropped = k;
  EXPECT_EQ(dropped, params.release_ticks);
}

// A landing foot dragged along the ground at 0.038 m/s, under the slip
// threshold and the creep threshold, against three standing feet (the body
// at 0.05 m/s): its travel in excess of landing_drag_allowance reaches
// landing_drag_travel after 1 mm / 0.008 m/s = 125 ticks, and drag_mask
// names it from then on, with no slip flag. A drag at the allowance never
// counts; a stance foot dragged the same way is left to the creep test; a
// foot that stops comes off the mask within landing_drag_travel /
// landing_drag_allowance ticks; off, the mask stays empty.
TEST_F(SlipDetectorTest, ALandingFootDraggedBelowTheThresholdIsNamedByItsTravel) {
  const Vec3 body(0.05, 0.0, 0.0);
  SlipInput dragged = standingInput(body, kAllStance, 0b0001, Vec3(0.038, 0.0, 0.0));
  dragged.landing_mask = 0b0001;
  ASSERT_LT(std::abs(dragged.u[0].norm() - body.norm()), params.threshold);
  const int expected = dragTicks(params, 0.038);
  EXPECT_NEAR(firstDragTick(dragged, 2 * expected), expected, 1);

  // Stopped: the excess travel, capped at twice the bound, runs down.
  const SlipInput stopped = [&] {
    SlipInput in = standingInput(body, kAllStance, 0, Vec3::Zero());
    in.landing_mask = 0b0001;
    return in;
  }();
  const int run_down = static_cast<int>(std::ceil(params.landing_drag_travel /
                                                  (params.landing_drag_allowance * kTickPeriod)));
  int cleared = -1;
  for (int k = 1; k <= 2 * run_down && cleared < 0; ++k)
    if (detector.update(stopped).drag_mask == 0) cleared = k;
  EXPECT_GT(cleared, 0);
  EXPECT_LE(cleared, run_down + 1);

  SlipInput at_allowance = standingInput(body, kAllStance, 0b0001,
                                         Vec3(0.99 * params.landing_drag_allowance, 0.0, 0.0));
  at_allowance.landing_mask = 0b0001;
  SlipInput stance_drag = dragged;
  stance_drag.landing_mask = 0;
  for (const SlipInput* in : {&at_allowance, &stance_drag}) {
    detector.reset(params);
    for (int k = 0; k < 10 * expected; ++k) ASSERT_EQ(detector.update(*in).drag_mask, 0u) << "tick " << k;
  }

  SlipParams off = params;
  off.landing_drag_travel = 0.0;
  detector.reset(off);
  for (int k = 0; k < 10 * expected; ++k) ASSERT_EQ(detector.update(dragged).drag_mask, 0u) << "tick " << k;
}

// A searching foot outside the stance set, dragged at 0.038 m/s against the
// median of three others that stand at 0.04, 0.05 and 0.06 m/s
// (SlipInput::drag_only_mask: the ground holds it up, its force below the
// watch): the drag test names it after the same travel as a watched landing
// foot, with no slip flag, and it takes no part in the median (with a share
// the median would move 5 mm/s toward it, and its drag take 333 ticks, not
// 125) nor in the other tests (even at 0.3 m/s, nothing is flagged).
// Outside stance and outside that mask it is not tested, and its travel
// starts again from zero.
TEST_F(SlipDetectorTest, ASearchingFootTheGroundHoldsUpIsNamedByItsDragAlone) {
  const Vec3 body(0.05, 0.0, 0.0);
  const auto spread = [](SlipInput in) {  // the standing feet 0.01 m/s apart
    in.u[1].x() += 0.01;
    in.u[2].x() -= 0.01;
    in.drag_only_mask = 0b0001;
    return in;
  };
  const SlipInput dragged = spread(standingInput(body, 0b1110, 0b0001, Vec3(0.038, 0.0, 0.0)));
  const int expected = dragTicks(params, 0.038);
  EXPECT_NEAR(firstDragTick(dragged, 2 * expected), expected, 1);

  const SlipInput fast = spread(standingInput(body, 0b1110, 0b0001, Vec3(0.3, 0.0, 0.0)));
  detector.reset(params);
  for (int k = 0; k < 3 * params.debounce_ticks; ++k) {
    const SlipResult r = detector.update(fast);
    ASSERT_EQ(r.raw_mask, 0u) << "tick " << k;
    ASSERT_EQ(r.slip_mask, 0u) << "tick " << k;
    EXPECT_DOUBLE_EQ(r.median_speed, body.norm()) << "tick " << k;
  }

  // In the air for one tick between: untested, and its travel restarts.
  SlipInput untested = dragged;
  untested.drag_only_mask = 0;
  detector.reset(params);
  for (int k = 1; k < expected - 1; ++k) ASSERT_EQ(detector.update(dragged).drag_mask, 0u) << "tick " << k;
  ASSERT_EQ(detector.update(untested).drag_mask, 0u);
  for (int k = 1; k < expected - 1; ++k) ASSERT_EQ(detector.update(dragged).drag_mask, 0u) << "tick " << k;
  for (int k = 0; k < 10 * expected; ++k) ASSERT_EQ(detector.update(untested).drag_mask, 0u) << "tick " << k;
}

// Two of four feet creeping together by (0.06, 0.06) m/s, the body still:
// the component-wise median lies halfway, every foot is 0.042 m/s off it,
// and the creep test would flag all four. It stands aside (more than one
// foot named); the speeds differ from their median by 0.042 m/s, under the
// threshold, and without an IMU velocity nothing is flagged.
TEST_F(SlipDetectorTest, TwoFeetCreepingTogetherAreLeftToTheOtherTests) {
  const SlipInput pair = standingInput(Vec3::Zero(), kAllStance, 0b0011, Vec3(0.06, 0.06, 0.0));
  for (int k = 0; k < 5 * params.creep_filter_ticks; ++k) {
    const SlipResult r = detector.update(pair);
    ASSERT_EQ(r.raw_mask, 0u) << "tick " << k;
    ASSERT_EQ(r.test, SlipTest::kMedianUnverified) << "tick " << k;
  }
}

// The creep test names LF alone (0.06 m/s off the component-wise median,
// the others at most 0.036), but RF and LH still differ by 0.072 m/s, more
// than holding_agreement: the trust gate fails even without LF, and with
// no IMU velocity the unverified fallback keeps the median test's flags
// only (none: the speeds are within 0.036 m/s of their median).
TEST_F(SlipDetectorTest, TheUnverifiedFallbackIgnoresTheCreepTest) {
  SlipInput in;
  in.stance_mask = kAllStance;
  in.u[0] = Vec3(0.0, 0.06, 0.0);
  in.u[1] = Vec3(-0.036, 0.0, 0.0);
  in.u[2] = Vec3(0.036, 0.0, 0.0);
  in.u[3] = Vec3::Zero();
  ASSERT_GT((in.u[1] - in.u[2]).norm(), params.holding_agreement);
  for (int k = 0; k < 5 * params.creep_filter_ticks; ++k) {
    const SlipResult r = detector.update(in);
    ASSERT_EQ(r.test, SlipTest::kMedianUnverified) << "tick " << k;
    ASSERT_EQ(r.raw_mask, 0u) << "tick " << k;
  }
}

TEST_F(SlipDetectorTest, LiftOffDropsTheFlagAtOnce) {
  const SlipInput slipping = standingInput(Vec3::Zero(), kAllStance, 0b0001, Vec3(0.4, 0, 0));
  for (int k = 0; k < params.debounce_ticks; ++k) detector.update(slipping);
  ASSERT_EQ(detector.slipMask(), 0b0001u);
  SlipInput lifted = slipping;
  lifted.stance_mask = 0b1110;
  EXPECT_EQ(detector.update(lifted).slip_mask, 0u);
}

TEST_F(SlipDetectorTest, NoFalseFlagsWithNoiseBelowThreshold) {
  // Per-component noise of +/-a: two feet differ by at most 2*sqrt(3)*a,
  // 0.99 threshold for the a below (0.020 m/s at 0.07 m/s), on 3 or 4 legs.
  std::mt19937_64 rng(7);
  const double a = 0.99 * params.threshold / (2.0 * std::sqrt(3.0));
  std::uniform_real_distribution<double> noise(-a, a);
  std::uniform_real_distribution<double> base(-0.3, 0.3);
  const uint32_t masks[5] = {0xF, 0xE, 0xD, 0xB, 0x7};
  int flagged_ticks = 0;
  for (int tick = 0; tick < 20000; ++tick) {
    const Vec3 bv(base(rng), base(rng) * 0.3, base(rng) * 0.2);
    SlipInput in = standingInput(bv, masks[(tick / 500) % 5], 0, Vec3::Zero());
    for (int leg = 0; leg < kSlipLegs; ++leg)
      in.u[leg] += Vec3(noise(rng), noise(rng), noise(rng));
    const SlipResult r = detector.update(in);
    if (r.raw_mask != 0 || r.slip_mask != 0) ++flagged_ticks;
    EXPECT_EQ(r.test, SlipTest::kMedian);
  }
  EXPECT_EQ(flagged_ticks, 0);
}

TEST_F(SlipDetectorTest, TwoLegsSlippingTogetherAreFoundByTheImuTest) {
  const Vec3 bv(0.05, 0.0, 0.0);
  // Both front feet slide forward together: norms are bimodal, the median
  // sits between the groups and flags nobody (or everybody).
  SlipInput in = standingInput(bv, kAllStance, 0b0011, Vec3(0.15, 0.0, 0.0));
  in.imu_base_velocity = bv + Vec3(0.01, -0.01, 0.0);  // a slightly drifted IMU
  in.imu_velocity_valid = true;
  SlipResult r;
  for (int k = 0; k < params.debounce_ticks; ++k) r = detector.update(in);
  EXPECT_EQ(r.test, SlipTest::kImu);
  EXPECT_EQ(r.raw_mask, 0b0011u);
  EXPECT_EQ(r.slip_mask, 0b0011u);
  ASSERT_TRUE(r.slip_velocity_valid);
  // Reference from the two feet that hold (2 legs are enough).
  EXPECT_NEAR((r.slip_velocity_world[0] - Vec3(0.15, 0, 0)).norm(), 0.0, 1e-12);

  // Without a valid IMU velocity, the legs alone cannot tell: unverified.
  SlipDetector blind;
  blind.reset(params);
  in.imu_velocity_valid = false;
  EXPECT_EQ(blind.update(in).test, SlipTest::kMedianUnverified);
}

TEST_F(SlipDetectorTest, TwoOfThreeStanceLegsSlippingUseTheImuAsReference) {
  const Vec3 bv(0.04, 0.0, 0.0);
  SlipInput in = standingInput(bv, 0b1101, 0b0101, Vec3(0.0, 0.25, 0.0));
  in.imu_base_velocity = bv;
  in.imu_velocity_valid = true;
  const SlipResult r = detector.update(in);
  EXPECT_EQ(r.test, SlipTest::kImu);
  EXPECT_EQ(r.raw_mask, 0b0101u);
  ASSERT_TRUE(r.slip_velocity_valid);
  EXPECT_NEAR((r.u_reference + bv).norm(), 0.0, 1e-12);  // fewer than 2 good legs
  EXPECT_NEAR((r.slip_velocity_world[2] - Vec3(0.0, 0.25, 0.0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR(r.slip_velocity_world[3].norm(), 0.0, 1e-12);
}

// The trot's two stance feet: held and agreeing with the IMU, they anchor it
// (legs_agree) when anchor_on_two_feet is set, never in the crawl, and never
// while either foot is flagged or the two disagree.
TEST_F(SlipDetectorTest, TwoHoldingFeetAnchorTheImuOnlyWhenAskedTo) {
  const Vec3 bv(0.4, 0.02, 0.0);
  SlipInput in = standingInput(bv, 0b1001, 0, Vec3::Zero());
  in.imu_base_velocity = bv + Vec3(0.03, 0.0, 0.0);  // drift within the IMU test's threshold
  in.imu_velocity_valid = true;
  SlipResult r = detector.update(in);
  EXPECT_EQ(r.test, SlipTest::kImu);
  EXPECT_EQ(r.raw_mask, 0u);
  EXPECT_FALSE(r.legs_agree);  // the crawl's rule: at least three feet
  in.anchor_on_two_feet = true;
  r = detector.update(in);
  EXPECT_TRUE(r.legs_agree);
  EXPECT_NEAR((r.base_velocity_legs - bv).norm(), 0.0, 1e-12);  // the anchor is the legs', not the IMU's
  // One of the two sliding: flagged by the IMU test, no anchor.
  SlipInput sliding = standingInput(bv, 0b1001, 0b0001, Vec3(0.0, 0.3, 0.0));
  sliding.imu_base_velocity = bv;
  sliding.imu_velocity_valid = true;
  sliding.anchor_on_two_feet = true;
  r = detector.update(sliding);
  EXPECT_EQ(r.raw_mask, 0b0001u);
  EXPECT_FALSE(r.legs_agree);
  // Both within the IMU test's threshold but apart by more than the anchor's
  // agreement: no anchor.
  ASSERT_GT(params.multi_leg_consistency, 0.08);
  ASSERT_LT(params.imu_anchor_agreement, 0.08);
  SlipInput apart = standingInput(bv, 0b1001, 0b0001, Vec3(0.0, 0.08, 0.0));
  apart.imu_base_velocity = bv;
  apart.imu_velocity_valid = true;
  apart.anchor_on_two_feet = true;
  SlipDetector fresh;
  fresh.reset(params);
  r = fresh.update(apart);
  EXPECT_EQ(r.raw_mask, 0u);
  EXPECT_FALSE(r.legs_agree);
}

TEST_F(SlipDetectorTest, NonFiniteInputsAreLeftOut) {
  SlipInput in = standingInput(Vec3(0.05, 0, 0), kAllStance, 0b0010, Vec3(0.4, 0, 0));
  in.u[3] = Vec3(std::nan(""), 0.0, 0.0);
  in.imu_base_velocity = Vec3(INFINITY, 0, 0);
  in.imu_velocity_valid = true;
  SlipResult r;
  for (int k = 0; k < params.debounce_ticks; ++k) r = detector.update(in);
  EXPECT_EQ(r.test, SlipTest::kMedian);  // 3 usable legs, IMU refused
  EXPECT_EQ(r.slip_mask, 0b0010u);
  EXPECT_TRUE(r.slip_velocity_world[3].allFinite());
  EXPECT_TRUE(r.u_reference.allFinite());
}

TEST(ImuVelocityIntegratorTest, IntegratesAnchorsAndExpires) {
  SlipParams params;
  ImuVelocityIntegrator imu;
  imu.reset(params);
  const double dt = 0.001;
  const Vec3 g(0, 0, -9.81);
  const Mat3 R = yaw(0.3);
  const Vec3 accel_world(0.5, -0.2, 0.0);
  // Accelerometer reads specific force f = R^T (a - g).
  const Vec3 f_base = R.transpose() * (accel_world - g);
  EXPECT_FALSE(imu.valid());  // never anchored
  imu.update(f_base, R, g, dt, Vec3(0.1, 0, 0), true);
  EXPECT_TRUE(imu.valid());
  EXPECT_NEAR((imu.velocityWorld() - (R * Vec3(0.1, 0, 0) + accel_world * dt)).norm(), 0.0,
              1e-12);
  const Vec3 start = imu.velocityWorld();
  const int window_ticks = static_cast<int>(std::lround(params.imu_integration_window / dt));
  for (int k = 1; k < window_ticks; ++k) {
    imu.update(f_base, R, g, dt, Vec3(9, 9, 9), false);  // untrusted: ignored
    ASSERT_TRUE(imu.valid()) << k;
  }
  EXPECT_NEAR((imu.velocityWorld() - (start + accel_world * dt * (window_ticks - 1))).norm(),
              0.0, 1e-9);
  EXPECT_NEAR((imu.velocityBase() - R.transpose() * imu.velocityWorld()).norm(), 0.0, 1e-12);
  imu.update(f_base, R, g, dt, Vec3::Zero(), false);
  imu.update(f_base, R, g, dt, Vec3::Zero(), false);
  EXPECT_FALSE(imu.valid());  // ran alone longer than the window
  imu.update(f_base, R, g, dt, Vec3(0.2, 0, 0), true);
  EXPECT_TRUE(imu.valid());
  EXPECT_NEAR(imu.timeSinceAnchor(), dt, 1e-15);

  const Vec3 before = imu.velocityWorld();
  imu.update(Vec3(std::nan(""), 0, 0), R, g, dt, Vec3::Zero(), false);
  EXPECT_FALSE(imu.valid());
  EXPECT_EQ(imu.velocityWorld(), before);
}

// Integrator and detector wired as in the controller's tick.
class SlipDetectionLoopTest : public ::testing::Test {
 protected:
  void SetUp() override {
    detector.reset(params);
    imu.reset(params);
  }
  // One tick: the IMU anchors on the previous tick's legs, then the test.
  SlipResult step(const Vec3& specific_force_base, SlipInput in) {
    imu.update(specific_force_base, in.rotation_world_base, g, dt, last.base_velocity_legs,
               last.legs_agree);
    in.imu_base_velocity = imu.velocityBase();
    in.imu_velocity_valid = imu.valid();
    last = detector.update(in);
    return last;
  }
  SlipParams params;
  SlipDetector detector;
  ImuVelocityIntegrator imu;
  SlipResult last;
  const double dt = 0.001;
  const Vec3 g = Vec3(0, 0, -9.81);
};

// A synthetic trunk that accelerates; both front feet start sliding at
// t = 0.3 s for 150 ms.
TEST_F(SlipDetectionLoopTest, TwoFeetSlipDetectedWhileTheTrunkAccelerates) {
  const Mat3 R = yaw(-0.2);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> acc_noise(0.0, 0.05);  // [m/s^2]
  int first_flag_tick = -1;
  uint32_t mask_during = 0;
  for (int tick = 0; tick < 600; ++tick) {
    const double t = tick * dt;
    const Vec3 accel_world(0.4 * std::sin(4.0 * t), 0.2, 0.0);
    const Vec3 vel_world(0.1 * (1.0 - std::cos(4.0 * t)), 0.2 * t, 0.0);
    const Vec3 f_base = R.transpose() * (accel_world - g) +
                        Vec3(acc_noise(rng), acc_noise(rng), acc_noise(rng));
    const bool slipping = t >= 0.3 && t < 0.45;
    SlipInput in = standingInput(R.transpose() * vel_world, kAllStance,
                                 slipping ? 0b0011u : 0u, Vec3(0.2, 0.05, 0.0));
    in.rotation_world_base = R;
    step(f_base, in);
    if (last.slip_mask != 0 && first_flag_tick < 0) first_flag_tick = tick;
    if (t >= 0.31 && t < 0.45) mask_during |= last.slip_mask;
    if (t >= 0.31 && t < 0.45) {
      EXPECT_EQ(last.slip_mask, 0b0011u) << "tick " << tick;
      EXPECT_EQ(last.test, SlipTest::kImu) << "tick " << tick;
      // The slip velocity of a front foot is measured against the hind feet.
      EXPECT_NEAR((last.slip_velocity_world[0] - R * Vec3(0.2, 0.05, 0.0)).norm(), 0.0, 1e-9);
    }
    if (t >= 0.5) {
      EXPECT_EQ(last.slip_mask, 0u) << "tick " << tick;
    }
  }
  EXPECT_EQ(first_flag_tick, 300 + params.debounce_ticks - 1);
  EXPECT_EQ(mask_during, 0b0011u);
}

// Both front feet start sliding slowly (5 m/s^2): while they still agree with
// the hind feet within imu_anchor_agreement the anchor absorbs half their
// speed; after that the IMU holds, and the front feet are flagged once their
// speed exceeds that offset + multi_leg_consistency (~0.13 m/s, 26 ms) plus
// the debounce. The hind feet are never flagged.
TEST_F(SlipDetectionLoopTest, SlowTwoFootSlipFlagsOnlyTheSlippingFeet) {
  const Vec3 bv(0.05, 0, 0);
  int first_flag_tick = -1;
  uint32_t seen = 0;
  for (int tick = 0; tick < 400; ++tick) {
    const double slip_speed = tick >= 100 && tick < 300 ? std::min(0.3, (tick - 100) * 0.005) : 0.0;
    step(-g, standingInput(bv, kAllStance, 0b0011, Vec3(slip_speed, 0, 0)));
    if (last.slip_mask && first_flag_tick < 0) first_flag_tick = tick;
    seen |= last.slip_mask;
  }
  EXPECT_EQ(seen, 0b0011u);
  EXPECT_GE(first_flag_tick, 100);
  EXPECT_LE(first_flag_tick, 100 + 26 + params.debounce_ticks + 2);
}

// A slip that outlasts the IMU window loses the IMU test: the detector falls
// back to the (unverified) median answer, and regains the IMU after the slip.
TEST_F(SlipDetectionLoopTest, ImuWindowExpiryFallsBackToTheMedian) {
  const Vec3 bv(0.05, 0, 0);
  const int slip_start = 100, slip_end = 500;
  const int window_ticks = static_cast<int>(std::lround(params.imu_integration_window / dt));
  for (int tick = 0; tick < 700; ++tick) {
    const bool slipping = tick >= slip_start && tick < slip_end;
    step(-g, standingInput(bv, kAllStance, slipping ? 0b0011u : 0u, Vec3(0.3, 0, 0)));
    if (tick > slip_start && tick < slip_start + window_ticks - 1) {
      ASSERT_EQ(last.test, SlipTest::kImu) << tick;
    }
    if (tick > slip_start + window_ticks + 1 && tick < slip_end) {
      ASSERT_EQ(last.test, SlipTest::kMedianUnverified) << tick;
    }
    if (tick > slip_end + 2) {
      ASSERT_EQ(last.test, SlipTest::kMedian) << tick;
      ASSERT_TRUE(imu.valid()) << tick;
    }
  }
}

}  // namespace
}  // namespace hyq
