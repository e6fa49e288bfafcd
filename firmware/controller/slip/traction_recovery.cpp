#include "firmware/controller/slip/traction_recovery.hpp"

#include "firmware/controller/model/sincos.hpp"

#include <cmath>

namespace hyq {

namespace {

constexpr double kUnitTolerance = 1e-3;  // |1 - |n|| accepted for a unit normal
// [s] durations are sums of dt; this keeps "lasted 40 ticks" from reading as
// 39.99999 or 40.00001 ms.
constexpr double kClockRounding = 1e-9;
// [-] a released brake has settled once mu in use is this close to its target
constexpr double kSettleTolerance = 1e-4;

bool isUnit(const Vec3& n) {
  return n.allFinite() && std::fabs(n.norm() - 1.0) < kUnitTolerance;
}

}  // namespace

Vec3 slipDampingVelocity(const Vec3& v, const Vec3& v_last, bool last_valid, const Vec3& n, bool landing) {
  const Vec3 mean = last_valid ? Vec3(0.5 * (v + v_last)) : v;
  const double along_n = mean.dot(n);  // [m/s] > 0: leaving the ground
  return mean - (landing && along_n > 0.0 ? 0.0 : along_n) * n;
}

Vec3 rotateToward(const Vec3& from, const Vec3& to, double gain, double dt) {
  const Vec3 axis_scaled = from.cross(to);
  const double s = axis_scaled.norm();
  const double c = from.dot(to);
  if (s < 1e-12) return c > 0.0 ? to : from;
  const double dtheta = angleOfSineCosine(s, c);
  double fraction = gain * dt;
  if (fraction > 1.0) fraction = 1.0;
  if (fraction < 0.0) fraction = 0.0;
  const double angle = fraction * dtheta;
  const Vec3 axis = axis_scaled / s;
  // Rodrigues' formula; the axis is orthogonal to `from`, so the (1-cos)
  // term vanishes.
  const SinCos turn = sinCos(angle);
  return (turn.c * from + turn.s * axis.cross(from)).normalized();
}

void TractionRecovery::reset(const RecoveryParams& params, const Vec3& terrain_normal) {
  params_ = params;
  cos_ground_min_ = std::cos(params.ground_plane_min_angle);
  terrain_normal_ = isUnit(terrain_normal) ? Vec3(terrain_normal.normalized()) : Vec3::UnitZ();
  for (int leg = 0; leg < kRecoveryLegs; ++leg) {
    normal_[leg] = terrain_normal_;
    mu_[leg] = params_.mu_default;
    mu_across_[leg] = params_.mu_default;
    stance_estimate_[leg] = 0.0;
    corrected_[leg] = false;
    in_stance_[leg] = false;
    new_foothold_[leg] = false;
    known_mu_[leg] = 0.0;
    held_[leg] = false;
    guessing_[leg] = false;
    light_slide_[leg] = false;
    guess_pending_[leg] = false;
    mu_before_guess_[leg] = params_.mu_default;
    mu_settle_[leg] = 0.0;
    probe_target_[leg] = 0.0;
    mu_before_slip_[leg] = params_.mu_default;
    was_slipping_[leg] = false;
    slip_time_[leg] = 0.0;
    slip_free_time_[leg] = 0.0;
    flagged_time_[leg] = 0.0;
    stance_time_[leg] = 0.0;
    travel_ground_[leg] = Vec3::Zero();
  }
  freezing_ = false;
  calm_time_ = 0.0;
  frozen_time_ = 0.0;
  freeze_count_ = 0;
}

void TractionRecovery::update(const RecoveryInput& in, double dt) {
  if (!std::isfinite(dt) || dt <= 0.0) return;
  if (isUnit(in.terrain_normal)) terrain_normal_ = in.terrain_normal.normalized();
  // K_mu's share of one tick: mu <- k * target + (1 - k) * mu.
  const double k_mu = params_.k_mu * dt < 1.0 ? params_.k_mu * dt : 1.0;
  uint32_t flagged = 0;
  for (int leg = 0; leg < kRecoveryLegs; ++leg) {
    const double floor = updateLeg(leg, in, dt, k_mu);
    updateAcross(leg, floor, k_mu);
    if (in_stance_[leg] && ((in.slip_mask >> leg) & 1u)) flagged |= 1u << leg;
  }
  updateFreezing(flagged, dt);
}

void TractionRecovery::updateAcross(int leg, double floor, double k_mu) {
  const double estimate = stance_estimate_[leg];
  // A square pyramid unless the slope floor holds mu in use above this
  // stance's estimate (on flat ground the floor is mu_floor: never).
  if (!(params_.enabled && in_stance_[leg] && floor > params_.mu_floor && estimate > 0.0 && floor > estimate)) {
    mu_across_[leg] = mu_[leg];
    return;
  }
  // Corners on the estimated cone: (mu^2 + across^2) pyramid_scale^2 = estimate^2.
  const double ps = params_.pyramid_scale;
  const double across_sq = estimate * estimate / (ps * ps) - mu_[leg] * mu_[leg];
  double target = across_sq > 0.0 ? std::sqrt(across_sq) : 0.0;
  if (target < params_.mu_floor) target = params_.mu_floor;
  mu_across_[leg] += k_mu * (target - mu_across_[leg]);
  if (mu_across_[leg] > mu_[leg]) mu_across_[leg] = mu_[leg];
}

double TractionRecovery::floorUnderEstimate(double floor, double estimate) const {
  // A slope's floor carries the foot's share of the weight there: it stays.
  if (floor > params_.mu_floor || !(estimate > 0.0) || params_.brake_margin * estimate >= floor) return floor;
  const double braked = params_.brake_margin * estimate;
  return braked > kEstimatedMuFloor ? braked : kEstimatedMuFloor;
}

// With a load limit (the trot behind a torque loop), a foot flagged while
// lighter than it carries none of the weight the slope floor is for: until it
// is loaded past the limit (or lifts) its floor is mu_floor, and its guess goes
// there (docs/design-notes.md, "A light trot foot's guess goes below the slope
// floor"). Without the limit, the slope floor always.
double TractionRecovery::weightFloor(int leg, const RecoveryInput& in, bool stance, double slope_floor) {
  const bool light = guess_load_limit_ < kAssumeLoaded && in.normal_force[leg] < guess_load_limit_;
  if (((in.slip_mask >> leg) & 1u) && light) light_slide_[leg] = true;
  if (!light || !stance) light_slide_[leg] = false;
  return light_slide_[leg] && slope_floor > params_.mu_floor ? params_.mu_floor : slope_floor;
}

double TractionRecovery::updateLeg(int leg, const RecoveryInput& in, double dt, double k_mu) {
  // Without recovery, every cone is about the plane through all feet (the
  // paper's controller).
  const Vec3 ground = params_.enabled ? groundUnder(in.ground_normal[leg]) : terrain_normal_;
  const bool stance = (in.stance_mask >> leg) & 1u;
  // The slope floor is taken on the plane the cone is taken about: the
  // foot's ground (turned to hold a stance slide's travel, where it was), or
  // once a slip's estimate has corrected the cone, the normal in use.
  const bool turned = stance && travel_ground_[leg].squaredNorm() > 0.0;
  const Vec3& cone_plane = stance && corrected_[leg] ? normal_[leg] : turned ? travel_ground_[leg] : ground;
  const double floor = weightFloor(leg, in, stance, muFloorFor(params_, cone_plane));
  if (!stance) {
    leaveStance(leg, ground);
    return floor;
  }
  if (!in_stance_[leg]) touchDown(leg, in.map_mu[leg], floor);
  if (params_.enabled) takeProbe(leg, in, floor);
  // The guess's target: the floor, or on known ground the braking target
  // of the map's mu.
  double guess_target = floor;
  if (known_mu_[leg] > 0.0 && params_.brake_margin * known_mu_[leg] > guess_target)
    guess_target = params_.brake_margin * known_mu_[leg];
  const bool slipping = (in.slip_mask >> leg) & 1u;
  if (slipping && !was_slipping_[leg]) mu_before_slip_[leg] = mu_[leg];
  was_slipping_[leg] = slipping;
  const bool estimate_ok = in.estimate_valid[leg] && isUnit(in.normal_estimate[leg]) &&
                           std::isfinite(in.mu_estimate[leg]) && in.mu_estimate[leg] > 0.0;
  if (params_.enabled && slipping && !estimate_ok) turnGroundToTravel(leg, in, ground);
  const Vec3& cone_ground = travel_ground_[leg].squaredNorm() > 0.0 ? travel_ground_[leg] : ground;

  if (params_.enabled && slipping && estimate_ok) {
    normal_[leg] = rotateToward(normal_[leg], in.normal_estimate[leg].normalized(),
                                params_.k_normal, dt);
    // [-] where mu in use settles after the slip, and its braking target now
    const double leg_floor = floorUnderEstimate(floor, in.mu_estimate[leg]);
    double settle = params_.estimate_margin * in.mu_estimate[leg];
    if (settle < leg_floor) settle = leg_floor;
    double target = params_.brake_margin * in.mu_estimate[leg];
    if (target < leg_floor) target = leg_floor;
    // After a guess, mu follows the estimate back up, but a slip never
    // takes it above where it was when the guess began.
    if (settle > mu_before_slip_[leg]) settle = mu_before_slip_[leg];
    if (guessing_[leg] && target > mu_before_guess_[leg]) target = mu_before_guess_[leg];
    if (target < mu_[leg] || guessing_[leg])
      mu_[leg] = k_mu * target + (1.0 - k_mu) * mu_[leg];
    mu_settle_[leg] = settle;
    corrected_[leg] = true;
    stance_estimate_[leg] = in.mu_estimate[leg];
    guess_pending_[leg] = false;
  } else if (params_.enabled && slipping && params_.guess_floor_before_estimate && guessDue(leg, in)) {
    // No estimate yet (a foot that slides with too little load to sample):
    // assume the worst until it comes.
    if (!guessing_[leg]) beginGuess(leg, in, guess_target);
    mu_[leg] = k_mu * guess_target + (1.0 - k_mu) * mu_[leg];
    guessing_[leg] = true;
    // Flagged again with no estimate in this event: the last estimate's cone
    // did not hold, so the cone goes back about the foot's ground (turned to
    // a slide's travel, where one turned it this stance) until a new
    // estimate corrects it.
    corrected_[leg] = false;
    guess_pending_[leg] = guess_holds_;
  } else {
    // Between flags, a guess not yet answered by an estimate goes on while
    // the foot is too light to sample one from. Once loaded the foot keeps
    // its mu in use, so that its next slip is a slide the estimator can
    // read, and the guess is over (its unloading before lift-off does not
    // restart it). The hold supersedes an earlier slip's settled mu.
    if (guess_pending_[leg] && !(in.normal_force[leg] < guess_hold_load_)) guess_pending_[leg] = false;
    if (params_.enabled && guess_holds_ && guess_pending_[leg]) {
      mu_[leg] = k_mu * guess_target + (1.0 - k_mu) * mu_[leg];
      mu_settle_[leg] = 0.0;
    }
  }
  // Until an estimate corrects it, the cone is taken about the foot's ground,
  // flagged or not: the ground its slope floor is taken on.
  if (!corrected_[leg]) normal_[leg] = rotateToward(normal_[leg], cone_ground, params_.k_normal, dt);

  advanceSlipClocks(leg, slipping, in.normal_force[leg], dt, k_mu);

  if (!params_.enabled) {
    mu_[leg] = params_.mu_default;
    return floor;
  }
  // The floor follows the terrain (a robot that walks onto a slope); mu in
  // use below it rises toward it by the correction's own law, as toward a
  // probe's answer (no lower than the floor).
  const double leg_floor = floorUnderEstimate(floor, stance_estimate_[leg]);
  if (!approachProbeTarget(leg, slipping, leg_floor, k_mu) && mu_[leg] < leg_floor)
    mu_[leg] += k_mu * (leg_floor - mu_[leg]);
  const bool may_rise = !slipping && !freezing_ && new_foothold_[leg] &&
                        slip_free_time_[leg] >= params_.mu_rise_delay - kClockRounding;
  if (may_rise && mu_[leg] < params_.mu_rise_ceiling) {
    mu_[leg] += params_.mu_rise_rate * dt;
    if (mu_[leg] > params_.mu_rise_ceiling) mu_[leg] = params_.mu_rise_ceiling;
  }
  return floor;
}

bool TractionRecovery::guessDue(int leg, const RecoveryInput& in) const {
  const bool light = !(in.normal_force[leg] > guess_load_limit_);
  const bool lasted = flagged_time_[leg] >= kLoadedSlideGuessAge - kClockRounding;
  return (light || lasted) && (flagged_time_[leg] >= guess_delay_ - kClockRounding ||
                               stance_time_[leg] - flagged_time_[leg] >= guess_delay_ - kClockRounding);
}

void TractionRecovery::turnGroundToTravel(int leg, const RecoveryInput& in, const Vec3& ground) {
  // A stance slide only (the foot stood kStanceSlideAge when its flag
  // rose, as in beginGuess): a landing's travel carries the impact's
  // velocity errors.
  if (stance_time_[leg] - flagged_time_[leg] < kStanceSlideAge - kClockRounding) return;
  const Vec3& travel = in.slip_travel[leg];
  const double length = travel.norm();
  if (!travel.allFinite() || !(length >= kTravelPlaneLength)) return;
  const Vec3 along = travel / length;
  const double off = ground.dot(along);  // sine of the travel's elevation from the plane
  // Out of the plane, but no more than the steepest ground is tilted: a
  // travel mostly along the normal is a contact that gives, not a slide.
  if (!(std::fabs(off) > kTravelPlaneSine) || !(std::fabs(off) < kSinMaxGroundTilt)) return;
  const Vec3 turned = (ground - off * along).normalized();
  if (turned.z() < kCosMaxGroundTilt) return;
  travel_ground_[leg] = turned;
}

void TractionRecovery::beginGuess(int leg, const RecoveryInput& in, double guess_target) {
  mu_before_guess_[leg] = mu_[leg];
  // A loaded stance foot slides on the ground's cone: start there, never
  // above mu in use (a target above it is reached by the law).
  // stance_time_ - flagged_time_: how long the foot had stood when its flag
  // rose (this tick, in the crawl, which guesses at once).
  const double ratio = in.force_ratio[leg];
  const double start = ratio < guess_target ? guess_target : ratio;  // NaN ratio: NaN, no start
  if (guess_from_ratio_ && stance_time_[leg] - flagged_time_[leg] >= kStanceSlideAge - kClockRounding &&
      in.normal_force[leg] >= kStanceSlideLoad && start < mu_[leg])
    mu_[leg] = start;
}

void TractionRecovery::takeProbe(int leg, const RecoveryInput& in, double floor) {
  const double found = in.probe_mu[leg], held = in.probe_held[leg];
  if (std::isfinite(found) && found > 0.0) {
    known_mu_[leg] = found;
    stance_estimate_[leg] = found;
    double mu = params_.estimate_margin * found;
    if (mu > params_.mu_default) mu = params_.mu_default;
    probe_target_[leg] = mu > floor ? mu : floor;
    probe_target_held_[leg] = false;
    guessing_[leg] = false;
    guess_pending_[leg] = false;
    mu_settle_[leg] = 0.0;
  } else if (std::isfinite(held) && held > 0.0) {
    held_[leg] = true;
    double mu = params_.estimate_margin * held;
    if (mu > params_.mu_default) mu = params_.mu_default;
    if (mu > mu_[leg]) {
      probe_target_[leg] = mu;
      probe_target_held_[leg] = true;
    }
    guessing_[leg] = false;
    guess_pending_[leg] = false;
  }
}

void TractionRecovery::touchDown(int leg, double map_mu, double floor) {
  in_stance_[leg] = true;
  new_foothold_[leg] = true;
  slip_free_time_[leg] = 0.0;
  // Ground the map knows: its friction at once, up or down.
  known_mu_[leg] = params_.enabled && map_mu > 0.0 ? map_mu : 0.0;
  if (known_mu_[leg] > 0.0) {
    double mu = params_.estimate_margin * known_mu_[leg];
    if (mu > params_.mu_default) mu = params_.mu_default;
    mu_[leg] = mu > floor ? mu : floor;
  }
}

void TractionRecovery::leaveStance(int leg, const Vec3& ground) {
  // A foot lifted while braking takes the settled mu to its next foothold.
  if (mu_settle_[leg] > mu_[leg]) mu_[leg] = mu_settle_[leg];
  mu_settle_[leg] = 0.0;
  probe_target_[leg] = 0.0;
  was_slipping_[leg] = false;
  normal_[leg] = ground;
  travel_ground_[leg] = Vec3::Zero();
  corrected_[leg] = false;
  stance_estimate_[leg] = 0.0;
  in_stance_[leg] = false;
  known_mu_[leg] = 0.0;
  held_[leg] = false;
  guessing_[leg] = false;
  guess_pending_[leg] = false;
  slip_time_[leg] = 0.0;
  slip_free_time_[leg] = 0.0;
  flagged_time_[leg] = 0.0;
  stance_time_[leg] = 0.0;
  if (!params_.enabled) mu_[leg] = params_.mu_default;
}

void TractionRecovery::advanceSlipClocks(int leg, bool slipping, double normal_force, double dt, double k_mu) {
  flagged_time_[leg] = slipping ? flagged_time_[leg] + dt : 0.0;
  stance_time_[leg] += dt;
  if (slipping) {
    const bool unloaded = normal_force < params_.freeze_min_load;
    if (!unloaded) slip_time_[leg] += dt;
    slip_free_time_[leg] = 0.0;
    new_foothold_[leg] = false;
  } else {
    guessing_[leg] = false;
    slip_time_[leg] = 0.0;
    slip_free_time_[leg] += dt;
    // The slip is over: release the brake, back to the settled mu.
    if (params_.enabled && mu_settle_[leg] > mu_[leg]) mu_[leg] += k_mu * (mu_settle_[leg] - mu_[leg]);
    if (mu_settle_[leg] - mu_[leg] < kSettleTolerance) mu_settle_[leg] = 0.0;
  }
}

bool TractionRecovery::approachProbeTarget(int leg, bool slipping, double leg_floor, double k_mu) {
  double target = probe_target_[leg];
  if (!(target > 0.0)) return false;
  // A flag ends it: the slip's own braking and settling take over (a found
  // mu is the foot's estimate for the rest of the stance). A held ratio
  // only raises mu in use.
  if (slipping || (probe_target_held_[leg] && mu_[leg] >= target)) {
    probe_target_[leg] = 0.0;
    return false;
  }
  if (target < leg_floor) target = leg_floor;
  mu_[leg] += k_mu * (target - mu_[leg]);
  if (std::fabs(target - mu_[leg]) < kSettleTolerance) probe_target_[leg] = 0.0;
  return true;
}

Vec3 TractionRecovery::groundUnder(const Vec3& ground_normal) const {
  if (!isUnit(ground_normal)) return terrain_normal_;
  const Vec3 ground = ground_normal.normalized();
  // Further apart than ground_plane_min_angle: a smaller cosine.
  return ground.dot(terrain_normal_) < cos_ground_min_ ? ground : terrain_normal_;
}

double TractionRecovery::muFloorFor(const RecoveryParams& params, const Vec3& ground) {
  // On ground tilted by theta (the foot's ground plane against W z: a plane
  // through feet and footholds, steadier than one foot's slip estimate) a
  // foot holds its share of the weight only with mu >= tan(theta), and the
  // inscribed pyramid gives pyramid_scale of mu along a diagonal: a narrower
  // cone cannot carry the robot there, whatever the estimate says.
  const double cos_tilt = ground.z();
  double slope_floor = 0.0;
  if (cos_tilt > 0.0 && cos_tilt < 1.0)
    slope_floor = params.slope_floor_factor * std::sqrt(1.0 - cos_tilt * cos_tilt) / cos_tilt /
                  params.pyramid_scale;
  return slope_floor > params.mu_floor ? slope_floor : params.mu_floor;
}

void TractionRecovery::updateFreezing(uint32_t flagged, double dt) {
  if (!params_.enabled || !params_.freeze) {
    freezing_ = false;
    return;
  }
  if (!freezing_) {
    for (int leg = 0; leg < kRecoveryLegs; ++leg) {
      if (slip_time_[leg] >= params_.freeze_after - kClockRounding) {
        freezing_ = true;
        calm_time_ = 0.0;
        frozen_time_ = 0.0;
        ++freeze_count_;
        break;
      }
    }
    return;
  }
  calm_time_ = flagged ? 0.0 : calm_time_ + dt;
  frozen_time_ += dt;
  if (calm_time_ >= params_.freeze_hold - kClockRounding ||
      frozen_time_ >= params_.freeze_max - kClockRounding) {
    freezing_ = false;
    for (int leg = 0; leg < kRecoveryLegs; ++leg) slip_time_[leg] = 0.0;
  }
}

}  // namespace hyq
