// Traction recovery: first-order correction rate, bounded per-tick changes,
// terrain normal handling, freezing entry/exit timing, friction rising again
// on a new foothold (timing and safety), recovery switched off, NaN inputs;
// the velocity the slip damping acts on.
#include "firmware/controller/slip/traction_recovery.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace hyq {
namespace {

constexpr double kDt = 0.001;
constexpr uint32_t kAllStance = 0xF;

double angleBetween(const Vec3& a, const Vec3& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

Vec3 tilted(double angle) { return Eigen::AngleAxisd(angle, Vec3::UnitY()) * Vec3::UnitZ(); }

// Leg `leg` slipping with a valid estimate (n_hat, mu_hat); all legs in stance.
RecoveryInput slipping(int leg, const Vec3& n_hat, double mu_hat) {
  RecoveryInput in;
  in.stance_mask = kAllStance;
  in.slip_mask = 1u << leg;
  in.estimate_valid[leg] = true;
  in.normal_estimate[leg] = n_hat;
  in.mu_estimate[leg] = mu_hat;
  return in;
}

RecoveryInput calm(uint32_t stance = kAllStance) {
  RecoveryInput in;
  in.stance_mask = stance;
  return in;
}

int ticks(double seconds) { return static_cast<int>(std::lround(seconds / kDt)); }

// A recovery whose leg 0 touched down and then stood `stood` [s] on
// `standing`, with the stance ratio's start on or off.
TractionRecovery stoodFor(const RecoveryParams& params, bool ratio_start, double stood,
                          const RecoveryInput& standing) {
  TractionRecovery r;
  r.reset(params);
  r.setGuessFromStanceRatio(ratio_start);
  r.update(calm(0), kDt);  // in the air: the next tick is a touch-down
  for (int k = 0; k < ticks(stood); ++k) r.update(standing, kDt);
  return r;
}

class TractionRecoveryTest : public ::testing::Test {
 protected:
  void SetUp() override {
    params.k_normal = 25.0;  // 1/K_n = 40 ticks exactly
    // The correction law alone: while flagged, mu heads for the same
    // estimate_margin * mu_hat it keeps afterwards. The brake (a lower target
    // while flagged) has its own test below.
    params.brake_margin = params.estimate_margin;
    params.freeze = true;  // the freezing mode's own tests (it is off by default)
    recovery.reset(params);
  }
  // A fresh slip of `leg` freezes again exactly when it has lasted freeze_after.
  void expectFreshSlipRefreezes(int leg, uint32_t expected_count) {
    const int enter = ticks(params.freeze_after);
    for (int k = 1; k < enter; ++k) recovery.update(slipping(leg, Vec3::UnitZ(), 0.2), kDt);
    EXPECT_FALSE(recovery.freezing());
    recovery.update(slipping(leg, Vec3::UnitZ(), 0.2), kDt);
    EXPECT_TRUE(recovery.freezing());
    EXPECT_EQ(recovery.freezeCount(), expected_count);
  }
  // Every foot touches down, with `leg`'s ground `ground`, and stands
  // `stood` [s]; returns that standing input.
  RecoveryInput standOn(int leg, const Vec3& ground, double stood) {
    RecoveryInput in = calm(0);
    in.ground_normal[leg] = ground;
    recovery.update(in, kDt);  // in the air: the next tick is a touch-down
    in.stance_mask = kAllStance;
    for (int k = 0; k < ticks(stood); ++k) recovery.update(in, kDt);
    return in;
  }
  RecoveryParams params;
  TractionRecovery recovery;
};

TEST_F(TractionRecoveryTest, NormalConvergesAtTheFirstOrderRate) {
  const Vec3 n_hat = tilted(0.3);
  const double start = angleBetween(recovery.normalInUse(1), n_hat);
  const int n = ticks(1.0 / params.k_normal);
  for (int k = 0; k < n; ++k) recovery.update(slipping(1, n_hat, 0.3), kDt);
  const double ratio = angleBetween(recovery.normalInUse(1), n_hat) / start;
  EXPECT_NEAR(ratio, std::pow(1.0 - params.k_normal * kDt, n), 1e-9);
  EXPECT_NEAR(ratio, std::exp(-1.0), 0.02 * std::exp(-1.0));  // discrete vs continuous
  // The rotation stays in the plane of n and n_hat (about their common axis).
  EXPECT_NEAR(recovery.normalInUse(1).y(), 0.0, 1e-12);
  // Other legs untouched.
  EXPECT_EQ(recovery.normalInUse(0), Vec3::UnitZ());
  EXPECT_EQ(recovery.muInUse(0), params.mu_default);
}

TEST_F(TractionRecoveryTest, PerTickChangesAreBoundedSoTorquesDoNotStep) {
  const double tilt = 0.1;
  const Vec3 n_hat = tilted(tilt);
  const double mu_hat = 0.3;
  const double mu_target = params.estimate_margin * mu_hat;  // above the floor, also the slope's
  ASSERT_GT(mu_target, params.mu_floor);
  ASSERT_GT(mu_target, params.slope_floor_factor * std::tan(tilt) / params.pyramid_scale);
  Vec3 n_prev = recovery.normalInUse(2);
  double mu_prev = recovery.muInUse(2);
  double largest_turn = 0.0, largest_mu_step = 0.0;
  for (int k = 0; k < 200; ++k) {
    recovery.update(slipping(2, n_hat, mu_hat), kDt);
    const double turn = angleBetween(recovery.normalInUse(2), n_prev);
    const double mu_step = std::fabs(recovery.muInUse(2) - mu_prev);
    EXPECT_LE(turn, params.k_normal * kDt * angleBetween(n_prev, n_hat) + 1e-12);
    EXPECT_NEAR(mu_step, params.k_mu * kDt * std::fabs(mu_target - mu_prev), 1e-12);
    largest_turn = std::max(largest_turn, turn);
    largest_mu_step = std::max(largest_mu_step, mu_step);
    n_prev = recovery.normalInUse(2);
    mu_prev = recovery.muInUse(2);
  }
  EXPECT_LE(largest_turn, tilt * params.k_normal * kDt + 1e-12);  // 2.5 mrad per tick
  EXPECT_LE(largest_mu_step, params.k_mu * kDt * (params.mu_default - mu_target) + 1e-12);
  // And it got there: mu_k = target + (mu_0 - target) (1 - K_mu dt)^k.
  EXPECT_NEAR(recovery.muInUse(2),
              mu_target + (params.mu_default - mu_target) * std::pow(1.0 - (params.k_mu * kDt), 200), 1e-12);
  EXPECT_NEAR(angleBetween(recovery.normalInUse(2), n_hat),
              tilt * std::pow(1.0 - params.k_normal * kDt, 200), 1e-9);
}

TEST_F(TractionRecoveryTest, CorrectionOnlyWhileSlippingWithAnEstimate) {
  // The paper's rule; the floor guess before an estimate is tested below.
  params.guess_floor_before_estimate = false;
  recovery.reset(params);
  RecoveryInput no_estimate = slipping(0, tilted(0.3), 0.2);
  no_estimate.estimate_valid[0] = false;
  RecoveryInput not_flagged = slipping(0, tilted(0.3), 0.2);
  not_flagged.slip_mask = 0;
  for (int k = 0; k < 100; ++k) {
    recovery.update(no_estimate, kDt);
    recovery.update(not_flagged, kDt);
  }
  EXPECT_EQ(recovery.normalInUse(0), Vec3::UnitZ());
  EXPECT_EQ(recovery.muInUse(0), params.mu_default);
  EXPECT_FALSE(recovery.corrected(0));
}

TEST_F(TractionRecoveryTest, CorrectedNormalHeldInStanceThenTerrainAfterLiftOff) {
  for (int k = 0; k < 30; ++k) recovery.update(slipping(3, tilted(0.3), 0.3), kDt);
  ASSERT_TRUE(recovery.corrected(3));
  const Vec3 corrected = recovery.normalInUse(3);
  RecoveryInput after = calm();
  after.terrain_normal = tilted(-0.1);  // a new plane fit from another touch-down
  for (int k = 0; k < 200; ++k) recovery.update(after, kDt);
  EXPECT_EQ(recovery.normalInUse(3), corrected);  // estimate beats the plane fit
  // An uncorrected stance leg follows the new plane fit smoothly.
  EXPECT_NEAR(angleBetween(recovery.normalInUse(0), tilted(-0.1)),
              0.1 * std::pow(1.0 - params.k_normal * kDt, 200), 1e-9);
  // Lift-off: the leg's normal is the terrain estimate again, correction over.
  after.stance_mask = kAllStance & ~(1u << 3);
  recovery.update(after, kDt);
  EXPECT_NEAR(angleBetween(recovery.normalInUse(3), tilted(-0.1)), 0.0, 1e-12);
  EXPECT_FALSE(recovery.corrected(3));
}

TEST_F(TractionRecoveryTest, FreezeEntersAfterFreezeAfterAndLeavesAfterFreezeHoldCalm) {
  const int enter = ticks(params.freeze_after);
  for (int k = 1; k <= enter; ++k) {
    recovery.update(slipping(0, Vec3::UnitZ(), 0.2), kDt);
    EXPECT_EQ(recovery.freezing(), k == enter) << "slip tick " << k;
  }
  EXPECT_EQ(recovery.freezeCount(), 1u);
  // Still slipping for a while, then calm with one interruption.
  for (int k = 0; k < 100; ++k) recovery.update(slipping(0, Vec3::UnitZ(), 0.2), kDt);
  for (int k = 0; k < 200; ++k) recovery.update(calm(), kDt);
  recovery.update(slipping(1, Vec3::UnitZ(), 0.2), kDt);  // a new flag restarts the count
  const int hold = ticks(params.freeze_hold);
  for (int k = 1; k <= hold; ++k) {
    recovery.update(calm(), kDt);
    EXPECT_EQ(recovery.freezing(), k < hold) << "calm tick " << k;
  }
  EXPECT_EQ(recovery.freezeCount(), 1u);
  expectFreshSlipRefreezes(2, 2u);
}

TEST_F(TractionRecoveryTest, UnloadedSlipsDoNotCountTowardFreezing) {
  // A foot dragged with 10 N before lift-off, for far longer than
  // freeze_after: flagged, but the robot does not stiffen.
  RecoveryInput dragged = slipping(2, Vec3::UnitZ(), 0.3);
  dragged.normal_force[2] = 0.2 * params.freeze_min_load;
  for (int k = 0; k < ticks(4 * params.freeze_after); ++k) recovery.update(dragged, kDt);
  EXPECT_FALSE(recovery.freezing());
  EXPECT_EQ(recovery.slipTime(2), 0.0);
  // The clock runs only while the foot is loaded, and holds in between.
  RecoveryInput loaded = dragged;
  loaded.normal_force[2] = 2.0 * params.freeze_min_load;
  const int half = ticks(params.freeze_after / 2);
  for (int k = 0; k < half; ++k) recovery.update(loaded, kDt);
  for (int k = 0; k < 100; ++k) recovery.update(dragged, kDt);
  EXPECT_NEAR(recovery.slipTime(2), half * kDt, 1e-9);
  for (int k = 0; k < ticks(params.freeze_after) - half - 1; ++k) recovery.update(loaded, kDt);
  EXPECT_FALSE(recovery.freezing());
  recovery.update(loaded, kDt);
  EXPECT_TRUE(recovery.freezing());
}

TEST_F(TractionRecoveryTest, AGuessGoesOnBetweenFlagsOnlyWhileTheFootIsLight) {
  // The crawl's guess hold, below 80 N: a flag without an estimate for 5
  // ticks, then 20 clear ticks at 10 N: mu goes on toward the floor.
  recovery.setGuessHolds(true, 80.0);
  const double k = params.k_mu * kDt;
  RecoveryInput flagged = calm();
  flagged.slip_mask = 0b0001;
  RecoveryInput light = calm();
  for (RecoveryInput* in : {&flagged, &light})
    for (int leg = 0; leg < kNumLegs; ++leg) in->normal_force[leg] = 10.0;
  double expected = params.mu_default;
  for (int i = 0; i < 5; ++i) {
    recovery.update(flagged, kDt);
    expected = k * params.mu_floor + (1.0 - k) * expected;
  }
  for (int i = 0; i < 20; ++i) {
    recovery.update(light, kDt);
    expected = k * params.mu_floor + (1.0 - k) * expected;
  }
  EXPECT_NEAR(recovery.muInUse(0), expected, 1e-12);
  EXPECT_EQ(recovery.muInUse(1), params.mu_default);
  // Loaded (200 N): mu in use stays where it is, and the guess is over:
  // light again (a foot unloaded before lift-off), mu still stays.
  RecoveryInput loaded = light;
  loaded.normal_force[0] = 200.0;
  for (int i = 0; i < 20; ++i) recovery.update(loaded, kDt);
  EXPECT_NEAR(recovery.muInUse(0), expected, 1e-12);
  for (int i = 0; i < 20; ++i) recovery.update(light, kDt);
  EXPECT_NEAR(recovery.muInUse(0), expected, 1e-12);
  // An estimate answers a guess: a new flag without one, then the estimate;
  // after it, a light foot's mu stays.
  for (int i = 0; i < 5; ++i) recovery.update(flagged, kDt);
  for (int i = 0; i < 300; ++i) recovery.update(slipping(0, Vec3::UnitZ(), 0.5), kDt);
  for (int i = 0; i < 300; ++i) recovery.update(loaded, kDt);  // the brake released
  const double after_estimate = recovery.muInUse(0);
  for (int i = 0; i < 20; ++i) recovery.update(light, kDt);
  EXPECT_NEAR(recovery.muInUse(0), after_estimate, 1e-12);
  // A lift-off ends the guess too.
  recovery.update(flagged, kDt);
  recovery.update(calm(0b1110), kDt);
  recovery.update(light, kDt);
  const double landed = recovery.muInUse(0);
  for (int i = 0; i < 20; ++i) recovery.update(light, kDt);
  EXPECT_NEAR(recovery.muInUse(0), landed, 1e-12);
  // Without the hold (the trot's), the guess stops with the flag.
  TractionRecovery trot;
  trot.reset(params);
  trot.setGuessHolds(false, 80.0);
  for (int i = 0; i < 5; ++i) trot.update(flagged, kDt);
  const double flag_end = trot.muInUse(0);
  for (int i = 0; i < 20; ++i) trot.update(light, kDt);
  EXPECT_NEAR(trot.muInUse(0), flag_end, 1e-12);
}

TEST_F(TractionRecoveryTest, ASlipNeverRaisesMu) {
  // An estimate above the mu in use (bad sample, or a slip due to the normal
  // alone): the normal is corrected, mu is left where it is.
  for (int k = 0; k < 100; ++k) recovery.update(slipping(0, tilted(0.2), 0.9), kDt);
  EXPECT_EQ(recovery.muInUse(0), params.mu_default);
  EXPECT_NEAR(angleBetween(recovery.normalInUse(0), tilted(0.2)),
              0.2 * std::pow(1.0 - params.k_normal * kDt, 100), 1e-9);
  // Lower estimates still pull it down, toward estimate_margin of them.
  recovery.update(slipping(0, tilted(0.2), 0.4), kDt);
  const double target = params.estimate_margin * 0.4;
  EXPECT_NEAR(recovery.muInUse(0), params.mu_default - (params.k_mu * kDt) * (params.mu_default - target),
              1e-12);
}

TEST_F(TractionRecoveryTest, ASlipWithoutEstimateHeadsForTheFloorThenFollowsTheEstimate) {
  ASSERT_TRUE(params.guess_floor_before_estimate);
  RecoveryInput no_estimate = calm();
  no_estimate.slip_mask = 0b0001;
  double expected = params.mu_default;
  for (int k = 0; k < 10; ++k) {
    recovery.update(no_estimate, kDt);
    expected = (params.k_mu * kDt) * params.mu_floor + (1.0 - (params.k_mu * kDt)) * expected;
    EXPECT_NEAR(recovery.muInUse(0), expected, 1e-12);
  }
  EXPECT_EQ(recovery.muInUse(1), params.mu_default);  // other feet untouched
  // The estimate arrives above the guess: mu in use rises to it, at K_mu.
  const double mu_hat = 0.4;
  const double target = params.estimate_margin * mu_hat;
  ASSERT_GT(target, expected);
  for (int k = 0; k < 300; ++k) recovery.update(slipping(0, Vec3::UnitZ(), mu_hat), kDt);
  EXPECT_NEAR(recovery.muInUse(0), target, 1e-6);
  // Once the slip is over, a later slip's higher estimate no longer raises it.
  recovery.update(calm(), kDt);
  for (int k = 0; k < 100; ++k) recovery.update(slipping(0, Vec3::UnitZ(), 0.55), kDt);
  EXPECT_NEAR(recovery.muInUse(0), target, 1e-6);
  // Nor does a guess: a new slip starts without an estimate (as every slip
  // does for its first samples), then a high estimate comes. mu goes back up
  // only to where it was when the guess began.
  recovery.update(calm(), kDt);
  for (int k = 0; k < 3; ++k) recovery.update(no_estimate, kDt);
  ASSERT_LT(recovery.muInUse(0), target);
  for (int k = 0; k < 300; ++k) recovery.update(slipping(0, Vec3::UnitZ(), 0.7), kDt);
  EXPECT_NEAR(recovery.muInUse(0), target, 1e-6);
  EXPECT_LE(recovery.muInUse(0), target + 1e-12);

  RecoveryParams paper = params;
  paper.guess_floor_before_estimate = false;
  TractionRecovery waits;
  waits.reset(paper);
  for (int k = 0; k < 10; ++k) waits.update(no_estimate, kDt);
  EXPECT_EQ(waits.muInUse(0), paper.mu_default);
}

// The trot's guess delay (30 ms): a flag that rises at touch-down (a
// landing slide) moves mu in use toward the floor only once it has lasted
// 30 ms; a flag that rises later in the stance at once.
TEST_F(TractionRecoveryTest, ALandingSlideWaitsForTheGuessDelayALaterSlipDoesNot) {
  recovery.setGuessDelay(0.03);
  RecoveryInput lifted = calm(0b1110);  // LF in the air, then lands flagged
  recovery.update(lifted, kDt);
  RecoveryInput landing = calm();
  landing.slip_mask = 0b0001;
  for (int k = 0; k < ticks(0.03); ++k) {
    recovery.update(landing, kDt);
    ASSERT_EQ(recovery.muInUse(0), params.mu_default) << "tick " << k;
  }
  recovery.update(landing, kDt);  // flagged 30 ms: the guess begins
  const double k_mu = params.k_mu * kDt;
  EXPECT_NEAR(recovery.muInUse(0), k_mu * params.mu_floor + (1.0 - k_mu) * params.mu_default, 1e-12);

  // A landing slide of 20 ms leaves mu alone; the same foot flagged 40 ms
  // into the stance is guessed down on the first tick.
  recovery.reset(params);
  recovery.update(lifted, kDt);
  for (int k = 0; k < ticks(0.02); ++k) recovery.update(landing, kDt);
  for (int k = 0; k < ticks(0.02); ++k) recovery.update(calm(), kDt);
  EXPECT_EQ(recovery.muInUse(0), params.mu_default);
  recovery.update(landing, kDt);
  EXPECT_NEAR(recovery.muInUse(0), k_mu * params.mu_floor + (1.0 - k_mu) * params.mu_default, 1e-12);

  // A flag that rises 10 ms after touch-down is within the window: it waits
  // until it has lasted 30 ms (40 ms into the stance).
  recovery.reset(params);
  recovery.update(lifted, kDt);
  for (int k = 0; k < ticks(0.01); ++k) recovery.update(calm(), kDt);
  for (int k = 0; k < ticks(0.03); ++k) {
    recovery.update(landing, kDt);
    ASSERT_EQ(recovery.muInUse(0), params.mu_default) << "tick " << k;
  }
  recovery.update(landing, kDt);
  EXPECT_NEAR(recovery.muInUse(0), k_mu * params.mu_floor + (1.0 - k_mu) * params.mu_default, 1e-12);
}

// With a load limit (the trot behind a torque loop), a flagged foot that
// carries more than it and has no estimate keeps its mu while its flag is
// younger than kLoadedSlideGuessAge: loaded that much, a slide on the cone
// would give an estimate, and a landing's skid is over by then. A flag that
// lasts longer is a slide whose estimate has not come, and is guessed down.
// Light, the same flag guesses at once.
TEST_F(TractionRecoveryTest, ALoadedFootWithoutAnEstimateIsGuessedDownOnlyOnceItsFlagHasLasted) {
  const double k_mu = params.k_mu * kDt;
  const double first_guess = k_mu * params.mu_floor + (1.0 - k_mu) * params.mu_default;
  recovery.setGuessLoadLimit(80.0);
  RecoveryInput flagged = calm();
  flagged.slip_mask = 0b0001;
  flagged.normal_force[0] = 200.0;
  ASSERT_EQ(ticks(kLoadedSlideGuessAge), 80);
  for (int k = 0; k < ticks(kLoadedSlideGuessAge); ++k) {
    recovery.update(flagged, kDt);
    ASSERT_EQ(recovery.muInUse(0), params.mu_default) << "tick " << k;
  }
  recovery.update(flagged, kDt);
  EXPECT_NEAR(recovery.muInUse(0), first_guess, 1e-12);
  // Light: at once.
  TractionRecovery light;
  light.reset(params);
  light.setGuessLoadLimit(80.0);
  flagged.normal_force[0] = 60.0;
  light.update(flagged, kDt);
  EXPECT_NEAR(light.muInUse(0), first_guess, 1e-12);
  // Without the limit (the default), the loaded foot is guessed down at once.
  TractionRecovery plain;
  plain.reset(params);
  flagged.normal_force[0] = 200.0;
  plain.update(flagged, kDt);
  EXPECT_NEAR(plain.muInUse(0), first_guess, 1e-12);
}

// With the stance ratio on (the crawl behind a torque loop), a foot that
// has stood kStanceSlideAge and carries kStanceSlideLoad starts its guess at
// its force ratio (not below the guess's target): it slides on the ground's
// cone. A younger foot (a touch-down slide), a lighter one, or a ratio above
// mu in use start from mu in use, as without it.
TEST_F(TractionRecoveryTest, ALoadedStanceSlideGuessesFromItsForceRatio) {
  const double k_mu = params.k_mu * kDt;
  const double from_mu = k_mu * params.mu_floor + (1.0 - k_mu) * params.mu_default;
  const double ratio = 0.12;
  ASSERT_GT(ratio, params.mu_floor);
  ASSERT_LT(ratio, params.mu_default);
  RecoveryInput standing = calm();
  standing.normal_force[0] = 2.0 * kStanceSlideLoad;
  standing.force_ratio[0] = ratio;
  RecoveryInput flagged = standing;
  flagged.slip_mask = 0b0001;
  // The first guess tick's mu in use, after `stood` of slip-free stance.
  auto firstGuess = [&](bool on, double stood, const RecoveryInput& flag) {
    TractionRecovery r = stoodFor(params, on, stood, standing);
    r.update(flag, kDt);
    return r.muInUse(0);
  };
  const double old_enough = kStanceSlideAge + 0.01, young = kStanceSlideAge - 0.05;
  EXPECT_NEAR(firstGuess(true, old_enough, flagged), k_mu * params.mu_floor + (1.0 - k_mu) * ratio, 1e-12);
  EXPECT_NEAR(firstGuess(false, old_enough, flagged), from_mu, 1e-12);
  EXPECT_NEAR(firstGuess(true, young, flagged), from_mu, 1e-12);
  RecoveryInput light = flagged;
  light.normal_force[0] = 0.5 * kStanceSlideLoad;
  EXPECT_NEAR(firstGuess(true, old_enough, light), from_mu, 1e-12);
  RecoveryInput below = flagged;  // the estimated force's error can put it under the floor
  below.force_ratio[0] = 0.5 * params.mu_floor;
  EXPECT_NEAR(firstGuess(true, old_enough, below), params.mu_floor, 1e-12);
  RecoveryInput wide = flagged;
  wide.force_ratio[0] = params.mu_default + 0.1;
  EXPECT_NEAR(firstGuess(true, old_enough, wide), from_mu, 1e-12);
  RecoveryInput unknown = flagged;  // a force estimate that failed
  unknown.force_ratio[0] = std::nan("");
  EXPECT_NEAR(firstGuess(true, old_enough, unknown), from_mu, 1e-12);
  unknown = flagged;
  unknown.normal_force[0] = std::nan("");
  EXPECT_NEAR(firstGuess(true, old_enough, unknown), from_mu, 1e-12);
  // Only where the guess begins: a flag that stays up keeps the law.
  TractionRecovery r = stoodFor(params, true, old_enough, standing);
  r.update(flagged, kDt);
  const double after_one = r.muInUse(0);
  RecoveryInput lower = flagged;  // a ratio it would start at, were this the guess's first tick
  lower.force_ratio[0] = 0.5 * (params.mu_floor + after_one);
  ASSERT_LT(lower.force_ratio[0], after_one);
  r.update(lower, kDt);
  EXPECT_NEAR(r.muInUse(0), k_mu * params.mu_floor + (1.0 - k_mu) * after_one, 1e-12);
}

// The start never raises mu in use: where the guess's target is above it (a
// foot's ground that tilts as the flag rises, lifting the slope floor), mu
// goes up by the law, one step a tick.
TEST_F(TractionRecoveryTest, AStanceSlideStartNeverRaisesMu) {
  const double k_mu = params.k_mu * kDt;
  RecoveryInput standing = calm();
  standing.normal_force[0] = 2.0 * kStanceSlideLoad;
  standing.force_ratio[0] = 0.1;
  TractionRecovery r = stoodFor(params, true, kStanceSlideAge + 0.01, standing);
  const double before = r.muInUse(0);
  ASSERT_NEAR(before, params.mu_default, 1e-12);
  // Ground tilted so far that its slope floor is 1.2 mu_default.
  const double floor = 1.2 * params.mu_default;
  const double tilt = std::atan(floor * params.pyramid_scale / params.slope_floor_factor);
  RecoveryInput flagged = standing;
  flagged.slip_mask = 0b0001;
  flagged.terrain_normal = Vec3(std::sin(tilt), 0.0, std::cos(tilt));
  r.update(flagged, kDt);
  EXPECT_GE(r.muInUse(0), before - 1e-12);
  EXPECT_LE(r.muInUse(0), before + 2.0 * k_mu * (floor - before) + 1e-12);
}

// A stance whose own estimate lies below the floor brakes below it, to the
// estimate's braking target and never under kEstimatedMuFloor; its next
// foothold, with no estimate, has the floor again.
TEST_F(TractionRecoveryTest, AStanceEstimatedBelowTheFloorBrakesBelowItDownToItsOwnFloor) {
  ASSERT_GT(params.mu_floor, params.brake_margin * 0.02);
  ASSERT_GT(params.brake_margin * 0.02, kEstimatedMuFloor);
  for (int k = 0; k < 300; ++k) recovery.update(slipping(3, Vec3::UnitZ(), 0.02), kDt);
  EXPECT_NEAR(recovery.muInUse(3), params.brake_margin * 0.02, 1e-6);
  EXPECT_GE(recovery.muInUse(3), params.brake_margin * 0.02 - 1e-12);
  for (int k = 0; k < 300; ++k) recovery.update(slipping(2, Vec3::UnitZ(), 0.005), kDt);
  EXPECT_NEAR(recovery.muInUse(2), kEstimatedMuFloor, 1e-6);
  EXPECT_GE(recovery.muInUse(2), kEstimatedMuFloor);
  // Lifted and set down again: the new stance has no estimate, and mu in
  // use rises to the floor by the correction's law.
  recovery.update(calm(kAllStance & ~(1u << 3)), kDt);
  for (int k = 0; k < 300; ++k) recovery.update(calm(), kDt);
  EXPECT_NEAR(recovery.muInUse(3), params.mu_floor, 1e-6);
}

TEST_F(TractionRecoveryTest, FreezingEndsAfterFreezeMaxEvenIfAFootKeepsCreeping) {
  const int enter = ticks(params.freeze_after), longest = ticks(params.freeze_max);
  for (int k = 0; k < enter; ++k) recovery.update(slipping(1, Vec3::UnitZ(), 0.2), kDt);
  ASSERT_TRUE(recovery.freezing());
  for (int k = 1; k <= longest; ++k) {
    recovery.update(slipping(1, Vec3::UnitZ(), 0.2), kDt);
    ASSERT_EQ(recovery.freezing(), k < longest) << k;
  }
  // Still creeping: a fresh freeze_after of loaded slip freezes it again.
  expectFreshSlipRefreezes(1, 2u);
}

TEST_F(TractionRecoveryTest, ShortSlipsDoNotFreeze) {
  for (int round = 0; round < 20; ++round) {
    for (int k = 0; k < ticks(params.freeze_after) - 1; ++k)
      recovery.update(slipping(round % 4, Vec3::UnitZ(), 0.3), kDt);
    recovery.update(calm(), kDt);
  }
  EXPECT_FALSE(recovery.freezing());
  EXPECT_EQ(recovery.freezeCount(), 0u);
}

// One leg's crawl: slips on ice (mu 0.15) right after a touch-down, stands on
// it for the rest of its stance, swings, lands on grip (mu 0.8).
TEST_F(TractionRecoveryTest, MuRisesAgainOnANewFootholdWithinTheStance) {
  const double stance_time = 6.8, swing_time = 1.2;  // 8 s crawl, duty 0.85
  const double ice_mu = 0.15;
  for (int k = 0; k < 100; ++k) recovery.update(slipping(0, Vec3::UnitZ(), ice_mu), kDt);
  EXPECT_NEAR(recovery.muInUse(0), params.estimate_margin * ice_mu, 0.01);
  const double mu_on_ice = recovery.muInUse(0);
  // Rest of the stance on ice: the ground under a still foot cannot change.
  for (int k = 100; k < ticks(stance_time); ++k) recovery.update(calm(), kDt);
  EXPECT_EQ(recovery.muInUse(0), mu_on_ice);
  for (int k = 0; k < ticks(swing_time); ++k) recovery.update(calm(0xE), kDt);
  EXPECT_EQ(recovery.muInUse(0), mu_on_ice);  // swing keeps the leg's mu
  // Touch-down on grip, no slip: holds for mu_rise_delay, then rises linearly.
  const int delay = ticks(params.mu_rise_delay);
  const double predicted_time_to_half =
      params.mu_rise_delay + (0.5 - mu_on_ice) / params.mu_rise_rate;
  int reached_half = -1;
  for (int k = 1; k <= ticks(stance_time); ++k) {
    recovery.update(calm(), kDt);
    if (k < delay) {
      ASSERT_EQ(recovery.muInUse(0), mu_on_ice) << k;
    }
    if (k == delay + 1000) {
      EXPECT_NEAR(recovery.muInUse(0), mu_on_ice + params.mu_rise_rate * 1.001, 1e-9);
    }
    if (reached_half < 0 && recovery.muInUse(0) >= 0.5) reached_half = k;
  }
  EXPECT_NEAR(reached_half * kDt, predicted_time_to_half, 2 * kDt);
  EXPECT_LT(reached_half * kDt, 3 * 2.0);  // within 3 crawl steps (~2 s each)
  EXPECT_EQ(recovery.muInUse(0), params.mu_rise_ceiling);  // and capped
}

TEST_F(TractionRecoveryTest, ANewSlipStopsTheRiseAndPullsMuDownAtOnce) {
  for (int k = 0; k < 100; ++k) recovery.update(slipping(1, Vec3::UnitZ(), 0.2), kDt);
  recovery.update(calm(0xD), kDt);  // lift-off
  recovery.update(calm(), kDt);     // touch-down somewhere new
  for (int k = 0; k < ticks(params.mu_rise_delay + 1.0); ++k) recovery.update(calm(), kDt);
  const double target = params.estimate_margin * 0.2;
  const double risen = recovery.muInUse(1);
  ASSERT_GT(risen, target + 0.9 * params.mu_rise_rate);
  // Still on ice after all: the first flagged tick already lowers mu.
  recovery.update(slipping(1, Vec3::UnitZ(), 0.2), kDt);
  EXPECT_NEAR(recovery.muInUse(1), risen - (params.k_mu * kDt) * (risen - target), 1e-12);
  for (int k = 0; k < 100; ++k) recovery.update(slipping(1, Vec3::UnitZ(), 0.2), kDt);
  EXPECT_NEAR(recovery.muInUse(1), target, 0.01);
  // And it does not rise again on that same foothold.
  for (int k = 0; k < ticks(5.0); ++k) recovery.update(calm(), kDt);
  EXPECT_NEAR(recovery.muInUse(1), target, 0.01);
}

TEST_F(TractionRecoveryTest, BrakeWhileFlaggedThenBackToTheEstimateMargin) {
  RecoveryParams brake;  // defaults: brake_margin < estimate_margin
  ASSERT_LT(brake.brake_margin, brake.estimate_margin);
  TractionRecovery r;
  r.reset(brake);
  const double mu_hat = 0.3;
  const double braking = brake.brake_margin * mu_hat, settled = brake.estimate_margin * mu_hat;
  ASSERT_GT(braking, brake.mu_floor);
  double expected = brake.mu_default;
  for (int k = 0; k < 100; ++k) {
    r.update(slipping(0, Vec3::UnitZ(), mu_hat), kDt);
    expected = (brake.k_mu * kDt) * braking + (1.0 - (brake.k_mu * kDt)) * expected;
    ASSERT_NEAR(r.muInUse(0), expected, 1e-12) << k;
  }
  EXPECT_NEAR(r.muInUse(0), braking, 1e-4);
  // Flag down: back up to estimate_margin * mu_hat at K_mu dt per tick, no further.
  for (int k = 0; k < 300; ++k) {
    r.update(calm(), kDt);
    expected += (brake.k_mu * kDt) * (settled - expected);
    ASSERT_NEAR(r.muInUse(0), expected, 1e-4) << k;
    ASSERT_LE(r.muInUse(0), settled + 1e-12);
  }
  EXPECT_NEAR(r.muInUse(0), settled, 1e-4);
  for (int k = 0; k < ticks(0.5); ++k) r.update(calm(), kDt);
  EXPECT_NEAR(r.muInUse(0), settled, 1e-4);  // and stays (no new foothold)

  // Never back above the mu in use when the slip began: a foot at 0.2
  // (0.8 x 0.25) slips again with an estimate of 0.3, brakes toward 0.15 ...
  TractionRecovery low;
  low.reset(brake);
  for (int k = 0; k < 300; ++k) low.update(slipping(1, Vec3::UnitZ(), 0.25), kDt);
  for (int k = 0; k < 300; ++k) low.update(calm(), kDt);
  const double before = low.muInUse(1);
  ASSERT_NEAR(before, brake.estimate_margin * 0.25, 1e-3);
  for (int k = 0; k < 50; ++k) low.update(slipping(1, Vec3::UnitZ(), 0.3), kDt);
  EXPECT_NEAR(low.muInUse(1), before - (before - brake.brake_margin * 0.3) *
                                           (1.0 - std::pow(1.0 - (brake.k_mu * kDt), 50)), 1e-9);
  // ... and after it, settles at min(0.8 * 0.3, before) = before.
  for (int k = 0; k < 300; ++k) low.update(calm(), kDt);
  EXPECT_NEAR(low.muInUse(1), before, 1e-4);
  EXPECT_LE(low.muInUse(1), before + 1e-12);

  // A foot lifted while still braking carries the settled mu, not the braked one.
  TractionRecovery lifted;
  lifted.reset(brake);
  for (int k = 0; k < 100; ++k) lifted.update(slipping(2, Vec3::UnitZ(), mu_hat), kDt);
  lifted.update(calm(0xB), kDt);
  EXPECT_NEAR(lifted.muInUse(2), settled, 1e-12);
}

TEST_F(TractionRecoveryTest, NoRiseWhileFrozen) {
  for (int k = 0; k < ticks(params.freeze_after) + 20; ++k)
    recovery.update(slipping(1, Vec3::UnitZ(), 0.2), kDt);
  ASSERT_TRUE(recovery.freezing());
  recovery.update(calm(0xD), kDt);
  const double mu = recovery.muInUse(1);
  for (int k = 0; k < ticks(params.freeze_hold) - 2; ++k) recovery.update(calm(), kDt);
  ASSERT_TRUE(recovery.freezing());
  EXPECT_EQ(recovery.muInUse(1), mu);
}

TEST(TractionRecoveryOffTest, DetectOnlyNothingCorrectedNothingFreezes) {
  RecoveryParams params;
  params.enabled = false;
  TractionRecovery recovery;
  recovery.reset(params);
  EXPECT_FALSE(recovery.enabled());
  RecoveryInput in = slipping(0, tilted(0.4), 0.1);
  in.terrain_normal = tilted(0.05);
  for (int k = 0; k < ticks(2.0); ++k) {
    recovery.update(in, kDt);
    ASSERT_FALSE(recovery.freezing());
    ASSERT_EQ(recovery.muInUse(0), params.mu_default);
  }
  EXPECT_FALSE(recovery.corrected(0));
  EXPECT_NEAR(angleBetween(recovery.normalInUse(0), tilted(0.05)), 0.0, 1e-9);
  EXPECT_EQ(recovery.freezeCount(), 0u);
  EXPECT_NEAR(recovery.slipTime(0), 2.0, 1e-6);  // the slip itself is still tracked
}

TEST_F(TractionRecoveryTest, NonFiniteInputsKeepTheStateFiniteAndCountAsNoEstimate) {
  const double nan = std::nan("");
  RecoveryInput bad = slipping(0, Vec3(nan, 0, 1), nan);
  bad.terrain_normal = Vec3(0, nan, 1);
  recovery.update(bad, kDt);
  recovery.update(slipping(1, tilted(0.2), 0.3), nan);
  recovery.update(slipping(1, tilted(0.2), 0.3), -kDt);
  RecoveryInput not_unit = slipping(2, Vec3(0, 0, 3), 0.3);
  recovery.update(not_unit, kDt);
  // Updates with a bad dt are skipped. A flagged foot whose estimate is
  // unusable is a slip without an estimate: one K_mu dt step toward the floor.
  const double guessed = (params.k_mu * kDt) * params.mu_floor + (1.0 - (params.k_mu * kDt)) * params.mu_default;
  for (int leg = 0; leg < kRecoveryLegs; ++leg) {
    EXPECT_TRUE(recovery.normalInUse(leg).allFinite());
    EXPECT_EQ(recovery.normalInUse(leg), Vec3::UnitZ());
    EXPECT_NEAR(recovery.muInUse(leg), leg == 0 || leg == 2 ? guessed : params.mu_default, 1e-12);
  }
}

// The slope floor, computed by hand: 1.2 * tan(0.25) / (1/sqrt(2)).
double slopeFloor(const RecoveryParams& p, double tilt) {
  return p.slope_floor_factor * std::tan(tilt) / p.pyramid_scale;
}

TEST_F(TractionRecoveryTest, OnASlopeMuNeverFallsBelowWhatCarriesTheWeight) {
  const double tilt = 0.25;  // the ramp scenario's slope [rad]
  const double floor = slopeFloor(params, tilt);
  ASSERT_NEAR(floor, 1.2 * 0.25534192122103627 * std::sqrt(2.0), 1e-12);
  ASSERT_GT(floor, params.mu_floor);
  recovery.reset(params, tilted(tilt));
  for (int k = 0; k < 300; ++k) {
    RecoveryInput in = slipping(0, tilted(tilt), 0.1);
    in.terrain_normal = tilted(tilt);
    recovery.update(in, kDt);
  }
  EXPECT_NEAR(recovery.muInUse(0), floor, 1e-6);
  EXPECT_GE(recovery.muInUse(0), floor - 1e-12);
}

// With a load limit (the trot behind a torque loop), a flagged foot lighter
// than it carries none of the weight the slope floor is for: its guess goes
// to mu_floor on the slope too, and stays there while the foot stays light,
// flagged or not. Once loaded the floor is back and mu in use rises to it by
// the correction law. Without the limit (the crawl) the same foot keeps the
// slope floor.
TEST_F(TractionRecoveryTest, ALightFlaggedFootOnASlopeIsGuessedBelowTheSlopeFloorUntilLoaded) {
  const double tilt = 0.25;
  const double floor = slopeFloor(params, tilt);
  ASSERT_GT(floor, 2.0 * params.mu_floor);
  RecoveryInput light = calm();
  light.terrain_normal = tilted(tilt);
  light.normal_force[0] = 10.0;
  RecoveryInput flagged = light;
  flagged.slip_mask = 0b0001;
  RecoveryInput loaded = light;
  loaded.normal_force[0] = 200.0;
  recovery.reset(params, tilted(tilt));
  recovery.setGuessLoadLimit(80.0);
  TractionRecovery plain;
  plain.reset(params, tilted(tilt));
  for (int k = 0; k < 300; ++k) {
    recovery.update(flagged, kDt);
    plain.update(flagged, kDt);
  }
  EXPECT_NEAR(recovery.muInUse(0), params.mu_floor, 1e-6);
  EXPECT_NEAR(plain.muInUse(0), floor, 1e-6);
  for (int k = 0; k < 50; ++k) recovery.update(light, kDt);
  EXPECT_NEAR(recovery.muInUse(0), params.mu_floor, 1e-6);
  const double k_mu = params.k_mu * kDt;
  const double before = recovery.muInUse(0);
  recovery.update(loaded, kDt);
  EXPECT_NEAR(recovery.muInUse(0), before + k_mu * (floor - before), 1e-12);
  for (int k = 0; k < 300; ++k) recovery.update(loaded, kDt);
  EXPECT_NEAR(recovery.muInUse(0), floor, 1e-6);
  EXPECT_GE(recovery.muInUse(0), floor - 1e-12);
}

TEST_F(TractionRecoveryTest, AboveItsEstimateTheSlopeFloorNarrowsTheConeAcrossTheSlope) {
  // ramp_035's numbers: a 0.35 rad slope, whose floor (0.62) is above the
  // ground's mu 0.55, which the estimate reads.
  const double tilt = 0.35, mu_hat = 0.55;
  const double floor = slopeFloor(params, tilt);
  ASSERT_GT(floor, mu_hat);
  recovery.reset(params, tilted(tilt));
  // Before any estimate, and on a foot without one: the square pyramid.
  RecoveryInput in = calm();
  in.terrain_normal = tilted(tilt);
  recovery.update(in, kDt);
  EXPECT_EQ(recovery.muAcross(0), recovery.muInUse(0));
  for (int k = 0; k < 500; ++k) {
    in = slipping(0, tilted(tilt), mu_hat);
    in.terrain_normal = tilted(tilt);
    recovery.update(in, kDt);
    // Never wider than the cone, never below the constant floor.
    ASSERT_LE(recovery.muAcross(0), recovery.muInUse(0));
    ASSERT_GE(recovery.muAcross(0), params.mu_floor - 1e-12);
  }
  EXPECT_NEAR(recovery.muInUse(0), floor, 1e-6);
  // The rectangle's corners on the estimated cone: (mu^2 + across^2) ps^2 = mu_hat^2.
  const double ps = params.pyramid_scale;
  const double across = std::sqrt(mu_hat * mu_hat / (ps * ps) - floor * floor);
  EXPECT_NEAR(recovery.muAcross(0), across, 1e-6);
  EXPECT_EQ(recovery.muAcross(1), recovery.muInUse(1));  // the other feet keep theirs
  // It stays for the stance (the slip is over) and ends at lift-off.
  in = calm();
  in.terrain_normal = tilted(tilt);
  for (int k = 0; k < 100; ++k) recovery.update(in, kDt);
  EXPECT_NEAR(recovery.muAcross(0), across, 1e-6);
  in.stance_mask = kAllStance & ~1u;
  recovery.update(in, kDt);
  EXPECT_EQ(recovery.muAcross(0), recovery.muInUse(0));
  // On the same slope with an estimate above the floor, and on flat ground
  // whatever the estimate: square.
  for (int k = 0; k < 300; ++k) {
    in = slipping(2, tilted(tilt), 1.2 * floor);
    in.terrain_normal = tilted(tilt);
    recovery.update(in, kDt);
    ASSERT_EQ(recovery.muAcross(2), recovery.muInUse(2));
  }
  recovery.reset(params);
  for (int k = 0; k < 300; ++k) {
    recovery.update(slipping(3, Vec3::UnitZ(), 0.05), kDt);
    ASSERT_EQ(recovery.muAcross(3), recovery.muInUse(3));
  }
}

TEST_F(TractionRecoveryTest, TheSlopeFloorFollowsTheTerrainAtTheCorrectionRate) {
  // Flat ice first: mu in use goes down to the constant floor (an estimate
  // whose braking target is the floor: brake_margin * mu_hat = mu_floor).
  const double at_floor = params.mu_floor / params.brake_margin;
  for (int k = 0; k < 300; ++k) recovery.update(slipping(1, Vec3::UnitZ(), at_floor), kDt);
  ASSERT_NEAR(recovery.muInUse(1), params.mu_floor, 1e-6);
  // Then the plane fit tilts (the robot has walked onto a slope) and the foot
  // lands again, on it: mu rises toward the slope floor by K_mu dt per tick,
  // never in one step.
  const double floor = slopeFloor(params, 0.25);
  RecoveryInput in = calm(kAllStance & ~2u);
  in.terrain_normal = tilted(0.25);
  recovery.update(in, kDt);
  ASSERT_FALSE(recovery.corrected(1));
  in.stance_mask = kAllStance;
  double mu = recovery.muInUse(1);
  for (int k = 0; k < 5; ++k) {
    recovery.update(in, kDt);
    mu += (params.k_mu * kDt) * (floor - mu);
    EXPECT_NEAR(recovery.muInUse(1), mu, 1e-12);
  }
  for (int k = 0; k < 300; ++k) recovery.update(in, kDt);
  EXPECT_NEAR(recovery.muInUse(1), floor, 1e-9);
  // Back on flat ground the floor is the constant one again: a slip pulls mu
  // below the slope floor.
  for (int k = 0; k < 300; ++k) recovery.update(slipping(1, Vec3::UnitZ(), at_floor), kDt);
  EXPECT_NEAR(recovery.muInUse(1), params.mu_floor, 1e-6);
  // On the slope (a new foothold), an estimate below the constant floor
  // leaves the slope's floor where it is: it carries the foot's share of the
  // weight there.
  in.stance_mask = kAllStance & ~2u;
  recovery.update(in, kDt);
  for (int k = 0; k < 300; ++k) {
    RecoveryInput tilted_slip = slipping(1, tilted(0.25), 0.02);
    tilted_slip.terrain_normal = tilted(0.25);
    recovery.update(tilted_slip, kDt);
  }
  EXPECT_NEAR(recovery.muInUse(1), floor, 1e-6);
}

TEST_F(TractionRecoveryTest, AFlaggedFootWithoutAnEstimateTurnsItsConeToItsGround) {
  // The foot's ground (its slope floor's) is tilted 0.2 rad; the foot slides
  // from its touch-down on, with no estimate: its cone turns toward that
  // ground at the correction rate all the same, flagged or not.
  RecoveryInput in = calm();
  in.ground_normal[0] = tilted(0.2);
  in.slip_mask = 1u;
  for (int k = 0; k < 60; ++k) recovery.update(in, kDt);
  EXPECT_NEAR(angleBetween(recovery.normalInUse(0), tilted(0.2)), 0.2 * std::pow(1.0 - params.k_normal * kDt, 60),
              1e-12);
  EXPECT_NEAR(recovery.muInUse(0), slopeFloor(params, 0.2), 0.05);  // the guess stops at that ground's floor
  in.slip_mask = 0;
  for (int k = 0; k < 60; ++k) recovery.update(in, kDt);
  EXPECT_NEAR(angleBetween(recovery.normalInUse(0), tilted(0.2)), 0.2 * std::pow(1.0 - params.k_normal * kDt, 120),
              1e-12);
  EXPECT_FALSE(recovery.corrected(0));
}

// A foot whose cone an estimate corrected slips again before a new estimate
// comes: the old estimate does not explain the slip (at a crest, the foot
// has rolled onto the other slope), so the cone goes back about the foot's
// ground at the correction rate and the guess heads for that ground's floor.
TEST_F(TractionRecoveryTest, ASlipItsEstimateDoesNotExplainTakesTheConeBackToItsGround) {
  for (int k = 0; k < 200; ++k) {
    RecoveryInput in = slipping(3, tilted(0.3), 0.5);
    in.ground_normal[3] = Vec3::UnitZ();
    recovery.update(in, kDt);
  }
  ASSERT_TRUE(recovery.corrected(3));
  const double start = angleBetween(recovery.normalInUse(3), Vec3::UnitZ());
  ASSERT_NEAR(start, 0.3, 5e-3);
  RecoveryInput held = calm();
  held.ground_normal[3] = Vec3::UnitZ();
  for (int k = 0; k < 100; ++k) recovery.update(held, kDt);
  EXPECT_TRUE(recovery.corrected(3));  // unflagged, the estimate's cone stays
  EXPECT_NEAR(angleBetween(recovery.normalInUse(3), Vec3::UnitZ()), start, 1e-12);
  RecoveryInput unexplained = held;
  unexplained.slip_mask = 1u << 3;
  const int n = 60;
  for (int k = 0; k < n; ++k) recovery.update(unexplained, kDt);
  EXPECT_FALSE(recovery.corrected(3));
  EXPECT_NEAR(angleBetween(recovery.normalInUse(3), Vec3::UnitZ()), start * std::pow(1.0 - params.k_normal * kDt, n),
              1e-9);
  EXPECT_LT(recovery.muInUse(3), 0.5 * params.estimate_margin * 0.5);  // heading for level ground's floor
}

TEST_F(TractionRecoveryTest, OnceCorrectedTheSlopeFloorIsTakenOnTheNormalInUse) {
  // Leg 0: its ground plane says 0.3 rad (a floor of 0.52), its slip's
  // estimate says level ground of mu 0.1. Leg 2: the other way round.
  const double mu_hat = 0.1;
  ASSERT_GT(slopeFloor(params, 0.3), 5.0 * mu_hat);
  for (int k = 0; k < 600; ++k) {
    RecoveryInput in = slipping(0, Vec3::UnitZ(), mu_hat);
    in.slip_mask |= 1u << 2;
    in.estimate_valid[2] = true;
    in.normal_estimate[2] = tilted(0.3);
    in.mu_estimate[2] = mu_hat;
    in.ground_normal[0] = tilted(0.3);
    in.ground_normal[2] = Vec3::UnitZ();
    recovery.update(in, kDt);
  }
  ASSERT_TRUE(recovery.corrected(0));
  ASSERT_TRUE(recovery.corrected(2));
  // Leg 0 at the estimate's target, as on level ground; leg 2 held at the
  // floor of the slope its estimate found.
  EXPECT_NEAR(recovery.muInUse(0), params.estimate_margin * mu_hat, 1e-6);
  EXPECT_NEAR(recovery.muInUse(2), slopeFloor(params, 0.3), 1e-3);
}

TEST_F(TractionRecoveryTest, EachConeIsAboutItsFootsGroundWhereThatDiffersFromTheTerrainPlane) {
  // The plane through all feet is tilted 0.15 rad between a ramp's slope
  // (hind feet, 0.25 rad) and its top (front feet, flat); the feet's ground
  // planes say which each stands on.
  RecoveryInput in = calm(0xC);  // hind feet in stance, front feet swinging
  in.terrain_normal = tilted(0.15);
  in.ground_normal[0] = Vec3::UnitZ();
  in.ground_normal[1] = tilted(0.15 + 0.5 * params.ground_plane_min_angle);  // within the angle
  in.ground_normal[2] = tilted(0.25);
  in.ground_normal[3] = Vec3::Zero();  // none: the terrain plane
  for (int k = 0; k < 600; ++k) recovery.update(in, kDt);
  EXPECT_NEAR(angleBetween(recovery.normalInUse(0), Vec3::UnitZ()), 0.0, 1e-12);  // swing: at once
  EXPECT_NEAR(angleBetween(recovery.normalInUse(1), tilted(0.15)), 0.0, 1e-12);
  // A stance foot's normal follows its ground from W z at the correction rate.
  const double left = std::pow(1.0 - params.k_normal * kDt, 600);
  EXPECT_NEAR(angleBetween(recovery.normalInUse(2), tilted(0.25)), 0.25 * left, 1e-12);
  EXPECT_NEAR(angleBetween(recovery.normalInUse(3), tilted(0.15)), 0.15 * left, 1e-12);
  // The slope floor is each foot's own: a slip without an estimate heads
  // for the floor of the slope under it, not of the terrain plane.
  for (int k = 0; k < 600; ++k) {
    RecoveryInput slip = in;
    slip.slip_mask = 0xC;
    recovery.update(slip, kDt);
  }
  EXPECT_NEAR(recovery.muInUse(2), slopeFloor(params, 0.25), 1e-6);
  EXPECT_NEAR(recovery.muInUse(3), slopeFloor(params, 0.15), 1e-6);
  // Without recovery every cone is about the terrain plane.
  RecoveryParams off = params;
  off.enabled = false;
  TractionRecovery plain;
  plain.reset(off);
  for (int k = 0; k < 10; ++k) plain.update(in, kDt);
  for (int leg = 0; leg < 2; ++leg) EXPECT_NEAR(angleBetween(plain.normalInUse(leg), tilted(0.15)), 0.0, 1e-12);
  for (int leg = 2; leg < 4; ++leg)
    EXPECT_NEAR(angleBetween(plain.normalInUse(leg), tilted(0.15)), 0.15 * std::pow(1.0 - off.k_normal * kDt, 10),
                1e-12);
}

// A stance foot 3 cm past a concave change of slope: its ground is the old
// plane (0.1 rad one way), the ground it stands on is tilted 0.15 rad the
// other way. It slides down the new slope with no estimate: once its travel
// has reached kTravelPlaneLength out of its ground's plane, its cone turns to
// the plane that holds the travel, with that plane's slope floor, and keeps
// it for the rest of the stance.
TEST_F(TractionRecoveryTest, AStanceSlideWhoseTravelLeavesItsGroundTurnsTheConeToHoldIt) {
  const Vec3 old_plane = tilted(0.1), new_plane = tilted(-0.15);
  const Vec3 down_new = -Vec3(std::cos(0.15), 0.0, std::sin(0.15));  // along the new plane, W
  ASSERT_NEAR(down_new.dot(new_plane), 0.0, 1e-15);
  const RecoveryInput in = standOn(1, old_plane, kStanceSlideAge);
  ASSERT_LT(angleBetween(recovery.normalInUse(1), old_plane), 0.01);
  RecoveryInput slide = in;
  slide.slip_mask = 1u << 1;
  // Short of the length; along the old plane; 2 deg out of it; and mostly
  // along its normal (a contact that gives): the cone stays about it.
  const Vec3 along_old = old_plane.cross(Vec3::UnitY());
  const Vec3 travels[] = {(kTravelPlaneLength - 1e-4) * down_new, 0.05 * along_old,
                          0.05 * (std::cos(0.035) * along_old + std::sin(0.035) * old_plane),
                          0.05 * (std::cos(1.0) * along_old + std::sin(1.0) * old_plane)};
  for (const Vec3& travel : travels) {
    slide.slip_travel[1] = travel;
    recovery.update(slide, kDt);
    EXPECT_EQ(recovery.travelGround(1), Vec3::Zero());
  }
  EXPECT_LT(angleBetween(recovery.normalInUse(1), old_plane), 0.01);
  slide.slip_travel[1] = (kTravelPlaneLength + 1e-4) * down_new;
  const double start = angleBetween(recovery.normalInUse(1), new_plane);
  const int n = 40;
  for (int k = 0; k < n; ++k) recovery.update(slide, kDt);
  EXPECT_NEAR(angleBetween(recovery.normalInUse(1), new_plane), start * std::pow(1.0 - params.k_normal * kDt, n), 1e-9);
  // The guess heads for the floor of the plane the cone is taken about.
  for (int k = 0; k < 2000; ++k) recovery.update(slide, kDt);
  ASSERT_GT(slopeFloor(params, 0.15), slopeFloor(params, 0.1) + 0.05);
  EXPECT_NEAR(recovery.muInUse(1), slopeFloor(params, 0.15), 1e-6);
  // The flag drops: the cone keeps turning to the new plane, not back.
  for (int k = 0; k < 400; ++k) recovery.update(in, kDt);
  EXPECT_LT(angleBetween(recovery.normalInUse(1), new_plane), 1e-3);
  EXPECT_FALSE(recovery.corrected(1));
  // The next stance is about its ground again.
  RecoveryInput swing = in;
  swing.stance_mask = kAllStance & ~(1u << 1);
  recovery.update(swing, kDt);
  EXPECT_NEAR(angleBetween(recovery.normalInUse(1), old_plane), 0.0, 1e-12);
  recovery.update(in, kDt);
  EXPECT_EQ(recovery.travelGround(1), Vec3::Zero());
}

// A slide with an estimate is the estimate's to correct: its travel turns no
// cone. Without one it does, and reset() forgets the turn.
TEST_F(TractionRecoveryTest, AnEstimatedSlidesTravelTurnsNoConeAndResetForgetsATurn) {
  standOn(3, tilted(0.1), kStanceSlideAge);
  RecoveryInput estimated = slipping(3, tilted(0.1), 0.3);
  estimated.ground_normal[3] = tilted(0.1);
  estimated.slip_travel[3] = 0.02 * Vec3(1.0, 0.0, 0.3).normalized();
  for (int k = 0; k < 100; ++k) recovery.update(estimated, kDt);
  EXPECT_EQ(recovery.travelGround(3), Vec3::Zero());
  RecoveryInput guessed = estimated;
  guessed.estimate_valid[3] = false;
  recovery.update(guessed, kDt);
  EXPECT_GT(recovery.travelGround(3).norm(), 0.5);
  recovery.reset(params);
  EXPECT_EQ(recovery.travelGround(3), Vec3::Zero());
}

// A landing's slide (the foot stood less than kStanceSlideAge when its flag
// rose) carries the impact's velocity errors: its travel turns no cone.
TEST_F(TractionRecoveryTest, ALandingSlidesTravelTurnsNoCone) {
  RecoveryInput in = standOn(2, tilted(0.1), 0.5 * kStanceSlideAge);
  in.slip_mask = 1u << 2;
  in.slip_travel[2] = 0.02 * Vec3(1.0, 0.0, 0.3).normalized();
  for (int k = 0; k < 200; ++k) recovery.update(in, kDt);
  EXPECT_EQ(recovery.travelGround(2), Vec3::Zero());
  EXPECT_LT(angleBetween(recovery.normalInUse(2), tilted(0.1)), 1e-3);
}

TEST_F(TractionRecoveryTest, WithFreezingSwitchedOffALongSlipOnlyCorrects) {
  RecoveryParams no_freeze = params;
  no_freeze.freeze = false;
  TractionRecovery plain;
  plain.reset(no_freeze);
  recovery.reset(params);
  for (int k = 0; k < ticks(2.0 * params.freeze_after); ++k) {
    recovery.update(slipping(1, Vec3::UnitZ(), 0.2), kDt);
    plain.update(slipping(1, Vec3::UnitZ(), 0.2), kDt);
  }
  EXPECT_TRUE(recovery.freezing());
  EXPECT_EQ(recovery.freezeCount(), 1u);
  EXPECT_FALSE(plain.freezing());
  EXPECT_EQ(plain.freezeCount(), 0u);
  // The correction itself is the same.
  EXPECT_EQ(plain.muInUse(1), recovery.muInUse(1));
  EXPECT_EQ(plain.normalInUse(1), recovery.normalInUse(1));
}

TEST_F(TractionRecoveryTest, PyramidMuIsTheInscribedScale) {
  EXPECT_NEAR(recovery.muPyramid(0), params.mu_default / std::sqrt(2.0), 1e-15);
}

// The slip damping's velocity: a slip that flips every tick (a 500 Hz ring)
// gives nothing, the part into or out of the ground is dropped, and a
// landing foot keeps the part that lifts it.
TEST(SlipDampingVelocity, TwoTickMeanAlongTheGroundAndALandingFootsLift) {
  const Vec3 up = Vec3::UnitZ();
  // A period-two oscillation: the mean is zero whatever its size.
  const Vec3 ring(0.4, -0.2, 0.3);
  EXPECT_NEAR(slipDampingVelocity(ring, -ring, true, up, false).norm(), 0.0, 1e-15);
  EXPECT_NEAR(slipDampingVelocity(ring, -ring, true, up, true).norm(), 0.0, 1e-15);
  // A steady slide: the mean is the slide; its part along z is dropped.
  const Vec3 slide(0.10, -0.05, 0.02);
  const Vec3 damped = slipDampingVelocity(slide, slide, true, up, false);
  EXPECT_NEAR((damped - Vec3(0.10, -0.05, 0.0)).norm(), 0.0, 1e-15);
  // No valid last tick: this tick's alone.
  const Vec3 first = slipDampingVelocity(slide, Vec3(9.0, 9.0, 9.0), false, up, false);
  EXPECT_NEAR((first - Vec3(0.10, -0.05, 0.0)).norm(), 0.0, 1e-15);
  // On a slope: along the ground of its normal, nothing across it.
  const Vec3 n = tilted(0.25);
  const Vec3 on_slope = slipDampingVelocity(Vec3(0.2, 0.1, -0.05), Vec3(0.2, 0.1, -0.05), true, n, false);
  EXPECT_NEAR(on_slope.dot(n), 0.0, 1e-15);
  // A landing foot lifting off (+n) keeps that part; one pushing in does not.
  const Vec3 lifting(0.05, 0.0, 0.3), sinking(0.05, 0.0, -0.3);
  EXPECT_NEAR(slipDampingVelocity(lifting, lifting, true, up, true).z(), 0.3, 1e-15);
  EXPECT_NEAR(slipDampingVelocity(lifting, lifting, true, up, false).z(), 0.0, 1e-15);
  EXPECT_NEAR(slipDampingVelocity(sinking, sinking, true, up, true).z(), 0.0, 1e-15);
}

}  // namespace
}  // namespace hyq
