// What the gaits share: the smooth blend and the normal-force caps of the
// load ramps.
#pragma once

#include "firmware/controller/gait/gait.hpp"
#include "firmware/controller/state/terrain_estimator.hpp"
#include "firmware/controller/model/types.hpp"

namespace hyq {

// Quintic blend 0 -> 1 with zero velocity and acceleration at both ends, and its derivative.
double smoothStep(double s);
double smoothStepDerivative(double s);
double smoothStepSecondDerivative(double s);
// [-] The largest |smoothStepSecondDerivative|, 10 / sqrt(3), at
// s = (3 -+ sqrt(3)) / 6: a blend over distance d in time T accelerates at
// most this times d / T^2.
constexpr double kSmoothStepPeakSecondDerivative = 5.773502691896258;

// GaitOutput::max_normal_force from out.load, out.unloading and
// out.stance_mask: from what the swing PD pushed with at touch-down
// (touchdown_force [N], at most ramp_force) up to no cap, and down to zero
// before lift-off.
void loadRampCaps(double ramp_force, const double (&touchdown_force)[kNumLegs], GaitOutput& out);

// The load (0..1) of a stance foot's force cap: `after_touchdown` (its ramp
// since touch-down), down to 0 while its lift-off is due (another foot holds
// the clock), or down toward 0 over the last unload_time [s] before it
// (to_liftoff [s]); `unloading` says the ramp is the one down.
double stanceLoad(double after_touchdown, bool liftoff_due, double to_liftoff, double unload_time, bool& unloading);

// Each leg's stance/swing state as a gait keeps it, and the steps every gait
// takes the same way: lift-off, the swing's end, the search for the ground,
// touch-down with the force its load ramp starts from.
struct GaitLegs {
  LegPhase phase[kNumLegs] = {LegPhase::kStance, LegPhase::kStance, LegPhase::kStance, LegPhase::kStance};
  long lifted_cycle[kNumLegs] = {-1000, -1000, -1000, -1000};  // [-] the gait cycle of each leg's last lift-off
  Vec3 liftoff_pos[kNumLegs];   // [m] W
  Vec3 foothold[kNumLegs];      // [m] W, the swing's target
  double search_depth[kNumLegs] = {0, 0, 0, 0};  // [m] below the foothold, while searching
  double touchdown_time[kNumLegs] = {-1e9, -1e9, -1e9, -1e9};  // [s]
  double touchdown_force[kNumLegs] = {0, 0, 0, 0};  // [N] normal force at the last touch-down, <= ramp_force

  // Every leg in stance where it stands.
  void reset(const Mat3x4& feet_world);
  bool anySearching() const;
  // The gait's clock puts `leg` at phase psi of its cycle number `cycle`;
  // its swing takes the first swing_frac of each cycle.
  // Lift-off is due: in the swing window of a cycle it has not lifted in.
  bool liftoffDue(int leg, double psi, long cycle, double swing_frac) const {
    return psi < swing_frac && lifted_cycle[leg] != cycle;
  }
  // At the start: a leg whose swing window is already open (or ends there,
  // up to rounding) skips that cycle's swing instead of lifting unprepared.
  void skipOpenSwing(int leg, double psi, long cycle, double swing_frac) {
    if (psi < swing_frac + 1e-9) lifted_cycle[leg] = cycle;
  }
  // Searching, or swinging past the time or the fraction (min_swing) from
  // which a touch-down is accepted.
  bool swingLate(int leg, double psi, double swing_frac, double min_swing) const {
    return phase[leg] == LegPhase::kSearch ||
           (phase[leg] == LegPhase::kSwing && (psi >= swing_frac || psi / swing_frac >= min_swing));
  }
  void liftOff(int leg, long cycle, const Vec3& foot, const Vec3& target, GaitOutput& out);
  // A swing at fraction s (1: its time is over): touch-down when the foot
  // touches late enough (s >= min_swing), else a search from s = 1.
  void endSwing(int leg, double s, double min_swing, bool touching, double time, double normal_force,
                double ramp_force, GaitOutput& out);
  // One tick of search at `speed` [m/s]: touch-down on contact or at max_depth [m].
  void search(int leg, double speed, double dt, bool touching, double max_depth, double time, double normal_force,
              double ramp_force, GaitOutput& out);
  void touchDown(int leg, double time, double normal_force, double ramp_force, GaitOutput& out);
  // Freezing called mid-swing: each swinging foot is searched for straight
  // down from where it is, toward depth [m] below the estimated ground.
  void dropSwingingFeet(const Mat3x4& feet_world, const TerrainEstimator& terrain, double depth);
  // The search reference of `leg` at `speed` [m/s] (foot_des, foot_vel_des).
  void searchReference(int leg, double speed, GaitOutput& out) const;
};

// [N] the touch-down force a load ramp starts from: the measured normal
// force fn, within [0, ramp_force].
inline double touchdownForce(double fn, double ramp_force) {
  return fn < 0.0 ? 0.0 : (fn > ramp_force ? ramp_force : fn);
}

// ---- definitions (inline: the board build has no link-time optimisation,
// and the crawl's gait stage runs them every tick)


inline double smoothStep(double s) {
  if (s <= 0.0) return 0.0;
  if (s >= 1.0) return 1.0;
  return s * s * s * (10.0 + s * (-15.0 + 6.0 * s));
}

inline double smoothStepDerivative(double s) {
  if (s <= 0.0 || s >= 1.0) return 0.0;
  const double t = s * (1.0 - s);
  return 30.0 * t * t;
}

inline double smoothStepSecondDerivative(double s) {
  if (s <= 0.0 || s >= 1.0) return 0.0;
  return 60.0 * s * (1.0 - s) * (1.0 - 2.0 * s);
}

namespace gait_detail {

inline double clamp01(double x) { return x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x); }

}  // namespace gait_detail

inline double stanceLoad(double after_touchdown, bool liftoff_due, double to_liftoff, double unload_time, bool& unloading) {
  double load = after_touchdown;
  if (liftoff_due) {
    load = 0.0;  // lift-off is due but the clock waits for another foot
    unloading = true;
  } else if (to_liftoff < unload_time) {
    const double unload = gait_detail::clamp01(to_liftoff / unload_time);
    if (unload < load) {
      load = unload;
      unloading = true;
    }
  }
  return load;
}

inline void GaitLegs::reset(const Mat3x4& feet_world) {
  for (int i = 0; i < kNumLegs; ++i) {
    phase[i] = LegPhase::kStance;
    lifted_cycle[i] = -1000;
    liftoff_pos[i] = feet_world.col(i);
    foothold[i] = feet_world.col(i);
    search_depth[i] = 0.0;
    touchdown_time[i] = -1e9;
    touchdown_force[i] = 0.0;
  }
}

inline bool GaitLegs::anySearching() const {
  bool searching = false;
  for (int i = 0; i < kNumLegs; ++i) searching = searching || phase[i] == LegPhase::kSearch;
  return searching;
}

inline void GaitLegs::liftOff(int leg, long cycle, const Vec3& foot, const Vec3& target, GaitOutput& out) {
  phase[leg] = LegPhase::kSwing;
  lifted_cycle[leg] = cycle;
  liftoff_pos[leg] = foot;
  foothold[leg] = target;
  out.liftoff_event.set(leg);
}

inline void GaitLegs::endSwing(int leg, double s, double min_swing, bool touching, double time, double normal_force,
                        double ramp_force, GaitOutput& out) {
  if (s >= min_swing && touching) {
    touchDown(leg, time, normal_force, ramp_force, out);
  } else if (s >= 1.0) {
    phase[leg] = LegPhase::kSearch;
    search_depth[leg] = 0.0;
  }
}

inline void GaitLegs::search(int leg, double speed, double dt, bool touching, double max_depth, double time,
                      double normal_force, double ramp_force, GaitOutput& out) {
  search_depth[leg] += speed * dt;
  if (touching || search_depth[leg] >= max_depth) touchDown(leg, time, normal_force, ramp_force, out);
}

inline void GaitLegs::touchDown(int leg, double time, double normal_force, double ramp_force, GaitOutput& out) {
  phase[leg] = LegPhase::kStance;
  touchdown_time[leg] = time;
  touchdown_force[leg] = touchdownForce(normal_force, ramp_force);
  out.touchdown_event.set(leg);
}

inline void GaitLegs::dropSwingingFeet(const Mat3x4& feet_world, const TerrainEstimator& terrain, double depth) {
  for (int i = 0; i < kNumLegs; ++i) {
    if (phase[i] != LegPhase::kSwing) continue;
    const Vec3 foot = feet_world.col(i);
    foothold[i] = Vec3(foot.x(), foot.y(), terrain.heightAt(foot.x(), foot.y()) - depth);
    search_depth[i] = foothold[i].z() - foot.z();  // <= 0: starts where the foot is
    phase[i] = LegPhase::kSearch;
  }
}

inline void GaitLegs::searchReference(int leg, double speed, GaitOutput& out) const {
  out.foot_des[leg] = foothold[leg] - Vec3(0.0, 0.0, search_depth[leg]);
  out.foot_vel_des[leg] = Vec3(0.0, 0.0, -speed);
}

inline void loadRampCaps(double ramp_force, const double (&touchdown_force)[kNumLegs], GaitOutput& out) {
  for (int i = 0; i < kNumLegs; ++i) {
    const double load = out.load[i];
    out.max_normal_force[i] = kNoForceCap;
    if (load < 1.0 && out.stance_mask.has(i)) {
      const double ramp = ramp_force;
      out.max_normal_force[i] = out.unloading[i] ? load * ramp
                                                 : touchdown_force[i] + load * (ramp - touchdown_force[i]);
    }
  }
}

}  // namespace hyq
