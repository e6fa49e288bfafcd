#include "sim_host/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <utility>

#include "sim_host/run_log.hpp"

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

// Negative means "no sample" and renders as null.
std::string optional(double v) { return v < 0.0 ? "null" : jsonNumber(v); }

// Index ranges [first, last] of consecutive ticks where pred(i) holds.
template <typename Pred>
std::vector<std::pair<size_t, size_t>> runs(size_t n, Pred pred) {
  std::vector<std::pair<size_t, size_t>> out;
  for (size_t i = 0; i < n; ++i) {
    if (!pred(i)) continue;
    if (!out.empty() && out.back().second + 1 == i)
      out.back().second = i;
    else
      out.push_back({i, i});
  }
  return out;
}

}  // namespace

Metrics::Metrics(const MetricsConfig& config) : config_(config) {}

void Metrics::onTick(const TickRecord& r) {
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
    l.mu_true = foot.mu;
    l.normal_true = foot.normal;
    l.mu_hat = tm.mu_hat[leg];
    for (int k = 0; k < 3; ++k) l.normal_hat[k] = tm.normal_hat[leg][k];
  }
  ticks_.push_back(t);

  recordQuietSpread(r);

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
  std::vector<double> speeds;
  for (int leg = 0; leg < 4; ++leg) {
    if (!bit(tm.stance_mask, leg)) continue;
    const FootTruth& foot = r.feet[leg];
    if (foot.in_contact && foot.slip_speed > config_.true_slip_speed) return;
    const double* u = tm.foot_vel_base[leg];
    speeds.push_back(std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]));
  }
  if (speeds.size() < 3) return;
  const double m = median(speeds);
  double spread = 0.0;
  for (double s : speeds) spread = std::max(spread, std::fabs(s - m));
  result_.quiet_spread_mps.push_back(spread);
}

void Metrics::sampleEstimates(TrueSlip& e, size_t i) const {
  const LegTick& l = ticks_[i].legs[e.leg];
  if (l.mu_hat > 0.0 && std::isfinite(l.mu_hat)) {
    // The true mu under the foot at the sample; once the foot has left the
    // ground, the mu of the event's last slipping tick.
    double mu_true = l.mu_true;
    if (!l.contact) {
      for (size_t k = i; k-- > 0;) {
        if (ticks_[k].time <= e.end + kClockRounding && ticks_[k].legs[e.leg].contact) {
          mu_true = ticks_[k].legs[e.leg].mu_true;
          break;
        }
      }
    }
    if (mu_true > 0.0) {
      e.has_mu_sample = true;
      e.mu_hat = l.mu_hat;
      e.mu_true = mu_true;
      e.mu_error_pct = 100.0 * std::fabs(l.mu_hat - mu_true) / mu_true;
    }
  }
  const auto& n = l.normal_hat;
  const auto& g = l.normal_true;
  const double n_norm = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  const double g_norm = std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
  if (n_norm >= config_.min_normal_hat_norm && g_norm > 0.5 && std::isfinite(n_norm)) {
    const double cx = n[1] * g[2] - n[2] * g[1];
    const double cy = n[2] * g[0] - n[0] * g[2];
    const double cz = n[0] * g[1] - n[1] * g[0];
    const double dot = n[0] * g[0] + n[1] * g[1] + n[2] * g[2];
    e.has_normal_sample = true;
    e.normal_error_deg = std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz), dot) * 180.0 / kPi;
  }
}

void Metrics::computeLeg(int leg) {
  const size_t n = ticks_.size();
  const double dt = n > 1 ? ticks_[1].time - ticks_[0].time : 0.001;
  auto time = [this](size_t i) { return ticks_[i].time; };

  // Ground truth: contact-point speed above the threshold, short gaps merged,
  // short events dropped.
  auto raw = runs(n, [&](size_t i) {
    const LegTick& l = ticks_[i].legs[leg];
    return l.contact && l.slip_speed > config_.true_slip_speed;
  });
  std::vector<std::pair<size_t, size_t>> merged;
  for (const auto& r : raw) {
    if (!merged.empty() && time(r.first) - time(merged.back().second) <=
                               config_.true_slip_merge_gap + kClockRounding)
      merged.back().second = r.second;
    else
      merged.push_back(r);
  }
  auto flagged = runs(n, [&](size_t i) { return bit(ticks_[i].slip_mask, leg); });
  std::vector<bool> flag_used(flagged.size(), false);

  for (const auto& r : merged) {
    if (time(r.second) - time(r.first) + dt < config_.true_slip_min_duration - kClockRounding) {
      const double hi = time(r.second) + config_.short_slip_match_after + kClockRounding;
      for (size_t k = 0; k < flagged.size(); ++k) {
        const double rise = time(flagged[k].first);
        if (rise >= time(r.first) - kClockRounding && rise <= hi) flag_used[k] = true;
      }
      continue;
    }
    TrueSlip e;
    e.leg = leg;
    e.start = time(r.first);
    e.end = time(r.second);
    for (size_t i = r.first; i <= r.second; ++i) {
      e.monitored = e.monitored || bit(ticks_[i].stance_mask, leg);
      if (ticks_[i].legs[leg].contact) e.distance += ticks_[i].legs[leg].slip_speed * dt;
    }
    const double lo = e.start - config_.match_before - kClockRounding;
    const double hi = e.end + config_.match_after + kClockRounding;
    size_t last_match = 0;
    for (size_t k = 0; k < flagged.size(); ++k) {
      if (time(flagged[k].second) < lo || time(flagged[k].first) > hi) continue;
      if (!e.detected) e.detected_at = std::max(time(flagged[k].first), lo);
      e.detected = true;
      flag_used[k] = true;
      last_match = k;
    }
    if (e.detected) sampleEstimates(e, flagged[last_match].second);
    if (e.monitored) {
      ++result_.slip_events;
      if (!e.detected) {
        ++result_.missed_slips;
        result_.missed_distance_max_m = std::max(result_.missed_distance_max_m, e.distance);
      } else {
        result_.latency_ms.push_back(1000.0 * std::max(0.0, e.detected_at - e.start));
        result_.after_detection_ms.push_back(1000.0 * std::max(0.0, e.end - e.detected_at));
      }
    } else {
      ++result_.unmonitored_slips;
    }
    result_.events.push_back(e);
  }
  for (bool used : flag_used)
    if (!used) ++result_.false_detections;
}

void Metrics::onFinish() {
  result_.slip_events = result_.unmonitored_slips = 0;
  result_.missed_slips = result_.false_detections = 0;
  result_.missed_distance_max_m = -1.0;
  result_.latency_ms.clear();
  result_.after_detection_ms.clear();
  result_.events.clear();
  for (int leg = 0; leg < 4; ++leg) computeLeg(leg);
  result_.mu_error_max_pct = result_.normal_error_max_deg = -1.0;
  result_.mu_error_per_leg_pct.fill(-1.0);
  for (const TrueSlip& e : result_.events) {
    if (!e.monitored) continue;
    if (e.has_mu_sample) {
      double& leg_max = result_.mu_error_per_leg_pct[e.leg];
      leg_max = std::max(leg_max, e.mu_error_pct);
      result_.mu_error_max_pct = std::max(result_.mu_error_max_pct, e.mu_error_pct);
    }
    if (e.has_normal_sample)
      result_.normal_error_max_deg = std::max(result_.normal_error_max_deg, e.normal_error_deg);
  }
}

SummaryFields Metrics::summaryFields() const {
  const MetricsResult& m = result_;
  SummaryFields f;
  f.push_back({"slip_events", std::to_string(m.slip_events)});
  f.push_back({"false_detections", std::to_string(m.false_detections)});
  f.push_back({"missed_slips", std::to_string(m.missed_slips)});
  f.push_back({"unmonitored_slips", std::to_string(m.unmonitored_slips)});
  f.push_back({"missed_slip_distance_mm",
               "{\"max\": " +
                   optional(m.missed_distance_max_m < 0.0 ? -1.0 : 1000.0 * m.missed_distance_max_m) +
                   "}"});
  f.push_back({"detection_latency_ms", "{\"median\": " + jsonNumber(median(m.latency_ms)) +
                                           ", \"max\": " + jsonNumber(maximum(m.latency_ms)) +
                                           "}"});
  f.push_back({"slip_duration_after_detection_ms",
               "{\"median\": " + jsonNumber(median(m.after_detection_ms)) +
                   ", \"max\": " + jsonNumber(maximum(m.after_detection_ms)) + "}"});

  // Per leg and patch (a patch = one true mu value under that leg).
  std::map<std::pair<int, double>, std::pair<double, int>> patches;
  for (const TrueSlip& e : m.events) {
    if (!e.monitored || !e.has_mu_sample) continue;
    auto& p = patches[{e.leg, e.mu_true}];
    p.first = std::max(p.first, e.mu_error_pct);
    ++p.second;
  }
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
  f.push_back({"odometry_error_m", "{\"final\": " + jsonNumber(m.odometry_error_final_m) +
                                       ", \"max\": " + jsonNumber(m.odometry_error_max_m) + "}"});
  f.push_back({"distance_walked_m", jsonNumber(m.distance_walked_m)});
  f.push_back({"freeze_events", std::to_string(m.freeze_events)});
  f.push_back({"max_stance_torque_step_nm", jsonNumber(m.max_stance_torque_step_nm)});
  std::vector<double> spread = m.quiet_spread_mps;
  double p99 = NAN;
  if (!spread.empty()) {
    const size_t k = (spread.size() * 99) / 100;
    std::nth_element(spread.begin(), spread.begin() + k, spread.end());
    p99 = spread[k];
  }
  f.push_back({"quiet_speed_spread_mps", "{\"p99\": " + jsonNumber(p99) +
                                             ", \"max\": " + jsonNumber(maximum(spread)) + "}"});
  return f;
}

}  // namespace hyq::sim
