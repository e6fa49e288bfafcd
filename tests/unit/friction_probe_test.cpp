// The friction probe: its pair is internal (no net force, no net moment),
// ramps at its rate, finds the friction of the foot that breaks away, holds
// at max_ratio, and keeps its bounds (four feet allowed, the loads, a foot
// already known, once per foothold unless aborted before it pulled or a
// guessed partner broke away first, one
// probe at a time, the release's ramp); its own watch on the pair's feet,
// confirmed by the detector; and the recovery's use of its answers.
#include "firmware/controller/slip/friction_probe.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "firmware/controller/slip/traction_recovery.hpp"

namespace hyq {
namespace {

constexpr double kDt = 0.001;  // [s]

ProbeParams on() {
  ProbeParams p;
  p.enabled = true;
  p.min_load = 150.0;
  p.settle_time = 0.05;
  p.quiet_time = 0.2;
  p.rate = 1000.0;
  p.max_force = 250.0;
  p.max_ratio = 0.6;
  p.break_release_rate = 8000.0;
  return p;
}

// Four feet on flat ground at full load, the QP's forces purely normal, all
// cones at mu 0.6. Legs 0-3: LF, RF, LH, RH.
ProbeInput standing() {
  ProbeInput in;
  in.allowed = true;
  in.stance = LegMask::all();
  in.feet << 0.37, 0.37, -0.37, -0.37,  //
      0.33, -0.33, 0.33, -0.33,         //
      0.0, 0.0, 0.0, 0.0;
  const double loads[4] = {220.0, 210.0, 200.0, 230.0};
  for (int i = 0; i < kNumLegs; ++i) {
    in.grf.col(i) = Vec3(0.0, 0.0, loads[i]);
    in.grf_des.col(i) = in.grf.col(i);
    in.mu_in_use[i] = 0.8;
  }
  in.grf_sample = in.grf;
  return in;
}

// Steps `probe` until a probe is under way (at most `ticks`); the ticks it took.
int stepUntilActive(FrictionProbe& probe, const ProbeInput& in, ProbeOutput& out, int ticks) {
  for (int k = 0; k < ticks; ++k) {
    probe.update(in, kDt, out);
    if (probe.active()) return k + 1;
  }
  return -1;
}

// A probe under way on the standing robot (on(), standing()); its foot,
// kNumLegs if none started.
int startStanding(FrictionProbe& probe, ProbeInput& in, ProbeOutput& out) {
  probe.reset(on());
  in = standing();
  if (stepUntilActive(probe, in, out, 1000) < 0) return kNumLegs;
  return out.leg;
}

// `foot` breaks away at `ratio`: kProbeRatioWindow samples at that ratio,
// the flag on the last of them.
void breakAway(FrictionProbe& probe, ProbeInput& in, ProbeOutput& out, int foot, double ratio) {
  const double fn = in.grf(2, foot);
  in.grf_sample.col(foot) = Vec3(ratio * fn, 0.0, fn);
  for (int k = 0; k < kProbeRatioWindow; ++k) {
    if (k == kProbeRatioWindow - 1) in.slipping.set(foot);
    probe.update(in, kDt, out);
  }
}

TEST(FrictionProbe, ItsPairAddsNoForceAndNoMomentToTheTrunk) {
  FrictionProbe probe;
  probe.reset(on());
  ProbeInput in = standing();
  in.feet(2, 0) = 0.008;  // one foot higher: the pair's line leaves the ground plane
  ProbeOutput out;
  ASSERT_GT(stepUntilActive(probe, in, out, 1000), 0);
  for (int k = 0; k < 50; ++k) probe.update(in, kDt, out);
  ASSERT_LT(out.leg, kNumLegs);
  Vec3 force = Vec3::Zero(), moment = Vec3::Zero();
  for (int i = 0; i < kNumLegs; ++i) {
    force += out.pair.col(i);
    moment += Vec3(in.feet.col(i)).cross(Vec3(out.pair.col(i)));
  }
  EXPECT_GT(out.pair.col(out.leg).norm(), 40.0);
  EXPECT_LT(force.norm(), 1e-12);
  EXPECT_LT(moment.norm(), 1e-12);
  // Only the two feet carry it.
  for (int i = 0; i < kNumLegs; ++i) {
    if (i != out.leg && i != out.partner) {
      EXPECT_EQ(out.pair.col(i).norm(), 0.0);
    }
  }
}

TEST(FrictionProbe, StartsOnTheMostLoadedGuessedFootAndRampsAtItsRate) {
  FrictionProbe probe;
  probe.reset(on());
  ProbeInput in = standing();
  in.known.set(3);  // RH (230 N) is known: LF (220 N) is the most loaded guess
  ProbeOutput out;
  // Not before quiet_time (no flag yet seen counts as quiet from the start) and settle_time.
  const int started = stepUntilActive(probe, in, out, 1000);
  EXPECT_EQ(started, 200);
  EXPECT_EQ(out.leg, 0);
  EXPECT_EQ(probe.started(), 1u);
  EXPECT_EQ(out.pair.col(0).norm(), 0.0);  // the ramp starts from zero
  for (int k = 1; k <= 100; ++k) {
    probe.update(in, kDt, out);
    EXPECT_NEAR(out.pair.col(0).norm(), 1000.0 * kDt * k, 1e-9);
  }
}

TEST(FrictionProbe, TheFootThatBreaksAwayGetsItsRatioAsItsFriction) {
  for (const bool partner_slips : {false, true}) {
    FrictionProbe probe;
    ProbeInput in;
    ProbeOutput out;
    const int leg = startStanding(probe, in, out), partner = out.partner;
    ASSERT_LT(leg, kNumLegs);
    const int slipping = partner_slips ? partner : leg;
    for (int k = 0; k < 26; ++k) probe.update(in, kDt, out);
    // The sliding foot's aligned samples over the ticks before the flag:
    // 0.19 of its load, tangential, but for one far off; their median counts.
    // Its cone's normal is tilted: the ratio is about it, and it is the
    // normal the answer carries.
    const Vec3 tilted = Vec3(0.05, -0.03, 1.0).normalized();
    in.normal[slipping] = tilted;
    const double fn = in.grf(2, slipping);
    Vec3 sample = Vec3::Zero();
    for (int k = 0; k < 5; ++k) {
      const double ratio = k == 2 ? 0.5 : 0.19;
      in.grf_sample.col(slipping) = Vec3(ratio * fn * 0.6, ratio * fn * 0.8, fn);
      if (k != 2) sample = in.grf_sample.col(slipping);
      if (k == 4) in.slipping.set(slipping);
      probe.update(in, kDt, out);
    }
    EXPECT_NEAR(out.mu_found[slipping], tangentialRatio(sample, tilted), 1e-12);
    EXPECT_EQ(out.normal_found[slipping], tilted);
    for (int i = 0; i < kNumLegs; ++i) {
      if (i != slipping) {
        EXPECT_EQ(out.mu_found[i], 0.0);
      }
    }
    EXPECT_EQ(probe.found(), 1u);
    // The pair steps down to kProbeBreakHoldShare of its 30 N (at
    // kProbeStepRate, 30 N a tick: in this one), then comes down at
    // break_release_rate, 8 N a tick.
    ASSERT_GE(kProbeStepRate * kDt, 30.0 * (1.0 - kProbeBreakHoldShare));
    EXPECT_NEAR(out.pair.col(leg).norm(), kProbeBreakHoldShare * 30.0, 1e-9);
    probe.update(in, kDt, out);
    EXPECT_NEAR(out.pair.col(leg).norm(), kProbeBreakHoldShare * 30.0 - 8.0, 1e-9);
    for (int k = 0; k < 2; ++k) probe.update(in, kDt, out);
    EXPECT_FALSE(probe.active());
    EXPECT_EQ(out.pair.norm(), 0.0);
  }
}

TEST(FrictionProbe, AFootThatHoldsMaxRatioIsKnownToHaveAtLeastThat) {
  FrictionProbe probe;
  ProbeInput in;
  ProbeOutput out;
  const int leg = startStanding(probe, in, out);
  ASSERT_LT(leg, kNumLegs);
  const double fn = in.grf(2, leg);
  int ticks = 0;
  while (out.mu_held[leg] == 0.0 && ticks < 1000) {
    // The estimate follows the pair, as on ground that holds.
    in.grf.col(leg) = Vec3(in.grf_des.col(leg) + out.pair.col(leg));
    probe.update(in, kDt, out);
    ++ticks;
  }
  EXPECT_EQ(probe.held(), 1u);
  EXPECT_GE(out.mu_held[leg], 0.6);
  EXPECT_LT(out.mu_held[leg], 0.6 + 1.5 / fn);  // within a tick of the ramp
  // The pair then comes down at `rate`, 1 N a tick, from the tick it held.
  const double at_end = out.pair.col(leg).norm();
  EXPECT_GT(at_end, 100.0);
  probe.update(in, kDt, out);
  EXPECT_NEAR(out.pair.col(leg).norm(), at_end - 1.0, 1e-9);
  // The partner breaks away while the pair comes down: the pair takes the
  // break-away's step, once: down at kProbeStepRate to kProbeBreakHoldShare
  // of itself, then at break_release_rate (8 N a tick); no friction is read
  // from it.
  const int partner = out.partner;
  in.slipping.set(partner);
  const double step_from = at_end - 1.0, step_to = kProbeBreakHoldShare * step_from;  // [N]
  const double per_tick = kProbeStepRate * kDt;                                      // [N]
  const int step_ticks = static_cast<int>(std::ceil((step_from - step_to) / per_tick));
  ASSERT_GE(step_ticks, 2);
  probe.update(in, kDt, out);
  EXPECT_NEAR(out.pair.col(leg).norm(), step_from - per_tick, 1e-9);
  EXPECT_EQ(out.mu_found[partner], 0.0);
  // The probed foot's break-away on the way down takes no second step.
  in.slipping.set(leg);
  for (int k = 1; k < step_ticks; ++k) probe.update(in, kDt, out);
  EXPECT_NEAR(out.pair.col(leg).norm(), step_to, 1e-9);
  probe.update(in, kDt, out);
  EXPECT_NEAR(out.pair.col(leg).norm(), step_to - 8.0, 1e-9);
  EXPECT_EQ(probe.found(), 0u);
}

// The probe's own watch: `foot` (0: the probed one, 1: its partner) slides
// away from the force the pair adds to it at `speed` for `ticks` ticks.
void slideAway(FrictionProbe& probe, ProbeInput& in, ProbeOutput& out, int foot, double speed, int ticks) {
  const int leg = out.leg, partner = out.partner;
  const Vec3 away = (foot == 0 ? -1.0 : 1.0) * out.pair.col(leg).normalized();
  in.velocity_valid = true;
  in.slip_velocity[foot == 0 ? leg : partner] = speed * away;
  for (int k = 0; k < ticks; ++k) probe.update(in, kDt, out);
}

TEST(FrictionProbe, TheWatchEndsTheRampAtASlideAndTheDetectorConfirmsItsAnswer) {
  for (const int foot : {0, 1}) {
    FrictionProbe probe;
    ProbeInput in;
    ProbeOutput out;
    const int leg = startStanding(probe, in, out), partner = out.partner;
    ASSERT_LT(leg, kNumLegs);
    const int sliding = foot == 0 ? leg : partner;
    for (int k = 0; k < 40; ++k) probe.update(in, kDt, out);
    const double fn = in.grf(2, sliding);
    const Vec3 tilted = Vec3(-0.04, 0.02, 1.0).normalized();  // its cone's normal while the ratios are taken
    in.normal[sliding] = tilted;
    in.grf_sample.col(sliding) = Vec3(0.21 * fn, 0.0, fn);
    const double expected = tangentialRatio(in.grf_sample.col(sliding), tilted);
    for (int k = 0; k < kProbeRatioWindow; ++k) probe.update(in, kDt, out);
    const double before = out.pair.col(leg).norm();  // [N]
    // One tick over the speed, then under it: the ramp goes on.
    slideAway(probe, in, out, foot, kProbeWatchSpeed + 0.005, kProbeWatchTicks - 1);
    slideAway(probe, in, out, foot, kProbeWatchSpeed - 0.005, 1);
    EXPECT_NEAR(out.pair.col(leg).norm(), before + kProbeWatchTicks * 1.0, 1e-9);
    // Sliding the other way (with the force) is not a break-away.
    slideAway(probe, in, out, foot, -0.2, 5);
    const double at_watch = out.pair.col(leg).norm() + 1.0;  // [N] the ramp's next tick
    // kProbeWatchTicks over the speed: the pair's step begins on the watch's
    // tick (kProbeStepRate), with no answer yet.
    slideAway(probe, in, out, foot, kProbeWatchSpeed + 0.005, kProbeWatchTicks);
    EXPECT_NEAR(out.pair.col(leg).norm(), std::fmax(kProbeBreakHoldShare * at_watch, at_watch - kProbeStepRate * kDt),
                1e-9);
    EXPECT_EQ(out.mu_found[sliding], 0.0);
    EXPECT_EQ(probe.found(), 0u);
    // Samples after the watch do not count, nor does the normal the foot's
    // cone turns to meanwhile; the pair is down, the probe waits.
    in.grf_sample.col(sliding) = Vec3(0.05 * fn, 0.0, fn);
    in.normal[sliding] = Vec3(0.2, 0.0, 1.0).normalized();
    for (int k = 0; k < 6; ++k) probe.update(in, kDt, out);
    EXPECT_TRUE(probe.active());
    EXPECT_EQ(out.pair.norm(), 0.0);
    // The detector's own test sees the foot: its friction is the median up to the watch.
    in.fast.set(sliding);
    probe.update(in, kDt, out);
    EXPECT_NEAR(out.mu_found[sliding], expected, 1e-12);
    EXPECT_EQ(out.normal_found[sliding], tilted);  // the normal it was read about
    EXPECT_EQ(probe.found(), 1u);
    EXPECT_EQ(probe.aborted(), 0u);
    probe.update(in, kDt, out);
    EXPECT_FALSE(probe.active());
  }
}

TEST(FrictionProbe, TheWatchWaitsForThePairsPullAndTheFlagConfirmsItToo) {
  FrictionProbe probe;
  ProbeInput in;
  ProbeOutput out;
  const int leg = startStanding(probe, in, out);
  ASSERT_LT(leg, kNumLegs);
  // Moving before the pair reaches kProbeRetryForce: not a break-away under it.
  slideAway(probe, in, out, 0, 0.1, 3);
  EXPECT_LT(out.pair.col(leg).norm(), kProbeRetryForce);
  EXPECT_NEAR(out.pair.col(leg).norm(), 3.0, 1e-9);
  in.slip_velocity[leg] = Vec3::Zero();
  for (int k = 0; k < 30; ++k) probe.update(in, kDt, out);
  const double fn = in.grf(2, leg);
  in.grf_sample.col(leg) = Vec3(0.0, 0.25 * fn, fn);
  for (int k = 0; k < kProbeRatioWindow; ++k) probe.update(in, kDt, out);
  slideAway(probe, in, out, 0, kProbeWatchSpeed + 0.02, kProbeWatchTicks);
  EXPECT_EQ(probe.found(), 0u);
  // The debounced flag confirms it as the raw test does.
  in.slipping.set(leg);
  probe.update(in, kDt, out);
  EXPECT_NEAR(out.mu_found[leg], 0.25, 1e-12);
  EXPECT_EQ(probe.found(), 1u);
}

// A probe 30 ticks into its ramp on the standing robot; `leg` its foot.
class FrictionProbeRamping : public ::testing::Test {
 protected:
  void SetUp() override {
    leg = startStanding(probe, in, out);
    ASSERT_LT(leg, kNumLegs);
    for (int k = 0; k < 30; ++k) probe.update(in, kDt, out);
  }
  FrictionProbe probe;
  ProbeInput in;
  ProbeOutput out;
  int leg = kNumLegs;
};

TEST_F(FrictionProbeRamping, AWatchedFootWhoseNormalIsUnsureGivesNoAnswer) {
  // [N] the pair at the watch: the ramp goes on until the watch's tick
  const double at_watch = out.pair.col(leg).norm() + (kProbeWatchTicks - 1) * 1.0;
  in.normal_unsure.set(leg);
  slideAway(probe, in, out, 0, kProbeWatchSpeed + 0.02, kProbeWatchTicks);
  // The step, and no wait for the detector: it gives no answer.
  EXPECT_NEAR(out.pair.col(leg).norm(), std::fmax(kProbeBreakHoldShare * at_watch, at_watch - kProbeStepRate * kDt),
              1e-9);
  EXPECT_EQ(probe.aborted(), 1u);
  in.fast.set(leg);
  for (int k = 0; k < 5; ++k) {
    probe.update(in, kDt, out);
    EXPECT_EQ(out.mu_found[leg], 0.0);
  }
  EXPECT_EQ(probe.found(), 0u);
  EXPECT_FALSE(probe.active());
}

TEST_F(FrictionProbeRamping, ADropEndsTheWatchsWaitWithoutAnAnswer) {
  slideAway(probe, in, out, 0, kProbeWatchSpeed + 0.02, kProbeWatchTicks);
  ASSERT_TRUE(probe.active());
  // A bad frame while the watch waits: the probe ends without an answer.
  probe.drop();
  EXPECT_FALSE(probe.active());
  EXPECT_EQ(probe.aborted(), 1u);
  in.fast.set(leg);
  probe.update(in, kDt, out);
  EXPECT_EQ(out.mu_found[leg], 0.0);
  EXPECT_EQ(probe.found(), 0u);
}

TEST_F(FrictionProbeRamping, AnUnconfirmedWatchGivesNoAnswerAndItsFootIsProbedOnceMoreWithoutIt) {
  // The foot creeps over the watch's speed, but never past the detector's
  // threshold: the watch's tick and the kProbeWatchConfirmTicks - 1 after it.
  slideAway(probe, in, out, 0, kProbeWatchSpeed + 0.01, kProbeWatchTicks + kProbeWatchConfirmTicks - 2);
  EXPECT_TRUE(probe.active());
  EXPECT_EQ(out.pair.norm(), 0.0);
  probe.update(in, kDt, out);
  EXPECT_FALSE(probe.active());
  for (int i = 0; i < kNumLegs; ++i) EXPECT_EQ(out.mu_found[i], 0.0);
  EXPECT_EQ(probe.found(), 0u);
  EXPECT_EQ(probe.aborted(), 1u);
  // Once more on the same foothold, without the watch: the creep goes on,
  // the ramp with it, and the break-away is read at the flag.
  ASSERT_GT(stepUntilActive(probe, in, out, 1000), 0);
  EXPECT_EQ(out.leg, leg);
  for (int k = 0; k < 30; ++k) probe.update(in, kDt, out);
  const double before = out.pair.col(leg).norm();  // [N]
  slideAway(probe, in, out, 0, kProbeWatchSpeed + 0.01, 10);
  EXPECT_NEAR(out.pair.col(leg).norm(), before + 10.0, 1e-9);
  breakAway(probe, in, out, leg, 0.3);
  EXPECT_NEAR(out.mu_found[leg], 0.3, 1e-12);
  EXPECT_EQ(probe.found(), 1u);
}

TEST(FrictionProbe, NeverWithoutFourFeetAllowedOrOnAKnownOrLightFoot) {
  ProbeOutput out;
  {  // the controller's conditions not met (a foot in swing, unloading, freezing)
    FrictionProbe probe;
    probe.reset(on());
    ProbeInput in = standing();
    in.allowed = false;
    EXPECT_EQ(stepUntilActive(probe, in, out, 2000), -1);
  }
  {  // every foot's friction known
    FrictionProbe probe;
    probe.reset(on());
    ProbeInput in = standing();
    in.known = LegMask::all();
    EXPECT_EQ(stepUntilActive(probe, in, out, 2000), -1);
  }
  {  // every foot below min_load
    FrictionProbe probe;
    probe.reset(on());
    ProbeInput in = standing();
    for (int i = 0; i < kNumLegs; ++i) in.grf(2, i) = 149.0;
    EXPECT_EQ(stepUntilActive(probe, in, out, 2000), -1);
  }
  {  // a foot flagged: quiet_time again from the flag
    FrictionProbe probe;
    probe.reset(on());
    ProbeInput in = standing();
    in.slipping.set(2);
    for (int k = 0; k < 500; ++k) probe.update(in, kDt, out);
    EXPECT_FALSE(probe.active());
    in.slipping = LegMask();
    EXPECT_EQ(stepUntilActive(probe, in, out, 1000), 200);
  }
  {  // switched off
    FrictionProbe probe;
    ProbeParams p = on();
    p.enabled = false;
    probe.reset(p);
    EXPECT_EQ(stepUntilActive(probe, standing(), out, 2000), -1);
    EXPECT_EQ(out.pair.norm(), 0.0);
  }
}

TEST(FrictionProbe, AbortsWhenTheStanceEndsOrALoadDrops) {
  FrictionProbe probe;
  probe.reset(on());
  ProbeInput in = standing();
  ProbeOutput out;
  ASSERT_GT(stepUntilActive(probe, in, out, 1000), 0);
  for (int k = 0; k < 20; ++k) probe.update(in, kDt, out);
  const int partner = out.partner;
  in.grf(2, partner) = 100.0;  // the partner unloads
  probe.update(in, kDt, out);
  EXPECT_EQ(probe.aborted(), 1u);
  for (int i = 0; i < kNumLegs; ++i) EXPECT_EQ(out.mu_held[i], 0.0);
  // Its pair (20 N) ramps down at `rate`.
  EXPECT_TRUE(probe.active());
  EXPECT_NEAR(out.pair.col(partner).norm(), 19.0, 1e-9);
  in.allowed = false;
  for (int k = 0; k < 19; ++k) probe.update(in, kDt, out);
  EXPECT_FALSE(probe.active());
  EXPECT_EQ(out.pair.norm(), 0.0);
}

TEST(FrictionProbe, StartsAboveMinLoadAndAnAbortBeforeItPulledIsRetried) {
  ProbeOutput out;
  {  // every foot between min_load and kProbeStartLoadShare of it: no start
    FrictionProbe probe;
    probe.reset(on());
    ProbeInput in = standing();
    for (int i = 0; i < kNumLegs; ++i) in.grf(2, i) = 170.0;
    EXPECT_EQ(stepUntilActive(probe, in, out, 2000), -1);
  }
  {  // the probed foot loaded, every partner between min_load and the start's share: no start
    FrictionProbe probe;
    probe.reset(on());
    ProbeInput in = standing();
    for (int i = 1; i < kNumLegs; ++i) in.grf(2, i) = 170.0;
    for (int i = 1; i < kNumLegs; ++i) in.known.set(i);
    EXPECT_EQ(stepUntilActive(probe, in, out, 2000), -1);
  }
  // The other feet known: only LF (220 N) is probed.
  ProbeInput in = standing();
  for (int i = 1; i < kNumLegs; ++i) in.known.set(i);
  for (const int pulled_ticks : {1, 20}) {
    FrictionProbe probe;
    probe.reset(on());
    ASSERT_GT(stepUntilActive(probe, in, out, 1000), 0);
    ASSERT_EQ(out.leg, 0);
    for (int k = 0; k < pulled_ticks; ++k) probe.update(in, kDt, out);
    ProbeInput light = in;
    light.grf(2, 0) = 140.0;  // under min_load: aborted
    probe.update(light, kDt, out);
    ASSERT_EQ(probe.aborted(), 1u);
    for (int k = 0; k < 100; ++k) probe.update(in, kDt, out);  // the release, then settle_time
    // 1 N of pair when it ended: the foot is probed again on this foothold;
    // 20 N: it has been pulled on, and is not.
    EXPECT_EQ(probe.started(), pulled_ticks == 1 ? 2u : 1u) << pulled_ticks;
  }
}

TEST(FrictionProbe, ADropEndsItAtOnceWithoutAnAnswer) {
  FrictionProbe probe;
  probe.reset(on());
  ProbeInput in = standing();
  ProbeOutput out;
  ASSERT_GT(stepUntilActive(probe, in, out, 1000), 0);
  for (int k = 0; k < 40; ++k) probe.update(in, kDt, out);
  probe.drop();
  EXPECT_FALSE(probe.active());
  EXPECT_EQ(probe.aborted(), 1u);
  // And the next needs settle_time of four feet again: none starts at once.
  probe.update(in, kDt, out);
  EXPECT_FALSE(probe.active());
  EXPECT_EQ(out.pair.norm(), 0.0);
}

TEST(FrictionProbe, EachFootOncePerFoothold) {
  FrictionProbe probe;
  probe.reset(on());
  ProbeInput in = standing();
  ProbeOutput out;
  int probes_of_leg0 = 0;
  // Every foot holds: each is probed once, then none again.
  for (int k = 0; k < 10000; ++k) {
    for (int i = 0; i < kNumLegs; ++i) in.grf.col(i) = Vec3(in.grf_des.col(i) + out.pair.col(i));
    const bool was_active = probe.active();
    probe.update(in, kDt, out);
    if (!was_active && probe.active() && out.leg == 0) ++probes_of_leg0;
  }
  EXPECT_EQ(probe.started(), 4u);
  EXPECT_EQ(probes_of_leg0, 1);
  // A new foothold of leg 0 (a swing and a touch-down) is probed again.
  in.stance = LegMask(0b1110);
  probe.update(in, kDt, out);
  in.stance = LegMask::all();
  for (int k = 0; k < 1000; ++k) {
    for (int i = 0; i < kNumLegs; ++i) in.grf.col(i) = Vec3(in.grf_des.col(i) + out.pair.col(i));
    probe.update(in, kDt, out);
  }
  EXPECT_EQ(probe.started(), 5u);
}

TEST(FrictionProbe, ThePartnerIsTheFootFurthestInsideItsCone) {
  FrictionProbe probe;
  probe.reset(on());
  ProbeInput in = standing();
  in.known = LegMask(0b1110);  // LF is probed
  // RF and LH already pushed sideways toward where the pair would load them.
  in.mu_in_use[1] = 0.2;
  in.mu_in_use[2] = 0.2;
  ProbeOutput out;
  ASSERT_GT(stepUntilActive(probe, in, out, 1000), 0);
  EXPECT_EQ(out.leg, 0);
  EXPECT_EQ(out.partner, 3);  // RH, at mu 0.8, the diagonal
}

// A foot whose guessed cone is narrowed (a floor after its own slip: the
// ground in question) is probed before a more loaded one at the default.
TEST(FrictionProbe, ANarrowedGuessIsProbedBeforeTheMostLoadedFoot) {
  for (const double lh_mu : {0.8, 0.1}) {
    FrictionProbe probe;
    probe.reset(on());
    ProbeInput in = standing();
    in.mu_in_use[2] = lh_mu;  // LH carries 200 N, the least
    ProbeOutput out;
    ASSERT_GT(stepUntilActive(probe, in, out, 1000), 0);
    EXPECT_EQ(out.leg, lh_mu < 0.5 ? 2 : 3) << lh_mu;  // else RH, 230 N
  }
}

// A partner whose cone is a guess narrowed to a floor is pulled past it, up
// to kProbeGuessedPartnerRatio, since its break-away is an answer too; a
// known partner stops the ramp at partner_margin of its cone. A partner
// that breaks away first leaves the probed foot to be probed again.
TEST(FrictionProbe, AGuessedPartnerIsProbedTooAndItsBreakAwayLeavesTheFootToProbe) {
  for (const bool partners_known : {true, false}) {
    FrictionProbe probe;
    probe.reset(on());
    ProbeInput in = standing();
    for (int i = 0; i < kNumLegs; ++i) in.mu_in_use[i] = 0.1;
    if (partners_known) in.known = LegMask(0b1110);  // only LF's cone a guess
    ProbeOutput out;
    ASSERT_GT(stepUntilActive(probe, in, out, 1000), 0);
    const int leg = out.leg, partner = out.partner;
    double peak = 0.0;  // [N] the pair's largest magnitude
    for (int k = 0; k < 60; ++k) {  // ground that holds
      for (int i = 0; i < kNumLegs; ++i) in.grf.col(i) = Vec3(in.grf_des.col(i) + out.pair.col(i));
      probe.update(in, kDt, out);
      peak = std::fmax(peak, out.pair.col(leg).norm());
    }
    if (partners_known) {
      // Held at 0.8 x 0.1 of the partner's 200-230 N, within a tick of the ramp.
      EXPECT_EQ(probe.held(), 1u);
      EXPECT_LT(peak, 0.08 * 230.0 + 1.0);
      continue;
    }
    // Still ramping, 1 N a tick: 60 N is a ratio of 0.26-0.3 on the partner,
    // under kProbeGuessedPartnerRatio.
    EXPECT_EQ(leg, 3);  // every guess narrowed: the most loaded, RH
    EXPECT_EQ(probe.held(), 0u);
    EXPECT_NEAR(peak, 60.0, 1e-9);
    breakAway(probe, in, out, partner, 0.3);
    EXPECT_NEAR(out.mu_found[partner], 0.3, 1e-12);
    EXPECT_EQ(out.mu_found[leg], 0.0);
    // The partner known now, the probed foot is probed again on this foothold.
    in.slipping = LegMask();
    in.known.set(partner);
    in.grf_sample = in.grf;
    bool again = false;
    for (int k = 0; k < 1000 && !again; ++k) {
      const bool was_active = probe.active();
      probe.update(in, kDt, out);
      again = !was_active && probe.active() && out.leg == leg;
    }
    EXPECT_TRUE(again);
  }
}

// A partner whose cone's normal is unsure gives no answer by breaking away:
// under a narrowed guess it is still held to partner_margin of its cone.
TEST(FrictionProbe, AnUnsurePartnerIsNotPulledPastItsCone) {
  FrictionProbe probe;
  probe.reset(on());
  ProbeInput in = standing();
  for (int i = 0; i < kNumLegs; ++i) in.mu_in_use[i] = 0.1;
  in.normal_unsure = LegMask(0b0111);  // only RH probed; its partners' normals unsure
  ProbeOutput out;
  ASSERT_GT(stepUntilActive(probe, in, out, 1000), 0);
  ASSERT_EQ(out.leg, 3);
  double peak = 0.0;  // [N]
  for (int k = 0; k < 60; ++k) {
    for (int i = 0; i < kNumLegs; ++i) in.grf.col(i) = Vec3(in.grf_des.col(i) + out.pair.col(i));
    probe.update(in, kDt, out);
    peak = std::fmax(peak, out.pair.col(3).norm());
  }
  EXPECT_EQ(probe.held(), 1u);
  EXPECT_LT(peak, 0.08 * 220.0 + 1.0);  // 0.8 x 0.1 of the partner's 200-220 N
}

// A known partner that breaks away first is read, and the probed foot stays
// probed on its foothold: no probe after probe against a known partner.
TEST(FrictionProbe, AKnownPartnersBreakAwayLeavesTheFootProbed) {
  FrictionProbe probe;
  probe.reset(on());
  ProbeInput in = standing();
  in.known = LegMask(0b1110);  // only LF's friction a guess
  ProbeOutput out;
  ASSERT_GT(stepUntilActive(probe, in, out, 1000), 0);
  const int partner = out.partner;
  ASSERT_EQ(out.leg, 0);
  for (int k = 0; k < 20; ++k) probe.update(in, kDt, out);
  breakAway(probe, in, out, partner, 0.3);
  EXPECT_NEAR(out.mu_found[partner], 0.3, 1e-12);
  in.slipping = LegMask();
  in.grf_sample = in.grf;
  for (int k = 0; k < 2000; ++k) probe.update(in, kDt, out);
  EXPECT_EQ(probe.started(), 1u);
}

// A foot whose cone's normal is not the feet's plane's is not probed, and
// its break-away as a partner gives no answer: its ratio about that normal
// is not its friction.
TEST(FrictionProbe, AFootWhoseNormalIsUnsureIsNeitherProbedNorRead) {
  ProbeOutput out;
  {
    FrictionProbe probe;
    probe.reset(on());
    ProbeInput in = standing();
    in.known = LegMask(0b0111);
    in.normal_unsure.set(3);  // RH, the only guess
    EXPECT_EQ(stepUntilActive(probe, in, out, 2000), -1);
  }
  FrictionProbe probe;
  probe.reset(on());
  ProbeInput in = standing();
  ASSERT_GT(stepUntilActive(probe, in, out, 1000), 0);
  const int partner = out.partner;
  for (int k = 0; k < 20; ++k) probe.update(in, kDt, out);
  in.normal_unsure.set(partner);
  in.grf_sample.col(partner) = Vec3(60.0, 0.0, 200.0);
  in.slipping.set(partner);
  for (int k = 0; k < kProbeRatioWindow; ++k) probe.update(in, kDt, out);
  EXPECT_EQ(probe.found(), 0u);
  EXPECT_EQ(probe.aborted(), 1u);
  for (int i = 0; i < kNumLegs; ++i) EXPECT_EQ(out.mu_found[i], 0.0);
}

// A recovery with `p`, its four feet in stance for a tick.
void standFour(TractionRecovery& recovery, const RecoveryParams& p, RecoveryInput& in) {
  recovery.reset(p);
  in.stance_mask = 0xF;
  recovery.update(in, kDt);
}

// The recovery: a found mu takes the foot's cone to estimate_margin x it by
// the correction's first-order law (K_mu dt of the gap a tick, never a step)
// and is what a later slip brakes toward; a held ratio lifts a guess the
// same way.
TEST(FrictionProbe, TheRecoveryTakesItsAnswers) {
  RecoveryParams p;
  TractionRecovery recovery;
  RecoveryInput in;
  standFour(recovery, p, in);
  EXPECT_FALSE(recovery.knowsFriction(0));
  const double k_mu = p.k_mu * kDt;  // [-] of the gap a tick
  const double before = recovery.muInUse(0), target = p.estimate_margin * 0.2;
  ASSERT_NEAR(before, p.mu_default, 1e-12);
  in.probe_mu[0] = 0.2;
  recovery.update(in, kDt);
  EXPECT_NEAR(recovery.muInUse(0), before + k_mu * (target - before), 1e-12);
  EXPECT_TRUE(recovery.knowsFriction(0));
  in.probe_mu[0] = 0.0;
  recovery.update(in, kDt);
  EXPECT_NEAR(recovery.muInUse(0), before + (1.0 - (1.0 - k_mu) * (1.0 - k_mu)) * (target - before), 1e-12);
  for (int k = 0; k < 200; ++k) recovery.update(in, kDt);
  EXPECT_NEAR(recovery.muInUse(0), target, 1e-4);
  // A slip of it without an estimate brakes toward brake_margin x 0.2, not the floor.
  in.slip_mask = 1u;
  for (int k = 0; k < 200; ++k) recovery.update(in, kDt);
  EXPECT_NEAR(recovery.muInUse(0), p.brake_margin * 0.2, 1e-6);
  // A foot guessed toward the floor that then holds 0.5: mu in use 0.8 x 0.5.
  in.slip_mask = 2u;
  for (int k = 0; k < 200; ++k) recovery.update(in, kDt);
  EXPECT_LT(recovery.muInUse(1), 0.1);
  in.slip_mask = 0u;
  in.probe_held[1] = 0.5;
  const double guessed = recovery.muInUse(1);
  recovery.update(in, kDt);
  EXPECT_NEAR(recovery.muInUse(1), guessed + k_mu * (p.estimate_margin * 0.5 - guessed), 1e-12);
  EXPECT_TRUE(recovery.knowsFriction(1));
  in.probe_held[1] = 0.0;
  for (int k = 0; k < 200; ++k) recovery.update(in, kDt);
  EXPECT_NEAR(recovery.muInUse(1), p.estimate_margin * 0.5, 1e-4);
  // Both are forgotten at lift-off.
  in.stance_mask = 0xC;
  recovery.update(in, kDt);
  EXPECT_FALSE(recovery.knowsFriction(0));
  EXPECT_FALSE(recovery.knowsFriction(1));
}

// The approach to an answer ends at a flag (the slip's own law takes over),
// never pulls a held ratio's foot down, and stops at no target under the
// foot's floor when its ground steepens meanwhile.
TEST(FrictionProbe, TheRecoverysApproachToAnAnswerYieldsToAFlagAndTheFloor) {
  RecoveryParams p;
  TractionRecovery recovery;
  RecoveryInput in;
  standFour(recovery, p, in);
  // Leg 0: found at 0.2, flagged two ticks later with no estimate: it brakes
  // toward brake_margin x 0.2 from where it was, and once the flag drops
  // mu in use is not taken back up to estimate_margin x 0.2.
  in.probe_mu[0] = 0.2;
  recovery.update(in, kDt);
  in.probe_mu[0] = 0.0;
  recovery.update(in, kDt);
  const double flagged_at = recovery.muInUse(0);
  EXPECT_GT(flagged_at, p.estimate_margin * 0.2 + 0.3);
  in.slip_mask = 1u;
  for (int k = 0; k < 200; ++k) recovery.update(in, kDt);
  EXPECT_NEAR(recovery.muInUse(0), p.brake_margin * 0.2, 1e-6);
  in.slip_mask = 0u;
  for (int k = 0; k < 200; ++k) recovery.update(in, kDt);
  EXPECT_LT(recovery.muInUse(0), p.brake_margin * 0.2 + 1e-6);
  // Leg 1 at mu_default holds a ratio whose estimate_margin x it is under
  // that: mu in use stays.
  in.probe_held[1] = 0.5;
  recovery.update(in, kDt);
  in.probe_held[1] = 0.0;
  for (int k = 0; k < 50; ++k) recovery.update(in, kDt);
  EXPECT_NEAR(recovery.muInUse(1), p.mu_default, 1e-12);
  // Leg 2 found at 0.2 on level ground; its ground then tilts by 0.3 rad
  // (a row refit), whose slope floor is far above estimate_margin x 0.2:
  // mu in use goes to the floor, not to a point between it and the answer.
  in.probe_mu[2] = 0.2;
  recovery.update(in, kDt);
  in.probe_mu[2] = 0.0;
  in.ground_normal[2] = Vec3(-std::sin(0.3), 0.0, std::cos(0.3));
  for (int k = 0; k < 300; ++k) recovery.update(in, kDt);
  EXPECT_GT(recovery.muInUse(2), 0.45);  // the slope floor, 1.2 tan(0.3) sqrt(2) = 0.53
  EXPECT_GT(recovery.muInUse(2), p.estimate_margin * 0.2 + 0.25);
}

TEST(FrictionProbe, FourFeetAcrossAChangeOfSlopeAreNotProbed) {
  ProbeInput in = standing();
  EXPECT_NEAR(stanceTwist(in.feet), 0.0, 1e-12);
  // One plane, tilted: still no twist.
  for (int i = 0; i < kNumLegs; ++i) in.feet(2, i) = 0.25 * in.feet(0, i) + 0.1 * in.feet(1, i);
  EXPECT_NEAR(stanceTwist(in.feet), 0.0, 1e-12);
  // One front foot 0.1 m up a 0.25 rad slope that starts under it (the
  // crawl steps one foot at a time; both front feet on it would be one
  // tilted plane with the hind ones).
  in = standing();
  in.feet(2, 0) = 0.1 * std::tan(0.25);
  const double twist = stanceTwist(in.feet);
  EXPECT_GT(twist, 0.01);
  EXPECT_LE(twist, 0.1 * std::tan(0.25));
  FrictionProbe probe;
  probe.reset(on());
  ProbeOutput out;
  EXPECT_EQ(stepUntilActive(probe, in, out, 2000), -1);
  // A foot 3 mm off its neighbours' plane (a footprint's give): probed.
  in.feet(2, 0) = 0.003;
  ASSERT_GT(stepUntilActive(probe, in, out, 2000), 0);
  // The feet move off one plane while the pair is on: a break-away then
  // gives no answer.
  const int leg = out.leg;
  for (int k = 0; k < 20; ++k) probe.update(in, kDt, out);
  in.feet(2, 0) = 0.1 * std::tan(0.25);
  in.slipping.set(leg);
  probe.update(in, kDt, out);
  EXPECT_EQ(probe.aborted(), 1u);
  EXPECT_EQ(probe.found(), 0u);
  for (int i = 0; i < kNumLegs; ++i) EXPECT_EQ(out.mu_found[i], 0.0);
}

TEST(FrictionProbe, TangentialRatioOfAForce) {
  const Vec3 n = Vec3(0.0, 0.6, 0.8);
  const Vec3 t = Vec3(1.0, 0.0, 0.0);
  EXPECT_NEAR(tangentialRatio(Vec3(200.0 * n + 50.0 * t), n), 0.25, 1e-12);
  EXPECT_GT(tangentialRatio(Vec3(-1.0 * n + 50.0 * t), n), 1e8);  // pulling: no ratio
}

}  // namespace
}  // namespace hyq
