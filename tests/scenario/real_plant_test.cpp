// The controller on the hyq plant (plant.model: hyq): HyQ's joints behind
// their 40 Hz torque loop and 12 rad/s valve limit, the transport delays,
// the encoders, the mounted IMU and the published description's bodies,
// none of which the controller's model has. Closed loop, on the figures the
// controller holds there (docs/results.md, "On the real plant"): no fall, the ice
// crossed, and slips after detection bounded, though longer than on the
// ideal plant's 40 ms.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "sim_host/physics/plant_params.hpp"
#include "sim_host/physics/terrain.hpp"
#include "tests/scenario/scenario_runner.hpp"

namespace hyq::test {
namespace {

// Loads `file` on the hyq plant (the files name no plant).
void loadOnHyqPlant(const std::string& file, ScenarioRun& run, uint64_t seed, double duration = -1.0,
                    sim::EngineKind engine = sim::EngineKind::ode) {
  run.scenario =
      sim::loadScenario(std::string(HYQ_SOURCE_DIR) + "/sim_host/scenarios/" + file, sim::PlantModel::hyq);
  run.scenario.physics.engine = engine;
  run.scenario.seed = seed;
  if (duration > 0.0) run.scenario.duration = duration;
}

// Loads `file` on the hyq plant and runs it.
void runOnHyqPlant(const std::string& file, ScenarioRun& run, uint64_t seed, double duration = -1.0,
                   sim::EngineKind engine = sim::EngineKind::ode) {
  loadOnHyqPlant(file, run, seed, duration, engine);
  runLoadedScenario(run);
}

// Prints the run's figures and expects it walked `goal` [m] without a fall,
// its slips stopped within `longest_bound` [ms] of detection.
void expectCrossed(const ScenarioRun& run, uint64_t seed, double goal, double longest_bound) {
  const double longest = longestAfterDetectionMs(run);
  std::printf("seed %llu: %.2f m, longest slip after detection %.0f ms, mu error %.1f %%, %d false\n",
              static_cast<unsigned long long>(seed), run.result.distance, longest, run.metrics.mu_error_max_pct,
              run.metrics.false_detections);
  EXPECT_FALSE(run.result.fell) << "seed " << seed;
  EXPECT_GE(run.result.distance, goal) << "seed " << seed;
  EXPECT_FALSE(run.metrics.after_detection_ms.empty()) << "seed " << seed;
  EXPECT_LE(longest, longest_bound) << "seed " << seed;
}

}  // namespace

// The paper's ice slab, crawling: crossed on both seeds, slips detected and
// stopped within 40 ms of detection, the ideal plant's bound (seeds 1-32:
// no fall, all crossed, the longest 27 ms; the ideal plant's 19 over seeds
// 1-8).
TEST(RealPlant, CrawlCrossesTheIcePatches) {
  for (uint64_t seed : {1u, 2u}) {
    ScenarioRun run;
    runOnHyqPlant("ice_patches.yaml", run, seed);
    expectCrossed(run, seed, 3.77, 40.0);
    EXPECT_LE(run.metrics.false_detections, 1) << "seed " << seed;
  }
}

// Ice of mu 0.1 under every patch, crawling: no slip that travels 5 mm or
// more goes unflagged. Behind the torque loop a front foot searching for the
// ground meets the ice with 3-10 N, under the watch's force; without the
// drag test on a searching foot the ground holds up (kSearchStallDepth) its
// swing PD drags it 15-20 mm before its stance trigger (seed 1: 8 such
// slips, 20.5 mm the longest; seeds 1-8: 71). With it, seeds 1-8: none.
TEST(RealPlant, ASearchingFootOnIceIsNotDraggedUnseen) {
  for (uint64_t seed : {1u, 2u}) {
    ScenarioRun run;
    runOnHyqPlant("ice_010.yaml", run, seed);
    const double missed_mm = std::max(0.0, 1000.0 * run.metrics.missed_distance_max_m);  // 0: none missed
    std::printf("seed %llu: %d slips, %d missed, the longest missed %.1f mm\n",
                static_cast<unsigned long long>(seed), run.metrics.slip_events, run.metrics.missed_slips,
                missed_mm);
    EXPECT_FALSE(run.result.fell) << "seed " << seed;
    EXPECT_GT(run.metrics.slip_events, 0) << "seed " << seed;
    EXPECT_LT(missed_mm, 5.0) << "seed " << seed;
  }
}

// The stance slip of the paper's Fig. 8 (a loaded front foot on mu 0.1 as
// the body shifts), and ice_010's loaded stance slides: each stops within
// 40 ms of detection. Behind the torque loop the guess's law from mu in use
// reaches the ground's 0.1 only 24 ms after the flag: over seeds 1-8,
// stance_slip slides 41-42 ms after detection in each, ice_010 up to 43.
// Started at the foot's force ratio (kStanceSlideAge), seeds 1-8: 13-16 and
// 29-33 ms.
TEST(RealPlant, ALoadedStanceSlideStopsWithin40ms) {
  for (const char* file : {"stance_slip.yaml", "ice_010.yaml"}) {
    for (uint64_t seed : {2u, 3u}) {
      ScenarioRun run;
      runOnHyqPlant(file, run, seed);
      const double longest = longestAfterDetectionMs(run);
      std::printf("%s seed %llu: %d slips, longest after detection %.0f ms\n", file,
                  static_cast<unsigned long long>(seed), run.metrics.slip_events, longest);
      EXPECT_FALSE(run.result.fell) << file << " seed " << seed;
      ASSERT_FALSE(run.metrics.after_detection_ms.empty()) << file << " seed " << seed;
      EXPECT_LE(longest, 40.0) << file << " seed " << seed;
    }
  }
}

// A strip of oil (mu 0.02) under both front feet, then the hind feet: the
// ground lies under the floor of mu in use (RecoveryParams::mu_floor, 0.07).
// A stance whose own estimate's braking target lies below the floor brakes
// below it, to kEstimatedMuFloor at least. With the floor kept for every
// stance (commit e10e192) every run fell (ODE seeds 1-8, MuJoCo seeds 1-4):
// LF at 400 N was asked 26 N along the oil under mu in use 0.07 while its
// estimate read 0.02. Braking below it, none falls (the base 1.11-1.15 m on
// after 30 s, the hind feet still on the strip); the slides go on 148-342 ms
// after detection.
TEST(RealPlant, AnOilStripUnderTheFloorIsStoodOn) {
  const struct {
    sim::EngineKind engine;
    uint64_t seed;
  } cases[] = {{sim::EngineKind::ode, 1}, {sim::EngineKind::ode, 2}, {sim::EngineKind::mujoco, 1}};
  for (const auto& c : cases) {
    ScenarioRun run;
    runOnHyqPlant("oil_strip.yaml", run, c.seed, -1.0, c.engine);
    const std::string where = std::string(sim::engineName(c.engine)) + " seed " + std::to_string(c.seed);
    std::printf("%s: %.2f m, fell %d, longest slip after detection %.0f ms\n", where.c_str(), run.result.distance,
                run.result.fell ? 1 : 0, longestAfterDetectionMs(run));
    EXPECT_FALSE(run.result.fell) << where;
    EXPECT_GT(run.result.distance, 1.0) << where;
  }
}

// The trot over the ice slab: no fall, slips after detection at most 90 ms.
// Seeds 1-32: 56 ms median, 87 worst; 51 worst with the ideal plant's duty
// factor, the IMU's lever arm left in and no hold of a stance leg in the
// air, the cost of what holds the trot up on this plant
// (RealPlant.TrotRidesOutPushesIceAtSpeedAndTheRampsCrest,
// RealPlant.ATrotsStanceLegInTheAirIsHeldNotDriven).
TEST(RealPlant, TrotCrossesTheIceSlab) {
  for (uint64_t seed : {1u, 2u}) {
    ScenarioRun run;
    runOnHyqPlant("trot_ice_patches.yaml", run, seed);
    const double longest = longestAfterDetectionMs(run);
    std::printf("seed %llu: %.2f m, longest slip after detection %.0f ms, %d false\n",
                static_cast<unsigned long long>(seed), run.result.distance, longest, run.metrics.false_detections);
    EXPECT_FALSE(run.result.fell) << "seed " << seed;
    ASSERT_FALSE(run.metrics.after_detection_ms.empty()) << "seed " << seed;
    EXPECT_LE(longest, 90.0) << "seed " << seed;
    EXPECT_LE(run.metrics.false_detections, 1) << "seed " << seed;
  }
}

// On the hyq plant the trot stands longer on four feet (kHyqTrotDutyFactor)
// and takes its IMU's lever arm out: with recovery it rides out three
// sideways pushes on ice (trot_push_ice), trots at 1 m/s onto ice of mu 0.05
// (trot_ice_fast) and over the slippery ramp's crest (trot_ramp). Seeds
// 1-32, ODE: 0, 0 and 0 falls of 32 (MuJoCo 0, 0, 0). trot_ice_fast fell in
// 1 (MuJoCo 4) before its swing was lengthened at speed (the next test); 0, 1
// and 0 with the cone's floor on the flagged foot's plane (docs/design-notes.md,
// "A flagged foot's cone and its floor on one plane"); 0, 2 and 0 before it (commit
// 47f5b0d); 0, 1 and 4 with the plane refit on a
// touch-down tick alone (the parent of commit "trot: refit the ground plane
// once a landing foot holds"); 6, 1 and 0 without the valves'
// limit ("The valves' limit in the hyq preset"). Without
// the limit or the hold of a stance leg in the air (7d41fad), with the ideal
// plant's duty factor and the lever arm left in, 29, 32 and 4 ("The trot's
// diagonal stance behind the torque loop").
TEST(RealPlant, TrotRidesOutPushesIceAtSpeedAndTheRampsCrest) {
  for (const char* file : {"trot_push_ice.yaml", "trot_ice_fast.yaml", "trot_ramp.yaml"}) {
    for (uint64_t seed : {1u, 2u}) {
      ScenarioRun run;
      runOnHyqPlant(file, run, seed);
      EXPECT_FALSE(run.result.fell) << file << " seed " << seed;
    }
  }
}

// A trot's swing is lengthened at speed so that the foot crosses its stride
// at no more than kTrotMaxSwingSpeed on average (TrotGait::swingFraction).
// At the hyq plant's duty factor, 0.7, a 1 m/s trot on good ground (trot_flat
// at 1 m/s) swings its feet in 0.18 s: behind the torque loop they land
// early and short, the trunk pitches nose down over its front feet, and it
// fell in every run within 5 s (seeds 1-16 on ODE and on MuJoCo; 0.9 m/s as
// well; 0.8 m/s in none). With the swing lengthened to 0.22 s, none of them
// falls (docs/design-notes.md, "A fast trot swings longer").
TEST(RealPlant, AOneMetrePerSecondTrotOnGoodGroundStands) {
  for (const sim::EngineKind engine : {sim::EngineKind::ode, sim::EngineKind::mujoco}) {
    ScenarioRun run;
    loadOnHyqPlant("trot_flat.yaml", run, 1, 10.0, engine);
    run.scenario.controller_params.gait.speed = 1.0;
    // At the commanded speed: without the cautiousness, a guess from a
    // landing's skid does not slow it (with it, the trot that swung 0.18 s
    // was slowed so in every run and covered 5.3-5.6 m).
    run.scenario.controller_params.gait.trot.speed_per_mu = 0.0;
    runLoadedScenario(run);
    const std::string where = sim::engineName(engine);
    std::printf("%s: %.2f m in 10 s, %s\n", where.c_str(), run.result.distance, run.result.fell ? "fell" : "stood");
    EXPECT_FALSE(run.result.fell) << where << " at " << run.result.fall_time << " s";
    EXPECT_GT(run.result.distance, 6.0) << where;  // 8.05 m on both engines; the runs that fell, 3.4-3.9 m
  }
}

namespace {

constexpr double kHindFeetBehindBase = 0.37;  // [m]

// Over a ramp's crest (the scenario's first ramp): the trunk's true height
// above the ground under its base, its mean over the flat start (1.5 s on,
// the base 0.5 m short of the ramp's foot), and, once the hind feet are a
// stride (0.6 m) past the ramp's top, its worst departure from that mean
// and the worst angle between a stance foot's cone normal in use and the
// ground's.
class RampTopPlane final : public sim::TickObserver {
 public:
  explicit RampTopPlane(const sim::TerrainSpec& spec)
      : terrain_(spec), foot_x_(spec.ramps.at(0).x0), top_x_(spec.ramps.at(0).x0 + spec.ramps.at(0).length) {}
  void onTick(const sim::TickRecord& r) override {
    const double x = r.base_pos[0], height = r.base_pos[2] - terrain_.height(x);
    if (r.time > 1.5 && x < foot_x_ - 0.5) {
      flat_sum_ += height;
      ++flat_count_;
    }
    if (x - kHindFeetBehindBase < top_x_ + 0.6 || flat_count_ == 0) return;
    ++top_ticks_;
    height_error_max_ = std::max(height_error_max_, std::fabs(height - flat_sum_ / flat_count_));
    const Vec3 ground = terrain_.normal(x);
    const hal::Telemetry& t = r.command.telemetry;
    for (int leg = 0; leg < kNumLegs; ++leg) {
      if (!((t.stance_mask >> leg) & 1u)) continue;
      const Vec3 used(t.normal_used[leg][0], t.normal_used[leg][1], t.normal_used[leg][2]);
      normal_tilt_max_deg_ =
          std::max(normal_tilt_max_deg_, std::acos(std::min(1.0, used.dot(ground))) * 180.0 / M_PI);
    }
  }
  int topTicks() const { return top_ticks_; }
  double heightErrorMax() const { return height_error_max_; }    // [m]
  double normalTiltMaxDeg() const { return normal_tilt_max_deg_; }  // [deg]

 private:
  sim::Terrain terrain_;
  double foot_x_, top_x_;  // [m]
  double flat_sum_ = 0.0;
  int flat_count_ = 0;
  int top_ticks_ = 0;
  double height_error_max_ = 0.0;
  double normal_tilt_max_deg_ = 0.0;
};

}  // namespace

// The trot refits its ground plane through a landing foot once it is loaded
// and holds, not only on its touch-down tick: on the hyq plant most landings
// skid for a few ms, and a refit without the landing foot has two collinear
// feet and keeps the old plane. Refit on the touch-down tick alone (the
// parent of commit "trot: refit the ground plane once a landing foot
// holds"), the plane stays the ramp's on the flat top, the trunk's height
// taken over it climbs on (0.14-0.16 m too high, the cones 11-13 deg off),
// the legs straighten and seeds 6, 22, 27 and 30 fall (ODE). Refit once the
// foot holds: the trunk within 3 mm of its height over the flat start, the
// cones within 0.4 deg of the top's normal.
TEST(RealPlant, ATrotsGroundPlaneFollowsTheRampsCrest) {
  for (uint64_t seed : {6u, 22u, 27u, 30u}) {
    ScenarioRun run;
    loadOnHyqPlant("trot_ramp.yaml", run, seed);
    RampTopPlane top(run.scenario.terrain);
    runLoadedScenario(run, {&top});
    std::printf("seed %llu: %d ticks on the top, height off by at most %.3f m, cone normals tilted %.1f deg\n",
                static_cast<unsigned long long>(seed), top.topTicks(), top.heightErrorMax(), top.normalTiltMaxDeg());
    EXPECT_FALSE(run.result.fell) << "seed " << seed;
    ASSERT_GT(top.topTicks(), 2000) << "seed " << seed;
    EXPECT_LT(top.heightErrorMax(), 0.03) << "seed " << seed;
    EXPECT_LT(top.normalTiltMaxDeg(), 5.0) << "seed " << seed;
  }
}

namespace {

// Ticks the controller answered with the safe hold of a rejected frame.
class RejectedFrames final : public sim::TickObserver {
 public:
  void onTick(const sim::TickRecord& r) override {
    if (r.command.flags & hal::kFlagBadSensorFrame) ++count;
  }
  int count = 0;
};

// Runs the loaded scenario, prints `label`, the joints' velocity limit and
// the outcome, and returns the ticks answered with a rejected frame's hold.
int runCountingRejectedFrames(ScenarioRun& run, const std::string& label) {
  RejectedFrames rejected;
  runLoadedScenario(run, {&rejected});
  std::printf("%s, velocity limit %.0f rad/s: %s, %d frames rejected\n", label.c_str(),
              run.scenario.plant.actuator.velocity_limit, run.result.fell ? "fell" : "walked on", rejected.count);
  return rejected.count;
}

// Runs drawn terrain `generate_seed` (seed `seed`), recovery on, on the hyq
// plant as its preset has it or, `without_limit`, with no joint velocity
// limit; returns the rejected frames.
int runDrawnTerrain(uint64_t generate_seed, uint64_t seed, bool without_limit, ScenarioRun& run) {
  const std::string yaml = "name: drawn\nduration: 60\nseed: " + std::to_string(seed) +
                           "\nterrain: {generate: {seed: " + std::to_string(generate_seed) +
                           "}}\ncontroller: {recovery: true}\nplant: {model: hyq}\n";
  run.scenario = sim::parseScenario(yaml, "drawn.yaml");
  if (without_limit) run.scenario.plant.actuator.velocity_limit = 0.0;
  return runCountingRejectedFrames(run, "terrain " + std::to_string(generate_seed) + " seed " + std::to_string(seed));
}

}  // namespace

// A trot's stance leg in the air is held still, not driven with the
// stance's torques against nothing: on these drawn validation terrains
// (trotting down slopes of 0.29 and 0.24 rad at 0.5 m/s) such a knee passed
// the frame check's 30 rad/s, 226 and 1051 frames were rejected as corrupt,
// the leg chattered between the safe hold and the controller, and the
// robot fell on seed 1 (docs/design-notes.md, "A stance leg in the air, and
// the joints' speed"). The joints here have no velocity limit: with the
// valves' (the hyq preset's) no knee gets there on these terrains (the next
// test). Both trots are on the edge of what the trot on this plant survives
// (1.8-4.7 m/s slips on landing before a fall), and which seeds fall moves
// with any change to the controller: over seeds 1-6, terrain 90 walks on in
// 5 (seed 1 falls, 812 frames rejected), terrain 113 in 3. The test holds
// terrain 90 at 4, one run of margin, and 113 at 3. Without the hold only
// seed 1 was measured (both fell).
TEST(RealPlant, ATrotsStanceLegInTheAirIsHeldNotDriven) {
  struct Terrain {
    uint64_t generate_seed;  // terrain.generate.seed
    int walks_on_at_least;   // of seeds 1-6
  };
  for (const Terrain terrain : {Terrain{90u, 4}, Terrain{113u, 3}}) {
    int walked_on = 0;
    for (uint64_t seed = 1; seed <= 6; ++seed) {
      ScenarioRun run;
      runDrawnTerrain(terrain.generate_seed, seed, true, run);
      walked_on += run.result.fell ? 0 : 1;
    }
    EXPECT_GE(walked_on, terrain.walks_on_at_least) << "terrain " << terrain.generate_seed;
  }
}

// The joints' velocity limit, the servo valves' 12 rad/s (the hyq preset's,
// kHyqJointVelocityLimit), holds a trot's legs from the speeds the frame
// check rejects. The same two terrains walk on with no frame rejected
// (seeds 1-6 all did), and trot_push_ice's seeds that fell without the limit
// (14, 15 and 18 of the six in 1-32, each after rejected frames) walk on
// with none (seeds 1-32: no fall, no frame rejected; docs/design-notes.md, "A
// stance leg in the air, and the joints' speed").
TEST(RealPlant, TheValvesLimitKeepsATrotsFramesValid) {
  for (uint64_t generate_seed : {90u, 113u}) {
    for (uint64_t seed : {1u, 2u, 3u}) {
      ScenarioRun run;
      const int rejected = runDrawnTerrain(generate_seed, seed, false, run);
      EXPECT_FALSE(run.result.fell) << "terrain " << generate_seed << " seed " << seed;
      EXPECT_EQ(rejected, 0) << "terrain " << generate_seed << " seed " << seed;
    }
  }
  for (uint64_t seed : {14u, 15u, 18u}) {
    ScenarioRun run;
    loadOnHyqPlant("trot_push_ice.yaml", run, seed);
    const int rejected = runCountingRejectedFrames(run, "trot_push_ice seed " + std::to_string(seed));
    EXPECT_FALSE(run.result.fell) << "trot_push_ice seed " << seed;
    EXPECT_EQ(rejected, 0) << "trot_push_ice seed " << seed;
  }
}

// The slippery ramp (0.25 rad, mu 0.5), crawling: climbed on both seeds,
// slips stopped within 50 ms of detection and the friction, where
// estimated, within 10 %. Seeds 1-32: no fall, all climbed, each run's
// longest slip after detection 23-34 ms (median 29.5); the crawl's body
// shift, bounded on this plant, leaves every run's slides too light to
// estimate. The bound is the 32 seeds' worst with a margin: a change in the
// controller's last bits deals the seeds anew.
TEST(RealPlant, CrawlClimbsTheSlipperyRamp) {
  for (uint64_t seed : {1u, 2u}) {
    ScenarioRun run;
    runOnHyqPlant("ramp.yaml", run, seed);
    expectCrossed(run, seed, 3.4, 50.0);
    EXPECT_LE(run.metrics.mu_error_max_pct, 10.0) << "seed " << seed;
    EXPECT_EQ(run.metrics.false_detections, 0) << "seed " << seed;
  }
}

// The first foot onto a ramp, crawling: every slip of 5 mm or more is
// flagged within 20 ms of its start. Its foothold's height comes from the
// still-flat ground plane; from a 6 cm apex behind the torque loop it came
// down onto the slope short of its foothold and was dragged up it at
// 3-15 N until its swing ended, flagged 131-179 ms (ramp) and 300-321 ms
// (ramp_035) late in every ODE run of seeds 1-32. The front feet's 10 cm
// apex (kFrontStepHeight) clears the slope: seeds 1-32, no such slip on
// either engine (docs/design-notes.md, "The front feet swing high, the
// hind feet low").
TEST(RealPlant, TheFirstFootOntoARampIsNotDraggedUpItUnseen) {
  for (const char* file : {"ramp.yaml", "ramp_035.yaml"}) {
    ScenarioRun run;
    runOnHyqPlant(file, run, 1, 30.0);
    double worst = 0.0;  // [ms]
    const int long_slips = expectLongSlipsCaughtWithin(run, 20.0, file, worst);
    std::printf("%s seed 1: %d slips over 5 mm, worst latency %.0f ms\n", file, long_slips, worst);
    EXPECT_FALSE(run.result.fell) << file;
  }
}

// Flat ground, crawling: no slip flag without a slip.
TEST(RealPlant, FlatGroundRaisesNoFalseDetection) {
  for (uint64_t seed : {1u, 2u}) {
    ScenarioRun run;
    runOnHyqPlant("flat.yaml", run, seed);
    EXPECT_FALSE(run.result.fell) << "seed " << seed;
    EXPECT_EQ(run.metrics.false_detections, 0) << "seed " << seed;
  }
}

// Flat ground, trotting: few slip flags without a slip. A foot braking at
// the end of its swing reads 15-27 N in the air here; without the approach
// test it is flagged before it lands (seeds 1-2: 2 and 4 false in 30 s).
// With it, seeds 1-8 over the scenario's 60 s: 0-3 false detections a run,
// 5 in all (docs/results.md, "The hyq plant, seeds 1-32": 23 over 32 runs);
// the ideal plant's trot has none (trot_test.cpp).
TEST(RealPlant, TrotOnFlatGroundRaisesFewFalseDetections) {
  for (uint64_t seed : {1u, 2u}) {
    ScenarioRun run;
    runOnHyqPlant("trot_flat.yaml", run, seed, 30.0);
    EXPECT_FALSE(run.result.fell) << "seed " << seed;
    EXPECT_GE(run.result.distance, 14.0) << "seed " << seed;
    EXPECT_LE(run.metrics.false_detections, 3) << "seed " << seed;
  }
}

// Flat ground, trotting without recovery: the trot stands on its own
// landings. Behind the torque loop the swing gains alone pressed a landed
// foot with 13-67 N, short of the 80 N that confirms touch-down; the trunk
// tipped about the standing diagonal while it waited, and every run fell
// within 2-5 s (seeds 1-8). With the landing's press (kLandingPressShare)
// seeds 1-8 walk the 30 s with no false detection.
TEST(RealPlant, TrotWithoutRecoveryStandsOnItsLandings) {
  for (uint64_t seed : {1u, 2u}) {
    ScenarioRun run;
    loadOnHyqPlant("trot_flat.yaml", run, seed, 30.0);
    run.scenario.controller_params.recovery.enabled = false;
    runLoadedScenario(run);
    std::printf("seed %llu: %.2f m, %d false\n", static_cast<unsigned long long>(seed), run.result.distance,
                run.metrics.false_detections);
    EXPECT_FALSE(run.result.fell) << "seed " << seed;
    EXPECT_GE(run.result.distance, 14.0) << "seed " << seed;
    EXPECT_LE(run.metrics.false_detections, 1) << "seed " << seed;
  }
}

// A trot that starts standing on a slope (trot_slope_start: 0.25 rad up or
// down, mu 0.8), recovery on and off. Started at once, as it stood, its
// first pair's step tipped the trunk about the standing diagonal (its CoM
// 5 cm off that line): over seeds 1-8, up: 5 falls with recovery on, 3
// off; down: 3 on, 0 off. With the CoM first moved over the diagonals'
// crossing, none of the 32 runs falls and each walks 2.5 m; seeds 1-2 here.
TEST(RealPlant, TrotStartsOnASlope) {
  for (double angle : {0.25, -0.25})
    for (bool recovery : {true, false})
      for (uint64_t seed : {1u, 2u}) {
        ScenarioRun run;
        loadOnHyqPlant("trot_slope_start.yaml", run, seed);
        ASSERT_EQ(run.scenario.terrain.ramps.size(), 1u);
        run.scenario.terrain.ramps[0].angle = angle;
        run.scenario.controller_params.recovery.enabled = recovery;
        runLoadedScenario(run);
        std::printf("angle %+.2f recovery %d seed %llu: %.2f m\n", angle, recovery ? 1 : 0,
                    static_cast<unsigned long long>(seed), run.result.distance);
        EXPECT_FALSE(run.result.fell) << angle << " recovery " << recovery << " seed " << seed;
        EXPECT_GE(run.result.distance, 2.5) << angle << " recovery " << recovery << " seed " << seed;
      }
}

// crawl_to_trot on the hyq plant, whose crawl shifts its body at 1 m/s^2 at
// most (kHyqShiftAcceleration): the crawl hands over mid-stride with its
// CoM up to 10 cm off the diagonals' crossing. A trot that lifts its first
// pair at once rolls over about the standing diagonal (without the trot's
// start shift, ODE seeds 1-8: 7 falls with recovery on, 8 off); with the
// CoM first moved over the crossing none falls, and each run trots across
// the ice slab: its hind feet, 0.37 m behind the base, past x = 4.0 m.
TEST(RealPlant, CrawlHandsOverToTheTrotMidStrideAndCrossesTheIce) {
  for (bool recovery : {true, false})
    for (uint64_t seed : {1u, 2u}) {
      ScenarioRun run;
      loadOnHyqPlant("crawl_to_trot.yaml", run, seed);
      ASSERT_EQ(run.scenario.controller_params.gait.max_shift_acceleration, sim::kHyqShiftAcceleration);
      run.scenario.controller_params.recovery.enabled = recovery;
      runLoadedScenario(run);
      std::printf("recovery %d seed %llu: %.2f m, fell %d\n", recovery ? 1 : 0,
                  static_cast<unsigned long long>(seed), run.path.x.back(), run.result.fell ? 1 : 0);
      EXPECT_FALSE(run.result.fell) << "recovery " << recovery << " seed " << seed;
      EXPECT_GT(run.path.x.back() - 0.37, 4.0) << "recovery " << recovery << " seed " << seed;
    }
}

// MuJoCo's contact under the same plant: the ice slab crawled across.
TEST(RealPlantOnMujoco, CrawlCrossesTheIcePatches) {
  ScenarioRun run;
  runOnHyqPlant("ice_patches.yaml", run, 1, -1.0, sim::EngineKind::mujoco);
  const double longest = longestAfterDetectionMs(run);
  std::printf("%.2f m, longest slip after detection %.0f ms, %d false\n", run.result.distance, longest,
              run.metrics.false_detections);
  EXPECT_FALSE(run.result.fell);
  EXPECT_GE(run.result.distance, 3.77);
  ASSERT_FALSE(run.metrics.after_detection_ms.empty());
  EXPECT_LE(longest, 60.0);
}

// The trot without recovery on MuJoCo's contact: without the landing's
// press it fell in every run (seeds 1-4); with it none does, and none
// raises a false detection (the bound leaves 3 for a new dealing of seeds).
TEST(RealPlantOnMujoco, TrotWithoutRecoveryStandsOnItsLandings) {
  ScenarioRun run;
  loadOnHyqPlant("trot_flat.yaml", run, 1, 30.0, sim::EngineKind::mujoco);
  run.scenario.controller_params.recovery.enabled = false;
  runLoadedScenario(run);
  std::printf("%.2f m, %d false\n", run.result.distance, run.metrics.false_detections);
  EXPECT_FALSE(run.result.fell);
  EXPECT_GE(run.result.distance, 14.0);
  EXPECT_LE(run.metrics.false_detections, 3);
}

}  // namespace hyq::test
