#include "sim_host/records/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <utility>

#include "sim_host/physics/plant_params.hpp"
#include "sim_host/records/run_log.hpp"

namespace hyq::sim {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kClockRounding = 1e-9;  // [s]

bool bit(uint32_t mask, int leg) { return (mask >> leg) & 1u; }

// The torque the joint loop is asked for: tau_ff + kp (q_ref - q) + kd (qd_ref - qd).
double commandedTorque(const TickRecord& r, int j) {
  const hal::CommandFrame& c = r.command;
  return c.tau_ff[j] + c.kp[j] * (c.q_ref[j] - r.sensors.q[j]) +
         c.kd[j] * (c.qd_ref[j] - r.sensors.qd[j]);
}

double horizontalDistance(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return std::hypot(a[0] - b[0], a[1] - b[1]);
}

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double maximum(const std::vector<double>& v) {
  return v.empty() ? NAN : *std::max_element(v.begin(), v.end());
}

// {"median": m, "max": x} of v (null for none).
std::string medianMaxJson(const std::vector<double>& v) {
  return "{\"median\": " + jsonNumber(median(v)) + ", \"max\": " + jsonNumber(maximum(v)) + "}";
}

// A detected slip's latency and how long it went on after its detection.
double latencyMs(const TrueSlip& e) { return 1000.0 * std::max(0.0, e.detected_at - e.start); }
double afterDetectionMs(const TrueSlip& e) { return 1000.0 * std::max(0.0, e.end - e.detected_at); }
double loadedAfterDetectionMs(const TrueSlip& e) {
  return e.loaded_end < 0.0 ? 0.0 : 1000.0 * std::max(0.0, e.loaded_end - e.detected_at);
}

// Per detected monitored event, the loaded slide after detection [ms].
std::vector<double> loadedAfterDetection(const std::vector<TrueSlip>& events) {
  std::vector<double> v;
  for (const TrueSlip& e : events)
    if (e.monitored && e.detected) v.push_back(loadedAfterDetectionMs(e));
  return v;
}

// The detected monitored event that went on longest after its detection
// (the first of equals to within the clock's rounding, in leg order): its
// leg (0-3: LF, RF, LH, RH), start, that time and its travel, path and net;
// null if none.
std::string longestAfterDetectionJson(const std::vector<TrueSlip>& events) {
  const TrueSlip* longest = nullptr;
  for (const TrueSlip& e : events)
    if (e.monitored && e.detected &&
        (!longest || afterDetectionMs(e) > afterDetectionMs(*longest) + 1000.0 * kClockRounding))
      longest = &e;
  if (!longest) return "null";
  return "{\"leg\": " + std::to_string(longest->leg) + ", \"start_s\": " + jsonNumber(longest->start) +
         ", \"after_detection_ms\": " + jsonNumber(afterDetectionMs(*longest)) +
         ", \"path_mm\": " + jsonNumber(1000.0 * longest->distance) +
         ", \"net_mm\": " + jsonNumber(1000.0 * longest->net_distance) + "}";
}

// The foot's force of the tick against its true normal: at least the
// loaded-slide force, and on the friction cone.
bool loadedOnCone(const FootTruth& foot, const MetricsConfig& c) {
  double fn = 0.0, f2 = 0.0;
  for (int k = 0; k < 3; ++k) {
    fn += foot.force[k] * foot.normal[k];
    f2 += foot.force[k] * foot.force[k];
  }
  const double ft = std::sqrt(std::max(0.0, f2 - fn * fn));
  return fn >= c.loaded_slide_min_force && ft >= c.loaded_slide_cone_fraction * foot.mu * fn;
}

// Negative means "no sample" and renders as null.
std::string optional(double v) { return v < 0.0 ? "null" : jsonNumber(v); }

// [%] An estimate's error against a true mu > 0.
double muErrorPct(double estimate, double truth) { return 100.0 * std::fabs(estimate - truth) / truth; }

}  // namespace

Metrics::Metrics(const MetricsConfig& config) : config_(config) {}

void Metrics::onTick(const TickRecord& r) {
  if (finished_) return;
  if (r.plant && plant_json_.empty()) plant_json_ = plantJson(*r.plant);
  const hal::Telemetry& tm = r.command.telemetry;
  Tick t;
  t.time = r.time;
  t.stance_mask = tm.stance_mask;
  t.slip_mask = tm.slip_mask;
  for (int leg = 0; leg < 4; ++leg) {
    LegTick& l = t.legs[leg];
    const FootTruth& foot = r.feet[leg];
    l.contact = foot.in_contact;
    l.slip_speed = foot.slip_speed;
    l.slip_velocity = foot.slip_velocity;
    l.mu_true = foot.mu;
    l.loaded_on_cone = loadedOnCone(foot, config_);
    l.normal_true = foot.normal;
    l.mu_hat = tm.mu_hat[leg];
    for (int k = 0; k < 3; ++k) l.normal_hat[k] = tm.normal_hat[leg][k];
    for (int k = 0; k < 3; ++k) l.normal_used[k] = tm.normal_used[leg][k];
  }
  // The slip distance needs the tick period: the first two ticks' times.
  if (ticks_ == 0) {
    first_tick_ = t;
  } else {
    if (ticks_ == 1) {
      dt_ = t.time - first_tick_.time;
      stepTick(0, first_tick_);
    }
    stepTick(ticks_, t);
  }
  ++ticks_;

  recordQuietSpread(r);
  for (uint32_t leg : {tm.probe_leg, tm.probe_partner}) {
    if (leg >= 4) continue;
    auto& spans = probe_spans_[leg];
    if (!spans.empty() && r.time <= spans.back().second + 1e-9)
      spans.back().second = r.time + kProbeTail;
    else
      spans.push_back({r.time, r.time + kProbeTail});
  }
  gradeProbeAnswers(r);
  result_.probes_started = tm.probe_counts[0];
  result_.probes_found = tm.probe_counts[1];
  result_.probes_held = tm.probe_counts[2];

  std::array<double, 3> odom{tm.base_pos_est[0], tm.base_pos_est[1], tm.base_pos_est[2]};
  const bool freeze = r.command.flags & hal::kFlagFreeze;
  if (!have_previous_) {
    odom_origin_ = odom;
    true_origin_ = r.base_pos;
    last_true_pos_ = r.base_pos;
    if (freeze) ++result_.freeze_events;
  } else {
    result_.distance_walked_m += horizontalDistance(r.base_pos, last_true_pos_);
    last_true_pos_ = r.base_pos;
    if (freeze && !(previous_.command.flags & hal::kFlagFreeze)) ++result_.freeze_events;
    const uint32_t both = tm.stance_mask & previous_.command.telemetry.stance_mask;
    for (int j = 0; j < hal::kNumJoints; ++j) {
      if (!bit(both, j / hal::kJointsPerLeg)) continue;
      const double step = std::fabs(commandedTorque(r, j) - commandedTorque(previous_, j));
      if (step > result_.max_stance_torque_step_nm) {
        result_.max_stance_torque_step_nm = step;
        result_.max_stance_torque_step_time = r.time;
        result_.max_stance_torque_step_joint = j;
      }
    }
  }
  // Odometry error in the horizontal plane, each side from its own start.
  const double ex = (odom[0] - odom_origin_[0]) - (r.base_pos[0] - true_origin_[0]);
  const double ey = (odom[1] - odom_origin_[1]) - (r.base_pos[1] - true_origin_[1]);
  result_.odometry_error_final_m = std::hypot(ex, ey);
  result_.odometry_error_max_m =
      std::max(result_.odometry_error_max_m, result_.odometry_error_final_m);
  previous_ = r;
  have_previous_ = true;
}

void Metrics::recordQuietSpread(const TickRecord& r) {
  const hal::Telemetry& tm = r.command.telemetry;
  std::array<double, 4> speeds{};
  size_t n = 0;
  for (int leg = 0; leg < 4; ++leg) {
    if (!bit(tm.stance_mask, leg)) continue;
    const FootTruth& foot = r.feet[leg];
    if (foot.in_contact && foot.slip_speed > config_.true_slip_speed) return;
    const double* u = tm.foot_vel_base[leg];
    speeds[n++] = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  }
  if (n < 3) return;
  for (size_t i = 1; i < n; ++i)  // sorted, for the median
    for (size_t j = i; j > 0 && speeds[j] < speeds[j - 1]; --j) std::swap(speeds[j], speeds[j - 1]);
  const double m = n % 2 ? speeds[n / 2] : 0.5 * (speeds[n / 2 - 1] + speeds[n / 2]);
  double spread = 0.0;
  for (size_t i = 0; i < n; ++i) spread = std::max(spread, std::fabs(speeds[i] - m));

  if (result_.quiet_spread_samples++ == 0 || spread > result_.quiet_spread_max_mps)
    result_.quiet_spread_max_mps = spread;
  // The largest kQuietSpreadKept samples, smallest on top.
  const auto greater = std::greater<double>();
  if (quiet_top_.size() < kQuietSpreadKept) {
    quiet_top_.push_back(spread);
    std::push_heap(quiet_top_.begin(), quiet_top_.end(), greater);
  } else if (spread > quiet_top_.front()) {
    std::pop_heap(quiet_top_.begin(), quiet_top_.end(), greater);
    quiet_top_.back() = spread;
    std::push_heap(quiet_top_.begin(), quiet_top_.end(), greater);
  }
}

void Metrics::stepTick(uint64_t index, const Tick& t) {
  for (int leg = 0; leg < 4; ++leg) {
    stepLeg(leg, index, t);
    matchLeg(leg, t.time, false);
  }
}

void Metrics::stepLeg(int leg, uint64_t index, const Tick& t) {
  Leg& l = legs_[leg];
  const LegTick& now = t.legs[leg];
  // Flag runs; a run's sample is its last tick's.
  if (bit(t.slip_mask, leg)) {
    if (!l.flag_open) {
      l.flag_open = true;
      l.flag = FlagRun{};
      l.flag.rise = t.time;
      l.flag.rose_in_air = !now.contact;
    }
    l.flag.end = t.time;
    l.flag.sample = Sample{index, now, l.any_contact, l.last_contact_mu};
  } else if (l.flag_open) {
    l.flag_open = false;
    l.flags.push_back(l.flag);
  }
  // contact_lost_at starts at 0: a foot on the ground from the first tick
  // has not touched down; one in the air from the start has, once down.
  if (now.contact && !l.contact && t.time - l.contact_lost_at >= config_.touchdown_min_air + dt_ - kClockRounding)
    l.touchdown_at = t.time;
  if (!now.contact && l.contact) l.contact_lost_at = t.time - dt_;
  l.contact = now.contact;
  if (now.contact) {
    l.any_contact = true;
    l.last_contact_mu = now.mu_true;
  }

  // Ground truth: contact-point speed above the threshold, runs closer
  // than the merge gap merged (short ones are dropped when decided).
  const double gap = config_.true_slip_merge_gap + kClockRounding;
  SlipRun* open = !l.slips.empty() && !l.slips.back().closed ? &l.slips.back() : nullptr;
  const bool slipping = now.contact && now.slip_speed > config_.true_slip_speed;
  if (slipping && !(open && t.time - open->end <= gap)) {
    if (open) open->closed = true;
    l.slips.emplace_back();
    open = &l.slips.back();
    open->start = t.time;
    open->touchdown = t.time - l.touchdown_at <= config_.touchdown_window + kClockRounding;
    open->next_flag = l.first_flag;
  }
  if (!open) return;
  open->monitored_so_far = open->monitored_so_far || bit(t.stance_mask, leg);
  if (now.contact) {
    open->distance_so_far += now.slip_speed * dt_;
    for (int k = 0; k < 3; ++k) open->travel_so_far[k] += now.slip_velocity[k] * dt_;
  }
  if (slipping) {
    open->end = t.time;
    open->end_index = index;
    open->end_mu = now.mu_true;
    if (now.loaded_on_cone) open->loaded_end = t.time;  // a slipping tick: a loaded slide
    open->monitored = open->monitored_so_far;
    open->distance = open->distance_so_far;
    open->travel = open->travel_so_far;
  } else if (t.time - open->end > gap) {
    open->closed = true;
  }
}

bool Metrics::isShort(const SlipRun& s) const {
  return s.end - s.start + dt_ < config_.true_slip_min_duration - kClockRounding;
}

// Matches the ended flag runs from s.next_flag on against s, as far as
// they can be decided now: a flag run detects a slip if it overlaps
// [start, end + match_after]; one that ended in [start - match_before,
// start) is excused (not false) but detects nothing, nor does one that
// rises within [start, end + short_slip_match_after] of a slip too short
// to count. An open slip already long enough to count matches what rose
// before its current end + match_after; one not yet that long waits.
void Metrics::fold(Leg& l, SlipRun& s) {
  const double lo = s.start - config_.match_before - kClockRounding;
  while (s.next_flag < l.first_flag + l.flags.size()) {
    FlagRun& f = l.flags[s.next_flag - l.first_flag];
    if (f.end < lo) {
      ++s.next_flag;
      continue;
    }
    const bool is_short = isShort(s);
    if (is_short && !s.closed) return;
    if (is_short) {
      if (f.rise > s.end + config_.short_slip_match_after + kClockRounding) return;
      if (f.rise >= s.start - kClockRounding) f.used = true;
    } else {
      if (f.rise > s.end + config_.match_after + kClockRounding) return;
      f.used = true;
      if (f.end >= s.start - kClockRounding) {
        if (!s.detected) s.detected_at = std::max(f.rise, s.start);
        s.detected = true;
        s.matches.push_back(f.sample);
      }
    }
    ++s.next_flag;
  }
}

void Metrics::matchLeg(int leg, double now, bool at_end) {
  Leg& l = legs_[leg];
  for (SlipRun& s : l.slips) fold(l, s);
  // A closed slip is decided once no flag run rising within its window
  // can still end or start.
  while (!l.slips.empty() && l.slips.front().closed) {
    const SlipRun& s = l.slips.front();
    const double bound =
        s.end + (isShort(s) ? config_.short_slip_match_after : config_.match_after) + kClockRounding;
    if (!at_end && (now < bound || (l.flag_open && l.flag.rise <= bound))) break;
    decide(leg, s);
    l.slips.pop_front();
  }
  // Flag runs that no slip, present or to come, can match any more.
  uint64_t needed = l.first_flag + l.flags.size();
  for (const SlipRun& s : l.slips) needed = std::min(needed, s.next_flag);
  const double expired = now - config_.match_before - kClockRounding;
  while (!l.flags.empty() && l.first_flag < needed && (at_end || l.flags.front().end < expired)) {
    if (!l.flags.front().used) {
      ++result_.false_detections;
      if (l.flags.front().rose_in_air) ++result_.false_detections_in_air;
    }
    l.flags.pop_front();
    ++l.first_flag;
  }
}

void Metrics::decide(int leg, const SlipRun& s) {
  if (isShort(s)) return;  // not an event
  Leg& l = legs_[leg];
  TrueSlip e;
  e.leg = leg;
  e.start = s.start;
  e.end = s.end;
  e.monitored = s.monitored;
  e.touchdown = s.touchdown;
  e.distance = s.distance;
  e.net_distance = std::sqrt(s.travel[0] * s.travel[0] + s.travel[1] * s.travel[1] + s.travel[2] * s.travel[2]);
  e.ground_mu = s.end_mu;
  e.loaded_end = s.loaded_end;
  e.detected = s.detected;
  e.detected_at = s.detected_at;
  if (e.detected)
    for (const Sample& m : s.matches) sampleEstimates(e, s, m);
  if (e.monitored) {
    ++result_.slip_events;
    if (!e.detected) {
      ++result_.missed_slips;
      result_.missed_distance_max_m = std::max(result_.missed_distance_max_m, e.distance);
    } else {
      l.latency_ms.push_back(latencyMs(e));
      l.after_detection_ms.push_back(afterDetectionMs(e));
    }
  } else {
    ++result_.unmonitored_slips;
  }
  l.events.push_back(e);
}

void Metrics::gradeProbeAnswers(const TickRecord& r) {
  const hal::Telemetry& tm = r.command.telemetry;
  // The answer reaches mu_hat a tick after the counter rises: watch the
  // probe's two feet (this tick's, or last tick's if its pair ended now)
  // on the next kProbeAnswerTicks ticks, for one answer.
  if (answer_ticks_left_ > 0) {
    --answer_ticks_left_;
    for (int leg = 0; leg < 4 && answer_legs_ != 0; ++leg) {
      if (!((answer_legs_ >> leg) & 1u) || !(tm.mu_hat[leg] > 0.0) || tm.mu_hat[leg] == last_mu_hat_[leg]) continue;
      answer_legs_ = 0;
      const double mu_true = r.feet[leg].mu;
      if (!(mu_true > 0.0)) continue;
      const double error = muErrorPct(tm.mu_hat[leg], mu_true);
      ++result_.probe_answers;
      if (error <= 10.0) ++result_.probe_answers_within_10pct;
      result_.probe_answer_error_max_pct = std::max(result_.probe_answer_error_max_pct, error);
    }
  }
  if (tm.probe_counts[1] != last_probes_found_) {
    answer_ticks_left_ = kProbeAnswerTicks;
    answer_legs_ = 0;
    const bool now = tm.probe_leg < 4 && tm.probe_partner < 4;
    for (uint32_t leg : {now ? tm.probe_leg : last_probe_legs_[0], now ? tm.probe_partner : last_probe_legs_[1]})
      if (leg < 4) answer_legs_ |= 1u << leg;
  }
  last_probes_found_ = tm.probe_counts[1];
  last_probe_legs_ = {tm.probe_leg, tm.probe_partner};
  for (int leg = 0; leg < 4; ++leg) last_mu_hat_[leg] = tm.mu_hat[leg];
}

void Metrics::sampleEstimates(TrueSlip& e, const SlipRun& s, const Sample& sample) const {
  const LegTick& l = sample.leg;
  if (l.mu_hat > 0.0 && std::isfinite(l.mu_hat)) {
    // The true mu under the foot at the sample; once the foot has left the
    // ground, the mu of the event's last slipping tick (or, sampled before
    // that tick, of the last tick before the sample with the foot down).
    double mu_true = l.mu_true;
    if (!l.contact) {
      if (sample.index > s.end_index)
        mu_true = s.end_mu;
      else if (sample.earlier_contact)
        mu_true = sample.earlier_contact_mu;
    }
    const double error = mu_true > 0.0 ? muErrorPct(l.mu_hat, mu_true) : -1.0;
    if (mu_true > 0.0 && (!e.has_mu_sample || error > e.mu_error_pct)) {
      e.has_mu_sample = true;
      e.mu_hat = l.mu_hat;
      e.mu_true = mu_true;
      e.mu_error_pct = error;
    }
  }
  const auto& g = l.normal_true;
  const double g_norm = std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
  if (!(g_norm > 0.5)) return;
  // [deg] angle to the true normal; < 0 if `n` is shorter than
  // min_normal_hat_norm (no estimate) or not finite.
  const auto errorDeg = [&](const std::array<double, 3>& n) {
    const double n_norm = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(n_norm >= config_.min_normal_hat_norm) || !std::isfinite(n_norm)) return -1.0;
    const double cx = n[1] * g[2] - n[2] * g[1];
    const double cy = n[2] * g[0] - n[0] * g[2];
    const double cz = n[0] * g[1] - n[1] * g[0];
    const double dot = n[0] * g[0] + n[1] * g[1] + n[2] * g[2];
    return std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz), dot) * 180.0 / kPi;
  };
  const double hat_error = errorDeg(l.normal_hat);
  if (hat_error >= 0.0 && (!e.has_normal_sample || hat_error > e.normal_error_deg)) {
    e.has_normal_sample = true;
    e.normal_error_deg = hat_error;
  }
  const double used_error = errorDeg(l.normal_used);
  if (used_error >= 0.0 && (!e.has_normal_in_use_sample || used_error > e.normal_in_use_error_deg)) {
    e.has_normal_in_use_sample = true;
    e.normal_in_use_error_deg = used_error;
  }
}

void Metrics::onFinish() {
  if (finished_) return;
  finished_ = true;
  if (ticks_ == 1) stepTick(0, first_tick_);  // dt_ stays at its 1 ms default
  const double last_time = ticks_ == 1 ? first_tick_.time : previous_.time;
  for (int leg = 0; leg < 4; ++leg) {
    Leg& l = legs_[leg];
    if (l.flag_open) {
      l.flag_open = false;
      l.flags.push_back(l.flag);
    }
    if (!l.slips.empty()) l.slips.back().closed = true;
    matchLeg(leg, last_time, true);
  }
  // Events and latencies in leg order.
  for (Leg& l : legs_) {
    result_.events.insert(result_.events.end(), l.events.begin(), l.events.end());
    result_.latency_ms.insert(result_.latency_ms.end(), l.latency_ms.begin(), l.latency_ms.end());
    result_.after_detection_ms.insert(result_.after_detection_ms.end(),
                                      l.after_detection_ms.begin(), l.after_detection_ms.end());
    l = Leg{};
  }
  for (const TrueSlip& e : result_.events) {
    if (!e.monitored) continue;
    if (e.has_mu_sample) {
      double& leg_max = result_.mu_error_per_leg_pct[e.leg];
      leg_max = std::max(leg_max, e.mu_error_pct);
      result_.mu_error_max_pct = std::max(result_.mu_error_max_pct, e.mu_error_pct);
    }
    if (e.has_normal_sample)
      result_.normal_error_max_deg = std::max(result_.normal_error_max_deg, e.normal_error_deg);
    if (e.has_normal_in_use_sample)
      result_.normal_in_use_error_max_deg =
          std::max(result_.normal_in_use_error_max_deg, e.normal_in_use_error_deg);
  }
  for (const TrueSlip& e : result_.events) {
    bool in_probe = false;
    for (const auto& span : probe_spans_[e.leg]) in_probe |= e.start >= span.first - 1e-9 && e.start <= span.second;
    if (!in_probe) continue;
    ++result_.probe_slides;
    result_.probe_slide_max_mm = std::max(result_.probe_slide_max_mm, 1000.0 * e.distance);
    result_.probe_slide_max_ms = std::max(result_.probe_slide_max_ms, 1000.0 * (e.end - e.start + dt_));
  }
  std::set<std::pair<int, double>> slipped, slid, estimated;
  for (const TrueSlip& e : result_.events) {
    if (!e.monitored) continue;
    if (e.detected && e.ground_mu > 0.0) {
      slipped.insert({e.leg, e.ground_mu});
      if (1000.0 * e.distance > kRecallTravelsMm[0]) slid.insert({e.leg, e.ground_mu});
    }
    if (e.has_mu_sample) estimated.insert({e.leg, e.mu_true});
  }
  for (const auto& pair : slipped) {
    ++result_.patches_slipped[pair.first];
    if (estimated.count(pair))
      ++result_.patches_estimated[pair.first];
    else
      result_.patches_missing.push_back(pair);
  }
  for (const auto& pair : slid) {
    ++result_.patches_slid[pair.first];
    if (estimated.count(pair)) ++result_.patches_slid_estimated[pair.first];
  }
  // The 99th percentile: the sample of rank floor(0.99 n) from the
  // smallest is the (n - floor(0.99 n))-th largest.
  const uint64_t n = result_.quiet_spread_samples;
  if (n > 0) {
    const uint64_t from_top = n - (n * 99) / 100;
    std::vector<double> top = quiet_top_;
    std::sort(top.begin(), top.end(), std::greater<double>());
    result_.quiet_spread_p99_mps = top[std::min<uint64_t>(from_top, top.size()) - 1];
  }
  quiet_top_ = std::vector<double>();
}

// The largest stance torque step's tick [s] and joint (3 leg + joint).
static std::string torqueStepAtJson(const MetricsResult& m) {
  return "{\"time\": " + jsonNumber(m.max_stance_torque_step_time) +
         ", \"joint\": " + std::to_string(m.max_stance_torque_step_joint) + "}";
}

// summary.json's "friction_probe": its counters, and its slides.
static std::string probeJson(const MetricsResult& m) {
  return "{\"started\": " + std::to_string(m.probes_started) + ", \"found\": " + std::to_string(m.probes_found) +
         ", \"held\": " + std::to_string(m.probes_held) + ", \"slides\": " + std::to_string(m.probe_slides) +
         ", \"slide_max_mm\": " + jsonNumber(m.probe_slide_max_mm) +
         ", \"slide_max_ms\": " + jsonNumber(m.probe_slide_max_ms) +
         ", \"answers\": " + std::to_string(m.probe_answers) +
         ", \"answers_within_10pct\": " + std::to_string(m.probe_answers_within_10pct) +
         ", \"answer_error_max_pct\": " + optional(m.probe_answer_error_max_pct) + "}";
}

// summary.json's "mu_estimate_coverage": the (leg, patch) pairs slipped and
// estimated per leg, over all detected slips and over those of more than
// 5 mm, and the slipped pairs without an estimate.
static_assert(kRecallTravelsMm[0] == 5.0, "slid_5mm names the first travel of recall_by_travel");
static std::string coverageJson(const MetricsResult& m) {
  std::string missing = "[";
  for (const auto& [leg, mu] : m.patches_missing) {
    if (missing.size() > 1) missing += ", ";
    missing += "{\"leg\": " + std::to_string(leg) + ", \"mu_true\": " + jsonNumber(mu) + "}";
  }
  missing += "]";
  const auto counts = [](const std::array<int, 4>& c) {
    return "[" + std::to_string(c[0]) + ", " + std::to_string(c[1]) + ", " + std::to_string(c[2]) + ", " +
           std::to_string(c[3]) + "]";
  };
  return "{\"slipped\": " + counts(m.patches_slipped) + ", \"estimated\": " + counts(m.patches_estimated) +
         ", \"slid_5mm\": " + counts(m.patches_slid) +
         ", \"slid_5mm_estimated\": " + counts(m.patches_slid_estimated) + ", \"missing\": " + missing + "}";
}

SummaryFields Metrics::summaryFields() const {
  const MetricsResult& m = result_;
  SummaryFields f;
  f.push_back({"slip_events", std::to_string(m.slip_events)});
  f.push_back({"false_detections", std::to_string(m.false_detections)});
  f.push_back({"false_detections_in_air", std::to_string(m.false_detections_in_air)});
  f.push_back({"missed_slips", std::to_string(m.missed_slips)});
  f.push_back({"unmonitored_slips", std::to_string(m.unmonitored_slips)});
  const double missed_mm = m.missed_distance_max_m < 0.0 ? -1.0 : 1000.0 * m.missed_distance_max_m;
  f.push_back({"missed_slip_distance_mm", "{\"max\": " + optional(missed_mm) + "}"});
  f.push_back({"detection_latency_ms", medianMaxJson(m.latency_ms)});
  f.push_back({"slip_duration_after_detection_ms", medianMaxJson(m.after_detection_ms)});
  f.push_back({"longest_slip_after_detection", longestAfterDetectionJson(m.events)});
  f.push_back({"loaded_slide_after_detection_ms", medianMaxJson(loadedAfterDetection(m.events))});
  // Touch-down and stance slips apart: their count, the missed, latency
  // and slip after detection; and the recall of slips by travel.
  auto latencies = [](const std::vector<const TrueSlip*>& events, bool after) {
    std::vector<double> v;
    for (const TrueSlip* e : events)
      if (e->detected) v.push_back(after ? afterDetectionMs(*e) : latencyMs(*e));
    return v;
  };
  auto classJson = [&](bool touchdown) {
    std::vector<const TrueSlip*> c;
    for (const TrueSlip& e : m.events)
      if (e.monitored && e.touchdown == touchdown) c.push_back(&e);
    int missed = 0;
    for (const TrueSlip* e : c) missed += e->detected ? 0 : 1;
    const std::vector<double> lat = latencies(c, false), after = latencies(c, true);
    return "{\"events\": " + std::to_string(c.size()) + ", \"missed\": " + std::to_string(missed) +
           ", \"detection_latency_ms\": " + medianMaxJson(lat) +
           ", \"slip_duration_after_detection_ms\": " + medianMaxJson(after) + "}";
  };
  f.push_back({"slip_classes", "{\"touchdown\": " + classJson(true) + ", \"stance\": " + classJson(false) + "}"});
  std::string recall = "[";
  for (double mm : kRecallTravelsMm) {
    std::vector<const TrueSlip*> c;
    for (const TrueSlip& e : m.events)
      if (e.monitored && 1000.0 * e.distance > mm) c.push_back(&e);
    int detected = 0;
    for (const TrueSlip* e : c) detected += e->detected ? 1 : 0;
    const std::vector<double> lat = latencies(c, false);
    if (recall.size() > 1) recall += ", ";
    recall += "{\"min_travel_mm\": " + jsonNumber(mm) + ", \"events\": " + std::to_string(c.size()) +
              ", \"detected\": " + std::to_string(detected) + ", \"detection_latency_ms\": " + medianMaxJson(lat) +
              "}";
  }
  recall += "]";
  f.push_back({"recall_by_travel", recall});

  // Per leg and patch (a patch = one true mu value under that leg).
  std::map<std::pair<int, double>, std::pair<double, int>> patches;
  for (const TrueSlip& e : m.events) {
    if (!e.monitored || !e.has_mu_sample) continue;
    auto& p = patches[{e.leg, e.mu_true}];
    p.first = std::max(p.first, e.mu_error_pct);
    ++p.second;
  }
  f.push_back({"mu_estimate_coverage", coverageJson(m)});
  std::string per_leg = "[";
  for (int leg = 0; leg < 4; ++leg)
    per_leg += (leg ? ", " : "") + optional(m.mu_error_per_leg_pct[leg]);
  per_leg += "]";
  std::string per_patch = "[";
  for (const auto& [key, value] : patches) {
    if (per_patch.size() > 1) per_patch += ", ";
    per_patch += "{\"leg\": " + std::to_string(key.first) +
                 ", \"mu_true\": " + jsonNumber(key.second) +
                 ", \"max_error_pct\": " + jsonNumber(value.first) +
                 ", \"samples\": " + std::to_string(value.second) + "}";
  }
  per_patch += "]";
  f.push_back({"mu_estimate_error_pct", "{\"max\": " + optional(m.mu_error_max_pct) +
                                            ", \"per_leg\": " + per_leg +
                                            ", \"per_patch\": " + per_patch + "}"});
  f.push_back({"normal_error_deg", "{\"max\": " + optional(m.normal_error_max_deg) + "}"});
  f.push_back({"normal_in_use_error_deg", "{\"max\": " + optional(m.normal_in_use_error_max_deg) + "}"});
  f.push_back({"odometry_error_m", "{\"final\": " + jsonNumber(m.odometry_error_final_m) +
                                       ", \"max\": " + jsonNumber(m.odometry_error_max_m) + "}"});
  f.push_back({"distance_walked_m", jsonNumber(m.distance_walked_m)});
  f.push_back({"freeze_events", std::to_string(m.freeze_events)});
  f.push_back({"friction_probe", probeJson(m)});
  f.push_back({"max_stance_torque_step_nm", jsonNumber(m.max_stance_torque_step_nm)});
  f.push_back({"max_stance_torque_step_at", torqueStepAtJson(m)});
  f.push_back({"quiet_speed_spread_mps", "{\"p99\": " + jsonNumber(m.quiet_spread_p99_mps) +
                                             ", \"max\": " + jsonNumber(m.quiet_spread_max_mps) +
                                             "}"});
  if (!plant_json_.empty()) f.push_back({"plant", plant_json_});
  return f;
}

}  // namespace hyq::sim
