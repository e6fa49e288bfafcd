#include "firmware/controller/gait/crawl_gait.hpp"

#include <cmath>

#include "firmware/controller/model/robot_params.hpp"

namespace hyq {

namespace {

double frac(double x) { return x - std::floor(x); }

double clamp01(double x) { return x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x); }

// 2D cross product of (b - a) and (c - a).
double cross2(const Vec3& a, const Vec3& b, const Vec3& c) {
  return (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
}

// Smallest distance [m] from p to the edges of triangle abc, in the xy plane;
// negative when p lies outside.
double triangleMargin(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& p) {
  const Vec3* v[3] = {&a, &b, &c};
  double margin = 1e9;
  for (int e = 0; e < 3; ++e) {
    const Vec3& p0 = *v[e];
    const Vec3& p1 = *v[(e + 1) % 3];
    const Vec3& other = *v[(e + 2) % 3];
    const double len = std::hypot(p1.x() - p0.x(), p1.y() - p0.y());
    if (len < 1e-9) return -1e9;
    const double side = cross2(p0, p1, other) >= 0.0 ? 1.0 : -1.0;
    const double d = side * cross2(p0, p1, p) / len;
    if (d < margin) margin = d;
  }
  return margin;
}

// The triangle whose edges lie `margin` inside those of `tri` (xy plane): the
// original scaled about its incentre by (r - margin) / r. False when the
// inradius r is not larger than the margin.
bool shrinkTriangle(const Vec3 tri[3], double margin, Vec3 inner[3]) {
  const double a = std::hypot(tri[1].x() - tri[2].x(), tri[1].y() - tri[2].y());
  const double b = std::hypot(tri[0].x() - tri[2].x(), tri[0].y() - tri[2].y());
  const double c = std::hypot(tri[0].x() - tri[1].x(), tri[0].y() - tri[1].y());
  const double perimeter = a + b + c;
  const double area = 0.5 * std::fabs(cross2(tri[0], tri[1], tri[2]));
  if (perimeter < 1e-9) return false;
  const double r = 2.0 * area / perimeter;
  if (r <= margin) return false;
  const Vec3 incentre = (a * tri[0] + b * tri[1] + c * tri[2]) / perimeter;
  const double k = (r - margin) / r;
  for (int i = 0; i < 3; ++i) inner[i] = incentre + k * (tri[i] - incentre);
  return true;
}

// Closest point to p (xy) on the boundary of triangle tri, for p outside it.
Vec3 closestPointOnTriangle(const Vec3 tri[3], const Vec3& p) {
  Vec3 best = tri[0];
  double best_d2 = 1e300;
  for (int e = 0; e < 3; ++e) {
    const Vec3& p0 = tri[e];
    const Vec3& p1 = tri[(e + 1) % 3];
    const double dx = p1.x() - p0.x(), dy = p1.y() - p0.y();
    const double len2 = dx * dx + dy * dy;
    double t = len2 > 0.0 ? ((p.x() - p0.x()) * dx + (p.y() - p0.y()) * dy) / len2 : 0.0;
    t = clamp01(t);
    const Vec3 q = p0 + t * (p1 - p0);
    const double d2 = (q.x() - p.x()) * (q.x() - p.x()) + (q.y() - p.y()) * (q.y() - p.y());
    if (d2 < best_d2) {
      best_d2 = d2;
      best = q;
    }
  }
  return best;
}

// The three feet that stay down while `leg` swings.
void supportTriangle(const Mat3x4& feet_world, int leg, Vec3 tri[3]) {
  int n = 0;
  for (int i = 0; i < kNumLegs; ++i)
    if (i != leg) tri[n++] = feet_world.col(i);
}

}  // namespace

void CrawlGait::reset(const GaitParams& params, double dt, const GaitInput& start, double yaw,
                      const Mat3x4& nominal_feet_base) {
  p_ = params;
  dt_ = dt;
  time_ = 0.0;
  gait_time_ = 0.0;
  yaw_ = yaw;
  ref_start_ = start.base_world;
  nominal_feet_base_ = nominal_feet_base;
  legs_.reset(start.feet_world);
  for (int i = 0; i < 4; ++i) legs_.skipOpenSwing(i, legCyclePhase(i), legCycleIndex(i), swingFraction());
  shift_leg_ = -1;
  com_from_ = start.com_world;
  com_target_ = start.com_world;
  shift_start_ = 0.0;
  shift_end_ = 0.0;
  shift_clock_ = 0.0;
  com_wait_ = 0.0;
  crouch_ = 0.0;
  tipping_ = false;
  for (double& r : reload_) r = 0.0;
  dropping_ = false;
}

void CrawlGait::replanFrom(const Vec3& com_world) {
  com_from_ = com_world;
  com_target_ = com_world;
  shift_leg_ = -1;
}

double CrawlGait::cycles() const { return p_.initial_phase + gait_time_ / p_.cycle_time; }

double CrawlGait::legCyclePhase(int leg) const { return frac(cycles() - p_.phase_offset[leg]); }

long CrawlGait::legCycleIndex(int leg) const {
  return static_cast<long>(std::floor(cycles() - p_.phase_offset[leg]));
}

bool CrawlGait::liftoffDue(int leg) const {
  return legs_.liftoffDue(leg, legCyclePhase(leg), legCycleIndex(leg), swingFraction());
}

bool CrawlGait::unloadingDue(int leg) const {
  return (1.0 - legCyclePhase(leg)) * p_.cycle_time < p_.unload_time;
}

int CrawlGait::nextLiftoffLeg() const {
  int best = 0;
  double best_wait = 2.0;
  for (int i = 0; i < 4; ++i) {
    // A lift-off that is due but not done yet (another foot still in the
    // air) comes first; otherwise the next one is when psi wraps to 0.
    const double wait = liftoffDue(i) ? 0.0 : 1.0 - legCyclePhase(i);
    if (wait < best_wait) {
      best_wait = wait;
      best = i;
    }
  }
  return best;
}

Vec3 CrawlGait::footholdFor(int leg, const Mat3x4& feet_world,
                            const TerrainEstimator& terrain) const {
  // Place the foot where the stand pattern puts it relative to the three feet
  // that stay down, plus half a stride. In a steady crawl this advances every
  // foot by one stride L = v T per cycle, the feet stay within 3L/8 of their
  // nominal offsets, and the body (which follows the feet) moves at v.
  const double c = std::cos(yaw_), s = std::sin(yaw_);
  const Vec3 heading(c, s, 0.0);
  const Vec3 lateral(-s, c, 0.0);
  Vec3 others = Vec3::Zero(), others_nominal = Vec3::Zero();
  for (int i = 0; i < 4; ++i) {
    if (i == leg) continue;
    others += feet_world.col(i) / 3.0;
    others_nominal += nominal_feet_base_.col(i) / 3.0;
  }
  const Vec3 offset = nominal_feet_base_.col(leg) - others_nominal;
  double stride = p_.speed * p_.cycle_time;
  // From the stand the stride grows from kCrawlStartStride (params.hpp).
  const double cap = kCrawlStartStride + kCrawlStrideGrowth * gait_time_;
  if (std::fabs(stride) > cap) stride = std::copysign(cap, stride);
  Vec3 foot = others + (0.5 * stride) * heading;
  foot.x() += c * offset.x() - s * offset.y();
  foot.y() += s * offset.x() + c * offset.y();
  // Each foot keeps to its lane beside the line the robot started on, so
  // lateral drift (a push, a slip) is walked back, at most lane_step per step.
  const Vec3& nom = nominal_feet_base_.col(leg);
  const Vec3 lane_point = ref_start_ + Vec3(c * nom.x() - s * nom.y(), s * nom.x() + c * nom.y(), 0.0);
  double lane_error = lateral.dot(lane_point - foot);
  if (lane_error > p_.lane_step) lane_error = p_.lane_step;
  if (lane_error < -p_.lane_step) lane_error = -p_.lane_step;
  foot += lane_error * lateral;
  foot.z() = terrain.heightAt(foot.x(), foot.y()) - p_.swing_depth;
  return foot;
}

Vec3 CrawlGait::shiftTarget(int leg, const Mat3x4& feet_world, const Vec3& com_world) const {
  // The smallest shift that makes the coming support triangle safe: project
  // the four feet's centre onto the triangle shrunk by the stability margin.
  // A short shift needs little tangential force, which on ice is all there is.
  Vec3 tri[3];
  supportTriangle(feet_world, leg, tri);
  Vec3 target = feet_world.rowwise().mean();
  Vec3 inner[3];
  if (!shrinkTriangle(tri, p_.stability_margin, inner))
    target = (tri[0] + tri[1] + tri[2]) / 3.0;  // too small for the margin: its centre
  else if (triangleMargin(inner[0], inner[1], inner[2], target) < 0.0)
    target = closestPointOnTriangle(inner, target);
  target.z() = com_world.z();
  return target;
}

// [m/s] How fast a searching foot goes down: put down by a tipping trunk,
// kCrawlTipDropSpeed; by a freeze, freeze_drop_speed; else at the search's
// own speed.
double CrawlGait::searchSpeed(bool paused) const {
  if (dropping_) return kCrawlTipDropSpeed;
  return paused ? p_.freeze_drop_speed : p_.touchdown_search_speed;
}

// Three feet support the trunk while the fourth lifts, unloads or swings.
// One of them, past its load ramp, carries under kCrawlTipForce while the
// trunk turns about the line through the other two faster than
// kCrawlTipRate, its side rising: the trunk tips toward the fourth foot.
bool CrawlGait::tipping(const GaitInput& in) const {
  int support[3] = {-1, -1, -1};
  int count = 0;
  for (int i = 0; i < 4; ++i) {
    if (legs_.phase[i] != LegPhase::kStance || liftoffDue(i) || unloadingDue(i)) continue;
    if (count == 3) return false;  // all four stand
    support[count++] = i;
  }
  if (count != 3) return false;
  for (int s = 0; s < 3; ++s) {
    const int k = support[s], a = support[(s + 1) % 3], b = support[(s + 2) % 3];
    if (time_ - legs_.touchdown_time[k] < p_.load_time || !(in.normal_force[k] < kCrawlTipForce)) continue;
    const Vec3 edge = (in.feet_world.col(b) - in.feet_world.col(a)).normalized();
    // Turning at w about `edge` moves foot k at w edge x r: up if (edge x r).z > 0.
    const double side = edge.cross(Vec3(in.feet_world.col(k) - in.feet_world.col(a))).z();
    const double rate = (side > 0.0 ? 1.0 : -1.0) * in.omega_world.dot(edge);  // [rad/s]
    if (rate > kCrawlTipRate) return true;
  }
  return false;
}

HYQ_INLINE CrawlGait::Clocks CrawlGait::advanceClocks(const GaitInput& in, const TerrainEstimator& terrain) {
  time_ += dt_;
  Clocks clocks;
  clocks.running = p_.walk && time_ >= p_.start_delay;
  const bool searching = legs_.anySearching();
  // The clock waits for a foot that has not found the ground: the next leg
  // must not lift before this one carries load.
  // ... and a lift-off waits for the CoM: on ice the body trails its target,
  // and a leg lifted before the CoM is inside the other three feet tips it.
  bool com_not_ready = false;
  // Crouched as far as it may and still short: the CoM only inside.
  const double needed_margin =
      crouch_ >= p_.crouch_max ? std::fmin(0.0, p_.liftoff_margin) : p_.liftoff_margin;  // [m]
  // ... and for where the CoM is going: a trunk pushed toward the lifting
  // foot tips over the other three, however far inside it stands. The CoM
  // carried on by its velocity over the inverted pendulum's time constant
  // (the extrapolated CoM, or capture point) must have the margin as well.
  const double pendulum_time = std::sqrt(std::fmax(p_.body_height - crouch_, 0.0) / robot::kGravity);  // [s]
  Vec3 com_ahead = in.com_world + pendulum_time * in.com_vel_world;
  com_ahead.z() = in.com_world.z();
  if (clocks.running) {
    for (int i = 0; i < 4; ++i) {
      if (legs_.phase[i] != LegPhase::kStance) continue;
      if (!liftoffDue(i) && !unloadingDue(i)) continue;
      Vec3 tri[3];
      supportTriangle(in.feet_world, i, tri);
      if (triangleMargin(tri[0], tri[1], tri[2], in.com_world) < needed_margin ||
          triangleMargin(tri[0], tri[1], tri[2], com_ahead) < needed_margin)
        com_not_ready = true;
    }
  }
  tipping_ = clocks.running && tipping(in);
  if (tipping_) com_not_ready = true;
  // A foot that took its load back while the trunk tipped unloads again
  // before it lifts.
  for (double r : reload_)
    if (r > 0.0) com_not_ready = true;
  clocks.gait_runs = clocks.running && !in.paused && !searching && !com_not_ready;
  // The wait counts from the end of the body shift until the next lift-off,
  // which clears it.
  if (clocks.running && !in.paused && !searching && com_not_ready && shift_clock_ >= shift_end_) com_wait_ += dt_;
  // Still short after the wait: crouch until the CoM has the margin (or is
  // inside, crouched crouch_max); rise again once the leg has lifted (the
  // wait cleared).
  const double crouch_step = p_.crouch_speed * dt_;  // [m]
  if (com_not_ready && com_wait_ > p_.liftoff_wait_max)
    crouch_ = std::fmin(p_.crouch_max, crouch_ + crouch_step);
  else if (com_wait_ == 0.0)
    crouch_ = std::fmax(0.0, crouch_ - crouch_step);
  // Freezing called mid-swing: put the foot down where it is (a search from
  // its current height, at freeze_drop_speed) rather than hold it in the air.
  // A trunk that tips over the feet that stand: the swinging foot down too,
  // at kCrawlTipDropSpeed until it stands (searchSpeed).
  bool swinging = false;
  for (int i = 0; i < 4; ++i) swinging = swinging || legs_.phase[i] == LegPhase::kSwing;
  if (tipping_ && swinging) dropping_ = true;
  if (in.paused || (tipping_ && swinging)) legs_.dropSwingingFeet(in.feet_world, terrain, p_.swing_depth);
  if (!legs_.anySearching()) dropping_ = false;
  // The body shift has its own clock: it must go on while the crawl clock
  // waits for the CoM, or a shift that starts late would wait for itself.
  clocks.shift_runs = clocks.running && !in.paused;
  if (clocks.shift_runs) shift_clock_ += dt_;
  if (clocks.gait_runs) {
    gait_time_ += dt_;
  }
  return clocks;
}

void CrawlGait::update(const GaitInput& in, const TerrainEstimator& terrain, GaitOutput& out) {
  const Clocks clocks = advanceClocks(in, terrain);
  const double swing_frac = swingFraction();
  out.phase = frac(cycles());
  out.touchdown_event = LegMask();
  out.liftoff_event = LegMask();
  out.swing_leg = kNumLegs;
  out.stance_mask = LegMask();

  bool other_in_air = false;
  for (int i = 0; i < 4; ++i) other_in_air = other_in_air || legs_.phase[i] != LegPhase::kStance;

  for (int i = 0; i < 4; ++i) {
    const double psi = legCyclePhase(i);
    const long idx = legCycleIndex(i);
    const bool touching = in.touchdown_mask.has(i);
    switch (legs_.phase[i]) {
      case LegPhase::kStance:
        if (clocks.gait_runs && !other_in_air && liftoffDue(i)) {
          legs_.liftOff(i, idx, in.feet_world.col(i), footholdFor(i, in.feet_world, terrain), out);
          other_in_air = true;
          com_wait_ = 0.0;
        }
        break;
      case LegPhase::kSwing: {
        const double s = (legs_.lifted_cycle[i] == idx && psi < swing_frac) ? psi / swing_frac : 1.0;
        legs_.endSwing(i, s, p_.touchdown_min_swing, touching, time_, in.normal_force[i], p_.ramp_force, out);
        break;
      }
      case LegPhase::kSearch:
        legs_.search(i, searchSpeed(in.paused), dt_, touching,
                     p_.touchdown_search_max, time_, in.normal_force[i], p_.ramp_force, out);
        break;
    }
    legReference(i, psi, in, clocks.running, out);
  }

  shiftBody(in, terrain.normal(), clocks, out);
  out.yaw_des = yaw_;
  out.crouch = crouch_;
  // From what the swing PD pushed with at touch-down up to no cap, and down
  // to zero before lift-off.
  loadRampCaps(p_.ramp_force, legs_.touchdown_force, out);
}

HYQ_INLINE void CrawlGait::legReference(int i, double psi, const GaitInput& in, bool running, GaitOutput& out) {
  const double swing_frac = swingFraction();
  out.swing_late[i] = legs_.swingLate(i, psi, swing_frac, p_.touchdown_min_swing);
  out.foot_vel_des[i].setZero();
  out.leg_phase[i] = legs_.phase[i];
  if (legs_.phase[i] == LegPhase::kStance) {
    out.stance_mask.set(i);
    out.foot_des[i] = in.feet_world.col(i);
    double load = clamp01((time_ - legs_.touchdown_time[i]) / p_.load_time);
    out.unloading[i] = false;
    if (running) load = stanceLoad(load, liftoffDue(i), (1.0 - psi) * p_.cycle_time, p_.unload_time, out.unloading[i]);
    // The trunk tips toward the foot that unloads (tipping(); the clock
    // holds): it takes its load back at the load ramp's rate, and gives it
    // up again at the unload's once the trunk stops tipping.
    if (running && out.unloading[i]) {
      reload_[i] = tipping_ ? std::fmin(1.0, reload_[i] + dt_ / p_.load_time)
                            : std::fmax(0.0, reload_[i] - dt_ / p_.unload_time);
      if (reload_[i] > load) load = reload_[i];
    } else {
      reload_[i] = 0.0;
    }
    out.load[i] = load;
  } else if (legs_.phase[i] == LegPhase::kSwing) {
    out.swing_leg = i;
    out.load[i] = 0.0;
    out.unloading[i] = false;
    const double s = (psi < swing_frac) ? psi / swing_frac : 1.0;
    const double sdot = in.paused ? 0.0 : 1.0 / (swing_frac * p_.cycle_time);
    const double a = p_.swing_lift_fraction;
    const double sxy = clamp01((s - 0.5 * a) / (1.0 - a));
    const double bxy = smoothStep(sxy);
    const double dbxy = (s > 0.5 * a && s < 1.0 - 0.5 * a) ? smoothStepDerivative(sxy) / (1.0 - a) : 0.0;
    double lift = 1.0, dlift = 0.0;
    if (s < a) {
      lift = smoothStep(s / a);
      dlift = smoothStepDerivative(s / a) / a;
    } else if (s > 1.0 - a) {
      lift = smoothStep((1.0 - s) / a);
      dlift = -smoothStepDerivative((1.0 - s) / a) / a;
    }
    const Vec3 d = legs_.foothold[i] - legs_.liftoff_pos[i];
    Vec3 pos = legs_.liftoff_pos[i];
    pos.x() += bxy * d.x();
    pos.y() += bxy * d.y();
    const double apex = robot::isFront(i) && p_.step_height < kFrontStepHeight ? kFrontStepHeight : p_.step_height;
    pos.z() += smoothStep(s) * d.z() + apex * lift;
    Vec3 vel(dbxy * d.x(), dbxy * d.y(), smoothStepDerivative(s) * d.z() + apex * dlift);
    out.foot_des[i] = pos;
    out.foot_vel_des[i] = vel * sdot;
  } else {
    out.swing_leg = i;
    out.load[i] = 0.0;
    out.unloading[i] = false;
    legs_.searchReference(i, searchSpeed(in.paused), out);
  }
}

// Body shift toward the next support triangle while all four feet are down.
HYQ_INLINE void CrawlGait::shiftBody(const GaitInput& in, const Vec3& ground_normal, const Clocks& clocks,
                                     GaitOutput& out) {
  out.com_vel_des.setZero();
  out.com_acc_des.setZero();
  if (!clocks.running) {
    out.com_des = com_from_;
    return;
  }
  if (out.swing_leg == 4) {
    const int next = nextLiftoffLeg();
    // Has a foot slid since the shift was planned, so that its target is no
    // longer inside the triangle the lift-off check will use?
    bool target_lost = false;
    if (next == shift_leg_) {
      Vec3 tri[3];
      supportTriangle(in.feet_world, next, tri);
      target_lost = triangleMargin(tri[0], tri[1], tri[2], com_target_) < p_.liftoff_margin;
    }
    if (next != shift_leg_ || target_lost) planShift(next, target_lost, in, ground_normal);
  }
  const double span = shift_end_ - shift_start_;
  const double sigma = span > 0.0 ? clamp01((shift_clock_ - shift_start_) / span) : 1.0;
  out.com_des = com_from_ + smoothStep(sigma) * (com_target_ - com_from_);
  if (clocks.shift_runs && span > 0.0) {
    out.com_vel_des = (smoothStepDerivative(sigma) / span) * (com_target_ - com_from_);
    out.com_acc_des = (smoothStepSecondDerivative(sigma) / (span * span)) * (com_target_ - com_from_);
  }
}

double slopeShiftDeceleration(const Vec3& shift, const Vec3& n, double traction) {
  if (!(traction < kNoFrictionLimit) || !(n.z() > 0.0)) return 0.0;
  const double norm = n.norm(), horizontal = n.head<2>().norm();
  const double sin_tilt = horizontal / norm, cos_tilt = n.z() / norm;
  if (sin_tilt < std::sin(kShiftBoundMinTilt)) return 0.0;
  const double length = shift.head<2>().norm();
  if (!(length > 0.0)) return 0.0;
  // n's horizontal part points down the fall line.
  const double cos_phi = n.head<2>().dot(shift.head<2>()) / (horizontal * length);
  const double across = sin_tilt * std::sqrt(std::fmax(0.0, 1.0 - cos_phi * cos_phi));
  const double budget = traction * cos_tilt;
  const double room = budget * budget - across * across;
  const double cap = room > 0.0 ? robot::kGravity * (std::sqrt(room) - sin_tilt * cos_phi) : 0.0;
  return cap > kSlopeShiftMinAcceleration ? cap : kSlopeShiftMinAcceleration;
}

void CrawlGait::planShift(int next, bool target_lost, const GaitInput& in, const Vec3& ground_normal) {
  const double sigma_prev =
      shift_end_ > shift_start_ ? clamp01((shift_clock_ - shift_start_) / (shift_end_ - shift_start_)) : 1.0;
  com_from_ = com_from_ + smoothStep(sigma_prev) * (com_target_ - com_from_);
  com_target_ = shiftTarget(next, in.feet_world, in.com_world);
  const double wait = frac(p_.phase_offset[next] - cycles()) * p_.cycle_time;  // [s]
  // All of the four-foot phase up to the unloading: the gentlest shift
  // that is over before the lift-off check looks at the CoM; a
  // re-planned one at reshift_speed on average.
  double duration = wait - p_.unload_time;
  if (target_lost) duration = (com_target_ - com_from_).norm() / p_.reshift_speed;
  // No faster than max_shift_acceleration allows, and on a slope braking
  // no harder than the friction the slope's pull leaves the feet (the
  // lift-off then waits for the CoM).
  double bound = p_.max_shift_acceleration;  // [m/s^2], <= 0: none
  const double cap = slopeShiftDeceleration(com_target_ - com_from_, ground_normal, in.traction);
  if (cap > 0.0 && (bound <= 0.0 || cap < bound)) bound = cap;
  if (bound > 0.0) {
    const double distance = (com_target_ - com_from_).head<2>().norm();  // [m]
    const double gentle = std::sqrt(kSmoothStepPeakSecondDerivative * distance / bound);
    if (duration < gentle) duration = gentle;
  }
  if (duration < p_.min_shift_time) duration = p_.min_shift_time;
  shift_start_ = shift_clock_;
  shift_end_ = shift_clock_ + duration;
  shift_leg_ = next;
}

}  // namespace hyq
