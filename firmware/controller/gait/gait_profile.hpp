// Every choice of the controller's stages that depends on the gait in use,
// in one plain struct, filled once when a gait is picked (at init, and at a
// switch from the crawl to the trot). The stages read the profile; none of
// them names the gait.
//
// The crawl lands its feet slowly and stands on three or four; the trot
// lands a diagonal pair at speed, and its landings slide by design. What
// differs follows from that (each field's reason is at its parameter in
// params.hpp).
#pragma once

#include "firmware/controller/params.hpp"

namespace hyq {

struct GaitProfile {
  GaitKind kind = GaitKind::kCrawl;  // the gait the profile is for

  // Slip detection.
  // [s] how long the IMU integration runs unanchored (the trot anchors it
  // in its four-foot hand-overs only: TrotParams::imu_integration_window;
  // the crawl: SlipParams::imu_integration_window).
  double imu_integration_window = 0.0;
  bool anchor_on_two_feet = false;        // the IMU anchor may rest on two agreeing feet (trot)
  // A landing foot still coming down toward the ground is in the air,
  // whatever its force reads (StanceParams::watch_approach_speed): the
  // crawl, and the trot on joints behind a torque loop.
  bool landing_approach_test = false;
  // A watched landing foot whose force dips is held, not restarted (crawl).
  bool hold_landing_dips = false;

  // Leg state and state estimate.
  // The GRF estimate takes out the links' share of the base's rotation
  // (EstimatorParams::grf_base_rotation, with the leg dynamics; trot).
  bool grf_base_rotation = false;
  // Only its angular acceleration's share, and only while the trunk turns
  // faster than kCrawlTurnAlphaMin (the same keys; crawl).
  bool grf_fast_turn = false;
  // The ground plane is refit through loaded feet only, not at a joint's
  // stop (trot: a foot can end its swing in the air).
  bool plane_through_loaded_feet = false;

  // Surface estimate.
  // The prior is the plane through the feet now, or their row's
  // (TrotParams::prior_from_feet_now); else each foot's local plane, with
  // the other row's as the alternative prior.
  bool prior_from_feet_now = false;
  bool peak_of_loaded_samples = false;    // TrotParams::peak_of_loaded_samples
  bool carry_over = false;                // samples kept across a foot's slides (TrotParams::carry_*)
  bool slip_along_ground = false;         // TrotParams::slip_along_ground

  // Traction recovery.
  double guess_delay = 0.0;               // [s] TrotParams::guess_delay; the crawl guesses at once
  bool guess_holds = false;               // RecoveryParams::guess_holds_for_stance (crawl)
  // A flagged foot is guessed down only while it carries at most
  // SlipParams::min_estimate_force (TractionRecovery::setGuessLoadLimit;
  // the trot behind a torque loop, whose landings skid and bounce for
  // 30-80 ms).
  bool guess_light_feet_only = false;
  // A loaded stance foot's guess starts at its force ratio (kStanceSlideAge;
  // the crawl behind a torque loop).
  bool guess_from_stance_ratio = false;
  double cone_force_offset = 0.0;         // [N] RecoveryParams::cone_force_offset (crawl), with recovery

  // Motion reference.
  bool stop_is_not_touchdown = false;     // a leg at a joint's stop reads the stop, not the ground (trot)
  bool drag_is_touchdown = false;         // a landing foot dragged below the slip threshold is down (crawl)
  // A landing foot on ground the friction map knows to be ice, not rising
  // (kKnownIceTouchdownRise), is down from kKnownIceTouchdownShare of
  // force_on (crawl: its press drags such a foot; a trot foot's swing,
  // stopping hard, reads 40 N with the foot in the air).
  bool early_touchdown_on_known_ice = false;
  bool switches_to_trot = false;          // GaitSchedule::trot_at is set (crawl)

  // Joint commands.
  bool press_landing_along_normal = false;  // StanceParams::press_landing_along_normal (crawl)
  bool swing_inertia_feedforward = false;   // the swing's inertia feed-forward (trot)
  // A landing foot on the ground pushes kLandingPressShare force_on along
  // the normal, fed forward (trot, joints behind a torque loop).
  bool landing_force_press = false;
  // Stance joints damped toward a holding foot's velocity, with joints
  // behind a torque loop (Controller::stanceHold). In the trot only a stance
  // foot that carries less than StanceParams::force_watch: on every stance
  // foot it gave trot_ice_patches on the hyq plant 47 false detections over
  // seeds 1-4 against 1 without, and no friction estimate.
  bool stance_hold = false;
  bool stance_hold_unloaded_only = false;
};

// The profile of `kind` under `params`.
GaitProfile gaitProfile(GaitKind kind, const Params& params);

}  // namespace hyq
