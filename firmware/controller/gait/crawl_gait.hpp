// Statically stable crawl: one leg swings at a time; before each lift-off the
// CoM shifts into the support triangle of the three remaining feet.
//
// The planner owns each leg's stance/swing state. The schedule decides
// lift-off; touch-down is detected by the controller (force threshold) and
// accepted only late in the swing. A foot that reaches the end of its swing
// without contact keeps lowering (searching) before it is declared in stance.
#pragma once
#include <cstdint>

#include "firmware/controller/gait/gait.hpp"
#include "firmware/controller/gait/gait_common.hpp"

namespace hyq {

// [m/s^2] The deceleration the feet's friction can give a body shift along
// `shift` (W) on ground of normal n (W), with usable friction ratio
// `traction` along any direction, while they hold the slope's pull: braking
// at a along d, the feet push m (a d + g sin(theta) f) along the ground (f
// the fall line, down), within traction m g cos(theta) for a <= g
// (sqrt((traction cos(theta))^2 - (sin(theta) sin(phi))^2) - sin(theta)
// cos(phi)), phi between the shift and f. Down the fall line that is
// g (traction cos(theta) - sin(theta)); up it gravity helps (a shift the
// feet cannot speed up uphill lags, and the lift-off waits for it). At
// least kSlopeShiftMinAcceleration; 0 (no bound) on ground tilted less than
// kSlopeShiftMinTilt, for no shift, or with no traction known (recovery off).
double slopeShiftDeceleration(const Vec3& shift, const Vec3& n, double traction);

class CrawlGait final : public Gait {
 public:
  void reset(const GaitParams& params, double dt, const GaitInput& start, double yaw,
             const Mat3x4& nominal_feet_base) override;
  void update(const GaitInput& in, const TerrainEstimator& terrain, GaitOutput& out) override;
  // Re-plan the body shift from where the robot is.
  void replanFrom(const Vec3& com_world) override;
  LegPhase legPhase(int leg) const { return legs_.phase[leg]; }

 private:
  double swingFraction() const { return 1.0 - p_.duty_factor; }
  double cycles() const;                       // gait time in cycles since phase 0
  double legCyclePhase(int leg) const;         // [0,1): 0 at this leg's lift-off
  long legCycleIndex(int leg) const;
  // This cycle's lift-off of `leg` is due (its swing window is open) and not done yet.
  bool liftoffDue(int leg) const;
  // Within unload_time of its lift-off: its force limit ramps down.
  bool unloadingDue(int leg) const;
  Vec3 footholdFor(int leg, const Mat3x4& feet_world, const TerrainEstimator& terrain) const;
  Vec3 shiftTarget(int leg, const Mat3x4& feet_world, const Vec3& com_world) const;
  int nextLiftoffLeg() const;
  // The tick's clocks: whether the crawl has started, whether its gait
  // clock runs (no foot searching, the CoM ready for the next lift-off, not
  // frozen) and whether the body shift's clock runs.
  struct Clocks {
    bool running = false;
    bool gait_runs = false;
    bool shift_runs = false;
  };
  // The trunk tips toward the foot that lifts or swings (kCrawlTipForce, kCrawlTipRate).
  bool tipping(const GaitInput& in) const;
  double searchSpeed(bool paused) const;
  // Advances the clocks, the wait for the CoM and the crouch.
  Clocks advanceClocks(const GaitInput& in, const TerrainEstimator& terrain);
  // Leg i's phase, load and foot reference for this tick (psi: its cycle phase).
  void legReference(int i, double psi, const GaitInput& in, bool running, GaitOutput& out);
  // The CoM reference: the body shift toward the next support triangle.
  void shiftBody(const GaitInput& in, const Vec3& ground_normal, const Clocks& clocks, GaitOutput& out);
  // A new shift toward leg `next`'s coming triangle (target_lost: the old
  // target left it, re-planned at reshift_speed).
  void planShift(int next, bool target_lost, const GaitInput& in, const Vec3& ground_normal);

  GaitParams p_{};
  double dt_ = kTickPeriod;
  double time_ = 0.0;        // [s] controller time since reset
  double gait_time_ = 0.0;   // [s] time the crawl clock has run
  double yaw_ = 0.0;
  Vec3 ref_start_ = Vec3::Zero();  // base origin at start: the line to walk along
  Mat3x4 nominal_feet_base_ = Mat3x4::Zero();

  GaitLegs legs_;

  // Body shift: from com_from_ at shift_start_ to com_target_ at shift_end_.
  int shift_leg_ = -1;
  Vec3 com_from_ = Vec3::Zero();
  Vec3 com_target_ = Vec3::Zero();
  double shift_start_ = 0.0, shift_end_ = 0.0;  // [s] on shift_clock_
  double shift_clock_ = 0.0;  // [s] runs while walking and not frozen
  double com_wait_ = 0.0;     // [s] the clock has waited this long for the CoM
  double crouch_ = 0.0;       // [m] below body_height, while a leg at its reach waits
  bool tipping_ = false;      // this tick: tipping()
  double reload_[4] = {0.0, 0.0, 0.0, 0.0};  // [-] load share an unloading foot took back while the trunk tipped
  bool dropping_ = false;     // a swinging foot put down by tipping(), until it stands
};

}  // namespace hyq
