// Trot: the diagonal pairs LF-RH and RF-LH swing in turn, each for
// (1 - duty_factor) of the period; with a duty factor above 0.5 all four feet
// stand together twice a cycle, when the load passes from one pair to the
// other. Balance is dynamic: while two feet stand, the body is kept up by
// placing the next pair's feet where its velocity needs them (a Raibert
// foothold: the hip's place at touch-down, half the stance's travel ahead at
// the commanded velocity, plus a gain times the velocity error).
//
// Commands: forward speed and yaw rate (GaitParams::speed, yaw_rate), ramped
// from standing at TrotParams::acceleration, and back to zero and standing
// after TrotParams::walk_time. Cautious on ice: the speed is held to
// TrotParams::speed_per_mu times the lowest mu in use (GaitInput::friction),
// the yaw rate in proportion. As in the crawl, the schedule decides
// lift-off; touch-down is the controller's force test, accepted late in the
// swing; a foot that has not touched down at the end of its swing keeps
// lowering (searching), and no foot lifts while another searches.
#pragma once
#include <cstdint>

#include "firmware/controller/gait/gait.hpp"
#include "firmware/controller/gait/gait_common.hpp"

namespace hyq {

// The trot's swing foot reference at swing fraction s (0 at lift-off, 1 at
// the end of the swing; TrotParams::landing_fraction, step_height,
// touchdown_speed): position [m], velocity [m/s] and acceleration [m/s^2], W.
void trotSwingReference(const Vec3& liftoff, const Vec3& foothold, double s, double swing_duration,
                        const TrotParams& trot, Vec3& position, Vec3& velocity, Vec3& acceleration);

class TrotGait final : public Gait {
 public:
  void reset(const GaitParams& params, double dt, const GaitInput& start, double yaw,
             const Mat3x4& nominal_feet_base) override;
  void update(const GaitInput& in, const TerrainEstimator& terrain, GaitOutput& out) override;
  // Re-plan the body's motion from where the robot is: the CoM reference
  // restarts there.
  void replanFrom(const Vec3& com_world) override;

  LegPhase legPhase(int leg) const { return legs_.phase[leg]; }
  // [m/s], [rad/s] the commands after their ramps.
  double speedCommand() const { return speed_; }
  double yawRateCommand() const { return yaw_rate_; }
  // [-] the pair a leg belongs to: 0 for LF and RH, 1 for RF and LH.
  static int pairOf(int leg) { return (leg == 0 || leg == 3) ? 0 : 1; }
  // [-] 0..1: where the leg is in its own cycle, 0 at its lift-off.
  double legCyclePhase(int leg) const;
  // [m] W: where a leg in swing at swing fraction s would land, for the base
  // at base_world moving at com_vel (W) and the commands as they are.
  Vec3 foothold(int leg, double s, const Vec3& base_world, const Vec3& com_vel,
                const TerrainEstimator& terrain) const;

 private:
  const TrotParams& t() const { return p_.trot; }
  // [-] the swing's share of the period: 1 - duty_factor, lengthened at
  // speed to keep the swing foot within kTrotMaxSwingSpeed (at most 0.5).
  double swingFraction() const;
  double stanceFraction() const;              // [-] 1 - swingFraction()
  double cycles() const;                       // trot time in cycles since phase 0
  long legCycleIndex(int leg) const;
  bool liftoffDue(int leg) const;              // its swing window is open and it has not lifted in it
  // [m/s] a searching foot's speed: freezing puts a swinging foot down faster.
  double searchSpeed(bool paused) const { return paused ? p_.freeze_drop_speed : t().touchdown_speed; }
  void updateCommands(bool running, double friction);
  // Before the first lift-off on a slope, or on level ground with the CoM
  // off the crossing: moves the CoM reference toward the point where the
  // diagonals LF-RH and RF-LH cross (horizontal), and says whether the trot
  // may start (kTrotStartShiftSpeed, Tolerance, MaxWait).
  bool startShift(const GaitInput& in, const TerrainEstimator& terrain);

  GaitParams p_{};
  double dt_ = kTickPeriod;
  double time_ = 0.0;       // [s] controller time since reset
  double trot_time_ = 0.0;  // [s] time the trot clock has run
  double yaw_ = 0.0;        // [rad] heading reference
  double ramp_ = 0.0;       // [-] 0..1: the commands' share of GaitParams::speed and yaw_rate
  double speed_ = 0.0;      // [m/s] speed command after its ramp
  double yaw_rate_ = 0.0;   // [rad/s] yaw-rate command after its ramp
  double speed_rate_ = 0.0; // [m/s^2] d(speed_)/dt this tick
  bool stopping_ = false;   // walk_time is over and the commands are zero: no more lift-offs
  Vec3 com_ref_ = Vec3::Zero();  // [m] W, CoM reference (x, y)
  bool start_shifted_ = true;    // the start shift is over (or none is needed)
  bool start_checked_ = false;   // on level ground: the CoM's distance to the crossing is known
  bool far_start_ = false;       // it was kTrotStartShiftTolerance or more at the first tick
  Mat3x4 nominal_feet_base_ = Mat3x4::Zero();

  GaitLegs legs_;
};

}  // namespace hyq
