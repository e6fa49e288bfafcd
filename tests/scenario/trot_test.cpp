// The trot on good ground, closed loop: from standing to 0.5 m/s, held,
// without a false slip flag; and back to standing. The trot over the ice
// slab, up the slippery ramp, and pushed sideways, on good ground and on ice.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

#include "tests/scenario/scenario_runner.hpp"

namespace hyq::test {

// The plant of the tests whose bounds hold on the ideal plant only: each
// names what the hyq plant, the default, misses
// (docs/design-notes.md, "Tests still on the ideal plant").
constexpr sim::PlantModel kIdeal = sim::PlantModel::ideal;

// [rad] the trunk's roll and pitch (Z-Y-X angles) from its quaternion (w, x, y, z).
double trunkRoll(const std::array<double, 4>& q) {
  return std::atan2(2.0 * (q[0] * q[1] + q[2] * q[3]), 1.0 - 2.0 * (q[1] * q[1] + q[2] * q[2]));
}
double trunkPitch(const std::array<double, 4>& q) {
  return std::asin(std::clamp(2.0 * (q[0] * q[2] - q[3] * q[1]), -1.0, 1.0));
}

// [m/s] ground-truth forward speed of the trunk from t0 to the end.
double heldSpeed(const TrunkPath& path, double t0) {
  size_t i = 0;
  while (i + 1 < path.time.size() && path.time[i] < t0) ++i;
  return (path.x.back() - path.x[i]) / (path.time.back() - path.time[i]);
}

TEST(Trot, HoldsHalfAMetrePerSecondWithoutFalseDetections) {
  // Three seeds of 15 s (the whole scenario, 60 s over seeds 1-32:
  // docs/scenarios.md).
  for (uint64_t seed : {1u, 2u, 3u}) {
    ScenarioRun run;
    runScenarioFile("trot_flat.yaml", run, -1, 15.0, {}, seed);
    ASSERT_EQ(run.scenario.controller_params.gait.kind, GaitKind::kTrot);
    EXPECT_FALSE(run.result.fell) << "seed " << seed;
    EXPECT_NEAR(heldSpeed(run.path, 5.0), 0.5, 0.01) << "seed " << seed;
    EXPECT_EQ(run.metrics.false_detections, 0) << "seed " << seed;
    EXPECT_LT(std::fabs(run.path.y.back() - run.path.y.front()), 0.05) << "seed " << seed;
  }
}

TEST(Trot, StopsAndStandsAfterItsWalkTime) {
  ScenarioRun run;
  run.scenario = sim::loadScenario(std::string(HYQ_SOURCE_DIR) + "/sim_host/scenarios/trot_flat.yaml");
  run.scenario.duration = 8.0;
  run.scenario.controller_params.gait.trot.walk_time = 4.0;  // from 1 s to 5 s, then 1 s of ramp down
  runLoadedScenario(run);
  EXPECT_FALSE(run.result.fell);
  EXPECT_EQ(run.metrics.false_detections, 0);
  EXPECT_GT(run.path.x.back() - run.path.x.front(), 1.5);
  // Standing still for the last second.
  EXPECT_LT(std::fabs(heldSpeed(run.path, 7.0)), 0.01);
}

// The paper's ice slab at 0.3 m/s, recovery on: every run crosses (the hind
// feet, 0.37 m behind the base, past x = 3.4 m) without a fall, as over
// seeds 1-32 (docs/scenarios.md); seeds 1-4 here. At most one false
// detection a run: on the hyq plant, whose trot guesses a flagged landing
// foot down at once (kHyqTrotGuessDelay), ODE seeds 1-32 have one in each of
// seeds 2 and 22 and none elsewhere (none at all with the 30 ms delay, whose
// slides after detection ran to 84 ms against 52: docs/design-notes.md,
// "The trot's guess delay on the hyq plant").
TEST(Trot, CrossesTheIceSlabWithRecovery) {
  for (uint64_t seed : {1u, 2u, 3u, 4u}) {
    ScenarioRun run;
    runScenarioFile("trot_ice_patches.yaml", run, -1, -1.0, {}, seed);
    EXPECT_FALSE(run.result.fell) << "seed " << seed;
    EXPECT_GT(run.path.x.back() - 0.37, 3.4) << "seed " << seed;
    EXPECT_LE(run.metrics.false_detections, 1) << "seed " << seed;
    // The landing slides that go on while the foot is loaded give estimates
    // with recovery too (TrotParams::peak_of_loaded_samples): 2 of the 20
    // leg-patches per run on these seeds, the run's worst mu error 7.3-13.7 %.
    ASSERT_GE(run.metrics.mu_error_max_pct, 0.0) << "seed " << seed << ": no estimate";
    EXPECT_LT(run.metrics.mu_error_max_pct, 20.0) << "seed " << seed;
    EXPECT_LT(run.metrics.normal_error_max_deg, 1.0) << "seed " << seed;
  }
}

// The ice slab, recovery on, seeds 1-16. A trot landing on ice slides for
// 15-25 ms after its impact, and its 3-5 samples share one error. The
// foot's earlier slides on the same ice, carried over
// (TrotParams::carry_distance), average it down; a slide that reads
// higher than them is kept with them up to 25 % above
// (carry_agreement_above). Measured on the hyq plant, each run's worst mu
// error: within 15 % in 16 of 16 runs with them and without, within 10 %
// in 13 and 10; the sum of the 16 runs' worst 123 % with them and 147 %
// without (seeds 1-32: 257 % and 295 %, within 10 % 24 and 19). The worst
// run no longer tells them apart: 13.0 % with them, 12.6 % without (10.8 %
// and 13.5 % before each cone's floor was taken on its normal in use, the
// parent of commit "recovery: a flagged foot's cone and its slope floor on
// one plane").
TEST(Trot, EarlierSlidesOnTheSameIceHoldTheEstimate) {
  int within = 0;
  double worst = 0.0, sum = 0.0, sum_without = 0.0;
  for (uint64_t seed = 1; seed <= 16; ++seed) {
    for (const bool carry : {true, false}) {
      ScenarioRun run;
      run.scenario = sim::loadScenario(std::string(HYQ_SOURCE_DIR) + "/sim_host/scenarios/trot_ice_patches.yaml");
      run.scenario.seed = seed;
      if (!carry) run.scenario.controller_params.gait.trot.carry_distance = 0.0;
      runLoadedScenario(run);
      EXPECT_FALSE(run.result.fell) << "seed " << seed;
      ASSERT_GE(run.metrics.mu_error_max_pct, 0.0) << "seed " << seed << ": no estimate";
      if (carry) {
        within += run.metrics.mu_error_max_pct <= 15.0 ? 1 : 0;
        worst = std::max(worst, run.metrics.mu_error_max_pct);
        sum += run.metrics.mu_error_max_pct;
      } else {
        sum_without += run.metrics.mu_error_max_pct;
      }
    }
  }
  std::printf("runs' worst mu errors over seeds 1-16, summed: %.1f %% with earlier slides, %.1f %% without\n", sum,
              sum_without);
  EXPECT_EQ(within, 16);
  EXPECT_LT(worst, 15.0);
  EXPECT_LT(sum, 0.9 * sum_without);
}

// The ice slab with recovery off (the estimates logged, not acted on): the
// trot's landing slides give friction and normal estimates, taken along
// each foot's ground plane. Taken from the whole slip velocity (the
// contacts' compression along the normal in it) the normal's worst error
// was 1.49 and 1.40 deg on these seeds and mu's 34.8 and 29.0 %; along the
// ground 0.60 and 0.61 deg, 27.8 and 16.3 % (seeds 1-8: 0.53-0.75 deg).
// With the event's peak speed taken over loaded samples only, the slide
// after the landing skid is sampled too: mu 7.0 and 6.1 %.
TEST(Trot, EstimatesTheIceSlabFromSlidesAlongTheGround) {
  for (uint64_t seed : {1u, 2u}) {
    ScenarioRun run;
    run.scenario = sim::loadScenario(std::string(HYQ_SOURCE_DIR) + "/sim_host/scenarios/trot_ice_patches.yaml");
    run.scenario.controller_params.recovery.enabled = false;
    ASSERT_TRUE(run.scenario.controller_params.gait.trot.slip_along_ground);
    run.scenario.seed = seed;
    runLoadedScenario(run);
    ASSERT_GE(run.metrics.normal_error_max_deg, 0.0) << "seed " << seed << ": no estimate";
    EXPECT_LT(run.metrics.normal_error_max_deg, 1.0) << "seed " << seed;
    EXPECT_LT(run.metrics.mu_error_max_pct, 15.0) << "seed " << seed;
  }
}

// Every patch at mu 0.05, recovery on, the two seeds that fell while two
// stance feet could not anchor the IMU integration (the detector then
// flagged both feet of every two-foot phase): both cross, and no foot is
// flagged while it holds. It runs on the hyq plant; without the valves'
// limit (kHyqJointVelocityLimit) seed 15 has 6 false detections there.
TEST(Trot, CrossesPatchesOfMuFiveHundredthsWithRecovery) {
  for (uint64_t seed : {15u, 24u}) {
    ScenarioRun run;
    run.scenario = sim::loadScenario(std::string(HYQ_SOURCE_DIR) + "/sim_host/scenarios/trot_ice_patches.yaml");
    for (auto& patch : run.scenario.terrain.patches) patch.mu = 0.05;
    run.scenario.seed = seed;
    runLoadedScenario(run);
    EXPECT_FALSE(run.result.fell) << "seed " << seed;
    EXPECT_GT(run.path.x.back() - 0.37, 3.4) << "seed " << seed;
    EXPECT_EQ(run.metrics.false_detections, 0) << "seed " << seed;
  }
}

// The trunk's roll and pitch from the first tick the trot lifts a foot, for
// one second, against their values just before it.
class FirstStepTilt final : public sim::TickObserver {
 public:
  void onTick(const sim::TickRecord& r) override {
    const double roll = trunkRoll(r.base_quat), pitch = trunkPitch(r.base_quat);
    if (start < 0.0) {
      if (r.command.telemetry.stance_mask != 0xFu) {
        start = r.time;
      } else {
        roll0 = roll;
        pitch0 = pitch;
        return;
      }
    }
    if (r.time > start + 1.0) return;
    roll_swing = std::max(roll_swing, std::fabs(roll - roll0));
    pitch_swing = std::max(pitch_swing, std::fabs(pitch - pitch0));
  }
  double start = -1.0;        // [s] first lift-off
  double roll0 = 0.0, pitch0 = 0.0;  // [rad] just before it
  double roll_swing = 0.0, pitch_swing = 0.0;  // [rad] largest change within its first second
};

// A trot that starts standing on a slope (0.25 rad up or down the walking
// direction, mu 0.8), recovery on, seeds 1-2: standing, the feet are
// 0.15 m uphill of the CoM, and the trot moves the CoM over its diagonals'
// crossing before it lifts a foot (kTrotStartShiftSpeed). Measured, seed 1:
// the trunk's roll and pitch change by at most 0.042 and 0.045 rad in the
// first second of the trot, and it starts 0.12-0.28 s past its start delay;
// started at once, as it stood, 0.26 and 0.25 rad (up), 0.20 and 0.17
// (down). On the hyq plant that first step felled 8 of 16 runs (seeds 1-8,
// up and down), none with the shift (RealPlant.TrotStartsOnASlope).
TEST(Trot, StartsOnASlopeWithItsCoMOverItsDiagonals) {
  for (double angle : {0.25, -0.25})
    for (uint64_t seed : {1u, 2u}) {
      ScenarioRun run;
      run.scenario = sim::loadScenario(std::string(HYQ_SOURCE_DIR) + "/sim_host/scenarios/trot_slope_start.yaml");
      ASSERT_EQ(run.scenario.terrain.ramps.size(), 1u);
      run.scenario.terrain.ramps[0].angle = angle;
      run.scenario.seed = seed;
      FirstStepTilt tilt;
      runLoadedScenario(run, {&tilt});
      const double delay = run.scenario.controller_params.gait.start_delay;
      std::printf("angle %+.2f seed %llu: start %.2f s, roll %.3f, pitch %.3f rad, %.2f m\n", angle,
                  static_cast<unsigned long long>(seed), tilt.start, tilt.roll_swing, tilt.pitch_swing,
                  run.result.distance);
      EXPECT_FALSE(run.result.fell) << angle << " seed " << seed;
      ASSERT_GE(tilt.start, delay) << angle << " seed " << seed;
      EXPECT_LE(tilt.start, delay + 0.5) << angle << " seed " << seed;
      EXPECT_LT(tilt.roll_swing, 0.08) << angle << " seed " << seed;
      EXPECT_LT(tilt.pitch_swing, 0.08) << angle << " seed " << seed;
      EXPECT_GE(run.result.distance, 2.5) << angle << " seed " << seed;
    }
}

// The slippery ramp (0.2 rad, mu 0.5) at 0.3 m/s, recovery on: every run
// climbs it (the hind feet past its top, x = 3.0 m) without a fall, with
// at most one false detection (a hind foot flagged in the air at the
// slope's foot), and no flagged slip lasts 80 ms after its detection;
// seeds 1-4 here. The ideal plant holds 70 ms (seeds 1-32). The
// hyq plant's slips after detection are 51-74 ms in seeds 1-4 and at most
// 75 ms over seeds 1-32 (the loaded slides at most 49 ms; docs/results.md,
// "The hyq plant, seeds 1-32"): a hind foot lands hard on the top, bounces
// and slides light ("A light trot foot's guess goes below the slope
// floor"); 80 ms holds that with a few ms to spare.
TEST(Trot, ClimbsTheSlipperyRampWithRecovery) {
  for (uint64_t seed : {1u, 2u, 3u, 4u}) {
    ScenarioRun run;
    runScenarioFile("trot_ramp.yaml", run, -1, -1.0, {}, seed);
    EXPECT_FALSE(run.result.fell) << "seed " << seed;
    EXPECT_GT(run.path.x.back() - 0.37, 3.0) << "seed " << seed;
    EXPECT_LE(run.metrics.false_detections, 1) << "seed " << seed;
    ASSERT_FALSE(run.metrics.after_detection_ms.empty()) << "seed " << seed;
    const double longest =
        *std::max_element(run.metrics.after_detection_ms.begin(), run.metrics.after_detection_ms.end());
    std::printf("trot_ramp seed %d: longest slip after detection %.0f ms, %d false detections\n",
                static_cast<int>(seed), longest, run.metrics.false_detections);
    EXPECT_LE(longest, 80.0) << "seed " << seed;
  }
}

// A steeper ramp (0.35 rad, mu 0.5), recovery on, seeds 1-8. As the hind
// feet reach its top the four feet's plane leans between the slope and the
// top, and a slipping hind foot's estimate leans with it; each row's own
// plane as the prior there (TrotParams::prior_row_split) keeps the
// estimates on the ground: every run up (the hind feet past the top,
// x = 3.0 m), the estimated normals within 5 deg in at least 7 of 8 runs
// and at least 5 of 8 runs' worst mu error within 15 %. Measured: 6 of 8
// within 15 % (seed 5 27.7 %, seed 7 37.6 %), every worst normal within
// 0.6 deg, 27 of seeds 1-32 within 10 %. With the
// feet's plane alone (prior_row_split 0) no run of seeds 1-32 falls (seeds
// 1, 20 and 31 did before each cone's floor was taken on its normal in use,
// the parent of commit "recovery: a flagged foot's cone and its slope floor
// on one plane"), but every estimate leans with that plane: seeds 1-8's
// worst normals 7-19 deg off and mu errors 15-59 %, none of 1-32 within
// 10 %. On the hyq plant no run of seeds 1-8 falls (4 with the plane refit
// on a touch-down tick alone, the parent of commit "trot: refit the ground
// plane once a landing foot holds"), but 7 of 8 get no friction estimate.
TEST(Trot, ClimbsASteepRampWithEachRowsPriorAtItsTop) {
  const auto load = [](ScenarioRun& run, uint64_t seed) {
    run.scenario = sim::loadScenario(std::string(HYQ_SOURCE_DIR) + "/sim_host/scenarios/trot_ramp.yaml", kIdeal);
    run.scenario.terrain.ramps.at(0).angle = 0.35;
    run.scenario.duration = 25.0;
    run.scenario.seed = seed;
  };
  int within = 0, normal_within = 0;
  for (uint64_t seed = 1; seed <= 8; ++seed) {
    ScenarioRun run;
    load(run, seed);
    runLoadedScenario(run);
    EXPECT_FALSE(run.result.fell) << "seed " << seed;
    EXPECT_GT(run.path.x.back() - 0.37, 3.0) << "seed " << seed;
    ASSERT_GE(run.metrics.mu_error_max_pct, 0.0) << "seed " << seed << ": no estimate";
    std::printf("seed %llu: worst mu error %.1f %%, normal %.1f deg\n", static_cast<unsigned long long>(seed),
                run.metrics.mu_error_max_pct, run.metrics.normal_error_max_deg);
    normal_within += run.metrics.normal_error_max_deg < 5.0 ? 1 : 0;
    within += run.metrics.mu_error_max_pct <= 15.0 ? 1 : 0;
  }
  EXPECT_GE(normal_within, 7);
  EXPECT_GE(within, 5);
  // Without each row's prior, on the same seeds.
  int normal_within_without = 0, within_without = 0;
  for (uint64_t seed = 1; seed <= 8; ++seed) {
    ScenarioRun run;
    load(run, seed);
    run.scenario.controller_params.gait.trot.prior_row_split = 0.0;
    runLoadedScenario(run);
    ASSERT_GE(run.metrics.mu_error_max_pct, 0.0) << "seed " << seed << ": no estimate";
    normal_within_without += run.metrics.normal_error_max_deg < 5.0 ? 1 : 0;
    within_without += run.metrics.mu_error_max_pct <= 15.0 ? 1 : 0;
  }
  EXPECT_LE(normal_within_without, 2);
  EXPECT_LE(within_without, 2);
}

// The GRF estimate's error on feet that have held their ground for at
// least 0.1 s, mean per axis [N]: each record's telemetry (the controller's
// answer to that tick's frame, whose torques drove the step before) against
// the previous record's true contact force (that step's).
class HoldingForceError final : public sim::TickObserver {
 public:
  void onTick(const sim::TickRecord& r) override {
    for (int leg = 0; leg < kNumLegs; ++leg) {
      held_[leg] = r.feet[leg].in_contact ? held_[leg] + 1 : 0;
      const Vec3 force(r.feet[leg].force[0], r.feet[leg].force[1], r.feet[leg].force[2]);
      if (held_[leg] > 100) {  // so previous_force_ is the last record's
        const double* est = r.command.telemetry.grf_est[leg];
        sum_ += Vec3(est[0], est[1], est[2]) - previous_force_[leg];
        ++count_;
      }
      previous_force_[leg] = force;
    }
  }
  Vec3 mean() const { return count_ > 0 ? Vec3(sum_ / count_) : Vec3(Vec3::Zero()); }
  int count() const { return count_; }

 private:
  int held_[kNumLegs] = {};
  Vec3 previous_force_[kNumLegs];
  Vec3 sum_ = Vec3::Zero();
  int count_ = 0;
};

// In the trot's stance the hips turn at 0.5-1 rad/s. The centrifugal and
// Coriolis torques of that motion, C(q, qd) qd, left out of the GRF
// estimate, read as extra normal force on every stance foot; with them
// (EstimatorParams::grf_leg_motion) the estimate's mean error on feet
// holding their ground is a fraction of a newton where the body is the
// controller's model. trot_flat (0.5 m/s), seed 1, 10 s, the ideal plant:
// measured +0.21 N along z with them, +1.85 N without. On the hyq plant
// the published body is not the model, and its error stays in the
// estimate (+5.49 N with them); the legs' motion still takes out about as
// much as on the ideal plant (+7.01 N without: 1.5 N).
TEST(Trot, TheLegsOwnMotionIsInTheForceEstimate) {
  for (const sim::PlantModel plant : {kIdeal, sim::PlantModel::hyq}) {
    double z_with = 0.0, z_without = 0.0;
    for (const bool motion : {true, false}) {
      ScenarioRun run;
      run.scenario = sim::loadScenario(std::string(HYQ_SOURCE_DIR) + "/sim_host/scenarios/trot_flat.yaml", plant);
      run.scenario.seed = 1;
      run.scenario.duration = 10.0;
      run.scenario.controller_params.estimator.grf_leg_motion = motion;
      HoldingForceError error;
      runLoadedScenario(run, {&error});
      ASSERT_FALSE(run.result.fell);
      ASSERT_GT(error.count(), 10000);
      (motion ? z_with : z_without) = error.mean().z();
    }
    const bool ideal = plant == kIdeal;
    std::printf("[ force ] %s plant, holding feet, mean z error: %.3f N with, %.3f N without\n",
                ideal ? "ideal" : "hyq", z_with, z_without);
    if (ideal) {
      EXPECT_LT(std::fabs(z_with), 0.5);
      EXPECT_GT(z_without, 1.0);
    } else {
      EXPECT_GT(z_without - z_with, 1.0);
    }
  }
}

// Roll of the trunk [rad], the largest over the run.
class MaxRoll final : public sim::TickObserver {
 public:
  void onTick(const sim::TickRecord& r) override {
    max_roll = std::max(max_roll, std::fabs(trunkRoll(r.base_quat)));
  }
  double max_roll = 0.0;
};

// 150 N sideways for 0.2 s at the trunk's CoM while trotting at 0.5 m/s,
// to the left and to the right, at six instants through one trot period
// (0.6 s): no fall, the trunk rolls less than 0.3 rad, and the trot is back
// at its speed 1.5 s after the push. Over seeds 1-4 and twelve instants the
// robot also rides out 250 N (docs/scenarios.md).
TEST(Trot, RidesOutSidewaysPushesAtEveryPhaseOfItsCycle) {
  for (double direction : {1.0, -1.0})
    for (int k = 0; k < 6; ++k) {
      ScenarioRun run;
      run.scenario = sim::loadScenario(std::string(HYQ_SOURCE_DIR) + "/sim_host/scenarios/trot_push.yaml");
      ASSERT_EQ(run.scenario.disturbances.size(), 2u);
      run.scenario.disturbances.resize(1);
      auto& push = run.scenario.disturbances[0];
      push.t = 8.0 + 0.1 * k;
      push.force = {0.0, 150.0 * direction, 0.0};
      ASSERT_NEAR(push.duration, 0.2, 1e-12);
      run.scenario.duration = push.t + 3.0;
      MaxRoll roll;
      runLoadedScenario(run, {&roll});
      const std::string where = "push at " + std::to_string(push.t) + " s, " + std::to_string(direction);
      EXPECT_FALSE(run.result.fell) << where;
      EXPECT_LT(roll.max_roll, 0.3) << where;
      EXPECT_NEAR(heldSpeed(run.path, push.t + 1.7), 0.5, 0.05) << where;
    }
}

// A run that falls is measured up to its fall: trot_ice_fast without
// recovery falls on the ice (seed 1, at 5.8 s); the simulator goes on for
// 0.5 s, its trunk path ends at the fall, and no true slip the metrics
// count starts after it.
TEST(Trot, AFallenRunIsMeasuredUpToItsFall) {
  ScenarioRun run;
  runScenarioFile("trot_ice_fast.yaml", run, 0, 8.0, {}, 1);
  ASSERT_TRUE(run.result.fell);
  EXPECT_NEAR(run.result.sim_time, run.result.fall_time + 0.5, 0.002);
  ASSERT_FALSE(run.path.time.empty());
  EXPECT_NEAR(run.path.time.back(), run.result.fall_time, 1e-9);
  ASSERT_FALSE(run.metrics.events.empty());
  for (const sim::TrueSlip& e : run.metrics.events) {
    EXPECT_LE(e.start, run.result.fall_time) << "leg " << e.leg;
    EXPECT_LE(e.end, run.result.fall_time) << "leg " << e.leg;
  }
}

// trot_push_ice: 250 N sideways for 0.2 s, three times, on mu 0.2 at the
// instants of the trot cycle where one push fells the robot without
// recovery. Without recovery the landing pair after the first push is
// asked for more tangential force than mu 0.2 gives, both its feet slide
// and every run falls, within 0.8 s of the first push. With recovery the
// cones are down to the ice before that landing, and no run falls at any
// of the three pushes: ODE seeds 1-8, MuJoCo seeds 1-4 (docs/scenarios.md
// has seeds 1-32). That is on the ideal plant.
// On the hyq plant these pushes fell no run without recovery (ODE seeds
// 1-8, MuJoCo 1-4), so the test pushes harder on slicker ice: 500 N on mu
// 0.15, at the same instants. Without recovery every run falls (ODE
// 9.07-13.24 s, MuJoCo 9.45-9.87 s: after the first push, at 8.40 s; seed
// 6 after the second, at 11.45 s; all before the third, at 14.50 s), with
// it none; on mu 0.8 the same pushes
// fell none of ODE seeds 1-4 without recovery: the ice fells it.
TEST(Trot, RecoveryRidesOutPushesOnIceThatFellItWithout) {
  sim::PhysicsSpec mujoco;
  mujoco.engine = sim::EngineKind::mujoco;
  struct Case {
    const sim::PhysicsSpec* physics;
    int seeds;
    int most_falls_with_recovery;
  } cases[] = {{nullptr, 8, 0}, {&mujoco, 4, 0}};
  // The file, on slicker ice and pushed harder, on the hyq plant.
  const ScenarioChange harsher = [](sim::Scenario& scenario) {
    scenario.terrain.mu = 0.15;
    for (sim::Disturbance& d : scenario.disturbances) d.force[1] = 500.0;
  };
  for (const Case& c : cases) {
    int falls_on = 0;
    for (uint64_t seed = 1; seed <= static_cast<uint64_t>(c.seeds); ++seed) {
      const std::string where = std::string(c.physics ? "MuJoCo" : "ODE") + " seed " + std::to_string(seed);
      ScenarioRun off;
      runScenarioFile("trot_push_ice.yaml", off, 0, -1.0, {}, seed, c.physics, harsher);
      ASSERT_EQ(off.scenario.disturbances.size(), 3u);
      EXPECT_TRUE(off.result.fell) << where;
      if (off.result.fell) {
        EXPECT_GT(off.result.fall_time, off.scenario.disturbances[0].t) << where;
        EXPECT_LT(off.result.fall_time, off.scenario.disturbances[2].t) << where;
      }
      ScenarioRun on;
      runScenarioFile("trot_push_ice.yaml", on, 1, -1.0, {}, seed, c.physics, harsher);
      if (on.result.fell) ++falls_on;
      EXPECT_FALSE(on.result.fell) << where << " fell at " << on.result.fall_time << " s";
    }
    EXPECT_LE(falls_on, c.most_falls_with_recovery) << (c.physics ? "MuJoCo" : "ODE");
  }
}

// trot_ice_fast: a 1 m/s trot onto four patches of mu 0.05. Without
// recovery every run falls on the ice. With it and the trot's cautiousness
// (TrotParams::speed_per_mu: the speed held to 7.5 m/s x the lowest mu in
// use, at least RecoveryParams::mu_floor), the robot slows to about 0.5 m/s
// on the ice and crosses. On the ideal plant the cautiousness changes the
// slips little: each run's longest slip after detection, seeds 1-32,
// cautious at most 142 ms, median 74; not cautious at most 99, median 78;
// no fall either way. (With mu in use held at the floor, commit e10e192,
// the trot without cautiousness fell 13 times in 32 on the ideal plant:
// docs/design-notes.md, "A cautious trot on ice", "A stance estimated
// under the floor brakes below it".) The test runs the hyq plant: there the
// longest slip after detection over seeds 1-32 is 129 ms on ODE and 131 ms
// on MuJoCo (101-124 ms on the seeds 1-8 here); cautious or not, no run
// falls with recovery (docs/design-notes.md, "A fast trot swings longer").
TEST(Trot, ACautiousTrotSlowsOnIceWhereItFellWithoutRecovery) {
  for (uint64_t seed = 1; seed <= 8; ++seed) {
    const std::string where = "seed " + std::to_string(seed);
    ScenarioRun off;
    runScenarioFile("trot_ice_fast.yaml", off, 0, -1.0, {}, seed);
    EXPECT_TRUE(off.result.fell) << where;
    ScenarioRun on;
    runScenarioFile("trot_ice_fast.yaml", on, 1, -1.0, {}, seed);
    ASSERT_GT(on.scenario.controller_params.gait.trot.speed_per_mu, 0.0);
    EXPECT_FALSE(on.result.fell) << where;
    const double last_patch_end = on.scenario.terrain.patches.back().x1;
    EXPECT_GT(on.path.x.back() - 0.37, last_patch_end) << where;  // the hind feet past the ice
    // The speed over the ice's middle two metres (base from 3.5 to 5.5 m).
    double t_in = -1.0, t_out = -1.0;
    for (size_t i = 0; i < on.path.x.size(); ++i) {
      if (t_in < 0.0 && on.path.x[i] > 3.5) t_in = on.path.time[i];
      if (t_out < 0.0 && on.path.x[i] > 5.5) t_out = on.path.time[i];
    }
    ASSERT_GT(t_out, t_in) << where;
    EXPECT_LT(2.0 / (t_out - t_in), 0.6) << where;
    const double cautious = *std::max_element(on.metrics.after_detection_ms.begin(), on.metrics.after_detection_ms.end());
    EXPECT_LE(cautious, 150.0) << where;
    std::printf("trot_ice_fast %s: longest slip after detection %.0f ms\n", where.c_str(), cautious);
  }
}

// The stance set over a run: the fewest feet down before a time; the
// first tick after it with only a diagonal pair down; the longest time a
// foot the controller has in stance is off the ground (truth), from a
// second before the switch until the trot has run a second; and the
// lowest mu in use on the good ground after the switch (the base short of
// x_ice, the front feet short of the first patch) over the legs whose mu
// was above 0.2 at the switch.
class StanceWatch final : public sim::TickObserver {
 public:
  StanceWatch(double until, double x_ice) : until_(until), x_ice_(x_ice) {}
  void onTick(const sim::TickRecord& r) override {
    const hal::Telemetry& t = r.command.telemetry;
    const uint32_t mask = t.stance_mask;
    int n = 0;
    for (int leg = 0; leg < 4; ++leg) n += (mask >> leg) & 1u;
    if (r.time < until_) fewest_before = std::min(fewest_before, n);
    const bool diagonal = mask == 0b1001u || mask == 0b0110u;  // LF+RH or RF+LH
    if (diagonal && first_pair < 0.0) first_pair = r.time;
    const bool around_switch = r.time > until_ - 1.0 && (first_pair < 0.0 || r.time < first_pair + 1.0);
    for (int leg = 0; leg < 4; ++leg) {
      const bool airborne_stance = around_switch && ((mask >> leg) & 1u) && !r.feet[leg].in_contact;
      airborne_[leg] = airborne_stance ? airborne_[leg] + 1 : 0;
      longest_airborne_stance_ms = std::max(longest_airborne_stance_ms, airborne_[leg]);
      if (first_pair < 0.0) mu_at_switch_[leg] = t.mu_used[leg];
      // A leg the crawl brought to the switch already guessed down (a
      // landing slip without an estimate holds its mu at the floor until
      // the leg's next foothold) is left out.
      if (first_pair > 0.0 && r.base_pos[0] < x_ice_ && mu_at_switch_[leg] > 0.2) {
        lowest_mu_after = std::min(lowest_mu_after, t.mu_used[leg]);
        legs_counted |= 1u << leg;
      }
    }
  }
  int fewest_before = 4;
  double first_pair = -1.0;           // [s]
  int longest_airborne_stance_ms = 0;  // [ms] (ticks)
  double lowest_mu_after = 1e9;       // [-]
  uint32_t legs_counted = 0;          // legs in lowest_mu_after

 private:
  double until_, x_ice_;
  double mu_at_switch_[4] = {0.0, 0.0, 0.0, 0.0};
  int airborne_[4] = {0, 0, 0, 0};
};

// crawl_to_trot: the crawl (never fewer than three feet down) hands over to
// the trot 10 s in, at its next four-foot moment with the CoM nearly still;
// the trot moves the CoM over its diagonals' crossing first (the first pair
// alone before 12.5 s; 12.12-12.27 s over seeds 1-32), with no foot held
// in stance in the air for more than a landing's bounce (40 ms), and it
// crosses the ice slab (the hind feet past x = 4.0 m) without a fall or a
// false detection, with recovery on, as over seeds 1-32 with it and without
// (docs/scenarios.md); seeds 1-2 here. With a guess delay
// (gait.trot.guess_delay 0.03 s, the ideal plant's; the hyq plant's is 0,
// kHyqTrotGuessDelay) the trot keeps its mu in use on the good ground well
// above the floor: its landing slides wait for the delay. Without the delay
// set at the switch: 0.08-0.10; with no delay at all (the hyq preset):
// 0.08-0.12, the floor (0.07) approached as on ice.
TEST(Trot, CrawlHandsOverToTheTrotAndCrossesTheIce) {
  for (uint64_t seed : {1u, 2u}) {
    ScenarioRun run;
    StanceWatch stance(10.0, 0.6);
    runScenarioFile("crawl_to_trot.yaml", run, -1, -1.0, {&stance}, seed);
    ASSERT_EQ(run.scenario.controller_params.gait.kind, GaitKind::kCrawl);
    ASSERT_DOUBLE_EQ(run.scenario.controller_params.gait.schedule.trot_at, 10.0);
    EXPECT_FALSE(run.result.fell) << "seed " << seed;
    EXPECT_EQ(stance.fewest_before, 3) << "seed " << seed;
    EXPECT_GT(stance.first_pair, 10.0) << "seed " << seed;
    EXPECT_LT(stance.first_pair, 12.5) << "seed " << seed;
    EXPECT_LE(stance.longest_airborne_stance_ms, 40) << "seed " << seed;
    EXPECT_GT(run.path.x.back() - 0.37, 4.0) << "seed " << seed;
    EXPECT_EQ(run.metrics.false_detections, 0) << "seed " << seed;

    // The same with the guess delay. Seed 1's LF came to the switch at the
    // floor (0.07), from its first landing's slip in the crawl (2.95 s); the
    // other three legs count.
    ScenarioRun delayed;
    StanceWatch watch(10.0, 0.6);
    delayed.scenario = sim::loadScenario(std::string(HYQ_SOURCE_DIR) + "/sim_host/scenarios/crawl_to_trot.yaml");
    delayed.scenario.seed = seed;
    ASSERT_EQ(delayed.scenario.controller_params.gait.trot.guess_delay, 0.0);
    delayed.scenario.controller_params.gait.trot.guess_delay = TrotParams{}.guess_delay;
    ASSERT_GT(delayed.scenario.controller_params.gait.trot.guess_delay, 0.0);
    runLoadedScenario(delayed, {&watch});
    EXPECT_FALSE(delayed.result.fell) << "seed " << seed << ", delayed";
    int counted = 0;
    for (int leg = 0; leg < 4; ++leg) counted += (watch.legs_counted >> leg) & 1u;
    EXPECT_GE(counted, 3) << "seed " << seed;
    EXPECT_GT(watch.lowest_mu_after, 0.2) << "seed " << seed;
    std::printf("seed %llu: lowest mu in use on good ground after the switch %.3f, %.3f with the delay\n",
                static_cast<unsigned long long>(seed), stance.lowest_mu_after, watch.lowest_mu_after);
  }
}

// ------------------------------------------------------------ on MuJoCo
// The trot's scenarios on the second engine (soft elliptic-cone contacts,
// rolling feet), seeds 1-2: the ice slab crossed and the ramp climbed with
// recovery, the crawl's hand-over to the trot and across the ice, 150 N
// pushes ridden out, without a fall, and on the ice and under the pushes
// with no false detection but of one kind. On the hyq plant a foot braking
// at the end of its swing reads 40-62 N in the air (the published leg's
// inertia and the torque loop's lag are not in the force estimate), is
// watched and flagged 1-3 ms before it lands, and then lands with a skid of
// up to 0.43 m/s that is over within 4 ms, shorter than a slip event: the
// flag rose before the skid, so it matches none (docs/metrics.md,
// false_detections_in_air). Seeds 1-2: one such flag in each of
// trot_ice_patches seed 1, crawl_to_trot seed 2 and trot_push seed 1 (in
// crawl_to_trot the run ends 3 ms after the flag rose, the foot still in
// the air: a flag on a landing the run's end cuts off); seeds 1-8: 13 in
// the 24 runs of these three files, at most 2 in a run, and no false
// detection of another kind. The bound: at most 2 in a run, every one
// flagged in the air. (On the ideal plant none in seeds 1-8.)
TEST(TrotOnMujoco, CrossesTheIceClimbsTheRampSwitchesGaitsAndRidesOutPushes) {
  sim::PhysicsSpec mujoco;
  mujoco.engine = sim::EngineKind::mujoco;
  struct Case {
    const char* file;
    double goal;                // [m] the hind feet (0.37 m behind the base) past this x; 0: none
    bool false_only_in_air;     // at most 2, all flagged in the air (trot_ramp: not bounded, a hind foot flagged in the air at the slope's foot)
  } cases[] = {{"trot_ice_patches.yaml", 3.4, true}, {"trot_ramp.yaml", 3.0, false},
               {"crawl_to_trot.yaml", 4.0, true}, {"trot_push.yaml", 0.0, true}};
  for (const Case& c : cases)
    for (uint64_t seed : {1u, 2u}) {
      ScenarioRun run;
      runScenarioFile(c.file, run, -1, -1.0, {}, seed, &mujoco);
      const std::string where = std::string(c.file) + " seed " + std::to_string(seed);
      std::printf("%s: %d false detections, %d of them flagged in the air\n", where.c_str(),
                  run.metrics.false_detections, run.metrics.false_detections_in_air);
      EXPECT_FALSE(run.result.fell) << where;
      if (c.goal > 0.0) {
        EXPECT_GT(run.path.x.back() - 0.37, c.goal) << where;
      }
      if (c.false_only_in_air) {
        EXPECT_LE(run.metrics.false_detections, 2) << where;
        EXPECT_EQ(run.metrics.false_detections_in_air, run.metrics.false_detections) << where;
      }
    }
}

// On MuJoCo, whose friction acts in the same step as a landing's impact,
// the trot's feet land on good ground with skids of a few millimetres and
// no flag that is not a slip. On the ideal plant they land at rest: no slip
// event at all (on ODE every landing skids for a few ms: docs/design-notes.md,
// "On ODE every trot landing skids; on MuJoCo none does"). On the hyq plant
// every landing skids behind the torque loop: 75 and 72 slip events in
// seeds 1 and 2, the longest 2.7 and 2.8 mm (the contact point's travel
// while it slips), and none is a false detection ("How a trot foot lands
// on the hyq plant"). A
// swing that landed moving faster, or pushed the foot along the ground at
// touch-down, would pass the 5 mm that a slip is missed at (docs/metrics.md),
// and on the ideal plant make a slip event.
TEST(TrotOnMujoco, LandingSkidsStayUnderFiveMillimetresOnGoodGround) {
  sim::PhysicsSpec mujoco;
  mujoco.engine = sim::EngineKind::mujoco;
  for (uint64_t seed : {1u, 2u}) {
    ScenarioRun run;
    runScenarioFile("trot_flat.yaml", run, -1, 15.0, {}, seed, &mujoco);
    double longest = 0.0;
    for (const auto& e : run.metrics.events) longest = std::max(longest, e.distance);
    std::printf("trot_flat on MuJoCo seed %d: %d slip events, the longest skid %.2f mm, %d false detections\n",
                static_cast<int>(seed), run.metrics.slip_events, 1e3 * longest, run.metrics.false_detections);
    EXPECT_FALSE(run.result.fell) << "seed " << seed;
    EXPECT_NEAR(heldSpeed(run.path, 5.0), 0.5, 0.01) << "seed " << seed;
    EXPECT_LT(longest, 0.005) << "seed " << seed;
    EXPECT_EQ(run.metrics.false_detections, 0) << "seed " << seed;
    // The swing itself lands at rest: on the ideal plant no slip event.
    ScenarioRun ideal;
    ideal.plant = kIdeal;
    runScenarioFile("trot_flat.yaml", ideal, -1, 15.0, {}, seed, &mujoco);
    EXPECT_FALSE(ideal.result.fell) << "seed " << seed;
    EXPECT_EQ(ideal.metrics.slip_events, 0) << "ideal plant, seed " << seed;
  }
}

}  // namespace hyq::test
