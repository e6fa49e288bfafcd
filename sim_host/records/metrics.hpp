// The slip metrics of summary.json, computed from the per-tick
// records of a run. Definitions, thresholds and matching rules are in
// docs/metrics.md; the numbers below are its defaults.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "sim_host/records/tick_observer.hpp"

namespace hyq::sim {

struct MetricsConfig {
  double true_slip_speed = 0.05;      // [m/s] contact-point tangential speed of a true slip
  double true_slip_min_duration = 0.005;  // [s] shorter true slips are ignored
  double true_slip_merge_gap = 0.02;  // [s] true slips closer than this are one event
  // A loaded slide: a slipping tick on which the foot carries at least
  // loaded_slide_min_force and its tangential force is on the friction cone
  // (at least loaded_slide_cone_fraction of mu times the normal force). The
  // contact's elastic deflection (about mu f_n / k_t, 1 mm) moves the
  // contact point faster than true_slip_speed when the force changes
  // quickly, inside the cone; a foot unloaded to a few N creeps at the
  // edge of its cone. Neither is a loaded slide.
  double loaded_slide_min_force = 50.0;     // [N]
  double loaded_slide_cone_fraction = 0.95; // [-]
  // A flag run detects a true slip if it is up on a tick in
  // [start, end + match_after]; one that ended at most match_before before
  // the slip's start detects nothing but is not a false detection (it rose
  // on the slip's onset, below the truth's threshold).
  double match_before = 0.02;         // [s]
  double match_after = 0.05;          // [s]
  // A real slip shorter than true_slip_min_duration is not an event, but a
  // flag that rises on it (the recovery can stop a flagged slip within a
  // few ms, before it reaches the minimum) is not a false detection either:
  // a flag run whose rising edge is in [start, end + this] is excused.
  double short_slip_match_after = 0.01;  // [s] debounce (4 ms) + the velocity filter's lag
  double min_normal_hat_norm = 0.5;   // [-] a shorter telemetry normal_hat means "none yet"
  // A touch-down: the foot's first contact after at least touchdown_min_air
  // without (a sliding foot's contact flickering for a few ms is not one). A
  // slip that starts within touchdown_window of its foot's touch-down is a
  // touch-down slip, any other a stance slip.
  double touchdown_min_air = 0.05;    // [s]
  double touchdown_window = 0.2;      // [s]
};

// The travels above which summary.json reports the recall of slips
// (recall_by_travel), [mm].
inline constexpr double kRecallTravelsMm[] = {5.0, 10.0, 20.0};

// One ground-truth slip event of one foot.
struct TrueSlip {
  int leg = 0;
  double start = 0.0;      // [s] first tick above true_slip_speed
  double end = 0.0;        // [s] last tick above it
  bool monitored = false;  // the controller had the leg in stance during it
  bool touchdown = false;  // started within touchdown_window of the foot's touch-down
  double distance = 0.0;   // [m] contact-point travel over the event (sum of speed * dt)
  // [m] the contact point's net travel over the event, |sum of slip velocity
  // * dt|: a contact that rings back and forth along the ground covers a
  // distance but goes nowhere.
  double net_distance = 0.0;
  double ground_mu = 0.0;  // [-] the true mu under the foot at the event's last slipping tick
  double loaded_end = -1.0;  // [s] its last loaded-slide tick, < 0: none
  bool detected = false;
  double detected_at = 0.0;  // [s] the matching flag's rising edge, or start if it was up already
  // Estimates at the end of each matching detection (its last flagged
  // tick); the event keeps the worst of them.
  bool has_mu_sample = false;
  double mu_hat = 0.0, mu_true = 0.0, mu_error_pct = 0.0;
  bool has_normal_sample = false;
  double normal_error_deg = 0.0;
  // The normal the QP's cone used at that tick, estimated or not.
  bool has_normal_in_use_sample = false;
  double normal_in_use_error_deg = 0.0;
};

struct MetricsResult {
  int slip_events = 0;        // monitored true slips
  int unmonitored_slips = 0;  // true slips entirely outside the controller's stance
  int missed_slips = 0;
  int false_detections = 0;   // flag runs matching no true slip
  int false_detections_in_air = 0;  // of those, runs that rose with the foot off the ground
  double missed_distance_max_m = -1.0;    // largest travel of a missed slip, < 0: none
  std::vector<double> latency_ms;         // per detected event
  std::vector<double> after_detection_ms; // per detected event
  double mu_error_max_pct = -1.0;         // < 0: no sample
  std::array<double, 4> mu_error_per_leg_pct{-1.0, -1.0, -1.0, -1.0};
  double normal_error_max_deg = -1.0;
  double normal_in_use_error_max_deg = -1.0;  // < 0: no sample
  double odometry_error_final_m = 0.0;
  double odometry_error_max_m = 0.0;
  double distance_walked_m = 0.0;
  int freeze_events = 0;
  // The friction probe (telemetry's probe counters at the run's end), and
  // the true slips that began on a probe's foot while its pair ramped or
  // within Metrics::kProbeTail after: their largest travel and duration.
  uint32_t probes_started = 0, probes_found = 0, probes_held = 0;
  int probe_slides = 0;
  double probe_slide_max_mm = 0.0;
  double probe_slide_max_ms = 0.0;
  // Each found probe's answer (the first change of the telemetry's mu_hat
  // on one of the probe's two feet in the kProbeAnswerTicks ticks after
  // the found counter rises) against the true mu under that foot then,
  // flagged slip or not.
  int probe_answers = 0, probe_answers_within_10pct = 0;
  double probe_answer_error_max_pct = -1.0;  // < 0: no answer
  double max_stance_torque_step_nm = 0.0;
  double max_stance_torque_step_time = 0.0;  // [s]
  // The median test's statistic max_i |s_i - median| on ticks where no
  // stance foot truly slips: the noise floor the detection threshold must
  // clear (one sample per such tick with >= 3 stance legs). Its count,
  // maximum and 99th percentile (the sample of rank floor(0.99 n) from the
  // smallest, 0-based; NaN: no sample), the percentile from the largest
  // Metrics::kQuietSpreadKept samples: exact up to 100 times as many
  // samples (4000 s at 1 kHz), beyond that the smallest kept sample.
  uint64_t quiet_spread_samples = 0;
  double quiet_spread_max_mps = std::numeric_limits<double>::quiet_NaN();
  double quiet_spread_p99_mps = std::numeric_limits<double>::quiet_NaN();
  int max_stance_torque_step_joint = -1;     // j = 3*leg + joint
  // Coverage (summary.json's mu_estimate_coverage): per leg, the true mu
  // values it had a detected slip event on, and of those the ones with a
  // friction estimate (a sampled event on that mu); the (leg, mu) pairs
  // without one, sorted. The same counts over the pairs with a detected
  // event that travelled more than kRecallTravelsMm[0] (5 mm), as
  // recall_by_travel counts travel.
  std::array<int, 4> patches_slipped{0, 0, 0, 0};
  std::array<int, 4> patches_estimated{0, 0, 0, 0};
  std::array<int, 4> patches_slid{0, 0, 0, 0};
  std::array<int, 4> patches_slid_estimated{0, 0, 0, 0};
  std::vector<std::pair<int, double>> patches_missing;
  std::vector<TrueSlip> events;              // all true slips, monitored or not
};

// Streams: the memory a run needs does not grow with its ticks, only with
// its slip events (one TrueSlip and two latencies each) and, up to
// kQuietSpreadKept doubles, the spread's percentile. A slip is decided a
// few tens of ms after it ends (or when a flag run over it ends).
class Metrics final : public TickObserver {
 public:
  static constexpr size_t kQuietSpreadKept = 40000;
  static constexpr double kProbeTail = 0.05;  // [s] after a probe's pair ends, a slip that starts is still its

  explicit Metrics(const MetricsConfig& config = MetricsConfig{});
  void onTick(const TickRecord& record) override;
  // Completes result() and ends the run: later onTick() and onFinish()
  // calls change nothing.
  void onFinish() override;
  SummaryFields summaryFields() const override;
  const MetricsResult& result() const { return result_; }

 private:
  struct LegTick {
    bool contact = false;
    double slip_speed = 0.0;
    std::array<double, 3> slip_velocity{};  // [m/s] W
    bool loaded_on_cone = false;     // loaded and on the friction cone (MetricsConfig); slipping too: a loaded slide
    double mu_true = 0.0;
    std::array<double, 3> normal_true{};
    double mu_hat = 0.0;
    std::array<double, 3> normal_hat{};
    std::array<double, 3> normal_used{};
  };
  struct Tick {
    double time = 0.0;
    uint32_t stance_mask = 0;
    uint32_t slip_mask = 0;
    std::array<LegTick, 4> legs{};
  };
  // The leg at the last tick of a flag run, where a matching slip's
  // estimates are sampled.
  struct Sample {
    uint64_t index = 0;              // tick number in the run
    LegTick leg;
    bool earlier_contact = false;    // the foot touched the ground on an earlier tick
    double earlier_contact_mu = 0.0; // the true mu on the latest such tick
  };
  // Consecutive ticks with the leg's slip flag set.
  struct FlagRun {
    double rise = 0.0, end = 0.0;    // [s] first and last flagged tick
    bool used = false;               // matched a true slip, or excused by a short one
    bool rose_in_air = false;        // the foot was off the ground on the first flagged tick
    Sample sample;
  };
  // Ticks above true_slip_speed merged across short gaps, and the flag
  // runs matched to it so far.
  struct SlipRun {
    double start = 0.0, end = 0.0;   // [s] first and last slipping tick
    uint64_t end_index = 0;
    double end_mu = 0.0;             // the true mu on the last slipping tick
    double loaded_end = -1.0;        // [s] the last loaded-slide tick, < 0: none
    bool monitored = false;          // over [start, end]
    bool touchdown = false;          // started within touchdown_window of a touch-down
    double distance = 0.0;           // over [start, end]
    bool monitored_so_far = false;   // over [start, the current tick]
    double distance_so_far = 0.0;
    std::array<double, 3> travel{}, travel_so_far{};  // [m] net travel over [start, end], and so far
    bool closed = false;             // no later tick can extend it
    uint64_t next_flag = 0;          // number of the next flag run to look at
    bool detected = false;
    double detected_at = 0.0;
    std::vector<Sample> matches;     // each matched flag run's last tick
  };
  struct Leg {
    bool flag_open = false;
    FlagRun flag;                    // the open flag run
    bool any_contact = false;
    double last_contact_mu = 0.0;
    bool contact = false;            // on the previous tick
    double contact_lost_at = 0.0;    // [s] last tick of the previous contact (0: the run's start)
    double touchdown_at = -1e300;    // [s] the latest touch-down
    std::deque<FlagRun> flags;       // ended ones a slip may still match
    uint64_t first_flag = 0;         // the number of flags.front()
    std::deque<SlipRun> slips;       // undecided, oldest first; the open one last
    std::vector<TrueSlip> events;
    std::vector<double> latency_ms, after_detection_ms;
  };

  void recordQuietSpread(const TickRecord& r);
  void stepTick(uint64_t index, const Tick& t);
  void stepLeg(int leg, uint64_t index, const Tick& t);
  bool isShort(const SlipRun& s) const;
  void fold(Leg& l, SlipRun& s);
  void matchLeg(int leg, double now, bool at_end);
  void decide(int leg, const SlipRun& s);
  void sampleEstimates(TrueSlip& e, const SlipRun& s, const Sample& sample) const;
  void gradeProbeAnswers(const TickRecord& r);

  MetricsConfig config_;
  MetricsResult result_;
  // Per leg, the spans [s] in which it was one of a probe's feet (extended by kProbeTail).
  std::array<std::vector<std::pair<double, double>>, 4> probe_spans_;
  // Last tick's found counter and mu_hat per leg: a probe's answer shows as
  // a change of them (gradeProbeAnswers).
  uint32_t last_probes_found_ = 0;
  std::array<uint32_t, 2> last_probe_legs_{4, 4};  // last tick's probe_leg, probe_partner
  std::array<double, 4> last_mu_hat_{};
  static constexpr int kProbeAnswerTicks = 3;  // [ticks] after the found counter's rise, an answer is looked for
  int answer_ticks_left_ = 0;
  uint32_t answer_legs_ = 0;                   // the found probe's two feet while no answer has come, bits
  std::array<Leg, 4> legs_{};
  uint64_t ticks_ = 0;
  Tick first_tick_;                  // held until the second tick gives the tick period
  double dt_ = 0.001;                // [s]
  bool finished_ = false;
  std::vector<double> quiet_top_;    // min-heap of the largest quiet spreads
  bool have_previous_ = false;
  TickRecord previous_{};
  std::array<double, 3> odom_origin_{}, true_origin_{};
  std::array<double, 3> last_true_pos_{};
  std::string plant_json_;           // summary.json's "plant", from the first record that names it
};

}  // namespace hyq::sim
