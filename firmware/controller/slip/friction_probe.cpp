#include "firmware/controller/slip/friction_probe.hpp"

#include <cmath>

namespace hyq {

namespace {
constexpr double kNoRatio = 1e9;        // [-] tangentialRatio of a force that does not press
constexpr double kMinFootDistance = 0.1;  // [m] two feet closer than this make no pair
// [s] durations are sums of dt; this keeps "lasted 200 ticks" from reading as 0.19999 s.
constexpr double kClockRounding = 1e-9;
}  // namespace

double tangentialRatio(const Vec3& f, const Vec3& n) {
  const double fn = f.dot(n);
  if (!(fn > 0.0)) return kNoRatio;
  return (f - fn * n).norm() / fn;
}

double stanceTwist(const Mat3x4& feet) {
  double twist = kNoRatio;  // [m] here: 1e9, no plane found
  for (int i = 0; i < kNumLegs; ++i) {
    int others[3], n = 0;
    for (int j = 0; j < kNumLegs; ++j)
      if (j != i) others[n++] = j;
    const Vec3 a = feet.col(others[0]);
    const Vec3 normal = Vec3(feet.col(others[1]) - a).cross(Vec3(feet.col(others[2]) - a));
    const double area = normal.norm();  // [m^2] twice the triangle's
    // Three feet closer than a square of kMinFootDistance's side span no plane.
    if (!(area > kMinFootDistance * kMinFootDistance)) continue;
    const double distance = std::fabs(Vec3(feet.col(i) - a).dot(normal)) / area;
    if (distance < twist) twist = distance;
  }
  return twist;
}

void FrictionProbe::reset(const ProbeParams& params) {
  params_ = params;
  leg_ = partner_ = kNumLegs;
  releasing_ = stepped_ = false;
  direction_.setZero();
  force_ = peak_ratio_ = 0.0;
  allowed_time_ = quiet_ = 0.0;
  probed_ = unsure_ = rewatched_ = LegMask();
  watch_ticks_[0] = watch_ticks_[1] = 0;
  watched_ = -1;
  confirm_ticks_ = 0;
  started_ = found_ = held_ = aborted_ = 0;
}

void FrictionProbe::drop() {
  if (active()) ++aborted_;
  leg_ = partner_ = kNumLegs;
  releasing_ = false;
  watched_ = -1;
  force_ = peak_ratio_ = 0.0;
  allowed_time_ = 0.0;
}

void FrictionProbe::end(ProbeEnd how) {
  if (how == ProbeEnd::kFound) ++found_;
  if (how == ProbeEnd::kHeld) ++held_;
  if (how == ProbeEnd::kAborted) {
    ++aborted_;
    if (force_ < kProbeRetryForce) probed_ = probed_ & ~LegMask::only(leg_);
  }
  endRamp(how == ProbeEnd::kFound);
}

void FrictionProbe::endRamp(bool broken) {
  allowed_time_ = 0.0;
  peak_ratio_ = 0.0;
  releasing_ = force_ > 0.0;
  release_rate_ = params_.rate;
  stepped_ = false;
  if (broken) stepDown();
  if (!releasing_) {
    leg_ = partner_ = kNumLegs;
    force_ = 0.0;
  }
}

bool FrictionProbe::narrowed(const ProbeInput& in, int foot) const {
  return params_.partner_margin * in.mu_in_use[foot] < kProbeGuessedPartnerRatio;
}

double FrictionProbe::partnerLimit(const ProbeInput& in, int foot) const {
  if (narrowed(in, foot) && !in.known.has(foot) && !unsure_.has(foot)) return kProbeGuessedPartnerRatio;
  return params_.partner_margin * in.mu_in_use[foot];
}

void FrictionProbe::findUnsure(const ProbeInput& in) {
  // Four feet across a change of slope: every cone's normal is unsure.
  unsure_ = in.normal_unsure;
  if (in.stance == LegMask::all() && stanceTwist(in.feet) > kProbeMaxTwist) unsure_ = LegMask::all();
}

double FrictionProbe::medianRatio(int foot) const {
  const int n = ratio_count_ < kProbeRatioWindow ? ratio_count_ : kProbeRatioWindow;
  double sorted[kProbeRatioWindow];
  for (int i = 0; i < n; ++i) sorted[i] = ratios_[foot][i];
  for (int i = 1; i < n; ++i)  // insertion sort of at most kProbeRatioWindow values
    for (int j = i; j > 0 && sorted[j - 1] > sorted[j]; --j) {
      const double swap = sorted[j];
      sorted[j] = sorted[j - 1];
      sorted[j - 1] = swap;
    }
  if (n == 0) return kNoRatio;
  return n % 2 ? sorted[n / 2] : 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]);
}

bool FrictionProbe::tryStart(const ProbeInput& in) {
  if (!in.allowed || allowed_time_ < params_.settle_time - kClockRounding ||
      quiet_ < params_.quiet_time - kClockRounding)
    return false;
  findUnsure(in);
  // The foot: of those whose friction is a guess, one whose guess is
  // narrowed (a floor after its own slip: the ground in question) first,
  // then the most loaded.
  int leg = kNumLegs;
  bool leg_narrowed = false;
  const double start_load = kProbeStartLoadShare * params_.min_load;  // [N]
  double load = start_load;
  for (int i = 0; i < kNumLegs; ++i) {
    if (in.known.has(i) || probed_.has(i) || unsure_.has(i)) continue;
    const double fn = in.grf.col(i).dot(in.normal[i]);
    if (fn < start_load) continue;
    const bool guess_narrowed = narrowed(in, i);
    if ((guess_narrowed && !leg_narrowed) || (guess_narrowed == leg_narrowed && fn >= load)) {
      load = fn;
      leg = i;
      leg_narrowed = guess_narrowed;
    }
  }
  if (leg == kNumLegs) return false;
  // The partner: the foot whose commanded force stays furthest inside
  // partner_margin of its own cone with the pair at its largest (the probed
  // foot at max_ratio); the ramp ends, held, if it reaches that first.
  const Vec3 f_leg = in.grf_des.col(leg);
  const Vec3 t_leg = f_leg - f_leg.dot(in.normal[leg]) * in.normal[leg];
  const double cap = std::fmin(params_.max_force, params_.max_ratio * load + t_leg.norm());  // [N]
  int partner = kNumLegs;
  double best_margin = -kNoRatio;  // [-] the partner's mu in use less its ratio with the pair at `cap`
  Vec3 best_direction = Vec3::Zero();
  for (int j = 0; j < kNumLegs; ++j) {
    if (j == leg) continue;
    const Vec3 line = in.feet.col(leg) - in.feet.col(j);
    const double length = line.norm();
    if (!(length > kMinFootDistance)) continue;
    if (in.grf.col(j).dot(in.normal[j]) < start_load) continue;
    const double limit = partnerLimit(in, j);  // [-]
    if (!(tangentialRatio(in.grf_des.col(j), in.normal[j]) < limit)) continue;
    // Along the tangential force the QP already asks of the probed foot.
    Vec3 d = line / length;
    if (d.dot(t_leg) < 0.0) d = -d;
    const double margin = limit - tangentialRatio(Vec3(in.grf_des.col(j) - cap * d), in.normal[j]);
    if (margin > best_margin) {
      best_margin = margin;
      partner = j;
      best_direction = d;
    }
  }
  if (partner == kNumLegs) return false;
  leg_ = leg;
  partner_ = partner;
  direction_ = best_direction;
  force_ = peak_ratio_ = 0.0;
  ratio_count_ = 0;
  watch_ticks_[0] = watch_ticks_[1] = 0;
  watched_ = -1;
  partner_guessed_ = !in.known.has(partner);
  probed_.set(leg);
  ++started_;
  return true;
}

void FrictionProbe::update(const ProbeInput& in, double dt, ProbeOutput& out) {
  out = ProbeOutput();
  probed_ = probed_ & in.stance;
  rewatched_ = rewatched_ & in.stance;
  quiet_ = in.slipping.any() ? 0.0 : quiet_ + dt;
  allowed_time_ = in.allowed ? allowed_time_ + dt : 0.0;
  if (!params_.enabled) return;
  if (releasing_) {
    release(in, dt, out);
  } else if (active()) {
    ramp(in, dt, out);
    if (releasing_) release(in, dt, out);  // the ramp ended: down from this tick on
  } else {
    tryStart(in);
  }
  if (!active()) return;
  out.leg = leg_;
  out.partner = partner_;
  out.pair.col(leg_) = force_ * direction_;
  out.pair.col(partner_) = -force_ * direction_;
}

void FrictionProbe::stepDown() {
  step_to_ = force_ * kProbeBreakHoldShare;
  release_rate_ = params_.break_release_rate;
  stepped_ = true;
}

bool FrictionProbe::watch(const ProbeInput& in) {
  // A foot probed again after an unconfirmed watch is probed without it.
  if (rewatched_.has(leg_)) return false;
  const int feet[2] = {leg_, partner_};
  for (int k = 0; k < 2; ++k) {
    // The probed foot slides against the force the pair adds to it, the partner along it.
    const double away = (k == 0 ? -1.0 : 1.0) * direction_.dot(in.slip_velocity[feet[k]]);
    watch_ticks_[k] = in.velocity_valid && away > kProbeWatchSpeed ? watch_ticks_[k] + 1 : 0;
  }
  for (int k = 0; k < 2; ++k) {
    if (watch_ticks_[k] < kProbeWatchTicks || force_ < kProbeRetryForce) continue;
    // A foot whose cone normal is unsure slides, but its ratio about that
    // normal is not its friction: the step, no answer.
    if (unsure_.has(feet[k])) {
      ++aborted_;
    } else {
      watched_ = k;
      watched_normal_ = in.normal[feet[k]];  // the last ratio's, taken this tick
      confirm_ticks_ = 0;
    }
    endRamp(true);
    return true;
  }
  return false;
}

void FrictionProbe::unconfirmed() {
  ++aborted_;
  // Once more on this foothold, without the watch (watch() skips a foot in rewatched_).
  rewatched_.set(leg_);
  probed_ = probed_ & ~LegMask::only(leg_);
  watched_ = -1;
}

void FrictionProbe::confirm(const ProbeInput& in, ProbeOutput& out) {
  const int foot = watched_ == 0 ? leg_ : partner_;
  if (in.fast.has(foot) || in.slipping.has(foot)) {
    // The ratios stopped at the watch: the median of the ticks before it.
    const double ratio = medianRatio(watched_);
    if (ratio < kNoRatio) {
      out.mu_found[foot] = ratio;
      out.normal_found[foot] = watched_normal_;
    }
    if (watched_ == 1 && partner_guessed_ && ratio < kNoRatio) probed_ = probed_ & ~LegMask::only(leg_);
    ++found_;
    watched_ = -1;
    return;
  }
  if (++confirm_ticks_ >= kProbeWatchConfirmTicks) unconfirmed();
}

void FrictionProbe::release(const ProbeInput& in, double dt, ProbeOutput& out) {
  if (watched_ >= 0) confirm(in, out);
  // A foot of the pair that breaks away while the pair comes down (after a
  // hold or an abort) takes the break-away's step.
  if (!stepped_ && (in.slipping.has(leg_) || in.slipping.has(partner_))) stepDown();
  if (stepped_ && force_ > step_to_) {
    force_ -= kProbeStepRate * dt;
    if (force_ < step_to_) force_ = step_to_;
  } else {
    force_ -= release_rate_ * dt;
  }
  if (force_ < 0.0) force_ = 0.0;
  // After a watch the probe waits for the detector, the pair down or not.
  const bool waiting = watched_ >= 0;
  if ((force_ <= 0.0 && !waiting) || !in.stance.has(leg_) || !in.stance.has(partner_)) {
    if (waiting) unconfirmed();
    releasing_ = false;
    leg_ = partner_ = kNumLegs;
    force_ = 0.0;
  }
}

void FrictionProbe::ramp(const ProbeInput& in, double dt, ProbeOutput& out) {
  findUnsure(in);
  const int feet[2] = {leg_, partner_};
  const int slot = ratio_count_ % kProbeRatioWindow;
  for (int k = 0; k < 2; ++k) ratios_[k][slot] = tangentialRatio(in.grf_sample.col(feet[k]), in.normal[feet[k]]);
  ++ratio_count_;
  // Broken away: the flagged foot's median ratio is its friction.
  for (int k = 0; k < 2; ++k) {
    if (!in.slipping.has(feet[k])) continue;
    if (unsure_.has(feet[k])) {
      end(ProbeEnd::kAborted);
      return;
    }
    const double ratio = medianRatio(k);
    if (ratio < kNoRatio) {
      out.mu_found[feet[k]] = ratio;
      out.normal_found[feet[k]] = in.normal[feet[k]];
    }
    // A guessed partner broke away first: the probed foot's friction is
    // still a guess, and it is probed again. The partner, known now, is
    // pulled no further than partner_margin of its cone: once per partner
    // and foothold.
    if (k == 1 && partner_guessed_ && ratio < kNoRatio) probed_ = probed_ & ~LegMask::only(leg_);
    end(ProbeEnd::kFound);
    return;
  }
  if (!in.allowed || in.slipping.any() || !in.stance.has(leg_) || !in.stance.has(partner_) ||
      in.grf.col(leg_).dot(in.normal[leg_]) < params_.min_load ||
      in.grf.col(partner_).dot(in.normal[partner_]) < params_.min_load) {
    end(ProbeEnd::kAborted);
    return;
  }
  if (watch(in)) return;
  const double ratio = tangentialRatio(in.grf.col(leg_), in.normal[leg_]);
  if (ratio > peak_ratio_) peak_ratio_ = ratio;
  const double next = force_ + params_.rate * dt;
  const Vec3 partner_force = in.grf_des.col(partner_) - next * direction_;
  if (peak_ratio_ >= params_.max_ratio || next > params_.max_force ||
      tangentialRatio(partner_force, in.normal[partner_]) > partnerLimit(in, partner_)) {
    out.mu_held[leg_] = peak_ratio_;
    end(ProbeEnd::kHeld);
    return;
  }
  force_ = next;
}

}  // namespace hyq
