// Slip detection for the stance feet (Focchi et al., Section 2, Algorithm 1),
// extended to two feet slipping at once with a short-time IMU integration.
//
// The test works on u_i = bv_fi + bw_b x bx_fi (foot velocity relative to the
// base, in B): every stance foot that does not slip has u_i = -bv_b, so the
// non-slipping feet agree with each other without any base-velocity estimate.
//
// Per tick, in order (see SlipDetector::update):
//  1. Median test (the paper): s_i = |u_i|, m = median over stance legs,
//     raw flag_i = |s_i - m| > threshold.
//     Creep test (>= 3 usable legs): each leg's u_i - median vector
//     (component-wise), low-passed over creep_filter_ticks; raw flag_i when
//     that exceeds creep_threshold. It sees a slow slide against the body's
//     motion, which barely changes |u_i|. A leg the norms flag this tick
//     holds its filter, and restarts it once its flag is up. Its flags count
//     only where they and the median's name one leg at most and the trust
//     gate (step 2) passes with them (two feet sliding together put the
//     median vector between the pairs).
//     Drag test (>= 3 usable legs, landing legs only): each landing leg's
//     deviation from the median vector less landing_drag_allowance, summed
//     over the ticks and floored at 0; past landing_drag_travel the leg is
//     in drag_mask (no slip flag: the crawl makes it touch down). A landing
//     leg too light to be watched (SlipInput::drag_only_mask) is tested
//     too, against the stance legs' median, without a share in it.
//  2. Trust gate: the median test is believed only if there are >= 3 stance
//     legs, it (with the creep test) flags at most one, and the legs it
//     leaves unflagged agree as vectors (pairwise |u_a - u_b| <=
//     holding_agreement). Two feet slipping together
//     break this: the norms become bimodal, the median sits between the
//     groups, and the "good" set no longer agrees. With 3 stance legs and one
//     flagged, two agreeing feet could as well be two feet sliding together:
//     if the IMU velocity is valid, their mean u must also match it
//     (|mean u + bv_b| <= multi_leg_consistency), otherwise step 3 decides.
//  3. Otherwise, if the IMU base velocity is valid, each stance leg is
//     flagged when |u_i + bv_b_imu| > multi_leg_consistency (IMU test).
//     Without a valid IMU velocity the median test's own flags are kept
//     (not the creep test's), marked unverified (the best the legs alone can
//     say).
//  4. Debounce per leg: the flag rises after debounce_ticks consecutive raw
//     detections, drops after release_ticks consecutive clear ticks, and drops
//     at once when the leg leaves stance (a lifted foot does not slip).
//
// The IMU integration that feeds step 3 is ImuVelocityIntegrator below; it is
// re-anchored from leg odometry only on ticks where at least 3 stance legs
// hold and agree within imu_anchor_agreement (SlipResult::legs_agree; a
// single slipping foot among four is excluded from the anchor), so a slip in
// progress does not corrupt it. Anchor on legs_agree and
// base_velocity_legs, not on "slip_mask == 0" with a filtered odometry: at
// the onset of a two-foot slip nothing is flagged yet (the median sees a
// bimodal set) while the legs' average is already corrupted; the IMU would
// follow it and the IMU test would never see the slip (or flag the wrong feet).
// Known limit: three feet sliding identically with one holding look like one
// foot slipping; the legs cannot tell that case apart.
// Wiring per tick (order matters: the anchor uses the previous tick's legs):
//   imu.update(f_b, R_wb, g_w, dt, last.base_velocity_legs, last.legs_agree);
//   in.imu_base_velocity = imu.velocityBase(); in.imu_velocity_valid = imu.valid();
//   last = detector.update(in);
#pragma once
#include <cstdint>

#include "firmware/controller/params.hpp"
#include "firmware/controller/model/types.hpp"

namespace hyq {

constexpr int kSlipLegs = kNumLegs;

// Base linear velocity from a short-time integration of the accelerometer,
// re-anchored from leg odometry whenever the legs can be trusted. Drift of an
// open-loop integration grows with time, so the estimate expires once it has
// run alone for longer than SlipParams::imu_integration_window; it becomes
// valid again at the next trusted anchor.
class ImuVelocityIntegrator {
 public:
  void reset(const SlipParams& params);

  // specific_force_base [m/s^2]: accelerometer reading, in B.
  // rotation_world_base: R_wb (orientation of B in W).
  // gravity_world [m/s^2]: e.g. (0, 0, -9.81).
  // dt [s]: tick period.
  // odometry_velocity_base [m/s]: leg-odometry base velocity (in B) of the
  //   previous tick, taken as the anchor when odometry_trusted is true.
  // First anchors (if trusted), then integrates this tick's acceleration.
  // Non-finite inputs are rejected: the state is kept, the clock still runs.
  void update(const Vec3& specific_force_base, const Mat3& rotation_world_base,
              const Vec3& gravity_world, double dt, const Vec3& odometry_velocity_base,
              bool odometry_trusted);

  // The longest integration without an anchor (SlipParams::imu_integration_window)
  // from now on, the state kept: for a gait switch.
  void setWindow(double window) { params_.imu_integration_window = window; }

  bool valid() const { return valid_; }
  Vec3 velocityWorld() const { return velocity_world_; }     // [m/s]
  Vec3 velocityBase() const { return velocity_base_; }       // [m/s]
  double timeSinceAnchor() const { return time_since_anchor_; }  // [s]

 private:
  SlipParams params_{};
  Vec3 velocity_world_ = Vec3::Zero();
  Vec3 velocity_base_ = Vec3::Zero();
  double time_since_anchor_ = 0.0;
  bool anchored_ = false;
  bool valid_ = false;
};

struct SlipInput {
  uint32_t stance_mask = 0;               // bit i: leg i in stance (watched)
  uint32_t landing_mask = 0;              // bit i: leg i watched while landing (SlipParams::landing_debounce_extra)
  uint32_t hold_mask = 0;                 // bit i: leg i in stance_mask whose detection holds this tick
  // bit i: landing leg i, not in stance_mask, that only the drag test
  // watches (a foot on the ground below the watch's force)
  uint32_t drag_only_mask = 0;
  Vec3 u[kSlipLegs] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
                                          // [m/s] bv_fi + bw_b x bx_fi, in B
  Mat3 rotation_world_base = Mat3::Identity();  // R_wb, for slip velocities in W
  Vec3 imu_base_velocity = Vec3::Zero();  // [m/s] bv_b from the IMU integration, in B
  // Ground normal in B: the tests use the velocities' parts along the ground
  // (slip velocities stay whole). Zero or non-finite: whole vectors.
  Vec3 ground_normal_base = Vec3::Zero();
  bool imu_velocity_valid = false;
  // The trot: two stance feet that the IMU test finds holding, unflagged and
  // agreeing within imu_anchor_agreement may anchor the IMU too (its
  // two-foot phases would otherwise outlast the integration window).
  bool anchor_on_two_feet = false;
};

enum class SlipTest : uint8_t {
  kNone = 0,            // fewer than 2 usable stance legs and no IMU velocity
  kMedian = 1,          // the paper's median test, confirmed by the trust gate
  kImu = 2,             // IMU consistency test (median test not trusted)
  kMedianUnverified = 3 // median not trusted and no IMU velocity: best effort
};

struct SlipResult {
  uint32_t slip_mask = 0;       // bit i: leg i slipping (debounced)
  uint32_t raw_mask = 0;        // bit i: this tick's detection before debounce
  SlipTest test = SlipTest::kNone;
  // bit i: landing leg i dragged along the ground past
  // SlipParams::landing_drag_travel (not a slip flag; the crawl makes it
  // touch down)
  uint32_t drag_mask = 0;
  double median_speed = 0.0;    // [m/s] m, median of |u_i| over stance legs
  // At least 3 stance legs hold (median test trusted) and agree within
  // imu_anchor_agreement: the legs' base velocity can anchor the IMU.
  bool legs_agree = false;
  // Reference u of a non-slipping foot (= -bv_b) and the base velocity it
  // implies; valid when slip velocities are.
  Vec3 u_reference = Vec3::Zero();         // [m/s] in B
  Vec3 base_velocity_legs = Vec3::Zero();  // [m/s] -u_reference, in B
  bool slip_velocity_valid = false;
  // v_i = R_wb (u_i - u_reference) for stance legs; zero for swing legs.
  Vec3 slip_velocity_world[kSlipLegs] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero(),
                                         Vec3::Zero()};  // [m/s] in W
};

class SlipDetector {
 public:
  void reset(const SlipParams& params);
  // One tick. A stance leg whose u is not finite is left out of the tests
  // (its debounce counters hold); a non-finite IMU velocity counts as invalid.
  SlipResult update(const SlipInput& in);
  uint32_t slipMask() const { return slip_mask_; }

 private:
  // The tests take the feet's velocities u[kSlipLegs] (along the ground, or
  // whole where the anchor needs their vertical part) and the IMU's.
  uint32_t medianTest(const Vec3* u, uint32_t usable, SlipResult& out) const;
  uint32_t imuTest(const Vec3* u, const Vec3& imu_base_velocity, uint32_t usable) const;
  bool agree(const Vec3* u, uint32_t legs, double tolerance) const;
  bool imuConfirms(const Vec3* u, const Vec3& imu_base_velocity, uint32_t legs) const;
  void debounce(uint32_t stance, uint32_t usable, uint32_t raw, uint32_t landing);
  void slipVelocities(const SlipInput& in, bool imu_valid, uint32_t usable, SlipResult& out) const;
  // Also sums each landing leg's drag (drag_travel_), and sets drag_mask.
  // drag_only: landing legs outside stance that only the drag test watches.
  uint32_t creepTest(const Vec3* u_along, uint32_t stance, uint32_t usable, uint32_t fast, uint32_t landing,
                     uint32_t drag_only, SlipResult& out);

  SlipParams params_{};
  // [m/s] each leg's low-passed deviation from the median vector, B
  Vec3 creep_[kSlipLegs] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
  // [m] each landing leg's travel against the median vector in excess of
  // landing_drag_allowance (a one-sided CUSUM, floored at 0)
  double drag_travel_[kSlipLegs] = {0.0, 0.0, 0.0, 0.0};
  int detect_count_[kSlipLegs] = {0, 0, 0, 0};
  int clear_count_[kSlipLegs] = {0, 0, 0, 0};
  uint32_t slip_mask_ = 0;
};

}  // namespace hyq
