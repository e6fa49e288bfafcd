// What the gaits share: the smooth blend and the normal-force caps of the
// load ramps.
#pragma once

#include "firmware/controller/gait.hpp"
#include "firmware/controller/terrain_estimator.hpp"
#include "firmware/controller/types.hpp"

namespace hyq {

// Quintic blend 0 -> 1 with zero velocity and acceleration at both ends, and its derivative.
double smoothStep(double s);
double smoothStepDerivative(double s);
double smoothStepSecondDerivative(double s);

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

}  // namespace hyq
