// The summary.json slip metrics on synthetic tick sequences with known
// answers: event extraction, matching, latencies, estimate errors, false and
// missed detections, freezes, stance torque steps, odometry error.
#include "sim_host/records/metrics.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "sim_host/records/run_log.hpp"

namespace hyq::sim {
namespace {

constexpr double kDt = 0.001;

// A robot walking at 0.1 m/s with all feet in contact and stance, no slips.
class SyntheticRun {
 public:
  explicit SyntheticRun(double duration) : records_(static_cast<size_t>(std::lround(duration / kDt))) {
    for (size_t i = 0; i < records_.size(); ++i) {
      TickRecord& r = records_[i];
      r.tick = static_cast<uint32_t>(i);
      r.time = (i + 1) * kDt;
      r.base_pos = {0.1 * r.time, 0.0, 0.6};
      r.command.telemetry.stance_mask = 0xF;
      for (int k = 0; k < 3; ++k) r.command.telemetry.base_pos_est[k] = r.base_pos[k];
      for (int leg = 0; leg < 4; ++leg) {
        r.feet[leg].in_contact = true;
        r.feet[leg].mu = 0.8;
        r.command.telemetry.mu_used[leg] = 0.6;
      }
    }
  }
  size_t at(double t) const { return static_cast<size_t>(std::lround(t / kDt)) - 1; }
  // f(record) for every tick with time in [t0, t1].
  template <typename F>
  void during(double t0, double t1, F f) {
    for (size_t i = at(t0); i <= at(t1); ++i) f(records_[i]);
  }
  void trueSlip(int leg, double t0, double t1, double speed = 0.2) {
    during(t0, t1, [&](TickRecord& r) { r.feet[leg].slip_speed = speed; });
  }
  void flag(int leg, double t0, double t1) {
    during(t0, t1, [&](TickRecord& r) { r.command.telemetry.slip_mask |= 1u << leg; });
  }
  MetricsResult evaluate(Metrics& m) const {
    for (const TickRecord& r : records_) m.onTick(r);
    m.onFinish();
    return m.result();
  }
  TickRecord& operator[](size_t i) { return records_[i]; }

 private:
  std::vector<TickRecord> records_;
};

std::string field(const SummaryFields& fields, const std::string& key) {
  for (const auto& [k, v] : fields)
    if (k == key) return v;
  return "<missing>";
}

TEST(MetricsTest, QuietRunHasNothingToReport) {
  SyntheticRun run(2.0);
  Metrics m;
  const MetricsResult r = run.evaluate(m);
  EXPECT_EQ(r.slip_events, 0);
  EXPECT_EQ(r.false_detections, 0);
  EXPECT_EQ(r.missed_slips, 0);
  EXPECT_EQ(r.freeze_events, 0);
  EXPECT_EQ(r.max_stance_torque_step_nm, 0.0);
  EXPECT_NEAR(r.odometry_error_max_m, 0.0, 1e-12);
  EXPECT_NEAR(r.distance_walked_m, 0.1 * (2.0 - kDt), 1e-9);
  const SummaryFields f = m.summaryFields();
  EXPECT_EQ(field(f, "detection_latency_ms"), "{\"median\": null, \"max\": null}");
  EXPECT_EQ(field(f, "missed_slip_distance_mm"), "{\"max\": null}");
  EXPECT_EQ(field(f, "mu_estimate_error_pct"),
            "{\"max\": null, \"per_leg\": [null, null, null, null], \"per_patch\": []}");
}

TEST(MetricsTest, DetectedSlipGivesLatencyDurationAndEstimateErrors) {
  SyntheticRun run(3.0);
  run.trueSlip(0, 1.000, 1.039);  // 40 ms true slip of LF on mu 0.2
  run.during(0.9, 1.2, [](TickRecord& r) {
    r.feet[0].mu = 0.2;
    r.feet[0].normal = {0.0, 0.0, 1.0};
  });
  run.flag(0, 1.008, 1.050);
  // Filtered estimates as telemetry: 0.3 until the last flagged tick, 0.22 there.
  const double tilt = 3.0 * M_PI / 180.0;
  run.during(1.008, 1.049, [](TickRecord& r) { r.command.telemetry.mu_hat[0] = 0.3; });
  run.during(1.050, 1.050, [tilt](TickRecord& r) {
    r.command.telemetry.mu_hat[0] = 0.22;
    r.command.telemetry.normal_hat[0][0] = std::sin(tilt);
    r.command.telemetry.normal_hat[0][2] = std::cos(tilt);
    // The cone the QP used, 5 deg about the other axis.
    r.command.telemetry.normal_used[0][1] = std::sin(5.0 * M_PI / 180.0);
    r.command.telemetry.normal_used[0][2] = std::cos(5.0 * M_PI / 180.0);
  });
  Metrics m;
  const MetricsResult r = run.evaluate(m);
  ASSERT_EQ(r.slip_events, 1);
  EXPECT_EQ(r.missed_slips, 0);
  EXPECT_EQ(r.false_detections, 0);
  ASSERT_EQ(r.latency_ms.size(), 1u);
  EXPECT_NEAR(r.latency_ms[0], 8.0, 1e-6);
  EXPECT_NEAR(r.after_detection_ms[0], 31.0, 1e-6);
  EXPECT_NEAR(r.mu_error_max_pct, 10.0, 1e-9);
  EXPECT_NEAR(r.mu_error_per_leg_pct[0], 10.0, 1e-9);
  EXPECT_LT(r.mu_error_per_leg_pct[1], 0.0);
  EXPECT_NEAR(r.normal_error_max_deg, 3.0, 1e-9);
  EXPECT_NEAR(r.normal_in_use_error_max_deg, 5.0, 1e-9);
  const SummaryFields f = m.summaryFields();
  EXPECT_EQ(field(f, "normal_in_use_error_deg"), "{\"max\": 5}");
  EXPECT_EQ(field(f, "detection_latency_ms"), "{\"median\": 8, \"max\": 8}");
  EXPECT_EQ(field(f, "slip_duration_after_detection_ms"), "{\"median\": 31, \"max\": 31}");
  EXPECT_EQ(field(f, "mu_estimate_error_pct"),
            "{\"max\": 10, \"per_leg\": [10, null, null, null], \"per_patch\": "
            "[{\"leg\": 0, \"mu_true\": 0.2, \"max_error_pct\": 10, \"samples\": 1}]}");
}


// The loaded slide: of a 50 ms slip on mu 0.2 flagged at 1.008 s, the foot
// slides on the cone under 300 N until 1.020 s, then moves at the slip
// speed inside the cone (the contact's elastic deflection) to 1.035 s and
// on the cone under 20 N (unloaded) to the end. Its loaded slide after
// detection is 12 ms against 41 ms of slip; an event that never slides
// loaded counts 0.
TEST(MetricsTest, LoadedSlideEndsAtTheLastLoadedTickOnTheCone) {
  SyntheticRun run(3.0);
  run.during(0.9, 1.2, [](TickRecord& r) { r.feet[0].mu = 0.2; });
  run.trueSlip(0, 1.000, 1.049);
  run.during(1.000, 1.020, [](TickRecord& r) { r.feet[0].force = {36.0, 48.0, 300.0}; });  // |f_t| 60 = mu f_n
  run.during(1.021, 1.035, [](TickRecord& r) { r.feet[0].force = {30.0, 0.0, 300.0}; });  // inside the cone
  run.during(1.036, 1.049, [](TickRecord& r) { r.feet[0].force = {4.0, 0.0, 20.0}; });    // on it, light
  run.flag(0, 1.008, 1.060);
  run.trueSlip(1, 2.000, 2.029);
  run.during(2.000, 2.029, [](TickRecord& r) { r.feet[1].force = {10.0, 0.0, 300.0}; });
  run.flag(1, 2.004, 2.030);
  Metrics m;
  const MetricsResult r = run.evaluate(m);
  ASSERT_EQ(r.slip_events, 2);
  EXPECT_NEAR(r.events[0].loaded_end, 1.020, 1e-9);
  EXPECT_LT(r.events[1].loaded_end, 0.0);
  const SummaryFields f = m.summaryFields();
  EXPECT_EQ(field(f, "slip_duration_after_detection_ms"), "{\"median\": 33, \"max\": 41}");
  EXPECT_EQ(field(f, "loaded_slide_after_detection_ms"), "{\"median\": 6, \"max\": 12}");
}

// One slip event seen by two flag runs (the controller's flag drops and
// rises again while the foot still slides): each run's last tick is
// sampled and the event keeps its worst estimate. A later flag run without
// an estimate (mu_hat 0: the estimator cleared it for the new run) does not
// hide the earlier one's.
TEST(MetricsTest, AnEventSeenByTwoFlagRunsKeepsTheWorstEstimate) {
  for (const double second : {0.0, 0.26, 0.205}) {
    SyntheticRun run(3.0);
    run.during(0.9, 1.2, [](TickRecord& r) {
      r.feet[0].mu = 0.2;
      r.feet[0].normal = {0.0, 0.0, 1.0};
    });
    run.trueSlip(0, 1.000, 1.059);
    run.flag(0, 1.005, 1.020);
    run.flag(0, 1.030, 1.050);
    run.during(1.010, 1.029, [](TickRecord& r) { r.command.telemetry.mu_hat[0] = 0.19; });
    run.during(1.030, 1.050, [second](TickRecord& r) { r.command.telemetry.mu_hat[0] = second; });
    Metrics m;
    const MetricsResult r = run.evaluate(m);
    ASSERT_EQ(r.slip_events, 1) << second;
    EXPECT_EQ(r.false_detections, 0) << second;
    ASSERT_EQ(r.events.size(), 1u);
    ASSERT_TRUE(r.events[0].has_mu_sample) << second;
    const double expected = second == 0.26 ? 30.0 : 5.0;  // 0.205 is 2.5 % off: the first run's 5 % kept
    EXPECT_NEAR(r.events[0].mu_error_pct, expected, 1e-9) << second;
    EXPECT_NEAR(r.events[0].mu_hat, second == 0.26 ? 0.26 : 0.19, 1e-12) << second;
    EXPECT_NEAR(r.mu_error_max_pct, expected, 1e-9) << second;
  }
}
TEST(MetricsTest, CoverageListsEachLegsSlippedPatchesWithoutAnEstimate) {
  // LF slips on mu 0.2 (flagged, estimated) and on mu 0.3 (flagged, no
  // estimate yet: mu_hat 0); RH slips on mu 0.3, flagged, no estimate; LH
  // slips unflagged (missed: not counted); RF skids 4 mm on mu 0.8, flagged,
  // no estimate. Three of the four (leg, patch) pairs lack an estimate; of the
  // three whose slips travelled 5 mm or more (8 mm each), two.
  SyntheticRun run(4.0);
  run.during(0.9, 1.2, [](TickRecord& r) { r.feet[0].mu = 0.2; });
  run.during(1.9, 3.2, [](TickRecord& r) {
    r.feet[0].mu = 0.3;
    r.feet[3].mu = 0.3;
  });
  run.trueSlip(0, 1.000, 1.039);
  run.flag(0, 1.008, 1.050);
  run.during(1.008, 1.050, [](TickRecord& r) { r.command.telemetry.mu_hat[0] = 0.21; });
  run.trueSlip(0, 2.000, 2.039);
  run.flag(0, 2.008, 2.050);
  run.trueSlip(3, 3.000, 3.039);
  run.flag(3, 3.008, 3.050);
  run.trueSlip(2, 3.000, 3.039);
  run.trueSlip(1, 3.500, 3.519);  // 20 ticks at 0.2 m/s: 4 mm
  run.flag(1, 3.506, 3.530);
  Metrics m;
  run.evaluate(m);
  EXPECT_EQ(field(m.summaryFields(), "mu_estimate_coverage"),
            "{\"slipped\": [2, 1, 0, 1], \"estimated\": [1, 0, 0, 0], \"slid_5mm\": [2, 0, 0, 1], "
            "\"slid_5mm_estimated\": [1, 0, 0, 0], \"missing\": [{\"leg\": 0, \"mu_true\": 0.3}, "
            "{\"leg\": 1, \"mu_true\": 0.8}, {\"leg\": 3, \"mu_true\": 0.3}]}");
  // A quiet run has nothing slipped.
  SyntheticRun quiet(1.0);
  Metrics q;
  quiet.evaluate(q);
  EXPECT_EQ(field(q.summaryFields(), "mu_estimate_coverage"),
            "{\"slipped\": [0, 0, 0, 0], \"estimated\": [0, 0, 0, 0], \"slid_5mm\": [0, 0, 0, 0], "
            "\"slid_5mm_estimated\": [0, 0, 0, 0], \"missing\": []}");
}

TEST(MetricsTest, TouchDownAndStanceSlipsApartAndTheRecallByTravel) {
  SyntheticRun run(4.0);
  // LF in the air for 0.1 s, down at 1.000 s: a slip from 1.050 s is a
  // touch-down slip (within 0.2 s), detected 6 ms in, 4 mm of travel.
  run.during(0.900, 0.999, [](TickRecord& r) { r.feet[0].in_contact = false; });
  run.trueSlip(0, 1.050, 1.069);  // 20 ticks at 0.2 m/s: 4 mm
  run.flag(0, 1.056, 1.075);
  // RH: a 3 ms contact flicker (too short to be a touch-down) at 2.000 s,
  // then an undetected 12 mm slip from 2.100 s: a stance slip.
  run.during(2.000, 2.002, [](TickRecord& r) { r.feet[3].in_contact = false; });
  run.trueSlip(3, 2.100, 2.159);  // 60 ticks at 0.2 m/s: 12 mm
  // LH: a detected 22 mm stance slip, flagged 10 ms in.
  run.trueSlip(2, 3.000, 3.109);  // 110 ticks: 22 mm
  run.flag(2, 3.010, 3.120);
  Metrics m;
  const MetricsResult r = run.evaluate(m);
  ASSERT_EQ(r.slip_events, 3);
  EXPECT_EQ(r.missed_slips, 1);
  EXPECT_EQ(r.false_detections, 0);
  int touchdown = 0;
  for (const TrueSlip& e : r.events) touchdown += e.touchdown ? 1 : 0;
  EXPECT_EQ(touchdown, 1);
  const SummaryFields f = m.summaryFields();
  EXPECT_EQ(field(f, "slip_classes"),
            "{\"touchdown\": {\"events\": 1, \"missed\": 0, \"detection_latency_ms\": {\"median\": 6, \"max\": 6}, "
            "\"slip_duration_after_detection_ms\": {\"median\": 13, \"max\": 13}}, "
            "\"stance\": {\"events\": 2, \"missed\": 1, \"detection_latency_ms\": {\"median\": 10, \"max\": 10}, "
            "\"slip_duration_after_detection_ms\": {\"median\": 99, \"max\": 99}}}");
  EXPECT_EQ(field(f, "recall_by_travel"),
            "[{\"min_travel_mm\": 5, \"events\": 2, \"detected\": 1, \"detection_latency_ms\": {\"median\": 10, "
            "\"max\": 10}}, "
            "{\"min_travel_mm\": 10, \"events\": 2, \"detected\": 1, \"detection_latency_ms\": {\"median\": 10, "
            "\"max\": 10}}, "
            "{\"min_travel_mm\": 20, \"events\": 1, \"detected\": 1, \"detection_latency_ms\": {\"median\": 10, "
            "\"max\": 10}}]");
}

TEST(MetricsTest, ATouchDownFollowsFiftyMillisecondsInTheAirNotTheRunsStart) {
  SyntheticRun run(3.0);
  // Every foot is on the ground from the first tick: LF's slip at 0.05 s
  // is a stance slip. RF is in the air for exactly 50 ms before 1.000 s, LH
  // for 49 ms: RF's slip just after is a touch-down slip, LH's is not.
  run.trueSlip(0, 0.050, 0.069);
  run.during(0.950, 0.999, [](TickRecord& r) { r.feet[1].in_contact = false; });
  run.trueSlip(1, 1.010, 1.029);
  run.during(1.951, 1.999, [](TickRecord& r) { r.feet[2].in_contact = false; });
  run.trueSlip(2, 2.010, 2.029);
  Metrics m;
  const MetricsResult r = run.evaluate(m);
  ASSERT_EQ(r.events.size(), 3u);
  for (const TrueSlip& e : r.events) EXPECT_EQ(e.touchdown, e.leg == 1) << "leg " << e.leg;
}

TEST(MetricsTest, FalseMissedShortMergedAndUnmonitoredSlips) {
  SyntheticRun run(8.0);
  run.flag(3, 1.0, 1.004);               // RH flag, no true slip: false
  run.trueSlip(1, 2.0, 2.019);           // RF slips 20 ms, never flagged: missed
  run.trueSlip(2, 3.0, 3.003);           // LH 4 ms blip: below min duration
  run.trueSlip(0, 4.0, 4.009);           // LF: two runs 15 ms apart -> one event
  run.trueSlip(0, 4.025, 4.034);
  run.flag(0, 4.005, 4.060);             // ... detected once
  // LH slides while the controller has it in swing (touch-down before the
  // stance trigger): not monitored, and its flag-free state is not a miss.
  run.during(5.0, 5.1, [](TickRecord& r) { r.command.telemetry.stance_mask = 0xB; });
  run.trueSlip(2, 5.02, 5.05);
  // A slip seen by the flag 15 ms before the true threshold is crossed,
  // the flag still up when it is: latency 0, not a false detection.
  run.flag(1, 6.985, 7.03);
  run.trueSlip(1, 7.0, 7.02);
  // A foot flying (no contact) at speed is not a slip.
  run.during(7.5, 7.6, [](TickRecord& r) {
    r.feet[3].in_contact = false;
    r.feet[3].slip_speed = 1.0;
  });
  Metrics m;
  const MetricsResult r = run.evaluate(m);
  EXPECT_EQ(r.slip_events, 3);  // RF@2, LF@4, RF@7
  EXPECT_EQ(r.missed_slips, 1);
  EXPECT_EQ(r.false_detections, 1);
  EXPECT_EQ(r.unmonitored_slips, 1);
  ASSERT_EQ(r.latency_ms.size(), 2u);
  EXPECT_NEAR(r.latency_ms[0], 5.0, 1e-6);   // LF (leg order)
  EXPECT_NEAR(r.latency_ms[1], 0.0, 1e-6);   // RF@7
  EXPECT_NEAR(r.after_detection_ms[0], 29.0, 1e-6);  // merged end 4.034 - 4.005
  EXPECT_NEAR(r.after_detection_ms[1], 20.0, 1e-6);  // 7.02 - 7.0: the slip's whole length, no more
  const SummaryFields f = m.summaryFields();
  EXPECT_EQ(field(f, "slip_events"), "3");
  EXPECT_EQ(field(f, "missed_slips"), "1");
  EXPECT_NEAR(r.missed_distance_max_m, 0.2 * 0.020, 1e-9);  // 20 ticks at 0.2 m/s
  EXPECT_EQ(field(f, "missed_slip_distance_mm"), "{\"max\": 4}");
  EXPECT_EQ(field(f, "false_detections"), "1");
  EXPECT_EQ(field(f, "detection_latency_ms"), "{\"median\": 2.5, \"max\": 5}");
}

TEST(MetricsTest, AFlagThatEndedBeforeTheSlipDetectsNothing) {
  SyntheticRun run(4.0);
  // LF's flag ends 8 ms before the slip starts (within match_before): the
  // slip is missed and the flag is not false. RF's flag ends 21 ms before:
  // false, and its slip missed. LH's flag ends on the slip's first tick:
  // detected, latency 0, after detection the slip's length.
  run.flag(0, 1.000, 1.010);
  run.trueSlip(0, 1.018, 1.037);
  run.flag(1, 2.000, 2.010);
  run.trueSlip(1, 2.031, 2.050);
  run.flag(2, 2.990, 3.000);
  run.trueSlip(2, 3.000, 3.019);
  Metrics m;
  const MetricsResult r = run.evaluate(m);
  EXPECT_EQ(r.slip_events, 3);
  EXPECT_EQ(r.missed_slips, 2);
  EXPECT_EQ(r.false_detections, 1);
  ASSERT_EQ(r.latency_ms.size(), 1u);
  EXPECT_NEAR(r.latency_ms[0], 0.0, 1e-6);
  EXPECT_NEAR(r.after_detection_ms[0], 19.0, 1e-6);
}

TEST(MetricsTest, FlagOnASlipStoppedBeforeTheMinimumIsNotFalse) {
  SyntheticRun run(4.0);
  // LF slips 4 ms (below true_slip_min_duration); the flag rises on its
  // last tick and the recovery stops it: not an event, not a false flag.
  run.trueSlip(0, 1.0, 1.003);
  run.flag(0, 1.003, 1.012);
  // RF: a flag rising 10 ms after a 2 ms blip is still excused ...
  run.trueSlip(1, 2.0, 2.001);
  run.flag(1, 2.011, 2.02);
  // ... 11 ms after is not; nor is one that rose before the blip began.
  run.trueSlip(2, 3.0, 3.001);
  run.flag(2, 3.012, 3.02);
  run.flag(3, 2.990, 2.995);
  run.trueSlip(3, 2.996, 2.997);
  Metrics m;
  const MetricsResult r = run.evaluate(m);
  EXPECT_EQ(r.slip_events, 0);
  EXPECT_EQ(r.missed_slips, 0);
  EXPECT_EQ(r.false_detections, 2);  // LH@3.012, RH@2.990
  EXPECT_EQ(r.false_detections_in_air, 0);
}

// A foot that rings along the ground, 0.2 m/s one way for 5 ticks and back
// for 5, covers its path and goes nowhere; one that slides on goes as far
// as it travels, in any direction. summary.json names the longest after its
// detection, the first leg of equals.
TEST(MetricsTest, ASlipsNetTravelTellsRingingFromSliding) {
  SyntheticRun run(4.0);
  run.trueSlip(0, 1.000, 1.039);  // 40 ticks
  run.during(1.000, 1.039, [&run](TickRecord& r) {
    const bool back = (run.at(r.time) - run.at(1.0)) % 10 >= 5;
    r.feet[0].slip_velocity = {back ? -0.2 : 0.2, 0.0, 0.0};
  });
  run.flag(0, 1.004, 1.050);
  run.trueSlip(1, 2.000, 2.019);  // 20 ticks, one way
  run.during(2.000, 2.019, [](TickRecord& r) { r.feet[1].slip_velocity = {0.0, 0.2, 0.0}; });
  run.flag(1, 2.004, 2.030);
  // RH slides as long after its detection as LF: LF, the first leg, is named.
  run.trueSlip(3, 3.000, 3.039);
  run.during(3.000, 3.039, [](TickRecord& r) { r.feet[3].slip_velocity = {0.0, 0.0, 0.2}; });
  run.flag(3, 3.004, 3.050);
  Metrics m;
  const MetricsResult r = run.evaluate(m);
  ASSERT_EQ(r.events.size(), 3u);
  EXPECT_NEAR(r.events[0].distance, 0.008, 1e-9);
  EXPECT_NEAR(r.events[0].net_distance, 0.0, 1e-9);
  EXPECT_NEAR(r.events[1].distance, 0.004, 1e-9);
  EXPECT_NEAR(r.events[1].net_distance, 0.004, 1e-9);
  EXPECT_NEAR(r.events[2].net_distance, 0.008, 1e-9);  // along z too
  EXPECT_EQ(field(m.summaryFields(), "longest_slip_after_detection"),
            "{\"leg\": 0, \"start_s\": 1, \"after_detection_ms\": " + jsonNumber(35.0) +
                ", \"path_mm\": " + jsonNumber(8.0) + ", \"net_mm\": " + jsonNumber(1000.0 * r.events[0].net_distance) +
                "}");
}

// A landing foot flagged while still in the air, whose skid on landing is
// too short for an event: a false detection that rose in the air. One
// flagged on the ground counts as false only.
TEST(MetricsTest, AFlagThatRoseInTheAirIsCountedApart) {
  SyntheticRun run(4.0);
  run.during(0.9, 1.002, [](TickRecord& r) { r.feet[2].in_contact = false; });
  run.flag(2, 1.002, 1.015);  // rises on the last tick in the air
  run.trueSlip(2, 1.003, 1.006);
  run.flag(3, 2.000, 2.015);
  Metrics m;
  const MetricsResult r = run.evaluate(m);
  EXPECT_EQ(r.slip_events, 0);
  EXPECT_EQ(r.false_detections, 2);
  EXPECT_EQ(r.false_detections_in_air, 1);
  EXPECT_EQ(field(m.summaryFields(), "false_detections_in_air"), "1");
}

TEST(MetricsTest, FreezeEventsAreRisingEdges) {
  SyntheticRun run(3.0);
  auto freeze = [](TickRecord& r) { r.command.flags |= hal::kFlagFreeze; };
  run.during(0.001, 0.2, freeze);  // already frozen on the first tick: counts
  run.during(1.0, 1.5, freeze);
  run.during(2.0, 2.0, freeze);
  Metrics m;
  EXPECT_EQ(run.evaluate(m).freeze_events, 3);
  EXPECT_EQ(field(m.summaryFields(), "freeze_events"), "3");
}

TEST(MetricsTest, TorqueStepCountsStanceLegsInBothTicksOnly) {
  SyntheticRun run(1.0);
  const size_t k = run.at(0.5);
  // A 7 N m step of the LF knee's feed-forward in stance: counted.
  for (size_t i = k; i < k + 10; ++i) run[i].command.tau_ff[2] = 7.0;
  // A 40 N m PD step on RF's HFE through kp (q_ref - q): counted (the
  // commanded torque includes the joint loop's feedback).
  run[k + 100].command.kp[4] = 400.0;
  run[k + 100].command.q_ref[4] = 0.1;  // q = 0 -> 40 N m, and back next tick
  // Swing leg LH: a 90 N m step is not a stance torque step.
  for (size_t i = 0; i < 1000; ++i) run[i].command.telemetry.stance_mask = 0xB;
  run[k + 200].command.tau_ff[7] = 90.0;
  // RH lifts off on the tick of a 60 N m step: not in stance in both ticks.
  run[k + 300].command.telemetry.stance_mask = 0x3;
  run[k + 300].command.tau_ff[10] = 60.0;
  Metrics m;
  const MetricsResult r = run.evaluate(m);
  EXPECT_NEAR(r.max_stance_torque_step_nm, 40.0, 1e-9);
  EXPECT_EQ(r.max_stance_torque_step_joint, 4);
  EXPECT_NEAR(r.max_stance_torque_step_time, run[k + 100].time, 1e-12);
  // summary.json says where: the tick's time and the joint.
  const std::string at = field(m.summaryFields(), "max_stance_torque_step_at");
  EXPECT_NE(at.find("\"joint\": 4}"), std::string::npos) << at;
  EXPECT_NE(at.find("\"time\": "), std::string::npos) << at;
}

TEST(MetricsTest, OdometryErrorIsHorizontalFromEachSidesStart) {
  SyntheticRun run(2.0);
  // The estimate starts 5 cm off (its own origin), drifts +2 cm in x by
  // t = 1 s, then back to 1 cm at the end; z errors are ignored.
  for (size_t i = 0; i < 2000; ++i) {
    const double t = run[i].time;
    const double drift = t <= 1.0 ? 0.02 * t : 0.02 - 0.01 * (t - 1.0);
    run[i].command.telemetry.base_pos_est[0] = run[i].base_pos[0] + 0.05 + drift - 0.00002;
    run[i].command.telemetry.base_pos_est[2] = 0.3;
  }
  Metrics m;
  const MetricsResult r = run.evaluate(m);
  EXPECT_NEAR(r.odometry_error_max_m, 0.02 - 0.00002, 1e-9);
  EXPECT_NEAR(r.odometry_error_final_m, 0.01 - 0.00002, 1e-9);
}

TEST(MetricsTest, MuErrorUsesTheTruthUnderTheFootAndEachPatch) {
  SyntheticRun run(4.0);
  // LH slips on a 0.25 patch (estimate 0.26) and later on a 0.15 patch
  // (estimate 0.12). At the second sample the foot has already lifted off:
  // the truth is the patch it slipped on.
  run.during(0.001, 2.0, [](TickRecord& r) { r.feet[2].mu = 0.25; });
  run.during(2.001, 4.0, [](TickRecord& r) { r.feet[2].mu = 0.15; });
  run.trueSlip(2, 1.0, 1.03);
  run.flag(2, 1.003, 1.04);
  run[run.at(1.04)].command.telemetry.mu_hat[2] = 0.26;
  run.trueSlip(2, 3.0, 3.03);
  run.flag(2, 3.003, 3.05);
  run.during(3.045, 3.2, [](TickRecord& r) {
    r.feet[2].in_contact = false;
    r.feet[2].mu = 0.8;  // whatever is under a lifted foot
  });
  run[run.at(3.05)].command.telemetry.mu_hat[2] = 0.12;
  Metrics m;
  const MetricsResult r = run.evaluate(m);
  EXPECT_NEAR(r.mu_error_per_leg_pct[2], 20.0, 1e-9);
  EXPECT_NEAR(r.mu_error_max_pct, 20.0, 1e-9);
  const std::string mu = field(m.summaryFields(), "mu_estimate_error_pct");
  EXPECT_NE(mu.find("{\"leg\": 2, \"mu_true\": 0.15, \"max_error_pct\": 20, \"samples\": 1}"),
            std::string::npos) << mu;
  EXPECT_NE(mu.find("{\"leg\": 2, \"mu_true\": 0.25, \"max_error_pct\": 4, \"samples\": 1}"),
            std::string::npos) << mu;
}

// A found probe's answer: the first change of mu_hat on one of its two
// feet in the 3 ticks after the found counter rises (the answer reaches
// mu_hat a tick after the counter), against the truth under that foot,
// flagged slip or not. A change on the rise's own tick, another foot's,
// a second one, or one after the window is not an answer.
TEST(MetricsTest, AFoundProbesAnswerIsGradedWithoutAFlag) {
  SyntheticRun run(3.0);
  run.during(0.001, 3.0, [](TickRecord& r) {
    r.feet[0].mu = 0.2;
    r.command.telemetry.probe_leg = 4;  // none
    r.command.telemetry.probe_partner = 4;
  });
  auto probe = [&](int leg, int partner, double found_at, uint32_t found) {
    run.during(found_at - 0.1, found_at + 0.02, [&](TickRecord& r) {
      r.command.telemetry.probe_leg = leg;
      r.command.telemetry.probe_partner = partner;
    });
    run.during(found_at, 3.0, [&](TickRecord& r) { r.command.telemetry.probe_counts[1] = found; });
  };
  auto estimate = [&](int leg, double from, double mu) {
    run.during(from, 3.0, [&](TickRecord& r) { r.command.telemetry.mu_hat[leg] = mu; });
  };
  // Found at 1.0 s: RF's estimate changes on that tick (not the answer),
  // LF's answer 0.21 (truth 0.2) a tick later, RF again after it, and
  // LH's, not one of the pair.
  probe(0, 1, 1.0, 1);
  estimate(1, 1.0, 0.3);
  estimate(0, 1.001, 0.21);
  estimate(1, 1.002, 0.35);
  estimate(2, 1.001, 0.5);
  // Found at 2.0 s: RH's answer 0.4 (truth 0.8) on the window's last tick.
  probe(3, 2, 2.0, 2);
  estimate(3, 2.003, 0.4);
  // Found at 2.5 s: LH's answer 4 ticks after, past the window.
  probe(2, 3, 2.5, 3);
  estimate(2, 2.504, 0.6);
  Metrics m;
  const MetricsResult r = run.evaluate(m);
  EXPECT_EQ(r.probes_found, 3u);
  EXPECT_EQ(r.probe_answers, 2);
  EXPECT_EQ(r.probe_answers_within_10pct, 1);
  EXPECT_NEAR(r.probe_answer_error_max_pct, 50.0, 1e-9);
  EXPECT_EQ(r.slip_events, 0);
  const std::string probe_json = field(m.summaryFields(), "friction_probe");
  EXPECT_NE(probe_json.find("\"answers\": 2, \"answers_within_10pct\": 1, \"answer_error_max_pct\": 50"),
            std::string::npos) << probe_json;
}

// The foot stops slipping on a 0.25 patch, stands two ticks on 0.6 ground
// and lifts; the flag ends after the lift: the truth is the patch it
// slipped on, not the ground it last touched.
TEST(MetricsTest, MuTruthOfALiftedFootIsTheLastSlippingTicks) {
  SyntheticRun run(2.0);
  run.during(0.001, 1.030, [](TickRecord& r) { r.feet[1].mu = 0.25; });
  run.during(1.031, 2.0, [](TickRecord& r) { r.feet[1].mu = 0.6; });
  run.trueSlip(1, 1.000, 1.030);
  run.during(1.033, 1.2, [](TickRecord& r) { r.feet[1].in_contact = false; });
  run.flag(1, 1.005, 1.034);
  run[run.at(1.034)].command.telemetry.mu_hat[1] = 0.26;
  Metrics m;
  const MetricsResult r = run.evaluate(m);
  ASSERT_EQ(r.events.size(), 1u);
  EXPECT_EQ(r.events[0].mu_true, 0.25);
  EXPECT_NEAR(r.mu_error_per_leg_pct[1], 4.0, 1e-9);
}

TEST(MetricsTest, QuietSpreadIsTheMedianStatisticWithoutTrueSlips) {
  SyntheticRun run(1.0);
  for (size_t i = 0; i < 1000; ++i) {
    for (int leg = 0; leg < 4; ++leg) run[i].command.telemetry.foot_vel_base[leg][0] = -0.05;
    run[i].command.telemetry.foot_vel_base[2][1] = (i % 250 == 0) ? 0.04 : 0.01;  // 3 rare outliers outside the slip
  }
  // During a true slip the spread is large but not noise: excluded.
  run.trueSlip(1, 0.5, 0.6);
  run.during(0.5, 0.6, [](TickRecord& r) { r.command.telemetry.foot_vel_base[1][0] = 0.5; });
  Metrics m;
  const MetricsResult r = run.evaluate(m);
  ASSERT_EQ(r.quiet_spread_samples, 1000u - 101u);
  const double small = std::hypot(0.05, 0.01) - 0.05, large = std::hypot(0.05, 0.04) - 0.05;
  EXPECT_NEAR(r.quiet_spread_max_mps, large, 1e-12);
  EXPECT_NEAR(r.quiet_spread_p99_mps, small, 1e-12);
  EXPECT_EQ(field(m.summaryFields(), "quiet_speed_spread_mps"),
            "{\"p99\": " + jsonNumber(small) + ", \"max\": " + jsonNumber(large) + "}");
}

// The matching rules of docs/metrics.md applied to a whole run at once, as
// plainly as they read: the reference the streaming Metrics must equal.
struct Reference {
  MetricsResult r;
  explicit Reference(const std::vector<TickRecord>& ticks, const MetricsConfig& c = MetricsConfig{}) {
    constexpr double kRound = 1e-9;
    const size_t n = ticks.size();
    const double dt = n > 1 ? ticks[1].time - ticks[0].time : 0.001;
    auto time = [&](size_t i) { return ticks[i].time; };
    auto runs = [n](auto pred) {
      std::vector<std::pair<size_t, size_t>> out;
      for (size_t i = 0; i < n; ++i) {
        if (!pred(i)) continue;
        if (!out.empty() && out.back().second + 1 == i)
          out.back().second = i;
        else
          out.push_back({i, i});
      }
      return out;
    };
    for (int leg = 0; leg < 4; ++leg) {
      auto contact = [&](size_t i) { return ticks[i].feet[leg].in_contact; };
      auto raw = runs([&](size_t i) { return contact(i) && ticks[i].feet[leg].slip_speed > c.true_slip_speed; });
      std::vector<std::pair<size_t, size_t>> merged;
      for (const auto& run : raw) {
        if (!merged.empty() && time(run.first) - time(merged.back().second) <= c.true_slip_merge_gap + kRound)
          merged.back().second = run.second;
        else
          merged.push_back(run);
      }
      auto flagged = runs([&](size_t i) { return (ticks[i].command.telemetry.slip_mask >> leg) & 1u; });
      std::vector<bool> used(flagged.size(), false);
      for (const auto& m : merged) {
        if (time(m.second) - time(m.first) + dt < c.true_slip_min_duration - kRound) {
          for (size_t k = 0; k < flagged.size(); ++k) {
            const double rise = time(flagged[k].first);
            if (rise >= time(m.first) - kRound && rise <= time(m.second) + c.short_slip_match_after + kRound)
              used[k] = true;
          }
          continue;
        }
        TrueSlip e;
        e.leg = leg;
        e.start = time(m.first);
        e.end = time(m.second);
        std::array<double, 3> travel{};
        for (size_t i = m.first; i <= m.second; ++i) {
          e.monitored = e.monitored || ((ticks[i].command.telemetry.stance_mask >> leg) & 1u);
          if (contact(i)) {
            e.distance += ticks[i].feet[leg].slip_speed * dt;
            for (int k = 0; k < 3; ++k) travel[k] += ticks[i].feet[leg].slip_velocity[k] * dt;
          }
        }
        e.net_distance = std::sqrt(travel[0] * travel[0] + travel[1] * travel[1] + travel[2] * travel[2]);
        const double lo = e.start - c.match_before - kRound, hi = e.end + c.match_after + kRound;
        std::vector<size_t> matched;
        for (size_t k = 0; k < flagged.size(); ++k) {
          if (time(flagged[k].second) < lo || time(flagged[k].first) > hi) continue;
          used[k] = true;
          if (time(flagged[k].second) < e.start - kRound) continue;  // ended before: detects nothing
          if (!e.detected) e.detected_at = std::max(time(flagged[k].first), e.start);
          e.detected = true;
          matched.push_back(k);
        }
        // Each matched flag run's last tick is sampled; the event keeps the worst.
        for (const size_t k : matched) {
          const size_t i = flagged[k].second;
          const TickRecord& t = ticks[i];
          const double mu_hat = t.command.telemetry.mu_hat[leg];
          if (mu_hat > 0.0 && std::isfinite(mu_hat)) {
            double mu_true = t.feet[leg].mu;
            if (!contact(i))
              for (size_t k = i; k-- > 0;)
                if (time(k) <= e.end + kRound && contact(k)) {
                  mu_true = ticks[k].feet[leg].mu;
                  break;
                }
            const double error = mu_true > 0.0 ? 100.0 * std::fabs(mu_hat - mu_true) / mu_true : 0.0;
            if (mu_true > 0.0 && (!e.has_mu_sample || error > e.mu_error_pct)) {
              e.has_mu_sample = true;
              e.mu_hat = mu_hat;
              e.mu_true = mu_true;
              e.mu_error_pct = error;
            }
          }
          const auto& g = t.feet[leg].normal;
          const double g_norm = std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
          // Whether `n` gives a sample, and its angle to the truth [deg].
          const auto sample = [&](const double* n, bool* has, double* deg) {
            const double n_norm = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            if (!(n_norm >= c.min_normal_hat_norm && g_norm > 0.5 && std::isfinite(n_norm))) return;
            const double cx = n[1] * g[2] - n[2] * g[1], cy = n[2] * g[0] - n[0] * g[2],
                         cz = n[0] * g[1] - n[1] * g[0];
            const double dot = n[0] * g[0] + n[1] * g[1] + n[2] * g[2];
            const double angle = std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz), dot) * 180.0 / M_PI;
            if (*has && angle <= *deg) return;
            *has = true;
            *deg = angle;
          };
          sample(t.command.telemetry.normal_hat[leg], &e.has_normal_sample, &e.normal_error_deg);
          sample(t.command.telemetry.normal_used[leg], &e.has_normal_in_use_sample, &e.normal_in_use_error_deg);
        }
        if (e.monitored) {
          ++r.slip_events;
          if (!e.detected) {
            ++r.missed_slips;
            r.missed_distance_max_m = std::max(r.missed_distance_max_m, e.distance);
          } else {
            r.latency_ms.push_back(1000.0 * std::max(0.0, e.detected_at - e.start));
            r.after_detection_ms.push_back(1000.0 * std::max(0.0, e.end - e.detected_at));
          }
        } else {
          ++r.unmonitored_slips;
        }
        r.events.push_back(e);
      }
      for (size_t k = 0; k < flagged.size(); ++k) {
        if (used[k]) continue;
        ++r.false_detections;
        if (!contact(flagged[k].first)) ++r.false_detections_in_air;
      }
    }
  }
};

// Random feet: slips of 1-80 ticks with gaps of 1-120, flag runs rising
// before, during and after them (some lasting seconds), contact, stance
// and estimates changing: the streaming Metrics gives exactly the
// reference's events, counts, latencies and samples (bit for bit).
TEST(MetricsTest, StreamingEqualsTheWholeRunRules) {
  for (int seed = 1; seed <= 12; ++seed) {
    std::mt19937 rng(seed);
    auto uniform = [&rng](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
    auto chance = [&rng](double p) { return std::bernoulli_distribution(p)(rng); };
    SyntheticRun run(12.0);
    const size_t n = run.at(12.0) + 1;
    for (int leg = 0; leg < 4; ++leg) {
      for (size_t i = uniform(0, 50); i < n;) {  // true slips
        const size_t len = uniform(1, 80);
        const double speed = chance(0.1) ? 0.03 : 0.06 + 0.3 * uniform(0, 100) / 100.0;
        const double heading = 0.1 * uniform(0, 62);  // [rad]
        const bool rings = chance(0.3);               // back and forth every 3 ticks
        for (size_t k = i; k < std::min(n, i + len); ++k) {
          const double sign = rings && (k - i) % 6 >= 3 ? -1.0 : 1.0;
          run[k].feet[leg].slip_speed = speed;
          const double along = sign * speed * std::cos(0.3);  // 0.3 rad out of the x-y plane
          run[k].feet[leg].slip_velocity = {along * std::cos(heading), along * std::sin(heading),
                                            sign * speed * std::sin(0.3)};
        }
        i += len + uniform(1, 120);
      }
      for (size_t i = uniform(0, 200); i < n;) {  // flags
        const size_t len = chance(0.05) ? uniform(500, 3000) : uniform(1, 60);
        for (size_t k = i; k < std::min(n, i + len); ++k) run[k].command.telemetry.slip_mask |= 1u << leg;
        i += len + uniform(1, 150);
      }
      for (size_t i = uniform(0, 300); i < n;) {  // lifted feet, swing (no stance)
        const size_t len = uniform(1, 100);
        const bool lift = chance(0.6);
        for (size_t k = i; k < std::min(n, i + len); ++k) {
          if (lift) run[k].feet[leg].in_contact = false;
          run[k].command.telemetry.stance_mask &= ~(1u << leg);
        }
        i += len + uniform(20, 400);
      }
      for (size_t i = 0; i < n; ++i) {  // truth and estimates drifting
        if (i % 7 == 0) run[i].feet[leg].mu = uniform(0, 10) / 10.0;
        else if (i > 0) run[i].feet[leg].mu = run[i - 1].feet[leg].mu;
        run[i].command.telemetry.mu_hat[leg] = chance(0.1) ? 0.0 : uniform(1, 100) / 100.0;
        run[i].feet[leg].normal = {0.0, 0.1 * uniform(-3, 3), 1.0};
        double* nh = run[i].command.telemetry.normal_hat[leg];
        nh[0] = 0.05 * uniform(-4, 4), nh[1] = 0.0, nh[2] = chance(0.2) ? 0.3 : 1.0;
        double* nu = run[i].command.telemetry.normal_used[leg];
        nu[0] = 0.0, nu[1] = 0.05 * uniform(-4, 4), nu[2] = chance(0.1) ? 0.0 : 1.0;
      }
    }
    Metrics m;
    const MetricsResult got = run.evaluate(m);
    std::vector<TickRecord> records(n);
    for (size_t i = 0; i < n; ++i) records[i] = run[i];
    const MetricsResult want = Reference(records).r;
    SCOPED_TRACE("seed " + std::to_string(seed));
    EXPECT_GT(want.events.size(), 40u);
    EXPECT_GT(want.false_detections, 0);
    EXPECT_EQ(got.slip_events, want.slip_events);
    EXPECT_EQ(got.unmonitored_slips, want.unmonitored_slips);
    EXPECT_EQ(got.missed_slips, want.missed_slips);
    EXPECT_EQ(got.false_detections, want.false_detections);
    EXPECT_GT(want.false_detections_in_air, 0);
    EXPECT_LT(want.false_detections_in_air, want.false_detections);
    EXPECT_EQ(got.false_detections_in_air, want.false_detections_in_air);
    EXPECT_EQ(got.missed_distance_max_m, want.missed_distance_max_m);
    EXPECT_EQ(got.latency_ms, want.latency_ms);
    EXPECT_EQ(got.after_detection_ms, want.after_detection_ms);
    ASSERT_EQ(got.events.size(), want.events.size());
    for (size_t k = 0; k < got.events.size(); ++k) {
      const TrueSlip &a = got.events[k], &b = want.events[k];
      SCOPED_TRACE("event " + std::to_string(k));
      EXPECT_EQ(a.leg, b.leg);
      EXPECT_EQ(a.start, b.start);
      EXPECT_EQ(a.end, b.end);
      EXPECT_EQ(a.monitored, b.monitored);
      EXPECT_EQ(a.distance, b.distance);
      EXPECT_EQ(a.net_distance, b.net_distance);
      EXPECT_EQ(a.detected, b.detected);
      EXPECT_EQ(a.detected_at, b.detected_at);
      EXPECT_EQ(a.has_mu_sample, b.has_mu_sample);
      EXPECT_EQ(a.mu_hat, b.mu_hat);
      EXPECT_EQ(a.mu_true, b.mu_true);
      EXPECT_EQ(a.mu_error_pct, b.mu_error_pct);
      EXPECT_EQ(a.has_normal_sample, b.has_normal_sample);
      EXPECT_EQ(a.normal_error_deg, b.normal_error_deg);
      EXPECT_EQ(a.has_normal_in_use_sample, b.has_normal_in_use_sample);
      EXPECT_EQ(a.normal_in_use_error_deg, b.normal_in_use_error_deg);
    }
  }
}

// More quiet-spread samples than the percentile keeps: the 99th
// percentile is still the exact nearest-rank one, and the maximum exact.
TEST(MetricsTest, QuietSpreadPercentileIsExactBeyondTheKeptSamples) {
  const size_t n = 3 * Metrics::kQuietSpreadKept + 12345;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> speed(0.0, 0.2);
  Metrics m;
  std::vector<double> spreads;
  TickRecord r;
  r.command.telemetry.stance_mask = 0x7;  // three legs: spread = |max - median| or |min - median|
  for (int leg = 0; leg < 4; ++leg) r.feet[leg].in_contact = true;
  for (size_t i = 0; i < n; ++i) {
    r.tick = static_cast<uint32_t>(i);
    r.time = (i + 1) * kDt;
    double s[3];
    for (int leg = 0; leg < 3; ++leg) r.command.telemetry.foot_vel_base[leg][0] = s[leg] = speed(rng);
    std::sort(s, s + 3);
    spreads.push_back(std::max(s[2] - s[1], s[1] - s[0]));
    m.onTick(r);
  }
  m.onFinish();
  std::vector<double> sorted = spreads;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(m.result().quiet_spread_samples, n);
  EXPECT_EQ(m.result().quiet_spread_p99_mps, sorted[(n * 99) / 100]);
  EXPECT_EQ(m.result().quiet_spread_max_mps, sorted.back());
}

}  // namespace
}  // namespace hyq::sim
