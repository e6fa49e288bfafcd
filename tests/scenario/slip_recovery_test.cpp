// Slip detection, estimation and recovery, closed loop, over several seeds
// of each scenario.
//
// One seed is one draw of the sensor noise and biases. The walk on ice is
// chaotic: a change anywhere re-deals which seeds fall, so a single seed is a
// coin toss, not a regression net. Each test runs seeds 1..kSeeds and asserts
// how many runs reach each goal, at bounds set from the measured counts
// (docs/results.md has them over seeds 1-32, against the goal, which asks
// for every run). A change that makes the controller worse on average
// fails here; one that only re-deals the seeds does not.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "hal/frames.hpp"
#include "tests/scenario/scenario_runner.hpp"

namespace hyq::test {
namespace {

constexpr int kSeeds = 8;

// The plant these tests run on. Most of this file's bounds were set on the
// ideal plant and do not yet hold on the hyq plant, the default; the tests
// that pass kIdeal run there, and each names what the hyq plant misses
// (docs/design-notes.md, "Tests still on the ideal plant"). The hyq plant's
// own bounds for the same scenarios are real_plant_test's.
constexpr sim::PlantModel kIdeal = sim::PlantModel::ideal;
constexpr sim::PlantModel kHyq = sim::PlantModel::hyq;

// Per leg: stance touch-downs on good ground (true mu > 0.7) and the count of
// them until the controller's mu in use for that leg is back to >= 0.5; ticks
// on which both front feet were flagged; ticks frozen with a foot in the air.
class LegWatch final : public sim::TickObserver {
 public:
  void onTick(const sim::TickRecord& r) override {
    const uint32_t stance = r.command.telemetry.stance_mask;
    const uint32_t slip = r.command.telemetry.slip_mask;
    for (int leg = 0; leg < 4; ++leg) {
      const bool st = (stance >> leg) & 1u;
      if (st && !((prev_stance_ >> leg) & 1u) && r.feet[leg].mu > 0.7) ++grip_touchdowns[leg];
      if (grip_touchdowns[leg] > 0 && rise_touchdowns[leg] < 0 && r.command.telemetry.mu_used[leg] >= 0.5)
        rise_touchdowns[leg] = grip_touchdowns[leg];
    }
    if ((slip & 0x3u) == 0x3u) ++front_pair_flagged_ticks;
    for (int leg = 0; leg < 4; ++leg)
      if ((slip >> leg) & 1u) ++flagged_ticks[leg];
    if ((r.command.flags & hal::kFlagFreeze) && stance != 0xFu) ++frozen_in_air_ticks;
    prev_stance_ = stance;
  }
  int grip_touchdowns[4] = {0, 0, 0, 0};
  int rise_touchdowns[4] = {-1, -1, -1, -1};
  int front_pair_flagged_ticks = 0;
  int flagged_ticks[4] = {0, 0, 0, 0};
  int frozen_in_air_ticks = 0;

 private:
  uint32_t prev_stance_ = 0xF;
};

struct SeededRun {
  uint64_t seed = 0;
  ScenarioRun run;
  LegWatch watch;
};

// Seeds 1..seeds of one scenario file, recovery on (1) or off (0), on
// `plant`; on the file's physics, or on `physics` when given; changed by
// `change` when given.
std::vector<std::unique_ptr<SeededRun>> runSeeds(const std::string& file, int recovery,
                                                 sim::PlantModel plant, int seeds = kSeeds,
                                                 const sim::PhysicsSpec* physics = nullptr,
                                                 const ScenarioChange& change = {}) {
  std::vector<std::unique_ptr<SeededRun>> runs;
  for (int seed = 1; seed <= seeds; ++seed) {
    auto r = std::make_unique<SeededRun>();
    r->seed = static_cast<uint64_t>(seed);
    r->run.plant = plant;
    runScenarioFile(file, r->run, recovery, -1.0, {&r->watch}, r->seed, physics, change);
    runs.push_back(std::move(r));
  }
  return runs;
}

double medianOf(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double maxOf(const std::vector<double>& v) { return v.empty() ? 0.0 : *std::max_element(v.begin(), v.end()); }

int falls(const std::vector<std::unique_ptr<SeededRun>>& runs) {
  int n = 0;
  for (const auto& r : runs) n += r->run.result.fell ? 1 : 0;
  return n;
}

std::string fallenSeeds(const std::vector<std::unique_ptr<SeededRun>>& runs) {
  std::string s;
  for (const auto& r : runs)
    if (r->run.result.fell) s += " " + std::to_string(r->seed);
  return s.empty() ? " none" : s;
}

// Recovery never freezes the robot with a foot in the air (a leg swinging
// when the freeze is called is put down first).
void expectNeverFrozenWithAFootUp(const std::vector<std::unique_ptr<SeededRun>>& runs) {
  for (const auto& r : runs) EXPECT_EQ(r->watch.frozen_in_air_ticks, 0) << "seed " << r->seed;
}

// Every slip over within `bound_ms` of its detection, in every run: each
// run's longest slip after its detection (the worst case; the paper
// gives 52 ms on its ramp and < 40 ms in stance).
void expectEverySlipOverWithin(const char* label, const std::vector<std::unique_ptr<SeededRun>>& runs,
                               double bound_ms) {
  std::vector<double> longest;
  for (const auto& r : runs) longest.push_back(maxOf(r->run.metrics.after_detection_ms));
  std::printf("%s: each run's longest slip after detection, median %.0f ms, worst %.0f ms\n", label,
              medianOf(longest), maxOf(longest));
  // Durations are whole 1 ms ticks; half a tick absorbs their rounding.
  for (size_t i = 0; i < runs.size(); ++i)
    EXPECT_LE(longest[i], bound_ms + 0.5) << label << " seed " << runs[i]->seed;
}

// How many of a run's slips are long.
long longSlips(const ScenarioRun& run) {
  return std::count_if(run.metrics.events.begin(), run.metrics.events.end(), isLongSlip);
}

// ramp_035 with recovery, seed `seed`, for `duration` [s], run twice: as
// it is and with `change` applied to the controller's parameters; on
// `physics` when given. Expects neither run to fall, no long slip in the
// first and at least one in the second.
template <class Change>
void expectLongSlipOnlyWithout(uint64_t seed, double duration, Change change,
                               const sim::PhysicsSpec* physics = nullptr) {
  ScenarioRun with, without;
  for (ScenarioRun* run : {&with, &without}) {
    run->scenario = sim::loadScenario(std::string(HYQ_SOURCE_DIR) + "/sim_host/scenarios/ramp_035.yaml", kIdeal);
    if (physics) run->scenario.physics = *physics;
    run->scenario.seed = seed;
    run->scenario.duration = duration;
    run->scenario.controller_params.recovery.enabled = true;
  }
  change(without.scenario.controller_params);
  runLoadedScenario(with);
  runLoadedScenario(without);
  EXPECT_FALSE(with.result.fell);
  EXPECT_FALSE(without.result.fell);
  EXPECT_EQ(longSlips(with), 0);
  EXPECT_GE(longSlips(without), 1);
}

// The run ends with the trunk's hind end (0.37 m behind the base) past the
// top edge of its scenario's first ramp.
bool onTheTop(const ScenarioRun& run) {
  const auto& ramp = run.scenario.terrain.ramps.at(0);
  return run.path.x.back() - 0.37 > ramp.x0 + ramp.length;
}

// Every slip with more than 5 mm of travel on a watched foot is flagged,
// within `latency_ms` of its start (latencies are whole ticks: half a tick
// absorbs their rounding). Returns how many such slips the runs had.
int expectEveryLongSlipCaughtWithin(const char* label, const std::vector<std::unique_ptr<SeededRun>>& runs,
                                    double latency_ms) {
  int count = 0;
  double worst = 0.0;
  for (const auto& r : runs)
    count += expectLongSlipsCaughtWithin(r->run, latency_ms, std::string(label) + " seed " + std::to_string(r->seed),
                                         worst);
  std::printf("%s: %d slips over 5 mm, worst latency %.0f ms\n", label, count, worst);
  return count;
}

// Each run's worst normal error at the end of its slip events (deg): the
// estimate's (events without one give no sample) and the cone's in use.
// The estimate must be within `estimate_max` in all runs but
// `estimate_misses`, and within the slope and a degree and a half in every
// run; the cone's may be the whole slope at a front foot's first touch-down
// on it (its footholds are all still on the flat), but no more than the
// slope and a degree and a half.
void expectNormalErrors(const char* label, const std::vector<std::unique_ptr<SeededRun>>& runs,
                        double estimate_max, int estimate_misses = 0) {
  int misses = 0;
  for (const auto& r : runs) {
    const sim::MetricsResult& m = r->run.metrics;
    const double slope_deg = r->run.scenario.terrain.ramps.at(0).angle * 180.0 / M_PI;
    std::printf("%s seed %d: normal error %.1f deg (estimate; < 0: none), %.1f deg (in use)\n", label,
                static_cast<int>(r->seed), m.normal_error_max_deg, m.normal_in_use_error_max_deg);
    if (m.normal_error_max_deg > estimate_max) ++misses;
    EXPECT_LE(m.normal_error_max_deg, slope_deg + 1.5) << label << " seed " << r->seed;
    EXPECT_GE(m.normal_in_use_error_max_deg, 0.0) << label << " seed " << r->seed;
    EXPECT_LE(m.normal_in_use_error_max_deg, slope_deg + 1.5) << label << " seed " << r->seed;
  }
  EXPECT_LE(misses, estimate_misses) << label;
}

TEST(SlipRecovery, FlatGroundRaisesNoFalseDetectionInSixtySecondsOnEverySeed) {
  for (const auto& r : runSeeds("flat.yaml", 1, kHyq)) {
    EXPECT_FALSE(r->run.result.fell) << "seed " << r->seed;
    EXPECT_NEAR(r->run.result.sim_time, 60.0, 1e-6) << "seed " << r->seed;
    EXPECT_EQ(r->run.metrics.false_detections, 0) << "seed " << r->seed;
    EXPECT_EQ(r->run.metrics.freeze_events, 0) << "seed " << r->seed;
  }
}

// The sensors at their specified worst (flat_hostile_sensors.yaml): every
// accelerometer axis 2 m/s^2 off, every joint-torque sensor 10 N m off, all
// noise tripled. The estimators take the biases out: no fall, no false
// slip read from a bias. On the hyq plant, seeds 1-8 walk 2.54-2.56 m with
// the odometry 0.4-2.5 cm off, and one run, seed 3, has one false
// detection: LH's landing at 37.24 s bounces (lifts off after a 2 ms skid,
// flagged in the air, lands again with 2 ms skids, each shorter than a slip
// event), not a bias read as force. The bound: one in all eight runs. (On
// the ideal plant none in seeds 1-8; over seeds 1-32 one, seed 32: a hind
// leg's first landing reads its unlearnt torque offsets as force;
// docs/design-notes.md.)
TEST(SlipRecovery, FlatWithWorstCaseSensorBiasesAndTripleNoiseWalksWithoutFalseSlips) {
  int false_detections = 0;
  for (const auto& r : runSeeds("flat_hostile_sensors.yaml", 1, kHyq)) {
    EXPECT_FALSE(r->run.result.fell) << "seed " << r->seed;
    EXPECT_NEAR(r->run.result.sim_time, 60.0, 1e-6) << "seed " << r->seed;
    EXPECT_GT(r->run.result.distance, 2.4) << "seed " << r->seed;
    EXPECT_EQ(r->run.metrics.freeze_events, 0) << "seed " << r->seed;
    EXPECT_LT(r->run.metrics.odometry_error_final_m, 0.05) << "seed " << r->seed;
    false_detections += r->run.metrics.false_detections;
  }
  EXPECT_LE(false_detections, 1);
}

// Accelerometer biases drawn with 2 m/s^2 as their standard deviation
// (flat_acc_bias.yaml): seeds 1-8 draw up to 4.75 m/s^2 on one axis, within
// the estimator's 5 m/s^2 clamp, so each bias is learnt whole and the
// odometry stays within 3 cm after 60 s (measured 0.3-2.6 cm; a bias past
// the clamp would drift it by 2 cm/s per m/s^2 beyond: docs/design-notes.md,
// "Sensors at their specified worst").
TEST(SensorOffsets, DrawnAccelerometerBiasesUpTo5AreLearntWhole) {
  for (const auto& r : runSeeds("flat_acc_bias.yaml", 1, kHyq, 8)) {
    EXPECT_FALSE(r->run.result.fell) << "seed " << r->seed;
    EXPECT_NEAR(r->run.result.sim_time, 60.0, 1e-6) << "seed " << r->seed;
    EXPECT_LT(r->run.metrics.odometry_error_max_m, 0.03) << "seed " << r->seed;
  }
}

// All patches crossed: the hind feet (0.37 m behind the base) past the last
// patch's far end, within the scenario's time, without a fall.
int crossedAllPatches(const std::vector<std::unique_ptr<SeededRun>>& runs) {
  int crossed = 0;
  for (const auto& r : runs) {
    double last_end = 0.0;
    for (const auto& p : r->run.scenario.terrain.patches) last_end = std::max(last_end, p.x1);
    if (!r->run.result.fell && r->run.path.x.back() - 0.37 > last_end) ++crossed;
  }
  return crossed;
}

// [cm] A run's largest odometry error per 50 cm walked.
double odometryPer50Cm(const ScenarioRun& run) {
  const sim::MetricsResult& m = run.metrics;
  return m.distance_walked_m > 0.0 ? 100.0 * m.odometry_error_max_m * 0.5 / m.distance_walked_m : 0.0;
}

// The paper's ice slab (ice_patches.yaml) with each patch's mu 0.8 times its
// own (0.2, 0.16, 0.24, 0.12): on the hyq plant the paper's slab is crossed
// without recovery in some runs.
void slipperierSlab(sim::Scenario& scenario) {
  ASSERT_EQ(scenario.terrain.patches.size(), 4u);
  for (auto& patch : scenario.terrain.patches) patch.mu *= 0.8;
}

// Runs whose leg odometry stayed within 1 cm of error per 50 cm walked.
int odometryWithinACmPer50(const std::vector<std::unique_ptr<SeededRun>>& runs) {
  int ok = 0;
  for (const auto& r : runs) {
    const sim::MetricsResult& m = r->run.metrics;
    if (m.distance_walked_m > 0.0 && m.odometry_error_max_m <= 0.01 * m.distance_walked_m / 0.5) ++ok;
  }
  return ok;
}

// The (leg, patch) pairs on which the front and the hind feet had a
// detected slip, and those of them with a friction estimate, all runs
// together (summary.json's mu_estimate_coverage): a pair is a leg and the
// true mu under it.
struct Coverage {
  int slipped[2] = {0, 0};    // front, hind
  int estimated[2] = {0, 0};
};

Coverage estimateCoverage(const char* label, const std::vector<std::unique_ptr<SeededRun>>& runs) {
  Coverage c;
  for (const auto& r : runs)
    for (int leg = 0; leg < 4; ++leg) {
      c.slipped[leg / 2] += r->run.metrics.patches_slipped[leg];
      c.estimated[leg / 2] += r->run.metrics.patches_estimated[leg];
    }
  std::printf("%s: slipped patches with an estimate, front feet %d/%d, hind feet %d/%d\n", label, c.estimated[0],
              c.slipped[0], c.estimated[1], c.slipped[1]);
  return c;
}

// Each run's worst friction-estimate error [%], over the runs that have one.
struct WorstMuErrors {
  std::vector<double> pct;
  long within10 = 0;  // runs within the goal's 10 %
};

WorstMuErrors worstMuErrors(const char* label, const std::vector<std::unique_ptr<SeededRun>>& runs) {
  WorstMuErrors w;
  for (const auto& r : runs)
    if (r->run.metrics.mu_error_max_pct >= 0.0) w.pct.push_back(r->run.metrics.mu_error_max_pct);
  w.within10 = std::count_if(w.pct.begin(), w.pct.end(), [](double pct) { return pct <= 10.0; });
  std::printf("%s: mu error max, median of runs %.1f %%, %ld/%zu runs <= 10 %%\n", label, medianOf(w.pct),
              w.within10, w.pct.size());
  return w;
}

// On the hyq plant: hind feet's patches 46 of 128 estimated, 70 estimates, and 1 of 8 runs crosses
// without recovery.
TEST(SlipRecovery, IcePatchesAreCrossedWithRecoveryAndNotWithout) {
  // Sixteen seeds: whether a run's worst event stays within 10 % turns on one
  // short event, and eight runs say little about the rate.
  constexpr int kIceSeeds = 16;
  const auto on = runSeeds("ice_patches.yaml", 1, kIdeal, kIceSeeds);
  for (const auto& r : on) EXPECT_GT(r->run.metrics.slip_events, 0) << "seed " << r->seed;
  const int crossed = crossedAllPatches(on), odometry_ok = odometryWithinACmPer50(on);
  // The friction estimate: each run's worst event (the goal: <= 10 %).
  // Measured: 16 of seeds 1-16 within 10 %, the median of the runs' max
  // 5.8 % (over seeds 1-32: 31 of 32, median 6.1 %, worst 11.1 %; with the
  // slide test's 6 ticks alone, SlipParams::slide_travel 0, 31 of 32, 5.9 %,
  // worst 14.8 %; before
  // a dragged landing foot touched down, 30 of 32, 5.1 %; 6.9 and 6.2 %
  // without the braking test,
  // SlipParams::max_slide_acceleration; without the slide test, SlipParams::max_slide_stiffness, 16 of
  // 16 and 5.8 %, 31 of 32 and 6.0 %: the test that keeps a soft contact's
  // elastic gives out also drops some of a stiff one's good samples; 5.5 %
  // before landing feet were pressed rather than dragged, 4.5 % before the
  // light feet's guess and cone offset). A light slip is where a run's
  // worst comes from: under 80 N, 1-2 N of force error is 0.02 in mu
  // (SlipParams::ending_slip_fraction). The bounds: all but one run, the
  // median 7.5 %. Every run has a sample. And the typical estimate: the
  // median over every sampled slip event of the sixteen runs (2.3 % of 112;
  // 2.1 % with the slide test's 6 ticks alone, and 1.8 % before a dragged
  // landing foot touched down, SlipParams::landing_drag_travel).
  const WorstMuErrors mu = worstMuErrors("ice_patches on", on);
  std::vector<double> mu_events;
  for (const auto& r : on)
    for (const auto& e : r->run.metrics.events)
      if (e.monitored && e.has_mu_sample) mu_events.push_back(e.mu_error_pct);
  std::printf("ice_patches on: fell on seeds%s; crossed %d/%d; odometry ok %d/%d; mu error, median of %zu events %.1f %%\n",
              fallenSeeds(on).c_str(), crossed, kIceSeeds, odometry_ok, kIceSeeds, mu_events.size(),
              medianOf(mu_events));
  EXPECT_EQ(falls(on), 0);
  EXPECT_EQ(crossed, kIceSeeds);
  // Every run within the goal's 1 cm per 50 cm (paper: < 1 cm): the worst
  // of seeds 1-32 measured 0.11 cm per 50 cm (without the IMU bias
  // estimates, 1-2.2 cm per 50 cm in 11 of 32 runs).
  EXPECT_EQ(odometry_ok, kIceSeeds);
  EXPECT_EQ(static_cast<int>(mu.pct.size()), kIceSeeds);
  EXPECT_GE(mu.within10, kIceSeeds - 1);
  EXPECT_LE(medianOf(mu.pct), 7.5);
  EXPECT_GE(mu_events.size(), 80u);
  EXPECT_LE(medianOf(mu_events), 2.5);
  // Fig. 5 per leg and patch: the hind feet are estimated on most patches
  // they slip on, the front feet on few (their slips on ice are light
  // touch-downs: docs/design-notes.md, "Why a landing front foot gets no
  // estimate"). Measured, seeds 1-16: hind feet 85 of 128 pairs (every
  // hind foot slips on all four patches), front feet 20 of 130; seeds 1-32:
  // 181/256 and 46/261 (169/256 and 48/259 with the slide test's 6 ticks
  // alone; 163/256 and 41/258 before a dragged landing foot
  // touched down; 172/256 and 40/259 without the braking test,
  // 202/256 and 59/258 without the slide test too). The
  // bounds: the hind feet slip on at least 100 pairs and are estimated on
  // at least 60 % of them.
  const Coverage coverage = estimateCoverage("ice_patches on", on);
  EXPECT_GE(coverage.slipped[1], 100);
  EXPECT_GE(coverage.estimated[1], 0.6 * coverage.slipped[1]);
  expectNeverFrozenWithAFootUp(on);
  expectEverySlipOverWithin("ice_patches on", on, 40.0);
  expectEveryLongSlipCaughtWithin("ice_patches on", on, 20.0);

  // The problem it solves. Without recovery the feet slide three times as
  // often and the slips stay in the odometry (the paper's baseline, its
  // Fig. 6): the robot believes it is further on than it is, and in the
  // 90 s it is about 1 m short of where it gets with recovery, on the last
  // patch (0 of seeds 1-32 crossed; odometry 8.4-9.9 cm off per 50 cm; the
  // paper: 18 cm per 50 cm). It does not fall here (0 of 32), where the
  // paper's robot fell: docs/design-notes.md.
  const auto off = runSeeds("ice_patches.yaml", 0, kIdeal);
  const int crossed_off = crossedAllPatches(off), odometry_ok_off = odometryWithinACmPer50(off);
  std::printf("ice_patches off: fell on seeds%s; crossed %d/%d; odometry ok %d/%d\n",
              fallenSeeds(off).c_str(), crossed_off, kSeeds, odometry_ok_off, kSeeds);
  EXPECT_EQ(crossed_off, 0);
  EXPECT_EQ(odometry_ok_off, 0);
}

// The ice patches on the hyq plant, ODE. There the paper's slab is crossed
// without recovery in 1 of seeds 1-8, and the odometry stays within
// 0.24-0.26 cm per 50 cm without it (0.17-0.21 with it), where the ideal
// plant's drifted 8.4-9.9 cm. On a slab of 0.8 times the paper's mu (0.2,
// 0.16, 0.24, 0.12), seeds 1-8: with recovery every run crosses, none
// falls, the odometry 0.15-0.17 cm per 50 cm, 7 of 8 runs' worst estimate
// within 10 %, the hind feet estimated on 48 of their 65 slipped patches
// (the front feet on none of 64), each run's longest slip after detection
// 29 ms at most; without, none crosses, none falls, and the odometry
// 0.45-0.52 cm. Seeds 1-16 with recovery (the test's): 15 of 16 within
// 10 %, the hind feet on 95 of their 129 slipped patches, every run across,
// the odometry 0.13-0.18 cm per 50 cm.
// The bounds: the ideal plant's for the crossing, the falls and the slips
// (over within 40 ms of their detection, the long ones caught within
// 20 ms) and the hind feet's patches (at least 60 %); at most two of the 16
// runs past 10 % (the ideal plant's one, and a run of margin for re-dealt
// seeds); for the problem recovery solves, no crossing without it, and
// every run's odometry without it further off than any run's with it.
TEST(SlipRecovery, ASlipperierSlabOnTheHyqPlantIsCrossedWithRecoveryAndNotWithout) {
  constexpr int kIceSeeds = 16;
  const auto on = runSeeds("ice_patches.yaml", 1, kHyq, kIceSeeds, nullptr, slipperierSlab);
  std::printf("ice_patches x0.8 on, hyq plant: fell on seeds%s; crossed %d/%d\n", fallenSeeds(on).c_str(),
              crossedAllPatches(on), kIceSeeds);
  EXPECT_EQ(falls(on), 0);
  EXPECT_EQ(crossedAllPatches(on), kIceSeeds);
  EXPECT_EQ(odometryWithinACmPer50(on), kIceSeeds);
  const WorstMuErrors mu = worstMuErrors("ice_patches x0.8 on, hyq plant", on);
  EXPECT_EQ(static_cast<int>(mu.pct.size()), kIceSeeds);
  EXPECT_GE(mu.within10, kIceSeeds - 2);
  const Coverage coverage = estimateCoverage("ice_patches x0.8 on, hyq plant", on);
  EXPECT_GE(coverage.estimated[1], 0.6 * coverage.slipped[1]);
  expectEverySlipOverWithin("ice_patches x0.8 on, hyq plant", on, 40.0);
  expectEveryLongSlipCaughtWithin("ice_patches x0.8 on, hyq plant", on, 20.0);
  const auto off = runSeeds("ice_patches.yaml", 0, kHyq, kSeeds, nullptr, slipperierSlab);
  double worst_on = 0.0, best_off = 1e9;
  for (const auto& r : on) worst_on = std::max(worst_on, odometryPer50Cm(r->run));
  for (const auto& r : off) best_off = std::min(best_off, odometryPer50Cm(r->run));
  std::printf("ice_patches x0.8 off, hyq plant: fell on seeds%s; crossed %d/%d; odometry per 50 cm at most "
              "%.2f cm with recovery, at least %.2f cm without\n",
              fallenSeeds(off).c_str(), crossedAllPatches(off), kSeeds, worst_on, best_off);
  EXPECT_EQ(crossedAllPatches(off), 0);
  EXPECT_GT(best_off, worst_on);
}

// Four patches of mu 0.10 (ice_010.yaml; the paper's iciest is 0.15).
// Measured on the ideal plant at commit e10e192 (docs/results.md has this
// tree's figures; on the hyq plant, seeds 1-8, the worst 14.5 %), seeds
// 1-32: with recovery every run crosses without a fall,
// odometry at most 0.12 cm per 50 cm, each run's worst friction estimate
// within 10 % in 30 of the 31 runs with one (median 6.5 %, worst 10.8 %);
// seeds 1-8: 8 of 8, median 7.0 %, worst 8.7 %. On mu 0.1 a hind foot's
// slide reaches 0.25 m/s within 3 ms and brakes as fast, while the force
// estimate's acceleration term lags its leg by 10-15 N: without the
// braking test 10 of 32 were within 10 % (median 12.7 %, worst 16.9 %;
// docs/design-notes.md, "A braking slide reads low"). The bounds: every
// run but one with an estimate, the median of the runs' worst 10 %, none
// past 15 %. Without recovery no run crosses (2.4-2.6 m in 90 s, the
// odometry 17 cm per 50 cm off).
TEST(SlipRecovery, IcePatchesOfMuTenPercentAreCrossedWithRecoveryAndNotWithout) {
  const auto on = runSeeds("ice_010.yaml", 1, kHyq);
  std::printf("ice_010 on: fell on seeds%s; crossed %d/%d\n", fallenSeeds(on).c_str(), crossedAllPatches(on),
              kSeeds);
  EXPECT_EQ(falls(on), 0);
  EXPECT_EQ(crossedAllPatches(on), kSeeds);
  EXPECT_EQ(odometryWithinACmPer50(on), kSeeds);
  const WorstMuErrors mu = worstMuErrors("ice_010 on", on);
  EXPECT_GE(static_cast<int>(mu.pct.size()), kSeeds - 1);
  EXPECT_LE(medianOf(mu.pct), 10.0);
  EXPECT_LE(maxOf(mu.pct), 15.0);
  expectNeverFrozenWithAFootUp(on);
  const auto off = runSeeds("ice_010.yaml", 0, kHyq);
  std::printf("ice_010 off: fell on seeds%s; crossed %d/%d\n", fallenSeeds(off).c_str(), crossedAllPatches(off),
              kSeeds);
  EXPECT_EQ(crossedAllPatches(off), 0);
}

// A 45 cm strip of oil (mu 0.02) across the path. Freezing is off by
// default: the correction alone carries the robot across (seeds 1-32: no
// fall, 30 across; with the paper's freezing, `controller.freeze: true`, 9
// falls and 1 across: docs/design-notes.md). Seeds 1-8: every run stands, 7
// get the hind feet off the strip within 30 s, on the ideal plant.
// The hyq plant's crawl walks slower (flat ground: 2.40-2.42 m in 60 s
// against 2.78 m), and in the file's 30 s none is across (the base
// 1.11-1.15 m on; on flat ground, seed 1, 1.16 m then). The test gives
// it 40 s: seeds 1-8 all across (the base 1.51-1.59 m on), no fall, no
// freeze. RealPlant.AnOilStripUnderTheFloorIsStoodOn holds it over the
// strip.
TEST(SlipRecovery, AnOilStripIsCrossedByTheCorrectionWithoutFreezing) {
  const auto on = runSeeds("oil_strip.yaml", 1, kHyq, kSeeds, nullptr,
                           [](sim::Scenario& scenario) { scenario.duration = 40.0; });
  int across = 0;
  for (const auto& r : on) {
    EXPECT_EQ(r->run.metrics.freeze_events, 0) << "seed " << r->seed;
    const double strip_end = r->run.scenario.terrain.patches.at(0).x1;
    if (!r->run.result.fell && r->run.path.x.back() - 0.37 > strip_end) ++across;
  }
  std::printf("oil_strip on: fell on seeds%s; across %d/%d\n", fallenSeeds(on).c_str(), across, kSeeds);
  EXPECT_EQ(falls(on), 0);
  EXPECT_GE(across, kSeeds - 1);
}

// Oil spilt under both hind feet on the 0.25 rad slope for 3 s
// (oil_slope.yaml). With the paper's freezing every run stands, and most walk
// on up the slope once the oil is gone; without freezing, seeds 1-32, none
// falls either (the body shifts back down the slope brake within what the
// slope leaves of the friction: docs/design-notes.md, "A body shift down a
// slope must be able to stop"). The hind feet, dragged back, hold the body
// back from the next triangle: the crawl crouches to step them, and without
// recovery too every run walks on.
TEST(SlipRecovery, AnOilSpillUnderTheHindFeetOnASlopeIsStoodOutByFreezing) {
  auto walkedOn = [](const std::vector<std::unique_ptr<SeededRun>>& runs) {
    int n = 0;  // past 2.2 m: 0.45 m beyond the oil; an undisturbed run reaches 3.6 m
    for (const auto& r : runs) n += !r->run.result.fell && r->run.path.x.back() > 2.2;
    return n;
  };
  const auto frozen = runSeeds("oil_slope.yaml", 1, kHyq);
  std::printf("oil_slope, freezing: fell on seeds%s; walked on %d/%d\n", fallenSeeds(frozen).c_str(),
              walkedOn(frozen), kSeeds);
  EXPECT_EQ(falls(frozen), 0);
  // A freeze needs a flagged slide of a foot carrying 50 N or more for
  // 0.3 s. In seeds 3 and 7 of 1-8 the right hind foot is in its swing when
  // the oil comes and lands on it at 44.1 s, searching; its 0.9 s slide is
  // light and freezes nothing, and those runs walk on like the others.
  const auto frozenRuns = std::count_if(frozen.begin(), frozen.end(),
                                        [](const auto& r) { return r->run.metrics.freeze_events >= 1; });
  std::printf("oil_slope, freezing: %ld/%d runs froze\n", static_cast<long>(frozenRuns), kSeeds);
  EXPECT_GE(frozenRuns, kSeeds - 2);
  EXPECT_GE(walkedOn(frozen), kSeeds - 1);
  expectNeverFrozenWithAFootUp(frozen);

  constexpr int kFreeSeeds = 32;
  std::vector<std::unique_ptr<SeededRun>> free;
  for (int seed = 1; seed <= kFreeSeeds; ++seed) {
    auto r = std::make_unique<SeededRun>();
    r->seed = static_cast<uint64_t>(seed);
    r->run.scenario = sim::loadScenario(std::string(HYQ_SOURCE_DIR) + "/sim_host/scenarios/oil_slope.yaml");
    r->run.scenario.controller_params.recovery.freeze = false;
    r->run.scenario.seed = r->seed;
    runLoadedScenario(r->run, {&r->watch});
    free.push_back(std::move(r));
  }
  std::printf("oil_slope, no freezing: fell on seeds%s; walked on %d/%d\n", fallenSeeds(free).c_str(),
              walkedOn(free), kFreeSeeds);
  EXPECT_EQ(falls(free), 0);
  EXPECT_EQ(walkedOn(free), kFreeSeeds);

  const auto off = runSeeds("oil_slope.yaml", 0, kHyq);
  std::printf("oil_slope, recovery off: fell on seeds%s; walked on %d/%d\n", fallenSeeds(off).c_str(),
              walkedOn(off), kSeeds);
  EXPECT_EQ(walkedOn(off), kSeeds);
}

// On the hyq plant: no estimate in 8 seeds, and no fall without recovery.
TEST(SlipRecovery, SlipperyRampIsClimbedWithoutTorqueSteps) {
  const auto on = runSeeds("ramp.yaml", 1, kIdeal);
  std::printf("ramp on: fell on seeds%s\n", fallenSeeds(on).c_str());
  EXPECT_EQ(falls(on), 0);
  for (const auto& r : on) {
    const ScenarioRun& run = r->run;
    if (run.result.fell) continue;
    EXPECT_TRUE(onTheTop(run)) << "seed " << r->seed;
    EXPECT_GT(run.metrics.slip_events, 0) << "seed " << r->seed;
    // No step discontinuity in a stance leg's torque: one sixth of the 150 N m
    // effort limit, against ~100 N m for a 300 N load switched in one tick.
    EXPECT_LT(run.metrics.max_stance_torque_step_nm, 25.0) << "seed " << r->seed;
  }
  // The slip is over <= 40 ms after its detection (paper: 52 ms on the ramp):
  // the median over the runs of each run's median, and in most runs (8 of 8
  // measured, 32 of seeds 1-32). And every slip: each run's longest after
  // its detection, at most 40 ms here (seed 8; median 15) and over seeds 1-32;
  // the light feet's guess and the cone offset keep it there
  // (docs/design-notes.md, "A light foot carries no tangential force").
  // Each foot's cone is about its own ground where the front and hind feet
  // stand on different slopes (RecoveryParams::ground_plane_min_angle); with
  // the plane through all feet for every foot, a hind foot slid downhill
  // for up to 1.4 s at the ramp's top (seeds 1-32: 4 runs of 1.0-1.4 s).
  expectEverySlipOverWithin("ramp on", on, 40.0);
  expectEveryLongSlipCaughtWithin("ramp on", on, 20.0);
  std::vector<double> run_medians;
  for (const auto& r : on)
    if (!r->run.metrics.after_detection_ms.empty())
      run_medians.push_back(medianOf(r->run.metrics.after_detection_ms));
  const int within = static_cast<int>(
      std::count_if(run_medians.begin(), run_medians.end(), [](double ms) { return ms <= 40.0; }));
  std::printf("ramp on: slip after detection, median of runs %.1f ms, %d/%d runs <= 40 ms\n",
              medianOf(run_medians), within, kSeeds);
  EXPECT_EQ(static_cast<int>(run_medians.size()), kSeeds);
  EXPECT_LE(medianOf(run_medians), 40.0);
  EXPECT_GE(within, 6);
  // The friction estimate, each run's worst event against mu 0.5. At the
  // ramp's foot and top the plane through the four feet is wrong under one
  // row of feet; each foot's prior is its own local plane
  // (prior_local_length). Measured: 7 of seeds 1-8 have an estimate, all
  // within 10 %, worst 3.8 %, median 1.4 % (seeds 1-32: 31 of 31, worst
  // 4.5 %); with the plane through the feet as every foot's prior, 4 of 8,
  // median 15 %. The estimates are RF's, from its slide at the front feet's
  // second step onto the slope, at 0.05-0.08 m/s: over 6 ticks that is
  // 0.25-0.4 mm of travel, and the slide test's 6-tick fit read the force
  // estimate's noise as a give in 2 of the 8 runs; its fit over 0.4 mm of
  // travel (SlipParams::slide_travel) keeps them (5 of 8 without it). The
  // bound: 7 of 8 runs with an estimate, every one within 10 %.
  const WorstMuErrors mu = worstMuErrors("ramp on", on);
  EXPECT_GE(static_cast<int>(mu.pct.size()), kSeeds - 1);
  EXPECT_EQ(mu.within10, static_cast<long>(mu.pct.size()));
  EXPECT_LE(medianOf(mu.pct), 7.0);
  // The normal: the estimate's worst per run under 1 deg (seeds 1-32:
  // median 0.2, worst 0.6 deg; 1.7 deg before the rows' turn at the slope
  // changes, SlipParams::prior_turn_margin); the cone's in use 14.3-14.5 deg
  // in every run: the slope, at the front feet's first touch-down on it.
  expectNormalErrors("ramp on", on, 1.0);
  expectNeverFrozenWithAFootUp(on);
  // Without recovery the front feet slide back down at the ramp's foot, the
  // slips stay in the odometry and the plane fit, and the robot falls
  // (23 of seeds 1-32, 5 of seeds 1-8; all 32 without the crawl's checks
  // for a tipping trunk, kCrawlTipRate, and a moving CoM at lift-off). A
  // falling trunk turns past kCrawlTurnAlphaMin, so which seeds fall moves
  // with the crawl's GRF estimate: 24 of 32 and 6 of 8 with that term left
  // out. The bound: 5 of 8, the rate's 72 % less one run.
  const auto off = runSeeds("ramp.yaml", 0, kIdeal);
  std::printf("ramp off: fell on seeds%s\n", fallenSeeds(off).c_str());
  EXPECT_GE(falls(off), 5);
}

// The paper's ramp on the hyq plant. At the paper's mu 0.5 the robot
// climbs there without recovery too (ODE, seeds 1-8: none falls, every run
// on the top, the base 3.69-3.86 m on in 100 s against 4.24-4.25 m with
// recovery), so the comparison takes a slipperier ramp. At mu 0.4 (ODE, seeds 1-8) with
// recovery every run is on the top, each run's longest slip after its
// detection 33 ms at most, the largest stance torque step 23.5 N m; without,
// none is on the top: the front feet slide back down at the ramp's foot, and
// 100 s leave the base 0.57-1.57 m from its start (seed 4 falls at 61.8 s).
// Every run has friction estimates; each run's worst is 5.9-9.0 % off. They
// hold through the prior at the changes of slope: RH's first slip 16 cm past
// the ramp's foot stands on a hind row whose four points lie on no one plane
// (the three its plane holds lean 6 deg for the slope's 14.3), and takes the
// ground plane its own and the front feet agree on
// (SlipParams::prior_agreed_ground; with the row's plane, 4 of the 8 runs
// read a hind foot 38.6-39.7 % low). The bounds: every run within 15 %, and
// 7 of 8 within 10 % (one run of margin on the measured 8). At mu 0.35 every
// run still climbs with recovery, but with slips up to 112 ms after
// detection, past the 40 ms bound.
TEST(SlipRecovery, ASlipperierRampOnTheHyqPlantIsClimbedWithRecoveryAndNotWithout) {
  const ScenarioChange slipperier = [](sim::Scenario& scenario) { scenario.terrain.mu = 0.4; };
  const auto on = runSeeds("ramp.yaml", 1, kHyq, kSeeds, nullptr, slipperier);
  std::printf("ramp at mu 0.4 on, hyq plant: fell on seeds%s\n", fallenSeeds(on).c_str());
  EXPECT_EQ(falls(on), 0);
  for (const auto& r : on) {
    EXPECT_TRUE(onTheTop(r->run)) << "seed " << r->seed;
    EXPECT_LT(r->run.metrics.max_stance_torque_step_nm, 25.0) << "seed " << r->seed;
  }
  expectEverySlipOverWithin("ramp at mu 0.4 on, hyq plant", on, 40.0);
  const WorstMuErrors mu = worstMuErrors("ramp at mu 0.4 on, hyq plant", on);
  EXPECT_EQ(static_cast<int>(mu.pct.size()), kSeeds);
  EXPECT_GE(mu.within10, kSeeds - 1);
  for (double pct : mu.pct) EXPECT_LE(pct, 15.0);
  const auto off = runSeeds("ramp.yaml", 0, kHyq, kSeeds, nullptr, slipperier);
  int on_top = 0;
  for (const auto& r : off) on_top += !r->run.result.fell && onTheTop(r->run) ? 1 : 0;
  std::printf("ramp at mu 0.4 off, hyq plant: fell on seeds%s, %d/%d on the top\n", fallenSeeds(off).c_str(), on_top,
              kSeeds);
  EXPECT_EQ(on_top, 0);
}

// A steeper ramp (ramp_035.yaml: 0.35 rad, mu 0.55). Measured, seeds 1-32:
// with recovery every run on the top, no fall, 22 of the 32 runs with a
// friction estimate, each run's worst within 10 % (median 1.2 %, worst
// 5.5 %); without, none on the top and none falls: they stand stalled on
// the slope (23 of 32 fall without the crawl's two checks, for a trunk that
// tips over its standing feet, kCrawlTipRate, and for a CoM still moving at
// a lift-off). The
// largest stance torque step is at most 14.7 N m; the bound guards the
// slip damping's two-tick mean (slipDampingVelocity): on the raw slip
// velocity the damping rings at 500 Hz here, 34.7-82.3 N m in 24 of the 32
// runs. Every slip is over within 15 ms of its detection (median of the
// runs' longest 10.5 ms): the slope's mu floor, 0.62, is above the ground's
// 0.55, so a foot with an estimate gets a pyramid narrowed across the slope
// (TractionRecovery::muAcross; with the square pyramid, up to 111 ms and
// none of the 32 runs within 40 ms). The cone's normal is 20 deg off at RF's
// first touch-down on the slope (its partner and footholds on the flat);
// from LF's first touch-down on it the front cones are about the slope
// (SlipParams::turn_sets_ground; before, about the 11.5 deg plane of the
// feet, a lightly loaded RF crept down the slope, which the creep test
// flags: SlipParams::creep_threshold). The front feet dragged onto the top
// before their stance began touch down (SlipParams::landing_drag_travel,
// the next test). One slip over 5 mm is left in seeds 1-32: seed 25, LF
// landing on the crest, 8.1 mm, flagged as its stance began, 62 ms after
// it started.
// On the hyq plant, seeds 1-8 (the figures above are the ideal plant's):
// every run on the top, the longest slip after detection 30-34 ms, none
// over 5 mm, each run's worst estimate 4.1-5.9 % (18.7-20.1 % with the
// crawl's GRF estimate leaving out the trunk's turn as the fourth foot
// lands: kCrawlTurnAlphaMin), without recovery none on the top and none
// falls.
TEST(SlipRecovery, ASteeperRampIsClimbedWithRecoveryAndNotWithout) {
  const auto on = runSeeds("ramp_035.yaml", 1, kHyq);
  std::printf("ramp_035 on: fell on seeds%s\n", fallenSeeds(on).c_str());
  EXPECT_EQ(falls(on), 0);
  expectEverySlipOverWithin("ramp_035 on", on, 40.0);
  expectEveryLongSlipCaughtWithin("ramp_035 on", on, 20.0);
  for (const auto& r : on) {
    EXPECT_TRUE(onTheTop(r->run)) << "seed " << r->seed;
    EXPECT_LT(r->run.metrics.max_stance_torque_step_nm, 25.0) << "seed " << r->seed;
  }
  // Seeds 1-8: 3 runs have an estimate (seeds 1, 4, 7), each within 10 %
  // (the ideal plant; the hyq plant: all 8, each LF's slide down the slope).
  // The slips the estimates came from were mostly made by the body shifts
  // back down the slope, which now brake within what the slope leaves of the
  // friction (kSlopeShiftMinTilt; docs/design-notes.md, "A body shift down a
  // slope must be able to stop"). A hind foot at the crest's edge, whose
  // contact normal is neither the slope's nor the top's, can read tens of
  // percent off (docs/design-notes.md, "A foot at a slope change has two
  // priors"); which seeds hold such an event moves with any change of the
  // runs, so the bounds allow one miss and one past 15 %.
  const WorstMuErrors mu = worstMuErrors("ramp_035 on", on);
  EXPECT_GE(static_cast<int>(mu.pct.size()), 2);
  EXPECT_GE(mu.within10, static_cast<long>(mu.pct.size()) - 1);
  EXPECT_LE(std::count_if(mu.pct.begin(), mu.pct.end(), [](double pct) { return pct > 15.0; }), 1);
  // The estimate's normal 0.2-0.4 deg in seeds 1-8 but seed 4's crest
  // sample, 20.2 deg (its prior the slope, the foot on the top); the hyq
  // plant 1.5-1.7 deg. The cone's in use 18.8-20.1 deg (the hyq plant
  // 20.1-20.3), the slope (20.05 deg) at RF's first touch-down on it.
  expectNormalErrors("ramp_035 on", on, 5.0, 1);
  const auto off = runSeeds("ramp_035.yaml", 0, kHyq);
  std::printf("ramp_035 off: fell on seeds%s\n", fallenSeeds(off).c_str());
  for (const auto& r : off) EXPECT_FALSE(onTheTop(r->run)) << "seed " << r->seed;
}

// ramp_035, seed 6: LF lands on the top's edge late in its swing and is
// dragged forward at 0.05 m/s by its own swing PD, at the slip threshold.
// Without the drag test (SlipParams::landing_drag_travel 0) that is a slip
// of 5-10 mm, flagged only once the foot's stance began, 94 ms after it
// started; with it the foot touches down after 1 mm of travel in excess of
// 0.03 m/s, the QP holds it, and the run has no slip over 5 mm. (Seeds 1-32
// without the test: 3 slips over 5 mm, seeds 6, 12 and 13; with it one,
// seed 21's.) On the hyq plant: no long slip without the drag watch either.
TEST(SlipRecovery, ALandingFootDraggedOntoTheCrestTouchesDown) {
  // 57 s: the crest is under LF at 55.9 s.
  expectLongSlipOnlyWithout(6, 57.0, [](Params& p) { p.slip.landing_drag_travel = 0.0; });
}

TEST(SlipRecovery, AStanceSlipDuringBodyMotionIsDetectedAndSurvived) {
  const auto on = runSeeds("stance_slip.yaml", 1, kHyq);
  EXPECT_EQ(falls(on), 0) << "fell on seeds" << fallenSeeds(on);
  std::vector<double> latency, after;
  for (const auto& r : on) {
    EXPECT_FALSE(r->run.metrics.latency_ms.empty()) << "seed " << r->seed << ": no slip detected";
    EXPECT_EQ(r->run.metrics.false_detections, 0) << "seed " << r->seed;
    if (r->run.metrics.latency_ms.empty()) continue;
    latency.push_back(medianOf(r->run.metrics.latency_ms));
    after.push_back(medianOf(r->run.metrics.after_detection_ms));
  }
  const int within = static_cast<int>(
      std::count_if(after.begin(), after.end(), [](double ms) { return ms <= 40.0; }));
  std::printf("stance_slip on: detection latency, median of runs %.1f ms; slip after detection, "
              "median of runs %.1f ms, %d/%d runs <= 40 ms\n",
              medianOf(latency), medianOf(after), within, kSeeds);
  // The loaded LF foot slips on the spot during the first body shift. The
  // slip is over <= 40 ms after detection (paper: < 40 ms in stance), in the
  // median over the runs (28 ms measured on seeds 1-8, 27.5 over seeds 1-32)
  // and in every run (8/8 measured; 32/32). Without the brake and slip
  // damping the same slip went on for 110-165 ms after detection (seeds 1-4).
  EXPECT_LE(medianOf(after), 40.0);
  EXPECT_EQ(within, kSeeds);
  expectEverySlipOverWithin("stance_slip on", on, 40.0);
  expectEveryLongSlipCaughtWithin("stance_slip on", on, 20.0);
  // Detection latency median <= 10 ms, the goal (5.0 ms measured on seeds
  // 1-8 and over seeds 1-32 on the ideal plant, 10 ms on the hyq plant;
  // the debounce is 4 ticks). The tolerance absorbs the ticks' rounding
  // (10 ticks read 10.000000000000009 ms).
  EXPECT_LE(medianOf(latency), 10.0 + 1e-9);
  expectNeverFrozenWithAFootUp(on);
}

TEST(SlipRecovery, TwoFrontFeetOnIceAreBothDetected) {
  // With recovery each front foot is caught on the ice and corrected, and
  // the two-foot slip of the body shift does not come (the cones keep a
  // margin, estimate_margin); both feet are flagged, no fall.
  const auto on = runSeeds("two_feet_ice.yaml", 1, kHyq);
  std::printf("two_feet_ice on: fell on seeds%s\n", fallenSeeds(on).c_str());
  EXPECT_EQ(falls(on), 0);
  for (const auto& r : on)
    for (int leg = 0; leg < 2; ++leg)
      EXPECT_GT(r->watch.flagged_ticks[leg], 0) << "seed " << r->seed << ": front leg " << leg << " never flagged";
  expectNeverFrozenWithAFootUp(on);
  // Each run's longest slip after detection at most 20 ms over seeds 1-32
  // (before the light feet's guess and cone offset, up to 98 ms).
  expectEverySlipOverWithin("two_feet_ice on", on, 40.0);
  expectEveryLongSlipCaughtWithin("two_feet_ice on", on, 20.0);
  // Without recovery both front feet slide together during the body shift,
  // and the multi-leg detection flags both at once. On the hyq plant the
  // strip of mu 0.1 holds the feet apart in time (seeds 1-4: their slides
  // overlap for 1 ms, their flags never), so this half runs a strip of
  // 0.04: the slides overlap for 0.31-0.38 s and the flags for 0.16-0.23 s
  // in each of seeds 1-8 (0.05: 0.15-0.30 s and 0-0.095 s, one run never
  // flagged both). On the ideal plant the 0.1 strip gave 8 of 8.
  const auto off = runSeeds("two_feet_ice.yaml", 0, kHyq, kSeeds, nullptr, [](sim::Scenario& scenario) {
    ASSERT_EQ(scenario.terrain.patches.size(), 1u);
    scenario.terrain.patches[0].mu = 0.04;
  });
  int together = 0;
  for (const auto& r : off) together += r->watch.front_pair_flagged_ticks > 0 ? 1 : 0;
  std::printf("two_feet_ice off: both front feet flagged together on %d/%d seeds\n", together, kSeeds);
  EXPECT_GE(together, 6);
}

TEST(SlipRecovery, IceToGripFrictionRisesAgainWithinThreeSteps) {
  const auto on = runSeeds("ice_to_grip.yaml", 1, kHyq);
  std::printf("ice_to_grip on: fell on seeds%s\n", fallenSeeds(on).c_str());
  EXPECT_EQ(falls(on), 0);
  for (const auto& r : on) {
    if (r->run.result.fell) continue;
    for (int leg = 0; leg < 4; ++leg) {
      ASSERT_GT(r->watch.grip_touchdowns[leg], 0) << "seed " << r->seed << " leg " << leg << " never reached good ground";
      EXPECT_GE(r->watch.rise_touchdowns[leg], 1) << "seed " << r->seed << " leg " << leg;
      EXPECT_LE(r->watch.rise_touchdowns[leg], 3) << "seed " << r->seed << " leg " << leg;
    }
  }
  expectNeverFrozenWithAFootUp(on);
  expectEverySlipOverWithin("ice_to_grip on", on, 40.0);
  expectEveryLongSlipCaughtWithin("ice_to_grip on", on, 20.0);
  // The friction estimate on the ice (mu 0.15), each run's worst event. The
  // robot starts on the ice: a leg that has not swung yet has not learnt its
  // torque offsets, and its samples carry their force error into the
  // sample gate (EstimatorParams::torque_offset_sigma). Measured on the
  // ideal plant: 7 of seeds 1-8 within 10 %, median 6.6 % (seeds 1-32: 23
  // of 32, median 7.9 %, worst 16.0 %); the misses are a front foot's first
  // slip, 3 s in, whose estimated force is 4-5 N off along the slip (0.016
  // in mu at mu 0.15). On the hyq plant: 5 of seeds 1-8 within 10 %,
  // median 9.02 % (seeds 1-32: worst 19.8 %, docs/results.md), held to the
  // 10 % goal.
  const WorstMuErrors mu = worstMuErrors("ice_to_grip on", on);
  EXPECT_EQ(static_cast<int>(mu.pct.size()), kSeeds);
  EXPECT_GE(mu.within10, 5);
  EXPECT_LE(medianOf(mu.pct), 10.0);
  // Without recovery the feet keep sliding on the ice and the robot gets
  // less far in the same time: every run short of the shortest run with
  // recovery (ideal plant, seeds 1-32: at most 2.41 m against at least
  // 3.21 m; hyq plant, seeds 1-8: 2.82 m against 2.97 m).
  const auto off = runSeeds("ice_to_grip.yaml", 0, kHyq);
  double on_least = 1e9, off_most = -1e9;
  for (const auto& r : on) on_least = std::min(on_least, r->run.path.x.back() - r->run.path.x.front());
  for (const auto& r : off) off_most = std::max(off_most, r->run.path.x.back() - r->run.path.x.front());
  std::printf("ice_to_grip off: fell on seeds%s; walked at most %.2f m, against at least %.2f m on\n",
              fallenSeeds(off).c_str(), off_most, on_least);
  EXPECT_LT(off_most, on_least);
}

// ------------------------------------------------------------ on MuJoCo
// The same scenarios, controller and metrics on a second engine with its
// own contact model: soft elliptic-cone contacts that creep inside the cone,
// feet that roll (sim_host/physics/mujoco_engine.hpp).

sim::PhysicsSpec mujoco(double timeconst = sim::MujocoParams{}.timeconst) {
  sim::PhysicsSpec p;
  p.engine = sim::EngineKind::mujoco;
  p.mujoco.timeconst = timeconst;
  return p;
}

TEST(SlipRecoveryOnMujoco, FlatGroundRaisesNoFalseDetection) {
  const sim::PhysicsSpec physics = mujoco();
  for (const auto& r : runSeeds("flat.yaml", 1, kHyq, kSeeds, &physics)) {
    EXPECT_FALSE(r->run.result.fell) << "seed " << r->seed;
    EXPECT_NEAR(r->run.result.sim_time, 60.0, 1e-6) << "seed " << r->seed;
    EXPECT_EQ(r->run.metrics.false_detections, 0) << "seed " << r->seed;
    EXPECT_EQ(r->run.metrics.freeze_events, 0) << "seed " << r->seed;
  }
}

// On the ideal plant (seeds 1-8): with recovery every run crossed, no
// fall, each run's worst friction estimate within 10 % in 7 of 8 runs
// (median 2.2 %, worst 12.3 %), odometry at most 0.06 cm per 50 cm;
// without, none crossed and none fell, as on ODE. On the hyq plant the
// paper's slab is crossed without recovery in 3 of 8 runs, and the worst
// estimates are 2.5-16.6 % (6 of 8 within 10 %). So the test runs the hyq
// plant on a slab with each patch's mu 0.8 times the paper's (0.2, 0.16,
// 0.24, 0.12): with recovery every run crosses, none falls, the worst
// estimates 1.8-4.1 %; without, none crosses and none falls. The bounds
// are the ideal plant's.
TEST(SlipRecoveryOnMujoco, IcePatchesAreCrossedWithRecoveryAndNotWithout) {
  const sim::PhysicsSpec physics = mujoco();
  const auto on = runSeeds("ice_patches.yaml", 1, kHyq, kSeeds, &physics, slipperierSlab);
  const int crossed = crossedAllPatches(on), odometry_ok = odometryWithinACmPer50(on);
  const WorstMuErrors mu = worstMuErrors("ice_patches on, MuJoCo", on);
  std::printf("ice_patches on, MuJoCo: fell on seeds%s; crossed %d/%d; odometry ok %d/%d\n",
              fallenSeeds(on).c_str(), crossed, kSeeds, odometry_ok, kSeeds);
  EXPECT_EQ(falls(on), 0);
  EXPECT_EQ(crossed, kSeeds);
  EXPECT_EQ(odometry_ok, kSeeds);
  EXPECT_EQ(static_cast<int>(mu.pct.size()), kSeeds);
  EXPECT_GE(mu.within10, 7);
  expectNeverFrozenWithAFootUp(on);
  const auto off = runSeeds("ice_patches.yaml", 0, kHyq, kSeeds, &physics, slipperierSlab);
  std::printf("ice_patches off, MuJoCo: fell on seeds%s; crossed %d/%d\n", fallenSeeds(off).c_str(),
              crossedAllPatches(off), kSeeds);
  EXPECT_EQ(crossedAllPatches(off), 0);
}

// Measured (seeds 1-8): with recovery every run on the top, each run's
// longest slip after its detection at most 12 ms (60-137 ms before the
// light feet's guess and cone offset), each run's worst friction estimate
// within 10 % (median 3.8 %); without, none on the top and 3 of 8 fall (8
// of 8 without the crawl's checks for a tipping trunk, kCrawlTipRate, and a
// moving CoM at lift-off). The largest stance
// torque step (up to 22 N m measured; ODE: 9-12) comes with that leg's
// slip flag:
// the flag adds the slip damping's D v_slip to the foot's force
// (RecoveryParams::slip_damping), and on MuJoCo the foot breaks away
// faster; the bound is 30 N m, a fifth of the effort limit.
// On the hyq plant: no estimate, and no fall without recovery.
TEST(SlipRecoveryOnMujoco, SlipperyRampIsClimbedWithRecoveryAndNotWithout) {
  const sim::PhysicsSpec physics = mujoco();
  const auto on = runSeeds("ramp.yaml", 1, kIdeal, kSeeds, &physics);
  std::printf("ramp on, MuJoCo: fell on seeds%s\n", fallenSeeds(on).c_str());
  EXPECT_EQ(falls(on), 0);
  for (const auto& r : on) {
    EXPECT_TRUE(onTheTop(r->run)) << "seed " << r->seed;
    EXPECT_LT(r->run.metrics.max_stance_torque_step_nm, 30.0) << "seed " << r->seed;
  }
  expectEverySlipOverWithin("ramp on, MuJoCo", on, 40.0);
  expectEveryLongSlipCaughtWithin("ramp on, MuJoCo", on, 20.0);
  EXPECT_EQ(odometryWithinACmPer50(on), kSeeds);
  const WorstMuErrors mu = worstMuErrors("ramp on, MuJoCo", on);
  EXPECT_EQ(static_cast<int>(mu.pct.size()), kSeeds);
  EXPECT_GE(mu.within10, 7);
  expectNeverFrozenWithAFootUp(on);
  const auto off = runSeeds("ramp.yaml", 0, kIdeal, kSeeds, &physics);
  std::printf("ramp off, MuJoCo: fell on seeds%s\n", fallenSeeds(off).c_str());
  for (const auto& r : off) EXPECT_FALSE(onTheTop(r->run)) << "seed " << r->seed;
}

// The steeper ramp (0.35 rad, mu 0.55) on MuJoCo, recovery on. Measured
// (seeds 1-8): every run on the top, no fall, each run's worst friction
// estimate within 10 % (worst 2.1 %); 4 slips over 5 mm, each flagged
// within 8 ms. The longest slips after detection, RH's on the slope at
// 67 s (78-132 ms in 4 runs), are not bounded here (docs/design-notes.md,
// "A turned row's plane is its feet's ground").
// At the front feet's first steps onto the slope (about 25 s) their cones
// are about the turned row's plane, then about the plane both feet still
// stand on (SlipParams::turn_sets_ground). Without that they are about the
// plane through all feet, 11.4 deg for the slope's 20.1: RF, at 60 N and at
// the edge of its true cone, creeps down the slope on MuJoCo's soft contact
// (ODE's holds it) in every run, under the slip threshold: 6 of those 8
// slips over 5 mm never flagged, 2 flagged 440-469 ms after they began.
// On the hyq plant: no estimate, and no long slip without the turn.
TEST(SlipRecoveryOnMujoco, ASteeperRampsFrontFeetTakeTheSlopeAsTheirGround) {
  const sim::PhysicsSpec physics = mujoco();
  const auto on = runSeeds("ramp_035.yaml", 1, kIdeal, kSeeds, &physics);
  std::printf("ramp_035 on, MuJoCo: fell on seeds%s\n", fallenSeeds(on).c_str());
  EXPECT_EQ(falls(on), 0);
  for (const auto& r : on) EXPECT_TRUE(onTheTop(r->run)) << "seed " << r->seed;
  expectEveryLongSlipCaughtWithin("ramp_035 on, MuJoCo", on, 20.0);
  const WorstMuErrors mu = worstMuErrors("ramp_035 on, MuJoCo", on);
  EXPECT_EQ(static_cast<int>(mu.pct.size()), kSeeds);
  EXPECT_GE(mu.within10, 7);
  expectNeverFrozenWithAFootUp(on);
  // Seed 3 up to the front feet's second touch-downs on the slope (RF
  // creeps at 25.7-26.2 s), with the cones about the plane through all feet
  // there.
  expectLongSlipOnlyWithout(3, 27.0, [](Params& p) { p.slip.turn_sets_ground = false; }, &physics);
}

// The friction estimate over MuJoCo's contact stiffness: solref's time
// constant from 0.004 s to MuJoCo's own default, 0.02 s (a softer contact,
// more sink and more creep). On a soft contact a slip ends with the foot
// re-sticking while it still moves, its force inside the cone; the
// estimator leaves out samples slower than ending_slip_fraction of the
// event's fastest, and those whose force ratio changes with the travel
// (the slide test). At the front feet's first steps onto the slope their
// prior is the plane through both feet that holds the horizontal square to
// the walk (SlipParams::prior_turn_margin; the consensus plane of their row
// is a blend of flat and slope, 2 deg low: 12-13 % mu error at 0.01 s).
// Measured on the ramp, seeds 1-8, runs within 10 % of those with an
// estimate: 0.004 s, 7 of 7 (median 1.0 %); 0.01 s, 8 of 8 (median 4.2 %,
// worst 7.2 %); 0.02 s, 8 of 8 (median 3.3 %). A run without a loaded slip has
// nothing to estimate from, and the light feet's guess and the cone offset
// (RecoveryParams::guess_holds_for_stance, cone_force_offset) stop most
// slips before they are loaded slides (docs/design-notes.md, "A light foot
// carries no tangential force").
// On the hyq plant: no estimate on the ramp.
TEST(SlipRecoveryOnMujoco, FrictionEstimateHoldsFromStiffToSoftContacts) {
  for (double timeconst : {0.004, 0.01, 0.02}) {
    const sim::PhysicsSpec physics = mujoco(timeconst);
    const auto on = runSeeds("ramp.yaml", 1, kIdeal, kSeeds, &physics);
    char label[64];
    std::snprintf(label, sizeof label, "ramp on, MuJoCo timeconst %.3f s", timeconst);
    const WorstMuErrors mu = worstMuErrors(label, on);
    EXPECT_EQ(falls(on), 0) << label;
    if (timeconst < 0.005) {
      EXPECT_GE(static_cast<int>(mu.pct.size()), kSeeds - 2) << label;
      EXPECT_GE(mu.within10, static_cast<long>(mu.pct.size()) - 1) << label;
    } else {
      EXPECT_GE(mu.within10, kSeeds - 1) << label;  // at least 7 of 8 runs within 10 %
    }
    EXPECT_EQ(odometryWithinACmPer50(on), kSeeds) << label;
  }
}

// The friction estimate on ice_patches over the contact's stiffness, on
// both engines: ODE's contact at 0.3 and 3 times its stiffness (the bristle
// at 3e4 and 3e5 N/m) and MuJoCo at solref's time constant 0.02 s (its own
// default, the softest of the range). On a soft contact a loaded foot gives
// elastically by millimetres at several cm/s when its tangential force
// changes; the detector and the truth both count that as a slip, and its
// force ratio is inside the cone. The slide test leaves such samples out
// (SlipParams::max_slide_stiffness; docs/design-notes.md, "A give is not a
// slide"). Measured, seeds 1-8, runs whose worst estimate is within 10 %
// (runs with an estimate), without the test -> with it: ODE x0.3 0/8 (8)
// -> 7/7, ODE x3 3/8 -> 8/8, MuJoCo 0.02 s 4/8 -> 7/8. The bounds: at most
// one run without an estimate, at most one past 10 % of those with one, on
// the ideal plant. The test runs the hyq plant, where each of seeds 1-8 has
// an estimate at every setting and the runs' worst estimates are ODE x0.3
// 3.8-11.0 % (6 of 8 within 10 %), x3 3.0-14.0 % (6 of 8), MuJoCo 0.02 s
// 2.9-10.6 % (6 of 8); at the default contacts ODE 1.5-7.3 % (8 of 8) and
// MuJoCo's 0.005 s 2.5-16.6 % (6 of 8). The bounds: every run with an
// estimate, at least 5 of 8 within 10 % (a run of margin for re-dealt
// seeds), and each within 20 % (a third over the worst measured).
TEST(SlipRecoveryOverStiffness, IcePatchesFrictionEstimateHoldsFromSoftToStiffContacts) {
  std::vector<std::pair<std::string, sim::PhysicsSpec>> settings;
  for (double scale : {0.3, 3.0}) {
    sim::PhysicsSpec p;
    p.engine = sim::EngineKind::ode;
    p.ode_stiffness_scale = scale;
    settings.emplace_back("ODE stiffness x" + std::to_string(scale).substr(0, 3), p);
  }
  settings.emplace_back("MuJoCo timeconst 0.02 s", mujoco(0.02));
  for (const auto& [name, physics] : settings) {
    const std::string label = "ice_patches on, " + name;
    const auto on = runSeeds("ice_patches.yaml", 1, kHyq, kSeeds, &physics);
    std::printf("%s: fell on seeds%s; crossed %d/%d\n", label.c_str(), fallenSeeds(on).c_str(),
                crossedAllPatches(on), kSeeds);
    EXPECT_EQ(falls(on), 0) << label;
    EXPECT_EQ(crossedAllPatches(on), kSeeds) << label;
    EXPECT_EQ(odometryWithinACmPer50(on), kSeeds) << label;
    const WorstMuErrors mu = worstMuErrors(label.c_str(), on);
    EXPECT_EQ(static_cast<int>(mu.pct.size()), kSeeds) << label;
    EXPECT_GE(mu.within10, kSeeds - 3) << label;
    for (double pct : mu.pct) EXPECT_LE(pct, 20.0) << label;
  }
}

// The ramp on ODE's contact at 3 times its stiffness: a hind foot that
// slips just past the crest, on the flat top, is estimated against its
// row's plane, the slope, unless it has a second prior (48-50 % low, 0 of 8
// within 10 %, with the one prior alone). The other row's plane is that
// second prior, taken when the foot's travel lies in it (SlipParams::prior_switch_angle, prior_switch_travel;
// docs/design-notes.md, "A foot at a slope change has two priors").
// Measured, seeds 1-8: 8/8 within 10 % (worst 8.0 %), no slip over 34 ms
// after its detection; without the switch 14 deg and 82 ms. The normal is
// at most 0.22 deg off with the rows' turn at the ramp's foot and top
// (SlipParams::prior_turn_margin), 1.6 deg without it.
// On the hyq plant: no estimate on the ramp.
TEST(SlipRecoveryOverStiffness, RampCrestOnAStiffContactIsEstimatedOnTheTop) {
  sim::PhysicsSpec physics;
  physics.engine = sim::EngineKind::ode;
  physics.ode_stiffness_scale = 3.0;
  const auto on = runSeeds("ramp.yaml", 1, kIdeal, kSeeds, &physics);
  EXPECT_EQ(falls(on), 0);
  const WorstMuErrors mu = worstMuErrors("ramp on, ODE stiffness x3", on);
  EXPECT_EQ(static_cast<int>(mu.pct.size()), kSeeds);
  EXPECT_GE(mu.within10, kSeeds - 1);
  for (const auto& r : on) {
    EXPECT_LT(r->run.metrics.normal_error_max_deg, 1.0) << "seed " << r->seed;
    EXPECT_TRUE(onTheTop(r->run)) << "seed " << r->seed;
  }
  expectEverySlipOverWithin("ramp on, ODE stiffness x3", on, 60.0);
}

}  // namespace
}  // namespace hyq::test
