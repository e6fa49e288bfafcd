// The gait interface: what the controller hands a gait each tick and what it
// gets back. The crawl (crawl_gait.hpp) and the trot (trot_gait.hpp)
// implement the same three calls; GaitParams::kind picks the one in use, and
// the rest of the controller stays as it is.
//
// A gait owns each leg's stance/swing state and the touch-down bookkeeping:
// the load ramps of the feet's normal-force caps, from the force a foot
// pushed with when it touched down.
#pragma once
#include <cstdint>
#include <new>

#include "firmware/controller/params.hpp"
#include "firmware/controller/state/terrain_estimator.hpp"
#include "firmware/controller/model/types.hpp"

namespace hyq {

enum class LegPhase : uint8_t { kStance, kSwing, kSearch };

// [N] GaitOutput::max_normal_force of a foot whose force is not capped.
constexpr double kNoForceCap = 1e9;
constexpr double kNoFrictionLimit = 1e9;  // [-] GaitInput::friction: no limit

struct GaitInput {
  Mat3x4 feet_world;            // [m] estimated foot centres, W
  Vec3 base_world;              // [m] estimated base origin, W
  Vec3 com_world;               // [m] estimated CoM, W
  // [m] W: where the trot centres its footholds: the base origin moved by
  // the CoM offset estimate (EstimatorParams::com_offset_time; the base
  // origin itself while that is off), so that each diagonal's line passes
  // under the real CoM, not the model's.
  Vec3 foothold_origin = Vec3::Zero();
  Vec3 com_vel_world = Vec3::Zero();  // [m/s] estimated CoM velocity, W
  Vec3 omega_world = Vec3::Zero();    // [rad/s] the trunk's angular velocity, W
  LegMask touchdown_mask;       // feet on the ground (force test, or flagged sliding)
  double normal_force[kNumLegs] = {0, 0, 0, 0};  // [N] estimated GRF along the terrain normal
  bool paused = false;          // freezing: the gait clock stops
  // [-] the lowest mu in use of the four feet, at RecoveryParams::mu_floor
  // at least (the trot's cautiousness, TrotParams::speed_per_mu); the
  // default sets no limit.
  double friction = kNoFrictionLimit;
  // [-] the friction ratio the QP may use along any direction: the lowest mu
  // in use times the pyramid's scale (the crawl's shifts on a slope); the
  // default sets no limit.
  double traction = kNoFrictionLimit;
};

struct GaitOutput {
  double phase = 0.0;           // [-] gait phase 0..1
  int swing_leg = kNumLegs;     // [-] a leg in swing or search, kNumLegs if none
  LegMask stance_mask = LegMask::all();  // legs in stance (controller's view)
  LegMask touchdown_event;      // legs that touched down this tick
  LegMask liftoff_event;        // legs that lifted off this tick
  LegPhase leg_phase[kNumLegs] = {LegPhase::kStance, LegPhase::kStance, LegPhase::kStance,
                                  LegPhase::kStance};
  double load[kNumLegs] = {1, 1, 1, 1};  // [-] 0..1 ramp of the foot's normal-force cap (1: no cap)
  bool unloading[kNumLegs] = {false, false, false, false};  // ramp toward lift-off (else after touch-down)
  bool swing_late[kNumLegs] = {false, false, false, false};  // swing past touchdown_min_swing, or searching
  // [N] cap on each stance foot's normal force (kNoForceCap: none): from the
  // force it touched down with up to ramp_force after touch-down, and down
  // to zero before lift-off, so that no foot's force steps.
  double max_normal_force[kNumLegs] = {kNoForceCap, kNoForceCap, kNoForceCap, kNoForceCap};
  Vec3 foot_des[kNumLegs] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};  // [m] swing foot reference, W
  Vec3 foot_vel_des[kNumLegs] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};  // [m/s] W
  // [m/s^2] W, the swing reference's acceleration: the trot's legs get its
  // inertia feed-forward (the crawl leaves it zero and gets none).
  Vec3 foot_acc_des[kNumLegs] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
  Vec3 com_des = Vec3::Zero();      // [m] CoM reference (x, y; z left to the caller), W
  Vec3 com_vel_des = Vec3::Zero();  // [m/s]
  Vec3 com_acc_des = Vec3::Zero();  // [m/s^2]
  double yaw_des = 0.0;         // [rad] heading to hold
  double crouch = 0.0;          // [m] trunk this far below the gait's body height
};

// Back to a fresh plan, in place: a plan is about 500 bytes, and an
// assignment from a temporary builds it and then copies it.
inline void clearPlan(GaitOutput& plan) {
  plan.~GaitOutput();
  ::new (&plan) GaitOutput();
}

class Gait {
 public:
  // start: the state at start (robot standing); nominal_feet_base: the
  // stand-posture foot positions in B, the footholds' pattern.
  virtual void reset(const GaitParams& params, double dt, const GaitInput& start, double yaw,
                     const Mat3x4& nominal_feet_base) = 0;
  virtual void update(const GaitInput& in, const TerrainEstimator& terrain, GaitOutput& out) = 0;
  // Re-plan the body's motion from where the robot is (after freezing or a bad frame).
  virtual void replanFrom(const Vec3& com_world) = 0;

 protected:
  ~Gait() = default;  // not deleted through the interface: no heap
};

}  // namespace hyq
