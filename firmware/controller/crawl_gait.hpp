// Statically stable crawl: one leg swings at a time; before each lift-off the
// CoM shifts into the support triangle of the three remaining feet.
//
// The planner owns each leg's stance/swing state. The schedule decides
// lift-off; touch-down is detected by the controller (force threshold) and
// accepted only late in the swing. A foot that reaches the end of its swing
// without contact keeps lowering (searching) before it is declared in stance.
#pragma once
#include <cstdint>

#include "firmware/controller/params.hpp"
#include "firmware/controller/terrain_estimator.hpp"
#include "firmware/controller/types.hpp"

namespace hyq {

enum class LegPhase : uint8_t { kStance, kSwing, kSearch };

struct GaitInput {
  Mat3x4 feet_world;            // [m] estimated foot centres, W
  Vec3 base_world;              // [m] estimated base origin, W
  Vec3 com_world;               // [m] estimated CoM, W
  uint32_t touchdown_mask = 0;  // bit i: foot i pushes on the ground (force test)
  bool paused = false;          // freezing: the gait clock stops
};

struct GaitOutput {
  double phase = 0.0;           // [-] crawl phase 0..1
  int swing_leg = 4;            // [-] leg in swing or search, 4 if none
  uint32_t stance_mask = 0xF;   // bit i: leg i in stance (controller's view)
  uint32_t touchdown_event = 0; // bit i: leg i touched down this tick
  uint32_t liftoff_event = 0;   // bit i: leg i lifted off this tick
  double load[4] = {1, 1, 1, 1};  // [-] 0..1 ramp of the foot's normal-force cap (1: no cap)
  bool unloading[4] = {false, false, false, false};  // ramp toward lift-off (else after touch-down)
  bool swing_late[4] = {false, false, false, false};  // swing past touchdown_min_swing, or searching
  Vec3 foot_des[4];             // [m] swing foot reference, W (stance: unused)
  Vec3 foot_vel_des[4];         // [m/s] swing foot velocity reference, W
  Vec3 com_des;                 // [m] CoM reference (x, y; z left to the caller), W
  Vec3 com_vel_des;             // [m/s]
  Vec3 com_acc_des;             // [m/s^2]
  double yaw_des = 0.0;         // [rad] heading to hold
};

class CrawlGait {
 public:
  // feet/base/com: the state at start (robot standing). nominal_feet_base:
  // the stand-posture foot positions in B, the footholds' pattern.
  void reset(const GaitParams& params, double dt, const GaitInput& start, double yaw,
             const Mat3x4& nominal_feet_base);
  void update(const GaitInput& in, const TerrainEstimator& terrain, GaitOutput& out);
  LegPhase legPhase(int leg) const { return leg_phase_[leg]; }
  // Re-plan the body shift from where the robot is (after freezing).
  void replanFrom(const Vec3& com_world);

 private:
  double swingFraction() const { return 1.0 - p_.duty_factor; }
  double cycles() const;                       // gait time in cycles since phase 0
  double legCyclePhase(int leg) const;         // [0,1): 0 at this leg's lift-off
  long legCycleIndex(int leg) const;
  Vec3 footholdFor(int leg, const Mat3x4& feet_world, const TerrainEstimator& terrain) const;
  Vec3 shiftTarget(int leg, const Mat3x4& feet_world, const Vec3& com_world) const;
  int nextLiftoffLeg() const;

  GaitParams p_{};
  double dt_ = 0.001;
  double time_ = 0.0;        // [s] controller time since reset
  double gait_time_ = 0.0;   // [s] time the crawl clock has run
  double yaw_ = 0.0;
  Vec3 ref_start_ = Vec3::Zero();  // base origin at start: the line to walk along
  Mat3x4 nominal_feet_base_ = Mat3x4::Zero();

  LegPhase leg_phase_[4] = {LegPhase::kStance, LegPhase::kStance, LegPhase::kStance,
                            LegPhase::kStance};
  long lifted_cycle_[4] = {-1000, -1000, -1000, -1000};
  Vec3 liftoff_pos_[4];
  Vec3 foothold_[4];
  double search_depth_[4] = {0, 0, 0, 0};
  double touchdown_time_[4] = {-1e9, -1e9, -1e9, -1e9};

  // Body shift: from com_from_ at shift_start_ to com_target_ at shift_end_.
  int shift_leg_ = -1;
  Vec3 com_from_ = Vec3::Zero();
  Vec3 com_target_ = Vec3::Zero();
  double shift_start_ = 0.0, shift_end_ = 0.0;  // [s] on shift_clock_
  double shift_clock_ = 0.0;  // [s] runs while walking and not frozen
};

// Quintic blend 0 -> 1 with zero velocity and acceleration at both ends, and its derivative.
double smoothStep(double s);
double smoothStepDerivative(double s);
double smoothStepSecondDerivative(double s);

}  // namespace hyq
