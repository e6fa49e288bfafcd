#include "firmware/controller/gait/trot_gait.hpp"

#include <cmath>

#include "firmware/controller/model/robot_params.hpp"

namespace hyq {

namespace {

double frac(double x) { return x - std::floor(x); }

double clamp01(double x) { return x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x); }

}  // namespace

void trotSwingReference(const Vec3& liftoff, const Vec3& foothold, double s, double swing_duration,
                        const TrotParams& trot, Vec3& position, Vec3& velocity, Vec3& acceleration) {
  // Along the ground: a quintic blend over the first 1 - landing_fraction.
  const double xy_span = 1.0 - trot.landing_fraction;
  const double sxy = clamp01(s / xy_span);
  const double bxy = smoothStep(sxy);
  const double dbxy = smoothStepDerivative(sxy) / xy_span;                         // per unit of s
  const double ddbxy = s < xy_span ? smoothStepSecondDerivative(sxy) / (xy_span * xy_span) : 0.0;
  // Up: a quintic blend from the lift-off height to the apex by mid-swing;
  // down: a cubic from the apex (at rest) to the foothold's height, where it
  // arrives at touchdown_speed.
  const double apex = (liftoff.z() > foothold.z() ? liftoff.z() : foothold.z()) + trot.step_height;
  double z, dz, ddz;  // [m], per unit of s, per unit of s^2
  if (s < 0.5) {
    const double rise = apex - liftoff.z();
    z = liftoff.z() + smoothStep(2.0 * s) * rise;
    dz = 2.0 * smoothStepDerivative(2.0 * s) * rise;
    ddz = 4.0 * smoothStepSecondDerivative(2.0 * s) * rise;
  } else {
    const double u = clamp01(2.0 * s - 1.0);
    const double m1 = -trot.touchdown_speed * 0.5 * swing_duration;  // [m per unit of u] at the end
    const double h00 = (2.0 * u - 3.0) * u * u + 1.0, h01 = 1.0 - h00, h11 = (u - 1.0) * u * u;
    const double drop = apex - foothold.z();
    z = h00 * apex + h01 * foothold.z() + h11 * m1;
    dz = 2.0 * (6.0 * u * (u - 1.0) * drop + (3.0 * u - 2.0) * u * m1);
    ddz = s < 1.0 ? 4.0 * ((12.0 * u - 6.0) * drop + (6.0 * u - 2.0) * m1) : 0.0;
  }
  const Vec3 d = foothold - liftoff;
  position = Vec3(liftoff.x() + bxy * d.x(), liftoff.y() + bxy * d.y(), z);
  const double sdot = swing_duration > 0.0 ? 1.0 / swing_duration : 0.0;  // [1/s]
  velocity = Vec3(dbxy * d.x(), dbxy * d.y(), dz) * sdot;
  acceleration = Vec3(ddbxy * d.x(), ddbxy * d.y(), ddz) * (sdot * sdot);
}

void TrotGait::reset(const GaitParams& params, double dt, const GaitInput& start, double yaw,
                     const Mat3x4& nominal_feet_base) {
  p_ = params;
  dt_ = dt;
  time_ = 0.0;
  trot_time_ = 0.0;
  yaw_ = yaw;
  ramp_ = 0.0;
  speed_ = 0.0;
  yaw_rate_ = 0.0;
  speed_rate_ = 0.0;
  stopping_ = false;
  start_shifted_ = !params.walk;
  start_checked_ = false;
  far_start_ = false;
  com_ref_ = start.com_world;
  nominal_feet_base_ = nominal_feet_base;
  legs_.reset(start.feet_world);
  // A pair whose swing window is already open when the trot starts skips
  // that swing instead of lifting without its unloading.
  for (int i = 0; i < 4; ++i) legs_.skipOpenSwing(i, legCyclePhase(i), legCycleIndex(i), swingFraction());
}

void TrotGait::replanFrom(const Vec3& com_world) { com_ref_ = com_world; }

namespace {
// The horizontal point where the lines a0-a1 and b0-b1 cross; false if they
// are (nearly) parallel.
bool linesCross(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1, Vec3& out) {
  const double ax = a1.x() - a0.x(), ay = a1.y() - a0.y();
  const double bx = b1.x() - b0.x(), by = b1.y() - b0.y();
  const double den = ax * by - ay * bx;  // [m^2]
  if (!(std::fabs(den) > 1e-6)) return false;
  const double t = ((b0.x() - a0.x()) * by - (b0.y() - a0.y()) * bx) / den;
  out = Vec3(a0.x() + t * ax, a0.y() + t * ay, 0.0);
  return true;
}
}  // namespace

bool TrotGait::startShift(const GaitInput& in, const TerrainEstimator& terrain) {
  if (start_shifted_) return true;
  if (in.paused) return false;  // frozen: the reference stays where the re-plan puts it
  const Vec3& n = terrain.normal();
  const double norm = n.norm();
  Vec3 cross;
  if (!linesCross(in.feet_world.col(robot::LF), in.feet_world.col(robot::RH), in.feet_world.col(robot::RF),
                  in.feet_world.col(robot::LH), cross)) {
    start_shifted_ = true;
    return true;
  }
  const double off = (cross - in.com_world).head<2>().norm();  // [m] the CoM from the crossing
  // Level ground: decided once, at the trot's first tick. A CoM near the
  // crossing starts as it stands; one kTrotStartShiftTolerance or more off
  // (a crawl handing over mid-stride, feet uphill on a gentle slope) shifts
  // first, as on a slope.
  const bool level = !(norm > 0.0) || n.head<2>().norm() < std::sin(kSlopeShiftMinTilt) * norm;
  if (level) {
    if (!start_checked_) {
      start_checked_ = true;
      far_start_ = off >= kTrotStartShiftTolerance;
    }
    if (!far_start_) {
      start_shifted_ = true;
      return true;
    }
  }
  Vec3 step = cross - com_ref_;
  step.z() = 0.0;
  const double size = step.norm(), max_step = kTrotStartShiftSpeed * dt_;
  com_ref_ += size > max_step ? Vec3((max_step / size) * step) : step;
  if ((size <= max_step && off < kTrotStartShiftTolerance) ||
      time_ >= p_.start_delay + kTrotStartShiftMaxWait)
    start_shifted_ = true;
  return start_shifted_;
}

// The first pair (LF-RH) lifts unload_time after the trot clock starts, once
// its feet have handed their load to the other pair.
double TrotGait::cycles() const { return (trot_time_ - t().unload_time) / t().cycle_time; }

double TrotGait::swingFraction() const {
  const double set = 1.0 - t().duty_factor;
  const double needed = std::fabs(speed_) / kTrotMaxSwingSpeed;  // [-] stride / period at the swing speed limit
  if (needed <= set) return set;
  return needed < 0.5 ? needed : 0.5;
}

double TrotGait::stanceFraction() const {
  // duty_factor itself while the swing is as set: 1 - (1 - d) need not be d
  // to the last bit, and the footholds of a trot at set timing stay as they were.
  const double swing = swingFraction();
  return swing > 1.0 - t().duty_factor ? 1.0 - swing : t().duty_factor;
}

double TrotGait::legCyclePhase(int leg) const { return frac(cycles() - 0.5 * pairOf(leg)); }

long TrotGait::legCycleIndex(int leg) const {
  return static_cast<long>(std::floor(cycles() - 0.5 * pairOf(leg)));
}

bool TrotGait::liftoffDue(int leg) const {
  return legs_.liftoffDue(leg, legCyclePhase(leg), legCycleIndex(leg), swingFraction());
}

void TrotGait::updateCommands(bool running, double friction) {
  // One ramp for both commands, so that a turn keeps its radius while the
  // speed builds up: 0..1 at acceleration / max(|speed|, 0.1 m/s) per second.
  const bool stop = t().walk_time > 0.0 && time_ >= p_.start_delay + t().walk_time;
  const double scale = std::fabs(p_.speed) > 0.1 ? std::fabs(p_.speed) : 0.1;  // [m/s]
  // Cautiousness: at most speed_per_mu x the lowest mu in use; the ramp's
  // target is that share of the commanded speed (and so of the yaw rate).
  double cautious = 1.0;
  if (t().speed_per_mu > 0.0 && friction < kNoFrictionLimit) {
    const double limit = t().speed_per_mu * (friction > 0.0 ? friction : 0.0);  // [m/s]
    if (limit < scale) cautious = limit / scale;
  }
  const double target = running && !stop ? cautious : 0.0;
  const double step = t().acceleration / scale * dt_;  // [-] per tick
  const double before = ramp_;
  if (ramp_ < target) ramp_ = ramp_ + step < target ? ramp_ + step : target;
  if (ramp_ > target) ramp_ = ramp_ - step > target ? ramp_ - step : target;
  speed_ = ramp_ * p_.speed;
  yaw_rate_ = ramp_ * p_.yaw_rate;
  speed_rate_ = (ramp_ - before) * p_.speed / dt_;
  if (stop && ramp_ <= 0.0) stopping_ = true;
}

Vec3 TrotGait::foothold(int leg, double s, const Vec3& base_world, const Vec3& com_vel,
                        const TerrainEstimator& terrain) const {
  const double c = std::cos(yaw_), sn = std::sin(yaw_);
  const Vec3& nom = nominal_feet_base_.col(leg);
  const Vec3 hip_offset(c * nom.x() - sn * nom.y(), sn * nom.x() + c * nom.y(), 0.0);  // [m] W, from the base
  const double swing_duration = swingFraction() * t().cycle_time;
  const double stance_duration = stanceFraction() * t().cycle_time;
  const Vec3 velocity(com_vel.x(), com_vel.y(), 0.0);
  const Vec3 command(speed_ * c - yaw_rate_ * hip_offset.y(), speed_ * sn + yaw_rate_ * hip_offset.x(), 0.0);
  // Where the hip will be at touch-down, then the neutral point half a
  // stance ahead of it at the commanded velocity (turning: the hip's own
  // velocity on the turn), then Raibert's correction.
  const double to_touchdown = (1.0 - clamp01(s)) * swing_duration;  // [s]
  Vec3 foot = base_world + hip_offset + to_touchdown * velocity + (0.5 * stance_duration) * command;
  Vec3 correction = t().foothold_gain * (velocity - Vec3(speed_ * c, speed_ * sn, 0.0));
  const double size = correction.norm();
  if (size > t().max_foothold_correction) correction *= t().max_foothold_correction / size;
  foot += correction;
  foot.z() = terrain.heightAt(foot.x(), foot.y());
  return foot;
}

void TrotGait::update(const GaitInput& in, const TerrainEstimator& terrain, GaitOutput& out) {
  time_ += dt_;
  const bool shifted = startShift(in, terrain);  // the CoM over the diagonals' crossing first
  const bool running = p_.walk && time_ >= p_.start_delay && shifted;
  updateCommands(running && !in.paused, in.friction);
  const bool lifting = running && !stopping_;  // lift-offs (and the unloading before them) go on
  const double swing_frac = swingFraction();
  const double swing_duration = swing_frac * t().cycle_time;

  // The clock waits while a foot searches for the ground and another is due
  // to lift or unloading for it: two feet must carry the robot.
  bool wait = false;
  if (legs_.anySearching() && lifting) {
    for (int i = 0; i < 4; ++i) {
      if (legs_.phase[i] != LegPhase::kStance) continue;
      if (liftoffDue(i) || (1.0 - legCyclePhase(i)) * t().cycle_time < t().unload_time) wait = true;
    }
  }
  // Freezing called mid-swing: the foot goes straight down where it is.
  if (in.paused) legs_.dropSwingingFeet(in.feet_world, terrain, 0.0);
  const bool clock_runs = running && !in.paused && !wait;
  if (clock_runs) trot_time_ += dt_;

  out.phase = frac(cycles());
  out.touchdown_event = LegMask();
  out.liftoff_event = LegMask();
  out.swing_leg = kNumLegs;
  out.stance_mask = LegMask();

  for (int i = 0; i < 4; ++i) {
    const double psi = legCyclePhase(i);
    const long idx = legCycleIndex(i);
    const bool touching = in.touchdown_mask.has(i);
    switch (legs_.phase[i]) {
      case LegPhase::kStance:
        if (clock_runs && lifting && liftoffDue(i))
          legs_.liftOff(i, idx, in.feet_world.col(i), foothold(i, 0.0, in.foothold_origin, in.com_vel_world, terrain),
                        out);
        break;
      case LegPhase::kSwing: {
        const double s = (legs_.lifted_cycle[i] == idx && psi < swing_frac) ? psi / swing_frac : 1.0;
        // The foothold follows the measured velocity until the foot comes down.
        if (s < p_.touchdown_min_swing) legs_.foothold[i] = foothold(i, s, in.foothold_origin, in.com_vel_world, terrain);
        legs_.endSwing(i, s, p_.touchdown_min_swing, touching, time_, in.normal_force[i], p_.ramp_force, out);
        break;
      }
      case LegPhase::kSearch:
        legs_.search(i, searchSpeed(in.paused), dt_, touching, p_.touchdown_search_max, time_, in.normal_force[i],
                     p_.ramp_force, out);
        break;
    }

    out.swing_late[i] = legs_.swingLate(i, psi, swing_frac, p_.touchdown_min_swing);
    out.foot_vel_des[i].setZero();
    out.foot_acc_des[i].setZero();
    out.leg_phase[i] = legs_.phase[i];
    out.unloading[i] = false;
    if (legs_.phase[i] == LegPhase::kStance) {
      out.stance_mask.set(i);
      out.foot_des[i] = in.feet_world.col(i);
      double load = clamp01((time_ - legs_.touchdown_time[i]) / t().load_time);
      if (lifting) load = stanceLoad(load, liftoffDue(i), (1.0 - psi) * t().cycle_time, t().unload_time, out.unloading[i]);
      out.load[i] = load;
    } else if (legs_.phase[i] == LegPhase::kSwing) {
      if (out.swing_leg == kNumLegs) out.swing_leg = i;
      out.load[i] = 0.0;
      const double s = (psi < swing_frac) ? psi / swing_frac : 1.0;
      Vec3 pos, vel, acc;
      trotSwingReference(legs_.liftoff_pos[i], legs_.foothold[i], s, swing_duration, t(), pos, vel, acc);
      out.foot_des[i] = pos;
      out.foot_vel_des[i] = in.paused ? Vec3::Zero() : vel;
      out.foot_acc_des[i] = in.paused ? Vec3::Zero() : acc;
    } else {
      if (out.swing_leg == kNumLegs) out.swing_leg = i;
      out.load[i] = 0.0;
      legs_.searchReference(i, searchSpeed(in.paused), out);
    }
  }

  // The body: the CoM reference moves at the commanded velocity along the
  // heading, which turns at the commanded yaw rate.
  const double c = std::cos(yaw_), sn = std::sin(yaw_);
  const Vec3 heading(c, sn, 0.0), lateral(-sn, c, 0.0);
  out.com_vel_des.setZero();
  out.com_acc_des.setZero();
  if (running && !in.paused) {
    yaw_ += yaw_rate_ * dt_;
    com_ref_ += (speed_ * dt_) * heading;
    Vec3 error = com_ref_ - in.com_world;
    error.z() = 0.0;
    const double size = error.norm();
    if (size > t().max_com_error) com_ref_ -= (1.0 - t().max_com_error / size) * error;
    out.com_vel_des = speed_ * heading;
    out.com_acc_des = speed_rate_ * heading + (speed_ * yaw_rate_) * lateral;
  }
  out.com_des = com_ref_;
  out.yaw_des = yaw_;
  loadRampCaps(p_.ramp_force, legs_.touchdown_force, out);
}

}  // namespace hyq
