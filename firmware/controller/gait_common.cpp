#include "firmware/controller/gait_common.hpp"

namespace hyq {

double smoothStep(double s) {
  if (s <= 0.0) return 0.0;
  if (s >= 1.0) return 1.0;
  return s * s * s * (10.0 + s * (-15.0 + 6.0 * s));
}

double smoothStepDerivative(double s) {
  if (s <= 0.0 || s >= 1.0) return 0.0;
  const double t = s * (1.0 - s);
  return 30.0 * t * t;
}

double smoothStepSecondDerivative(double s) {
  if (s <= 0.0 || s >= 1.0) return 0.0;
  return 60.0 * s * (1.0 - s) * (1.0 - 2.0 * s);
}

namespace {

double clamp01(double x) { return x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x); }

}  // namespace

double stanceLoad(double after_touchdown, bool liftoff_due, double to_liftoff, double unload_time, bool& unloading) {
  double load = after_touchdown;
  if (liftoff_due) {
    load = 0.0;  // lift-off is due but the clock waits for another foot
    unloading = true;
  } else if (to_liftoff < unload_time) {
    const double unload = clamp01(to_liftoff / unload_time);
    if (unload < load) {
      load = unload;
      unloading = true;
    }
  }
  return load;
}

void GaitLegs::reset(const Mat3x4& feet_world) {
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

bool GaitLegs::anySearching() const {
  bool searching = false;
  for (int i = 0; i < kNumLegs; ++i) searching = searching || phase[i] == LegPhase::kSearch;
  return searching;
}

void GaitLegs::liftOff(int leg, long cycle, const Vec3& foot, const Vec3& target, GaitOutput& out) {
  phase[leg] = LegPhase::kSwing;
  lifted_cycle[leg] = cycle;
  liftoff_pos[leg] = foot;
  foothold[leg] = target;
  out.liftoff_event.set(leg);
}

void GaitLegs::endSwing(int leg, double s, double min_swing, bool touching, double time, double normal_force,
                        double ramp_force, GaitOutput& out) {
  if (s >= min_swing && touching) {
    touchDown(leg, time, normal_force, ramp_force, out);
  } else if (s >= 1.0) {
    phase[leg] = LegPhase::kSearch;
    search_depth[leg] = 0.0;
  }
}

void GaitLegs::search(int leg, double speed, double dt, bool touching, double max_depth, double time,
                      double normal_force, double ramp_force, GaitOutput& out) {
  search_depth[leg] += speed * dt;
  if (touching || search_depth[leg] >= max_depth) touchDown(leg, time, normal_force, ramp_force, out);
}

void GaitLegs::touchDown(int leg, double time, double normal_force, double ramp_force, GaitOutput& out) {
  phase[leg] = LegPhase::kStance;
  touchdown_time[leg] = time;
  touchdown_force[leg] = touchdownForce(normal_force, ramp_force);
  out.touchdown_event.set(leg);
}

void GaitLegs::dropSwingingFeet(const Mat3x4& feet_world, const TerrainEstimator& terrain, double depth) {
  for (int i = 0; i < kNumLegs; ++i) {
    if (phase[i] != LegPhase::kSwing) continue;
    const Vec3 foot = feet_world.col(i);
    foothold[i] = Vec3(foot.x(), foot.y(), terrain.heightAt(foot.x(), foot.y()) - depth);
    search_depth[i] = foothold[i].z() - foot.z();  // <= 0: starts where the foot is
    phase[i] = LegPhase::kSearch;
  }
}

void GaitLegs::searchReference(int leg, double speed, GaitOutput& out) const {
  out.foot_des[leg] = foothold[leg] - Vec3(0.0, 0.0, search_depth[leg]);
  out.foot_vel_des[leg] = Vec3(0.0, 0.0, -speed);
}

void loadRampCaps(double ramp_force, const double (&touchdown_force)[kNumLegs], GaitOutput& out) {
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
