// Every tuning number of the controller, in one place, each with its unit.
// Physical numbers of the robot are in robot_params.hpp.
// Defaults are the values the project ships and the scenarios run with.
#pragma once
#include "firmware/controller/slip/friction_map.hpp"
#include "hal/frames.hpp"

namespace hyq {

struct QpParams {
  double regularisation = 1e-4;     // [-] Tikhonov weight on forces (per N^2, relative)
  // Extra weight on each stance foot's tangential force (in its cone's
  // frame). Internal forces (feet pushing against each other) leave the
  // wrench unchanged, so with force_smoothing only the weights on the forces
  // themselves remove them: 1e-4 alone keeps 98 % after 100 ticks, and a
  // foot that landed pushing sideways keeps pushing, at the edge of its cone
  // on ice; with 0.01, 13 % (tests/unit/grf_qp_test.cpp). 0.01 costs a 50 N
  // tangential force as much as a 5 N wrench error (docs/design-notes.md,
  // "A weight on tangential forces in the QP").
  double tangential_weight = 0.01;  // [-] per N^2, relative to the wrench error
  double wrench_weight_lin = 1.0;   // [-] weight of force rows of the wrench error
  double wrench_weight_ang = 1.0;   // [-] weight of moment rows of the wrench error
  double f_normal_min = 10.0;       // [N] min normal force on a stance foot
  double f_normal_max = 1000.0;     // [N] max normal force on a stance foot
  int max_iterations = 64;          // [-] active-set iteration bound (worst case)
  double force_smoothing = 0.5;     // [-] weight of ||f - f_previous||^2 vs the wrench error (controller's GRF QP)
  double feasibility_tolerance = 1e-9;  // [N] constraint violation accepted as satisfied
};

// Which gait the controller runs (both are held statically; the other one idles).
enum class GaitKind : uint8_t { kCrawl = 0, kTrot = 1 };

// The trot (trot_gait.hpp): diagonal pairs LF-RH and RF-LH swing in turn.
// Shared with the crawl (GaitParams): walk, speed, yaw_rate, body_height,
// start_delay, touchdown_min_swing, touchdown_search_max, freeze_drop_speed,
// ramp_force, max_tilt.
struct TrotParams {
  // HyQ-class robots trot at about 1.4-2 Hz with a duty factor of 0.5-0.65.
  double cycle_time = 0.6;          // [s] trot period (each pair swings once)
  // Above 0.5 both pairs stand together for (duty_factor - 0.5) cycle_time
  // twice a cycle: the load hand-over and the slip detector's IMU anchor
  // (it needs three feet that hold) happen there.
  double duty_factor = 0.6;         // [-] stance fraction of the cycle per leg
  double step_height = 0.08;        // [m] swing apex above the higher of lift-off and foothold
  // The swing's last part only lowers the foot, onto the foothold: from the
  // apex at mid-swing down to the estimated ground, reached at the end of
  // the swing at touchdown_speed, and on at that speed until the foot
  // touches down. At 2 m/s (a plain quintic down from 8 cm in 70 ms) a
  // landing foot hit with 1.2 kN and jolted the other feet into sliding.
  double landing_fraction = 0.2;    // [-] share of the swing at its end with the foot above its foothold
  double touchdown_speed = 0.4;     // [m/s] downward foot speed at the end of the swing, and of the search
  // The swing legs keep the crawl's joint gains (JointParams::swing_kp,
  // swing_kd) and get, in the trot only, the leg's inertia times their
  // reference's joint acceleration fed forward (GaitOutput::foot_acc_des):
  // the feet swing at up to 2.7 m/s and 50 m/s^2. Without it a hind foot
  // overshoots its foothold by 5 cm and lands sliding back at up to 1.2 m/s
  // (seed 1: 0.52 m/s median, 0.9 bounces per touch-down); with it 0.38 m/s
  // and 0.06.
  double load_time = 0.03;          // [s] after touch-down a foot's force limit ramps up over this
  double unload_time = 0.05;        // [s] a foot's force limit ramps down before lift-off
  // Foothold: the hip's place at touch-down, plus half the stance's travel at
  // the commanded velocity (the neutral point), plus this gain times the
  // measured minus the commanded velocity (Raibert's correction; the capture
  // point's sqrt(h / g) is 0.25 s at h = 0.6 m).
  double foothold_gain = 0.2;       // [s]
  double max_foothold_correction = 0.15;  // [m] |gain (v - v_cmd)| at most this
  // The commanded speed and yaw rate ramp from standing (and back to zero
  // when stopping) at this acceleration.
  double acceleration = 0.5;        // [m/s^2]
  // The CoM reference moves at the commanded velocity, kept within this of
  // the measured CoM (along the ground), so that a lag never winds up.
  double max_com_error = 0.05;      // [m]
  // The slip detector's IMU integration (SlipParams::imu_integration_window
  // in the crawl) is anchored to the legs only while three feet hold and
  // agree: in the trot, in the four-foot hand-overs, once every half period.
  // With the crawl's 0.2 s it lapses before each hand-over (0.24 s of two
  // feet, then a landing), where the median test, untrusted and without
  // the IMU, flags feet that hold: 155 false detections over seeds 1-32
  // (60 s each, up to 11 in a run); with 0.3 s or 0.4 s none. Its drift
  // over 0.4 s with the biases learnt is far below the 0.1 m/s its test
  // allows (SlipParams::multi_leg_consistency).
  double imu_integration_window = 0.4;  // [s]
  // On ODE every trot landing slides for a few ms, on any ground (the
  // impact pushes the foot along the ground before the simulator's bristle
  // friction holds it; MuJoCo's landings hold), and is flagged; with the
  // crawl's immediate guess toward the floor
  // (RecoveryParams::guess_floor_before_estimate) every foot's mu in use
  // sits at the floor (0.07) within 4 s on mu 0.8, since no trot stance
  // is slip-free long enough for mu to rise again. In the trot a flag that
  // rises within this long of touch-down starts the guess only once it has
  // lasted this long without an estimate; a later flag at once
  // (TractionRecovery::setGuessDelay). On a 0.35 rad ramp of mu 0.5, seeds
  // 1-100: 4 falls without the delay, none with it.
  double guess_delay = 0.03;        // [s]
  // A trot landing slides while its foot is loaded and the other pair's
  // feet are unloaded; their contacts compress and relax along the normal
  // (ODE, ice patches: +-0.05 m/s, the slip velocity 10-20 deg below the
  // ground), and the slip normal tilts by as much. In the trot the friction
  // and normal estimates take the slip velocity's part along the foot's
  // ground plane (its prior). Recovery off, ice patches, seeds 1-8: the
  // run's worst mu error 13-28 % with it and 24-35 % without, the normal's
  // 0.5-0.8 deg with it and 1.3-1.5 deg without.
  bool slip_along_ground = true;    // [-]
  // The prior of each foot's surface estimate (and the ground plane above)
  // in the trot: true, the plane through the feet at the last touch-down
  // (TerrainEstimator::normal), one instant's kinematics; false, the local
  // planes, which join the feet with footholds left a stride or two
  // earlier. Over a push those footholds sit 2-3 cm off in height (the
  // odometry drifts while slipping feet are left out of it) and tilt the
  // local plane by about 10 deg on flat ground; every mu taken against it
  // is then off by 40-100 % (trot_push_ice, seeds 1-32).
  bool prior_from_feet_now = true;  // [-]
  // Where the front and the hind feet stand on two slopes (a ramp's foot or
  // top) the plane of the four feet leans between them and is wrong for
  // both rows. With prior_from_feet_now, a foot whose row's local plane and
  // the other row's are further apart than prior_row_split, with the feet's
  // plane inside the arc between them (off their great circle by less than
  // half the split, at least prior_row_interior of the way from each as a
  // ratio of sines), takes its row's local plane as its prior
  // (TerrainEstimator::feetOrRowNormal). Over a push one row's local plane
  // tilts by its footholds' height drift (up to 10 deg) while the feet's
  // plane stays with the other's (at most 0.11 of the way across in the 7
  // trot_push_ice runs of 32 where it lay inside the arc); at a ramp's foot
  // or top it lies 0.15-0.5 of the way most of the time. trot_ramp at
  // 0.35 rad, seeds 1-32, recovery on: 8 falls with the feet's plane alone,
  // none with this. 0: off.
  double prior_row_split = 0.1;     // [rad]
  double prior_row_interior = 0.15; // [-]
  // A trot landing skids at impact (0.3-0.4 m/s, under 80 N or with a force
  // uncertain by ~10 N) and slides on, slower, while its load builds. In the
  // trot a slip event's peak speed, against which the estimate drops an
  // ending slide's samples (SlipParams::ending_slip_fraction), is taken over
  // the samples that pass the load and force-uncertainty gates only, so
  // that the impact's skid does not hide the slide. Ice patches, seeds 1-32,
  // leg-patches estimated of 640: with recovery 85 with it and 0 without (the
  // run's worst mu error 10 % at the median); without recovery 328 and 147.
  // In the crawl it is off: there it lets creep samples in on the ramp
  // without recovery (the run's worst mu error 34 % at the median with it,
  // 9 % without, seeds 1-16). With it, a
  // foot that stopped within the event (slip speed below min_slip_speed)
  // gives no more samples: on the trot ramp (mu 0.5) a hind foot's landing
  // slide stops and its contact rebounds inside the cone at 0.05-0.1 m/s,
  // which read as mu 0.12-0.15.
  bool peak_of_loaded_samples = true;  // [-]
  // A trot landing on ice slides for 15-25 ms after its impact, while the
  // force estimate still rings from it: a slide's 3-5 samples share one
  // error. A foot that slips again within carry_distance (horizontal) of
  // its last accepted sample, after a slip that gave fewer than
  // carry_max_samples (a longer slide stands on its own), keeps the earlier
  // samples in its estimate with the new slip's, until the new slip's own
  // samples (from its min_estimate_samples-th on) disagree with them: their
  // mean mu below the carried samples' by more than carry_agreement of it,
  // or above by more than carry_agreement_above (other ground: the carried
  // samples are dropped). A slide that reads lower is believed sooner than
  // one that reads higher: an estimate too low costs grip, one too high
  // asks the ice for friction it has not. The estimate is offered, as
  // without the carry-over, once the new slip has min_estimate_samples of
  // its own (docs/design-notes.md, "A trot slide's samples share one error"
  // and "Bad news sooner than good"). carry_distance 0: off.
  double carry_distance = 0.5;          // [m]
  double carry_agreement = 0.15;        // [-] the new slip's mean below the carried mean by this fraction
  double carry_agreement_above = 0.25;  // [-] ... above it by this fraction
  int carry_max_samples = 8;            // [-] a slip that gave this many of its own is not carried
  // Cautiousness (the paper's future work): with recovery, the trot's speed
  // and yaw-rate commands are held to at most speed_per_mu times the lowest
  // mu in use of the four feet (GaitInput::friction), reached at
  // `acceleration`. On good ground (mu in use 0.6) that is 4.5 m/s and never
  // binds; on ice whose slips have brought a foot's mu in use to the floor
  // (0.07) it is 0.53 m/s. A 1 m/s trot onto patches of mu 0.05
  // (trot_ice_fast.yaml), seeds 1-32: without it 3 falls, slips up to 429 ms
  // after detection; 10 m/s: none, 171 ms; 7.5: none, 111 ms; 5: none, but
  // 13 runs short of the goal (docs/design-notes.md, "A cautious trot on
  // ice"). 0: off.
  double speed_per_mu = 7.5;        // [m/s]
  // After this long trotting (from start_delay) the commands ramp to zero and
  // the robot stops, all four feet down. 0: trot for ever.
  double walk_time = 0.0;           // [s]
};

// A gait switch in one run: the crawl hands over to the trot once the run
// (from the first good frame) is trot_at old, at the crawl's next moment
// with four feet down, none loading or unloading, and the CoM nearly still
// (max_com_speed). The trot then starts
// from where the feet are, unloads its first pair and ramps its speed from
// zero to trot_speed at TrotParams::acceleration.
struct GaitSchedule {
  double trot_at = 0.0;             // [s] 0: no switch, GaitParams::kind throughout
  double trot_speed = 0.3;          // [m/s] the trot's forward speed after the switch
  // The switch also waits for the CoM to move slower than this: the crawl's
  // body shifts move it at up to 0.5 m/s, and a trot started from rest in
  // the middle of one stopped the trunk at once (all four feet slid, and
  // their mu in use fell to 0.13-0.25 on mu 0.8).
  double max_com_speed = 0.08;      // [m/s] horizontal
};

struct GaitParams {
  GaitKind kind = GaitKind::kCrawl; // [-] the gait at start
  bool walk = true;                 // [-] false: stand on four feet, the crawl never starts
  double cycle_time = 8.0;          // [s] crawl cycle (each leg swings once)
  double duty_factor = 0.85;        // [-] stance fraction of the cycle per leg
  double phase_offset[4] = {0.05, 0.55, 0.8, 0.3};  // [-] LF RF LH RH lift-off phase
  double speed = 0.05;              // [m/s] forward speed (scenario may override)
  double yaw_rate = 0.0;            // [rad/s] turning rate (trot only; the crawl walks straight: 0)
  double step_height = 0.10;        // [m] swing apex above lift-off (the front feet: at least kFrontStepHeight)
  double body_height = 0.60;        // [m] base above the ground plane
  double stability_margin = 0.05;   // [m] CoM inside the support triangle
  double liftoff_margin = 0.03;     // [m] measured CoM this far inside the remaining triangle before a foot unloads
  // A CoM that has not reached liftoff_margin this long after its body
  // shift ended will not: a leg at its reach (a foot dragged back by a
  // slide, its knee straight) holds it back, and the crawl would wait for
  // ever. The trunk then crouches, at crouch_speed, which lengthens that
  // leg's reach along the ground, until the CoM has the margin; crouched by
  // crouch_max, the lift-off needs the CoM only inside the triangle. The
  // trunk rises again at crouch_speed once the leg has lifted.
  double liftoff_wait_max = 2.0;    // [s]
  double crouch_speed = 0.02;       // [m/s]
  double crouch_max = 0.10;         // [m]
  double start_delay = 1.0;         // [s] standing still before the first body shift
  // A foot that slides after the body shift was planned can leave the shift
  // target outside the coming triangle: the shift is re-planned, at most this
  // fast on average.
  double reshift_speed = 0.05;      // [m/s]
  double min_shift_time = 0.2;      // [s] the shortest body shift
  // A body shift fills the four-foot phase before the next lift-off's
  // unloading (0.5 s at the crawl's cycle): its peak horizontal
  // acceleration reaches 2.9 m/s^2 with ideal tracking
  // (tests/unit/crawl_gait_test.cpp), 250 N on HyQ's 85 kg, all of it from
  // the feet's friction. Above 0: the shift is made long enough that its
  // peak stays within this, and the lift-off waits for the CoM. 0: off
  // (docs/design-notes.md, "A gentler body shift").
  double max_shift_acceleration = 0.0;  // [m/s^2]
  double initial_phase = 0.95;      // [-] crawl phase at the end of start_delay
  double swing_lift_fraction = 0.3; // [-] share of the swing spent lifting (and lowering)
  double swing_depth = 0.0;         // [m] swing target below the estimated ground
  double touchdown_search_speed = 0.10;  // [m/s] keep lowering a foot that has not touched down
  double touchdown_search_max = 0.10;    // [m] then give up and call it stance
  // Freezing called while a leg swings: that foot is put straight down where
  // it is at this speed, and the robot freezes once all four feet are down.
  double freeze_drop_speed = 0.30;       // [m/s]
  double touchdown_min_swing = 0.6;      // [-] touch-down accepted only after this swing fraction
  double load_time = 0.10;          // [s] after touch-down a foot's force limit ramps up over this
  double unload_time = 0.30;        // [s] a foot's force limit ramps down before lift-off
  double ramp_force = 500.0;        // [N] normal force the load/unload ramps span
  double lane_step = 0.05;          // [m] max lateral foothold correction toward the foot's lane per step
  double max_tilt = 0.35;           // [rad] trunk roll/pitch target limit (terrain following)
  TrotParams trot;                  // the trot's own numbers (kind kTrot)
  GaitSchedule schedule;            // a switch from the crawl to the trot (kind kCrawl)
};

struct TrunkParams {
  double kp_lin = 2000.0;           // [N/m]
  // The lab's teaching value is 200 N s/m; on HyQ's 85 kg that is zeta ~ 0.24
  // and the CoM overshoots each crawl shift by several cm. 600: zeta ~ 0.73.
  double kd_lin = 600.0;            // [N s/m]
  double kp_ang = 1000.0;           // [N m/rad]
  double kd_ang = 100.0;            // [N m s/rad]
};

struct JointParams {
  double posture_kp = 400.0;        // [N m/rad] posture hold / freezing stiffness
  double posture_kd = 6.0;          // [N m s/rad]
  // Swing-leg tracking. On HyQ the joint board runs the command's PD around
  // its closed torque loop (this project's plant: 40 Hz, damping 0.71), on
  // its encoder's differentiated, filtered (100 Hz) velocity, sampled at
  // 1 kHz; a damping loop kd / I that crosses over near that bandwidth
  // oscillates (kd 8 on the lower leg, 0.026 kg m^2 about the knee: 49 Hz,
  // the knee at 28 Hz). With torque_bandwidth set, each swing joint's gains
  // follow its inertia I, the diagonal of the leg's mass matrix (the
  // controller's model): kd = I wc and kp = I wc^2 / 4 (critically damped),
  // wc = 2 pi swing_crossover_fraction torque_bandwidth, each at most
  // swing_kp, swing_kd. A quarter of 40 Hz leaves 45 deg of phase margin and
  // 9 dB of gain margin behind the torque loop, the sampling and the
  // velocity filter (a third: 35 deg, 6.6 dB); the knee (the model's
  // 0.034 kg m^2) gets kp 34, kd 2.1, the hips (0.2-0.3 kg m^2) about
  // 200-300 and the cap 8. The same crossover bounds the slip damping of a flagged foot
  // (RecoveryParams::slip_damping): see Controller::slipDampingGain.
  // torque_bandwidth 0, the default: joints that deliver the asked torque at
  // once (the ideal plant); swing_kp and swing_kd on every joint and the
  // full slip damping. The simulator's hyq plant sets 40 (the robot's
  // configuration; docs/scenarios.md, "The plant").
  double swing_kp = 300.0;          // [N m/rad] swing-leg stiffness, at most
  double swing_kd = 8.0;            // [N m s/rad] swing-leg damping, at most
  double torque_bandwidth = 0.0;    // [Hz] the joints' closed torque loop (natural frequency); 0: ideal joints
  double swing_crossover_fraction = 0.25;  // [-] swing damping-loop crossover over torque_bandwidth
  double stance_kd = 0.0;           // [N m s/rad] extra joint damping in stance
};

// [-] On ground the friction map knows to be worse than mu_default, a
// landing foot's touch-down is confirmed at this share of force_on: the QP
// and its cone (the map's) take it before the swing PD's press drags it
// (a hind foot landing on a patch a front foot has estimated slides at
// 19-79 N under that press). A constant, not a Params field: Params fills
// the board link's configuration frame.
inline constexpr double kKnownIceTouchdownShare = 0.5;
// [m/s] ... and only while the landing foot does not rise off the ground
// faster than this along the terrain normal: the joint torques lag the
// contact by 5-8 ms (torque loop and filters), so a hard landing's bounce
// reads 40-56 N with the foot already in the air (rising at 0.04-0.07 m/s),
// and a stance foot in the air is flagged as slipping.
inline constexpr double kKnownIceTouchdownRise = 0.02;
// [-] mu in use of a stance whose own estimate's braking target lies below
// RecoveryParams::mu_floor never falls below this: under the oil strip's
// 0.02, the iciest ground of the scenarios.
inline constexpr double kEstimatedMuFloor = 0.015;

// [-] With joints behind a torque loop (JointParams::torque_bandwidth), in
// the trot, a landing foot on the ground (watched) pushes along the ground's
// normal with this share of StanceParams::force_on, as a feed-forward force
// through J^T on top of its swing PD. The swing gains that loop allows
// (the knee's kp about 34 N m/rad) press a foot that has reached its
// foothold with 13-67 N: short of force_on, its touch-down waited 100-300 ms
// while the trunk tipped about the diagonal that stood, until the next pair
// could no longer reach the ground. hyq plant, ODE seeds 1-8, recovery off:
// trot_flat, trot_ramp, trot_ice_patches, crawl_to_trot fell in 8 of 8 runs
// each, none with the press (docs/design-notes.md, "A landing foot pushes
// with a force"). A constant, not a Params field: Params fills the board
// link's configuration frame.
inline constexpr double kLandingPressShare = 1.25;

// In the crawl, a searching foot (its swing over, no touch-down yet) that
// moves along the ground's normal slower than kSearchStallSpeed, either
// way, while its reference has sunk kSearchStallDepth below it is held up
// by the ground: the drag test watches it whatever its force reads
// (SlipInput::drag_only_mask). Behind a torque loop the search's swing PD
// presses about 4 N per cm of the reference's depth: a front foot that had
// met ice read 3-10 N, under force_watch, and would be dragged 15-20 mm
// over 230-300 ms before its stance trigger, unseen (hyq plant, ice_010,
// ODE seeds 1-8: 71 slips over 5 mm without this test, none with it;
// docs/design-notes.md, "A searching foot the ground holds up"). A foot
// bouncing off the ground as it lands rises on every other tick, faster
// than that. Constants, not Params fields: Params fills the board link's
// configuration frame.
inline constexpr double kSearchStallSpeed = 0.02;  // [m/s]
inline constexpr double kSearchStallDepth = 0.005; // [m]

// [m] The crawl's front feet swing at least this high
// (GaitParams::step_height is the hind feet's, and the front feet's above
// it). The front feet meet ground no foot has stood on: where it rises
// ahead of the estimated plane (a ramp's foot), a lower swing comes down
// onto the slope short of its foothold and is dragged up it lightly, at
// 3-15 N, unseen, until its swing ends. The hind feet step where the front
// feet stood, on ground the estimate knows; from a high apex behind a
// torque loop they bounce as they land (kHyqCrawlStepHeight). hyq plant
// (hind feet 6 cm), recovery on, seeds 1-32, slips of 5 mm or more,
// detected late by at most (ODE / MuJoCo), 6 -> 10 cm: ramp 179 / 135 ms
// -> none, ramp_035 321 / 310 ms -> none; the longest slip after detection
// on them 25 -> 34 ms (ODE); the drawn validation set's runs over 100 ms
// 52 -> 57, falls 9 -> 8 (docs/design-notes.md, "The front feet swing
// high, the hind feet low"). Not a Params field: Params fills
// the board link's configuration frame.
inline constexpr double kFrontStepHeight = 0.10;

// A loaded stance foot's slide, behind a torque loop: a flag that rises
// after the foot has stood kStanceSlideAge, while it carries at least
// kStanceSlideLoad along the normal in use, starts its guess toward the
// floor at the foot's force ratio |f_t| / f_n (RecoveryInput::force_ratio;
// not below the guess's target) where that is below mu in use: a foot that
// slides under load has its force on the ground's cone. Touch-down slides
// (younger feet) keep the guess's law from mu in use, and their estimates.
// Constants, not Params fields: Params fills the board link's frame.
inline constexpr double kStanceSlideAge = 0.2;     // [s]
inline constexpr double kStanceSlideLoad = 100.0;  // [N]

// A stance foot's slide (the foot stood kStanceSlideAge when its flag rose)
// without an estimate, whose travel since its flag rose has reached
// kTravelPlaneLength and points out of its ground's plane by more than
// kTravelPlaneSine (3 deg), stands on other ground: a sliding foot moves in
// the ground it slides on. Its cone and its slope floor are taken about its
// ground turned the least to hold the travel, for the rest of that stance:
// a turn by less than kMaxGroundTilt (a travel further out of the plane is
// a contact that gives, not a slide), to a plane not steeper than it.
// Drawn terrain 108 (hyq plant, ODE): RF 3 cm past a
// concave change of slope, its ground the old plane's 14 deg off, slid for
// 286 ms at 0.15-0.24 m/s under 50-85 N, under the estimate's load; 72 ms
// with the turn (docs/design-notes.md, "A stance slide's travel turns its
// cone").
// Constants, not Params fields: Params fills the board link's frame.
inline constexpr double kTravelPlaneLength = 0.006;  // [m]
inline constexpr double kTravelPlaneSine = 0.05;     // [-]

// A loaded foot's flag that has lasted this long is a slide, not a
// landing's skid or bounce (the trot behind a torque loop: 30-80 ms), and
// is guessed toward the floor without an estimate
// (TractionRecovery::setGuessLoadLimit). Pushed sideways on ice
// (trot_push_ice, hyq plant, ODE), a front foot under 370 N spread out
// 0.58 m in 0.43 s at up to 4.5 m/s with mu in use at 0.6: its landing
// had stopped once within the flag, after which the event gives no more
// samples (TrotParams::peak_of_loaded_samples), so no estimate came, and
// a loaded foot was never guessed. ODE seeds 1-32, recovery on: the
// longest slip after detection 432 -> 173 ms (MuJoCo seeds 1-16: 348 ->
// 130), the other trot scenarios within 5 ms. Constant, not a Params
// field: Params fills the board link's frame.
inline constexpr double kLoadedSlideGuessAge = 0.08;  // [s]

// The CoM offset estimate (EstimatorParams::com_offset_time) learns only
// while the trunk is still: its CoM slower than kComOffsetRestSpeed and its
// rotation slower than kComOffsetRestRate. A trot's four-foot hand-overs
// pass the estimate's force test (the forces' sum the weight, vertical)
// while the trunk accelerates and pitches; learning there, on the hyq plant
// trotting up a 0.25 rad slope (trot_slope_start, seeds 1-4, com_offset_time
// 1 s), gave 8-11 false detections a run, 0-3 learning at rest only
// (docs/design-notes.md, "The CoM offset estimate on the trot, measured
// again"). Constants, not Params fields: Params fills the board link's frame.
inline constexpr double kComOffsetRestSpeed = 0.05;  // [m/s]
inline constexpr double kComOffsetRestRate = 0.1;    // [rad/s]

// [rad] The steepest plane the terrain fit takes as a foot's ground
// (TerrainEstimator::groundNormal: a plane four points agree on, or a
// row's turned plane) or as a row's turned plane: one tilted further than
// this from W z is not taken, and the foot's ground is the next choice (the
// row's turned plane, its last own ground, or the plane through all feet,
// which is not bounded). The crawl is specified for slopes up to 0.35 rad
// along the walk and 0.2 rad across it (0.40 rad together); this bound is
// that and 3 deg. On drawn terrains such planes were a row's square-on
// plane where the row crossed a slope change at an angle (47 deg for a
// 14 deg ramp), and the slope floor they set (1.2 tan / 0.707: 1.8) held mu
// in use far above the ground's while the foot slid (docs/design-notes.md,
// "A row's turned plane only where the change is square to the walk").
// A constant, not a Params field: Params fills the board link's frame.
inline constexpr double kMaxGroundTilt = 0.45;  // [rad]
inline constexpr double kCosMaxGroundTilt = 0.90044710235267692;  // [-] cos(kMaxGroundTilt)
inline constexpr double kSinMaxGroundTilt = 0.43496553411123023;  // [-] sin(kMaxGroundTilt)
// [-] A row turns onto a new slope only where the plane through all feet
// is level across the walk within this sine (3 deg): both slopes of a
// change crossed square-on hold the horizontal across the walk, and so
// does their blend. On a ramp crossed square-on the crawl's stagger of the
// feet rolls that plane by about 1.3 deg.
inline constexpr double kMaxRowTurnCrossSine = 0.05;
// [m] ... and only where each foot of the other row lies within this of
// the row's old plane or its new one: on a change crossed square-on the
// other row stands on the slope behind or the one ahead (the project's
// ramps: within 15 mm at a row's first turn). A change crossed at an
// angle whose feet's plane is still level across the walk (a 6 deg change
// crossed 57 deg off square) puts the other row 4-18 cm off both
// (docs/design-notes.md, "A row's turned plane only where the change is
// square to the walk").
inline constexpr double kMaxRowTurnOtherRowDistance = 0.03;
// [-] A turn onto the row's prior as its last fit left it (within 2 deg:
// cos) is kept without that test (a ramp's top: the front row turns again
// once its footholds are on the slope, the hind feet 4-6 cm off).
inline constexpr double kCosRowTurnKeptAngle = 0.99939082701909576;

// The lever arm's angular acceleration (ImuLeverArm, with
// EstimatorParams::imu_position set) is the gyro's one-tick difference
// through a first-order low-pass of this time constant. The bare difference
// carries the gyro's noise times sqrt(2) / dt: 2.8 rad/s^2 per axis with the
// simulator's 2e-3 rad/s, 1.2 m/s^2 at HyQ's mount, in every tick's legs'
// apparent gravity and so in their GRF estimates, where a crawl's trunk
// turns at under 1 rad/s^2; 2 ms keeps a quarter of it (0.32 m/s^2). Drawn
// validation terrains, hyq plant, recovery on, 201 crawls: 14 falls with the
// IMU's lever arm left in, 19 with it taken out by the bare difference, 9
// with 2 ms (10 with 5 ms, 13 with 10 ms; 9 with the IMU at the origin). A
// constant, not a Params field: Params fills the board link's configuration
// frame.
inline constexpr double kImuAlphaTime = 0.002;  // [s]

// [rad/s^2] The crawl leaves the trunk's turn out of its GRF estimate
// (EstimatorParams::grf_base_rotation's whole term is the trot's): its trunk turns at
// under 1 rad/s^2 at the median and 3-7 rad/s^2 at the 99th percentile (hyq
// plant), where the term's own noise (the gyro's slope) costs more than it
// takes out. But on the hyq plant a fourth foot's landing can roll the trunk
// at 40-46 rad/s^2 for 20 ms, and the legs' links, turned with it, push on
// their feet by about 0.6 N per rad/s^2: ramp_035 (ODE seeds 1-8), LF
// sliding down the slope then read 0.44 for 0.55 with its normal 6 deg
// sideways, every run's estimate 19-20 % off. So in the crawl the turn's
// angular acceleration term enters the estimate while the trunk's angular
// acceleration (the gyro's slope over grf_accel_window) is above this: 10
// rad/s^2 is 6 N at a foot, over the estimate's 2-5 N of noise. Those runs:
// 4.1-5.9 % (docs/design-notes.md, "The crawl's trunk turns its legs at a
// landing"). A constant, not a Params field (the link's configuration frame).
inline constexpr double kCrawlTurnAlphaMin = 10.0;  // [rad/s^2]

// The crawl starts with its feet at their stand, and each foothold is the
// other three feet's centre plus half a stride: each foot of the first cycle
// lands further ahead than the last, and the fourth (the left hind) trails
// its stand place by half a stride before its lift-off, where the steady
// crawl's feet trail by 0.38 of one. At 0.08 m/s (a 0.64 m stride) that is
// 0.39 m against 0.28 m (the shift included), and the shift toward its
// lift-off triangle stretches its knee onto its stop, where the GRF estimate
// and the QP lose the force along the leg and the foot is dragged. So the
// stride starts at kCrawlStartStride, the default crawl's (0.05 m/s over
// its 8 s cycle; crawl_fast and the drawn terrains go up to 0.08 m/s), and
// grows by at most kCrawlStrideGrowth per second of the crawl's clock (at
// the 8 s cycle 0.12 m a cycle): a 0.64 m stride after two cycles, no foot
// on the way trailing more than 1 mm further than in the steady crawl
// (docs/design-notes.md, "The crawl's first cycle").
inline constexpr double kCrawlStartStride = 0.40;     // [m]
inline constexpr double kCrawlStrideGrowth = 0.015;  // [m/s]

// On a slope the crawl's body shift is made long enough that its peak
// deceleration stays within what the feet's friction leaves once they hold
// the slope's pull (CrawlGait::planShift, with recovery on; the friction is
// the lowest mu in use times the pyramid's scale). A shift the feet cannot
// brake runs on: on slope_down's 0.2 rad of mu 0.31 a 0.14 m shift's
// 3.2 m/s^2 ran the body 0.36 m past its target at 0.5 m/s, down the slope,
// the front legs stretched until a hip's torque saturated. Flat ground, or
// ground tilted less than kShiftBoundMinTilt, keeps the shift as it is. On
// 0.04 rad, every cone at the floor (0.07-0.08), a shift's 1 m/s^2 ran the
// trunk to 0.28 m/s down the slope, where the feet could brake it at
// 0.1 m/s^2 only; it rolled on 0.45 m over the feet and fell (a drawn
// validation terrain, 116, simulator seed 2). Constants, not Params fields:
// Params fills the board link's configuration frame.
inline constexpr double kShiftBoundMinTilt = 0.02;            // [rad]
// The trot's start shift (below) counts ground tilted less than this level.
inline constexpr double kSlopeShiftMinTilt = 0.05;            // [rad]
inline constexpr double kSlopeShiftMinAcceleration = 0.2;    // [m/s^2] the bound at least this

// The crawl's trunk tips over the line through two of its standing feet:
// a push toward the lifting foot, or a CoM the model misplaces by
// centimetres. The third standing foot (past its load ramp, not the one
// that unloads) then carries next to nothing, and the trunk turns about
// that line, the third foot's side rising. Both at once, a force under
// kCrawlTipForce and a turn faster than kCrawlTipRate, hold the crawl's
// clock (no lift-off; an unloading foot takes its load back at the load
// ramp's rate, and unloads again before it lifts), and a
// swinging foot is put straight down where it is, at kCrawlTipDropSpeed
// (CrawlGait::tipping). On the drawn terrains, pushes of 117-185 N toward
// the lifting foot (ODE and MuJoCo) turned the trunk at 0.35-0.58 rad/s
// about that line, the third foot at the QP's floor, for a second before
// the fall; a crawl that holds its trunk has that foot under 15 N often
// enough (the published body's CoM is 3.5 cm nearer LF than the model's),
// but turns at 0.03 rad/s at most then. Constants, not Params fields:
// Params fills the board link's frame.
inline constexpr double kCrawlTipForce = 15.0;  // [N]
inline constexpr double kCrawlTipRate = 0.1;    // [rad/s]
inline constexpr double kCrawlTipDropSpeed = 0.6;  // [m/s]

// A trot that starts standing on a slope first moves its CoM over the point
// where its two diagonals cross (TrotGait's start shift). Feet that stand
// under the hips along the trunk's own axes sit uphill of the CoM by the
// trunk's height times the slope's sine (0.11 m on 0.19 rad): the first
// diagonal pair then holds a CoM 5 cm off its line, and two feet on a line
// cannot hold that moment. The drawn validation trots that start on a
// slope: in the trot's first second the trunk rolled and pitched by up to
// 0.36 and 0.31 rad on the ideal plant, 0.41 and 0.36 rad on the hyq plant,
// where 11 of 26 fell within 5 s; with the shift 0.07 and 0.05 rad, 0.21 and
// 0.14 rad (docs/design-notes.md, "A trot starts with its CoM over its
// diagonals").
// Ground tilted less than kSlopeShiftMinTilt keeps its start as it is,
// unless the CoM stands kTrotStartShiftTolerance or more off the crossing at
// the trot's first tick: a crawl that hands over mid-stride leaves it up to
// 10 cm off, and its first pair's lift-off then rolled the hyq plant over
// (crawl_to_trot, with the crawl's shift bounded at 1 m/s^2). The
// reference moves at kTrotStartShiftSpeed; the trot waits, past its
// start_delay, until the CoM is within kTrotStartShiftTolerance of the
// crossing, or kTrotStartShiftMaxWait at most. Constants, not Params fields:
// Params fills the board link's configuration frame.
inline constexpr double kTrotStartShiftSpeed = 0.15;      // [m/s]
inline constexpr double kTrotStartShiftTolerance = 0.02;  // [m]
inline constexpr double kTrotStartShiftMaxWait = 2.0;     // [s] after start_delay

// A trot's swing foot crosses a stride (speed x period) in its swing time
// ((1 - duty_factor) x period): over the ground it moves at speed /
// (1 - duty_factor) on average. The swing is lengthened (the duty factor
// lowered, to 0.5 at most) so that this stays within kTrotMaxSwingSpeed at
// the commanded speed. Behind HyQ's torque loop and valve limits (the hyq
// plant, duty factor 0.7), a 1 m/s trot on flat good ground (3.3 m/s in
// swing) fell in every run within 5 s, 0.9 m/s (3.0) as well, 0.8 m/s (2.7)
// in none; at duty factor 0.65, 1 m/s (2.9) in none (docs/design-notes.md,
// "A fast trot swings longer"). Below 0.81 m/s at 0.7, and below 1.08 m/s at
// the ideal plant's 0.6, the duty factor stays as set.
inline constexpr double kTrotMaxSwingSpeed = 2.7;  // [m/s] stride / swing time

struct StanceParams {
  double force_on = 80.0;           // [N] normal GRF that confirms touch-down
  // A leg with a joint at its stop pushes on the stop: the torque-based
  // force then reads the stop's reaction (a trot's foot that reaches down
  // into the air after a push stretches its knee onto the stop and reads
  // 500-1700 N). Such a leg's force confirms no touch-down and does not
  // place the ground plane.
  double joint_stop_margin = 0.01;  // [rad] from a joint limit: the leg is at its stop
  // Feet landing lightly on ice slide at 10-30 N for up to 130 ms, below a
  // 30 N watch. With the leg dynamics in the GRF estimate a foot in the air
  // reads a few N (1.5-3 N rms), below 15 N; a watched foot is flagged only
  // after landing_debounce_extra more ticks than a stance foot.
  double force_watch = 15.0;        // [N] normal GRF of a landing foot that slip detection watches
  // A foot dragged lightly over ice reads 7-30 N; each dip below the watch
  // restarted its debounce (two_feet_ice seed 25: flagged 64 ms late).
  // In the crawl, between force_watch_release and force_watch a foot
  // watched last tick is held: its debounce neither counts nor restarts.
  double force_watch_release = 5.0; // [N] normal GRF down to which a watched landing foot's detection holds
  // In the crawl, a foot still coming down at the ground is in the air,
  // whatever its force estimate reads (sensors at their specified worst:
  // 20-37 N spikes in the air while falling at 0.2-1.1 m/s). Landed feet
  // move along the normal at under 0.07 m/s. The trot too, on joints
  // behind a torque loop (JointParams::torque_bandwidth > 0): there a foot
  // braking at the end of its swing reads 15-27 N in the air, as the
  // published leg's inertia and the loop's lag are not in the estimate;
  // without the test such a foot is watched, flagged and put in stance up
  // to 9 ms before it lands (trot_flat, hyq plant, seeds 1-2, 30 s: 2 and
  // 4 false detections; with it 0 over seeds 1-4).
  double watch_approach_speed = 0.1; // [m/s] speed toward the ground above which a landing foot is in the air
  // In the crawl, a watched (or held) landing foot's swing PD pushes along
  // the ground's normal only, and damps its slip rather than the body's
  // motion over it: the PD's pull toward its target along the ground
  // dragged such feet at the slip threshold for 100-170 ms before the
  // stance trigger (the ramp's slips over 5 mm; docs/design-notes.md, "A
  // landing foot is pressed, not dragged").
  bool press_landing_along_normal = true;  // [-]
};

struct EstimatorParams {
  double vel_filter_tau = 0.02;     // [s] time constant pulling the IMU-integrated velocity to leg odometry
  // IMU biases. Uncorrected, the simulator's (1e-3 rad/s gyro, 0.02 m/s^2
  // accelerometer, per axis, docs/scenarios.md) put the leg odometry 1-13 cm
  // off after 60 s on flat ground (seeds 1-16); both zeroed in the
  // simulator, 0.1-0.3 cm; estimated here, 0.2-0.6 cm (seeds 1, 2, 5, 6, 9, 14).
  // Gyro: a complementary attitude filter against the IMU's orientation,
  // critically damped at 1 / gyro_bias_time (gyro_bias.hpp). Accelerometer:
  // integral action in the velocity filter, the bias error decaying with
  // acc_bias_time. <= 0 switches an estimate off.
  double gyro_bias_time = 1.0;      // [s] 1 / natural frequency of the gyro-bias filter
  double gyro_bias_limit = 0.02;    // [rad/s] largest gyro bias accepted, per axis (about 1.1 deg/s)
  double acc_bias_time = 3.0;       // [s] time constant of the accelerometer-bias estimate
  // From the start the estimate averages what it has seen, as a running
  // mean does: its time constant is the time it has learnt for, at least
  // acc_bias_start_time and at most acc_bias_time. Learnt at acc_bias_time
  // from the start, a 2 m/s^2 vertical bias moves the height estimate by
  // vel_filter_tau * 2 m/s^2 * acc_bias_time = 12 cm, and the trunk
  // controller moves the real trunk by as much, the other way. At least
  // 4 vel_filter_tau keeps the bias loop from overshooting; >= acc_bias_time
  // learns at acc_bias_time throughout.
  double acc_bias_start_time = 0.1; // [s] shortest time constant of the accelerometer-bias estimate
  // The clamps bound what a wrong estimate can do, not what the sensors may
  // have: the controller is specified for accelerometer biases up to
  // 2 m/s^2 and joint-torque offsets up to 10 N m (flat_hostile_sensors);
  // clamps at 0.5 m/s^2 and 3 N m cannot take those out (docs/design-notes.md,
  // "Sensors at their specified worst"). A bias past the clamp is not learnt
  // at all beyond it: the rest, db, stays in the filtered velocity as
  // vel_filter_tau * db, and in the odometry as that times the time walked
  // (a 2 m/s^2-sigma draw of 3.49 m/s^2 against a 3 m/s^2 clamp: 1 cm/s,
  // 0.59 m in 60 s). 5 m/s^2 is checkParams' ceiling: 2.5 sigma of such draws.
  double acc_bias_limit = 5.0;      // [m/s^2] largest accelerometer bias accepted, per axis
  // Joint-torque offsets from the residual torque in mid-swing
  // (torque_bias.hpp): from torque_bias_settle after lift-off until the
  // swing turns late (touchdown_min_swing), about 0.6 s of each 1.2 s swing.
  // Averaged over the last torque_bias_time of such samples; <= 0, or
  // grf_leg_dynamics off, switches it off, and then every mu sample keeps
  // the whole torque_offset_sigma in its force error (most are gated).
  double torque_bias_time = 1.0;    // [s] of swing samples in the offset average
  double torque_bias_settle = 0.1;  // [s] after lift-off before samples count
  double torque_bias_limit = 15.0;  // [N m] largest offset accepted, per joint (see acc_bias_limit)
  // The first samples are averaged as if this many zero residuals came
  // before them: each step stays small against the few ticks by which the
  // residual's force estimate lags, so the mean cannot overshoot (1.45 N m
  // past a 2 N m offset without it, tests/unit/torque_bias_test.cpp).
  double torque_bias_start_weight = 100.0;  // [samples]
  // The whole body's CoM, relative to the model's, from the ground forces
  // while three or four feet stand at rest (com_offset.hpp). HyQ's
  // published body has its CoM 32 mm forward and 15 mm left of the model's;
  // standing, the estimate reads 28 mm and 15 mm within 0.5 s. A running
  // mean over the first com_offset_time, then a low-pass at it; samples
  // whose forces' sum is off the model's weight by more than
  // com_offset_weight_tolerance, in size or from the vertical, are not at
  // rest (a payload heavier than that stops the learning), nor is a trunk
  // that moves or turns (kComOffsetRestSpeed, kComOffsetRestRate). The CoM the
  // crawl's margins, the wrench and the QP use is the model's plus the
  // estimate, and the trot centres its footholds on the base moved by it
  // (GaitInput::foothold_origin): a diagonal's line then passes under the
  // real CoM, where two feet on it can hold the trunk (the published body's
  // is about 3 cm off the RF-LH diagonal: roll up to 0.07 rad in trot_flat's
  // first second of trot, 0.03 with the footholds centred, 0.11 with the
  // estimate in the wrench and the QP alone; docs/design-notes.md,
  // "A landing foot pushes with a force"). com_offset_time 0: off (the
  // model's CoM), the default: the
  // forces come from the joint torques, and offsets not yet learnt (up to
  // 10 N m, flat_hostile_sensors) misplace the CoM by centimetres: that
  // crawl fell at 4.7 s (seed 1) with the estimate at 2 s.
  double com_offset_time = 0.0;       // [s] time constant of the CoM offset estimate
  double com_offset_start_time = 0.2; // [s] shortest time constant (the running mean's start)
  double com_offset_limit = 0.08;     // [m] largest offset accepted, per horizontal axis of B
  double com_offset_weight_tolerance = 0.15;  // [-] of the weight
  // The spread (1 sigma) of a joint-torque sensor's offset before it is
  // learnt (the simulator draws 0.5 N m, docs/scenarios.md), each joint
  // alike. What the leg has not yet learnt of it, through J^-T, adds in
  // quadrature to a mu sample's force error, which the sample gate
  // (SlipParams::max_estimate_force_sigma) compares with the force; like that
  // gate it needs the aligned estimate (grf_estimate_aligned). 0: offsets
  // assumed known. A foot that slips before its leg's first swing (the
  // stance_slip spot) thus gets no estimate; the floor guess handles it
  // (docs/design-notes.md, "Torque offsets not yet learnt").
  double torque_offset_sigma = 0.5;  // [N m]
  // [m] The IMU's position in B. Its accelerometer reads the specific force
  // of that point: besides the origin's, alpha x r + omega x (omega x r),
  // r this position. In a trot the trunk pitches and rolls at 10-50
  // rad/s^2: at HyQ's mount (0.29 m ahead of the origin, 0.10 m above) that
  // is 3-15 m/s^2, which the IMU-integrated velocity the slip detector
  // compares the feet with, the odometry and the legs' apparent gravity would
  // all take for the trunk's. The controller takes both terms out (ImuLeverArm;
  // alpha from the gyro's one-tick difference through kImuAlphaTime's
  // low-pass, whose noise the velocity's integral telescopes away). Zeros,
  // the default: the IMU at the origin, nothing taken out (docs/design-notes.md,
  // "The IMU's lever arm": why the hyq plant's preset leaves it so).
  double imu_position[3] = {0.0, 0.0, 0.0};
  // Ground reaction force from joint torques, f = -J^-T (tau - b qd - g(q) - M(q) qdd):
  // a sliding foot accelerates at 5-15 m/s^2, and its leg's inertia (about
  // 1.2 kg at a front foot, 0.5 kg at a hind one, fitted on ice_patches
  // logs) then hides 5-10 N of the friction force, more than the friction
  // of a lightly loaded foot on ice. false: the static estimate tau = g - J^T f.
  bool grf_leg_dynamics = true;     // [-] leg inertia, joint damping and base acceleration in the GRF estimate
  // The links also turn with the base: in a trot the trunk rolls by
  // 20-30 rad/s^2 each half cycle, and a leg's links, 0.2-0.5 m below the
  // HAA axis, then push on the foot by about 0.6 N per rad/s^2 of roll,
  // sideways (fitted on trot_push_ice logs): 10-15 N, a third of the
  // friction of a 300 N foot on mu 0.15. true: the angular acceleration
  // (the gyro's slope over grf_accel_window) and the centrifugal and
  // Coriolis terms in the estimate (legBaseRotation; needs grf_leg_dynamics).
  // The trot takes all of them; the crawl, whose trunk turns at under
  // 1 rad/s^2 at the median (there the whole term cost the ramp one run
  // within 10 %, 6 of 8, and let one slip last 84 ms after detection, for
  // reasons not yet found), the angular acceleration's term alone, past
  // kCrawlTurnAlphaMin. false: neither gait.
  bool grf_base_rotation = true;    // [-]
  // With grf_base_rotation, the leg's own centrifugal and Coriolis torques
  // too, C(q, qd) qd (legBaseRotation). In the trot's stance the hips turn
  // at 0.5-1 rad/s, the knees up to 2.5 rad/s as a foot lands; left out,
  // these terms read as 1-2 N of extra normal force on every stance foot
  // and up to 0.2 N of extra friction in a slide (docs/design-notes.md,
  // "The trot's legs swing their own links").
  bool grf_leg_motion = true;       // [-]
  int grf_accel_window = 10;        // [ticks] joint velocity samples behind each joint acceleration (2..17: the GRF delay line holds (N - 1) / 2)
  // The friction and normal estimates take the force of the instant the
  // acceleration is centred on, (N - 1) / 2 ticks back, with that instant's
  // slip velocity (GrfDelayLine); false: this tick's mixed-time estimate.
  bool grf_estimate_aligned = true; // [-] (needs grf_leg_dynamics)
  // The ground pushes on the foot sphere's lowest point, kFootRadius below
  // its centre; true: forces go through that point's Jacobian (normal: the
  // terrain plane's) in the GRF estimate, the torque offsets and the stance
  // torques, and the leg odometry and the slip detector take that point's
  // velocity (the point that sticks while the sphere rolls); false: the
  // centre's (docs/design-notes.md, "The force acts at the contact point",
  // "Rolling feet").
  bool grf_contact_point = true;    // [-]
};

struct SlipParams {
  // The truth counts a slip from 0.05 m/s (docs/metrics.md); with the cones
  // right the slips that remain creep, and the time they take from 0.05 to
  // the threshold is most of the latency. At 0.04-0.05 the detector flags
  // real slides of 0.04-0.05 m/s that the truth does not count: false
  // detections on flat (docs/design-notes.md, "The detection threshold").
  double threshold = 0.055;         // [m/s] |s_i - median| above which a leg slips (velocities along the ground)
  // The trust gate's test that the feet the median leaves unflagged agree as
  // vectors: |u_a - u_b| carries the noise of both in-plane components, more
  // than the norms the median test compares, so it has its own, wider
  // tolerance.
  double holding_agreement = 0.07;  // [m/s] pairwise |u_a - u_b| of the holding feet
  int debounce_ticks = 4;           // [ticks] consecutive detections to raise a flag
  // A landing foot's first milliseconds on the ground: the impact slides
  // it a few mm at up to ~0.08 m/s for 3-4 ms (flat, seed 4), real but not
  // a slip; a landing foot must exceed the threshold this much longer.
  int landing_debounce_extra = 1;   // [ticks] added to debounce_ticks for a watched landing foot
  int release_ticks = 10;           // [ticks] consecutive clear ticks to drop it
  // A slow creep the norms miss: a foot sliding against the body's own
  // motion changes |u_i| by less than its slip speed (ramp_035: RF creeping
  // down the slope at 0.05-0.1 m/s for 0.3 s, its norm 0.04 m/s off the
  // median: flagged 286 ms late, or never). Each usable foot's deviation
  // from the component-wise median vector (>= 3 usable feet), low-passed
  // with time constant creep_filter_ticks, flags the foot above
  // creep_threshold; the average takes out the per-tick noise that keeps a
  // per-tick vector test off (docs/design-notes.md, "A creep against the
  // body's motion"). While the per-tick test flags the foot the filter
  // holds, and it restarts once the foot's flag is up, so that it does not
  // hold a fast slip's flag after the slide stops, nor lose a slow slide
  // whose norm flickers about the threshold (docs/design-notes.md, "A
  // flickering norm keeps a creep's evidence"); its flags count only where
  // the trust gate then believes the median.
  double creep_threshold = 0.04;    // [m/s] |filtered u_i - median vector| above which a leg creeps (<= 0: off)
  int creep_filter_ticks = 40;      // [ticks] time constant of that filter
  // A landing foot dragged along the ground below the threshold: in late
  // swing, on the ground (watched), its swing PD still pulls it, and on
  // good ground it slides at 0.04-0.06 m/s and 10-60 N for 60-200 ms
  // (ramp_035's crest: 5-12 mm, flagged only once the foot is in
  // stance). Each landing foot sums its deviation from the median vector
  // less landing_drag_allowance, over the ticks, floored at 0 (a one-sided
  // CUSUM test: the travel in excess of the allowance); past
  // landing_drag_travel the foot touches down (the crawl), so the QP holds
  // it instead of the swing PD dragging it. No slip flag: the stance tests
  // judge it from there (docs/design-notes.md, "A landing foot dragged
  // below the slip threshold").
  double landing_drag_allowance = 0.03;  // [m/s] deviation a landing foot may have without counting
  double landing_drag_travel = 0.001;    // [m] excess travel that makes it touch down (<= 0: off)
  double multi_leg_consistency = 0.10;  // [m/s] |u_i + bv_b| for an IMU-consistent leg
  double imu_integration_window = 0.2;  // [s] max time the IMU integration runs alone
  // Tighter than threshold: a slip of two feet together builds up speed
  // before the feet disagree by threshold; anchoring stops earlier than that.
  double imu_anchor_agreement = 0.05;  // [m/s] pairwise |u_a - u_b| of feet that may anchor the IMU
  // The paper averages 4 samples; ours come every 1 ms tick from a
  // torque-based GRF, so 4 samples span 4 ms of its noise. 12 (12 ms) cuts the
  // noise of the linear-weighted average by sqrt(0.30/0.11) ~ 1.7x for ~4 ms lag.
  int estimate_samples_mu = 24;     // [-] N of the linearly weighted mu average (1..32)
  int estimate_samples_n = 12;      // [-] N of the geodesic normal average (1..32)
  double min_slip_speed = 0.02;     // [m/s] below it, no estimate is taken
  // A sample slower than this fraction of the fastest slip velocity offered
  // in its event (every slipping tick's) is the slip ending: on a compliant
  // contact (MuJoCo's soft constraints, a softer bristle) the foot re-sticks
  // and its force falls inside the cone while it still moves; such samples
  // read mu 10-50 % low (docs/design-notes.md, "A slip's ending samples").
  double ending_slip_fraction = 0.7; // [-] 0: every sample counts
  // Where the peak counts every slipping tick (the crawl; without
  // TrotParams::peak_of_loaded_samples), it is the fastest of the last one
  // to two of these holds: a re-stick follows its peak within tens of ms,
  // while a light jolt as a stance begins may be followed by a loaded slide
  // of up to a second that it would otherwise hide from the estimate
  // (docs/design-notes.md, "A light jolt hides a loaded slide from the
  // estimate"). 0: the fastest of the whole event.
  double ending_peak_hold = 0.05;    // [s]
  int min_estimate_samples = 3;     // [-] accepted samples in this slip event before the estimate is offered
  // With 3-5 N of GRF error a sample's mu is off by ~4 / F: 0.08 at 50 N,
  // a third of an ice patch's mu. Below 80 N the worst estimates are all
  // such feet (landing, lifting, or a front foot on ice); their slips are
  // handled by the floor guess (guess_floor_before_estimate).
  double min_estimate_force = 80.0; // [N] |GRF| below it, no estimate is taken (a dragged, unloaded foot)
  // A sample's force is only as good as the joint acceleration in its
  // leg-inertia term. The acceleration's fit over its window gives a standard
  // error (JointAccelerationFilter::accelerationSigma: ~1 rad/s^2 of noise,
  // ten times that or more when an impact or a slip's onset kinks the
  // window, unknown for two ticks after a restart),
  // and A = J^-T M maps it to sigma_F at the foot (with, in quadrature, the
  // torque offsets not yet learnt: EstimatorParams::torque_offset_sigma);
  // sigma_F / |F| is then
  // about the sample's own mu error. 0.015 is 10 % of the lowest patch's mu
  // (0.15) (docs/design-notes.md, "Only samples whose acceleration term is
  // certain"). Needs the aligned estimate (grf_estimate_aligned): without it
  // there is no sigma_F and the gate is inert.
  double max_estimate_force_sigma = 0.015;  // [-] sigma_F / |F| above it: no sample (0: off)
  // The GRF estimate's acceleration term is a linear fit of each joint's
  // velocity over grf_accel_window ticks: while the foot's slip speed
  // changes fast (a slide braking from 0.25 m/s within a few ms) the leg's
  // acceleration changes inside that window, the fit misses it, and the
  // force is off by 10-15 N. On mu 0.1, samples taken while the foot
  // braked harder than 20 m/s^2 read mu 42 % low at the median, those
  // under 5 m/s^2 1 % (docs/design-notes.md, "A braking slide reads low").
  double max_slide_acceleration = 30.0;  // [m/s^2] |slip acceleration| over the slide window above it: no sample (0: off)
  double min_force_slip_angle = 0.1;  // [rad] GRF closer than this to +/- slip direction: no sample
  // Sliding friction points against the slip. A foot that moves while its
  // contact still sticks (the pad's give, a rebound after a slide) carries a
  // force inside the cone in any direction: not a mu sample. 45 deg leaves
  // room for 3-5 N of GRF error on 10-20 N of friction.
  double max_friction_slip_angle = 0.79;  // [rad] GRF along the ground (prior's plane) further than this from -slip: no sample (0: off)
  double max_normal_tilt = 1.0;     // [rad] sampled normal further than this from W z: rejected
  // A sliding foot moves along the ground; a steep slip velocity is a foot
  // bouncing or lifting, whose force says nothing about the cone.
  double max_slip_elevation = 0.45; // [rad] slip velocity steeper than this from W's horizontal: rejected
  double max_mu_estimate = 2.0;     // [-] sampled mu above it: rejected as implausible
  // A foot that moves while its contact sticks shows the contact's
  // tangential stiffness: its force ratio rises with its travel at k / F_n
  // (SurfaceEstimator's slide test). A slide's stays at mu: 0 N/m but for
  // the GRF estimate's noise (~5e3 N/m over 6 ticks at 0.1 m/s). The softest
  // contact tested, ODE's bristle at x0.3, is 3e4 N/m; the default is 1e5.
  // The choice of both numbers: docs/design-notes.md, "A give is not a slide".
  double max_slide_stiffness = 1.5e4;  // [N/m] |stiffness| above it: no sample (0: off)
  // A give shows over any span of its travel; the force estimate's noise
  // grows as the travel a fit spans shrinks. So the slide test also fits
  // the ratio over the fewest ticks, at least slide_window, in which the
  // foot travels slide_travel (at most kMaxSlideWindow, 16), and takes the
  // smaller of the two stiffnesses. At 0.08 m/s or faster the two spans are
  // one; a slower slide's travel span is longer (7 ticks at 0.07 m/s, 9 at
  // 0.05). With the 6-tick fit alone, a loaded slide at 0.05-0.08 m/s on
  // the ramp loses 3 of its 5 samples to the noise; 0.3-0.5 mm are measured
  // (docs/design-notes.md, "A slow slide's give test spans its travel").
  double slide_travel = 0.0004;     // [m] travel the slide test spans besides slide_window (0: that window alone)
  int slide_window = 6;             // [ticks] history the slide test regresses over (2..16)
  int normal_mean_iterations = 5;   // [-] most Karcher-mean iterations on the sphere
  // Each Karcher step is shorter than the last by about the samples' spread
  // squared (a slip's normals: under 0.1 rad, so 1e-2 and less): a step under
  // 1e-6 rad leaves the mean within 1e-8 rad of the geodesic one, and saves
  // the one more iteration (about 1,000 instructions on the board) that 1e-9 takes.
  double normal_mean_tolerance = 1e-6;  // [rad] a Karcher step shorter than this ends the iterations
  // The slip-based normal is noisy: its direction error (slip velocity
  // elevation, leg dynamics while sliding) is a few degrees at any load, plus
  // GRF error over the normal force. With mu 0.1 the cone's half angle is
  // only 5.7 deg, so n_hat is fused with the plane through the footholds
  // (the prior), each weighted by its inverse variance. 0 = no prior: the
  // paper's estimate alone.
  double normal_prior_sigma = 0.03;   // [rad] a foothold's tilt from the footholds' plane
  // The prior is each foot's local plane (terrain_estimator.hpp): the plane
  // of its row's feet and their last footholds that holds most of them;
  // before a row has 3 such points, all feet and footholds weighted
  // exp(-d^2 / 2 L^2) by the horizontal distance d from the foot. L = 0: the
  // plane through the feet.
  // At the ramp's top the plane through the four feet is 4-10 deg off under
  // the hind feet, and a slow slip's normal barely moves the estimate off
  // it (docs/design-notes.md, "Each foot's own plane as its prior").
  double prior_local_length = 0.4;    // [m] L
  // A row's feet and footholds within this of a plane lie on it: the feet's
  // heights from leg odometry agree to a millimetre over a stride; a
  // foothold a stride back on a 0.25 rad ramp's flat foot lies 9 cm off the
  // slope's plane (docs/design-notes.md, "Each foot's own plane as its prior").
  double prior_inlier_distance = 0.005;  // [m]
  // A row across a slope change. Where both feet of a row lie off the plane
  // of their footholds by more than this, on the same side, the row has
  // crossed onto new ground (a ramp's foot or top), and the plane the
  // consensus holds (the two feet and one foothold) is a blend of the two
  // slopes: 12.4 deg for the 14.3 deg ramp at the front feet's first steps
  // onto it. The row's plane is then the one through its two feet that
  // holds the horizontal square to the walk (a change crossed square-on).
  // Three inlier distances: a foot 1-2 cm from a crest, whose place leg
  // odometry knows to a centimetre, does not count as past it. 0: off
  // (docs/design-notes.md, "A row across a slope change").
  double prior_turn_margin = 0.015;     // [m]
  // Where no four of the six points agree on a foot's ground plane (about
  // which its cone is taken, TerrainEstimator::groundNormal), a row that
  // turned takes its turned plane, and a row whose feet both still stand on
  // its last ground keeps it. false: the plane through all four feet there,
  // 6-11 deg for the slope's 20 at the front feet's first steps onto
  // ramp_035's slope, where on MuJoCo a lightly loaded RF at the edge of its
  // true cone creeps 16-32 mm down the slope, most of it never flagged
  // (docs/design-notes.md, "A turned row's plane is its feet's ground").
  bool turn_sets_ground = true;
  // A foot whose row's own four points do not all lie on one plane (a foot
  // just past a slope change): the plane three of them hold may be a blend
  // of the two slopes (any three points make a plane). Where the row did
  // not turn (prior_turn_margin), four points of both rows agree on the
  // foot's ground plane (TerrainEstimator::groundNormal), and the foot lies
  // off its row's footholds' plane by more than prior_inlier_distance (it
  // stepped past the change: a foot at a crest lies on both sides'
  // planes), that ground plane is its prior instead
  // (TerrainEstimator::priorNormal). ramp.yaml at mu 0.4, hyq plant, seeds
  // 1-8, each run's worst estimate: ODE 5.9-9.0 % (the row's plane alone:
  // 4 runs of 8 at 38.6-39.7 %, RH 16 cm past the ramp's foot on a 6 deg
  // prior for the slope's 14.3); MuJoCo at a 0.02 s contact time constant
  // 6.6-8.8 % in 7 runs, LF at the crest 18.5 % in one (all 8 at
  // 35.9-43.5 %). The validation set's slipped patches within 10 %: ODE
  // 73.1 % (71.4), MuJoCo 91.7 % (91.3). false: the row's plane always
  // (docs/design-notes.md, "The prior at a change of slope").
  bool prior_agreed_ground = true;  // [-]
  // Two priors at a slope change. A hind foot that lands just past a ramp's
  // crest stands on the flat top while its row's plane is still the slope
  // (and a front foot's row plane is the top): its prior is 14 deg off and
  // the mu taken against it half the true value. While a foot slips, its
  // travel since the slip event began (the slip velocity summed, leg
  // kinematics against the feet that stand) lies in the ground it slides on.
  // Where the other row's plane differs from the foot's own by more than
  // prior_switch_angle and the travel has reached prior_switch_travel, the
  // prior is the other plane if the travel lies in it (within half the sine
  // of the angle between the two) and closer to it than to the own plane by
  // as much. ODE ramp at contact stiffness x3, seeds 1-8: 8 runs of 8
  // within 10 % mu error with the switch, none without. Under 3 mm a soft contact's travel is not in its
  // ground (MuJoCo: the penetration grows with the load, 0.25 mm per mm of
  // travel), docs/design-notes.md, "A foot at a slope change has two
  // priors". prior_switch_angle 0: the own row's plane always.
  double prior_switch_angle = 0.05;     // [rad]
  double prior_switch_travel = 0.003;   // [m]
  // Measured: the slip normal alone (no prior) ended the ice patches' events
  // 5.6 deg rms from the truth (seeds 1-6, aligned GRF and friction gate).
  double slip_direction_sigma = 0.10; // [rad] direction error of one event's slip-based normal
  double estimate_force_sigma = 3.0;  // [N] GRF estimate error across the slip, per event
  // A slow slip's direction is uncertain: the foot velocity's noise (0.02 m/s
  // rms vertically, measured on loaded stance feet of ice_patches, seed 3) over
  // the slip speed. A 7 cm/s slip's normal is thus 17 deg uncertain, not
  // 6: the fusion keeps 1 % of it, not 8 % (docs/design-notes.md, "A slow
  // slip's normal counts less").
  double slip_velocity_sigma = 0.02;  // [m/s] slip velocity noise, per axis (0: off)
};

// The friction probe's settings (slip/friction_probe.hpp, where they are explained).
struct ProbeParams {
  bool enabled = false;        // [-] false: no pair is ever applied
  // [N] the probed foot's and its partner's normal force (estimate) at
  // least; kProbeStartLoadShare of it to start (friction_probe.hpp).
  double min_load = 150.0;
  double settle_time = 0.05;   // [s] the four feet allowed this long before a probe starts
  double quiet_time = 0.2;     // [s] no foot flagged this long before a probe starts
  // [N/s] the pair's ramp, up and, after a hold or an abort, down (no
  // faster down than up: a faster release during the crawl's body shift
  // moved a partner foot faster than a slip). The ramp lasts at most
  // max_force / rate.
  double rate = 1000.0;
  double max_force = 250.0;    // [N] the pair's magnitude at most
  double max_ratio = 0.6;      // [-] the probed foot's |f_t| / f_n (estimate) at which the probe ends, held
  // [-] the partner's commanded |f_t| / f_n stays below this share of its
  // mu in use (or kProbeGuessedPartnerRatio under a narrowed guess,
  // friction_probe.hpp), itself a guess on a foot not yet probed: with the whole cone
  // (mu 0.6 on the ramp's mu 0.5) partners unloaded by the body shift broke
  // away sideways and slid 60-100 ms (ramp, seeds 1-8).
  double partner_margin = 0.8;
  // [rad] a foot whose cone's normal is further than this from the feet's
  // plane's is not probed, nor read as a partner (its ratio about that
  // normal is not its friction).
  double max_normal_angle = 0.05;
  double break_release_rate = 1000.0;  // [N/s] the pair's release after a break-away, from kProbeBreakHoldShare of it
};

struct RecoveryParams {
  bool enabled = true;              // [-] false: detect and log only; the flags change nothing (QP, freeze, odometry, plane fit)
  // K_n and K_mu: a slip ends only once the cone in use fits inside the true
  // one; slower gains let the foot build up speed meanwhile (bench in
  // tests/unit/slip_pipeline_test.cpp: K_n 30 / K_mu 50 -> ~115 ms of slip
  // after detection, 100 / 100 -> ~50 ms) at <= K_n*dt*dtheta of normal
  // turn per tick (20 mrad for a 0.2 rad error: a ramp, not a step).
  double k_normal = 100.0;          // [1/s] K_n, normal correction rate
  double k_mu = 100.0;              // [1/s] K_mu, mu correction rate (K_mu dt of the gap per tick)
  double pyramid_scale = 0.70710678118654752;  // [-] 1/sqrt(2), cone -> inscribed pyramid
  double mu_default = 0.6;          // [-] friction coefficient before any estimate
  // Freezing (docs/design-notes.md, "Freezing only after 0.3 s, and off by
  // default") is off. On a strip of oil (oil_strip.yaml, mu 0.02) it makes
  // the robot fall: seeds 1-32, 9 falls and 1 run across with freezing, 0
  // falls and 30 across without. Oil spilt under the hind feet on a 0.25 rad
  // slope (oil_slope.yaml) is the one case where it saves it (0 falls
  // against 6); on a 0.3 rad slope the same spill gives 15 falls against 0.
  bool freeze = false;              // [-] true: the paper's freezing mode, after freeze_after
  // With freeze on: the paper freezes after "tens of ms". Here a freeze is
  // not stable on ice (the stiff legs push wherever friction lets them: the
  // robot slides apart and tips), so it is the last resort for a slip the
  // correction has not stopped in 0.3 s (the same note).
  double freeze_after = 0.3;        // [s] flagged slip lasting this long -> freeze
  double freeze_hold = 0.5;         // [s] no leg flagged for this long -> leave freezing
  double unfreeze_blend = 0.2;      // [s] frozen command handed back to walking over this
  // A nearly unloaded foot dragged before lift-off slips harmlessly; only a
  // foot that carries the robot counts toward freezing.
  double freeze_min_load = 50.0;    // [N] normal GRF below which a slip does not count toward freeze_after
  // A frozen robot whose foot keeps creeping on ice never gets freeze_hold of
  // calm; after this long it resumes with the corrected cones (a fresh slip
  // must last freeze_after again to re-freeze).
  double freeze_max = 3.0;          // [s] longest freeze
  // The inscribed pyramid's corners lie on the cone of the mu in use: a QP
  // that pushes a foot diagonally asks for exactly mu_in_use. Driving mu in
  // use to the estimate itself leaves a foot whose estimate is right sliding
  // at the edge of its true cone (kinetic friction then cannot stop it); the
  // correction aims at this fraction of the estimate instead.
  double estimate_margin = 0.8;     // [-] mu target = estimate_margin * mu_hat
  // While the foot is still flagged, the target is lower: a sliding foot
  // stops only by the difference between kinetic friction and the
  // tangential force the leg still asks for, against ~1 kg of leg inertia
  // (a front foot). At 0.8 that difference is ~5 N at 200 N of load
  // (docs/design-notes.md, "Slip damping and the brake stop a loaded slip").
  // Once the flag drops, mu in use returns to estimate_margin * mu_hat at K_mu.
  // brake_margin = estimate_margin: no brake.
  double brake_margin = 0.5;        // [-] mu target while flagged = brake_margin * mu_hat
  // Slip damping: while a stance foot is flagged, the leg is commanded the
  // QP's force plus D v_slip (v_slip: the detector's slip velocity, W,
  // averaged over two ticks, along the foot's ground: slipDampingVelocity),
  // i.e. D |v_slip| less force against the slip. It fades with the slip
  // speed (no step when the slip ends); the slip velocity's noise
  // (~0.02 m/s) costs ~2 N. stance_slip, seeds 1-32, median of the runs' slip after
  // detection, D = 50 / 75 / 100: 41 / 33 / 28 ms; without damping or brake,
  // 110-165 ms (docs/design-notes.md, "Slip damping and the brake stop a
  // loaded slip").
  double slip_damping = 100.0;      // [N s/m] D
  // A foot can slide with too little load for an estimate (min_estimate_force):
  // a landing foot on ice at 10-20 N, pushed by the QP to the edge of the
  // default cone, reached 0.9 m/s. true: such a foot's
  // mu in use goes toward the floor at K_mu until the estimate comes, then
  // follows the estimate (up or down, never above the mu in use when the
  // guess began) for the rest of that slip. Every slip starts with a few
  // ticks without an estimate (min_estimate_samples), so this acts on all.
  bool guess_floor_before_estimate = true;  // [-]
  // true (in the crawl): once a stance foot's guess has begun, its mu in use
  // goes on toward the floor after the flag drops, while the foot carries
  // less than min_estimate_force; it is over once an estimate comes, the
  // foot carries that much, or it lifts off. The ground under a foot that
  // stands still does not change, and a flag often drops with the slip
  // slowed but not over: a landing front foot on mu 0.1, flagged for 12 ms,
  // is left at mu 0.17 without the hold and creeps on for 100 ms more. A loaded foot keeps
  // its mu, so that its next slip is a slide an estimate can be read from
  // (docs/design-notes.md, "A light foot carries no tangential force"). The
  // trot's landings slide by design.
  bool guess_holds_for_stance = true;  // [-]
  // With recovery, in the crawl, a stance foot's tangential force in the
  // GRF QP is bounded by mu_p (f_n - offset), not mu_p f_n: a foot held at
  // the QP's least normal force (f_normal_min) carries none, and a lightly
  // loaded one keeps a margin of a few N against its leg's force errors. A
  // landing foot held at 10 N at the edge of its pyramid crept at the slip
  // threshold for 100 ms (docs/design-notes.md, "A light foot carries no
  // tangential force"). At most the foot's lower normal bound, so the QP
  // stays feasible.
  double cone_force_offset = 10.0;  // [N]
  double mu_rise_rate = 0.15;       // [1/s] how fast mu in use may rise on good ground
  double mu_rise_delay = 1.0;       // [s] slip-free stance on a new foothold before mu may rise
  double mu_rise_ceiling = 0.6;     // [-] mu in use never rises above this by itself
  // Estimates from violent whole-body slips can be far too low; a QP with
  // mu ~ 0 cannot push the body anywhere. Below the stance_slip spot's 0.1,
  // so that estimate_margin holds there. A stance whose own estimate's
  // braking target (brake_margin x mu_hat) lies below it, an estimate under
  // mu_floor / brake_margin (0.14), brakes below it, to kEstimatedMuFloor
  // at least (docs/design-notes.md, "A stance estimated under the floor
  // brakes below it").
  double mu_floor = 0.07;           // [-] mu in use never falls below this, but for that stance
  // On a surface tilted by theta, mu in use never falls below
  // slope_floor_factor * tan(theta) / pyramid_scale: the narrowest pyramid
  // that still carries the foot's share of the weight there (factor > 1 for
  // a margin). 0 = the constant mu_floor only. Where this floor is above a
  // foot's estimate, its pyramid is narrowed across the slope to the
  // estimated cone, no narrower than mu_floor (TractionRecovery::muAcross).
  // In the trot behind a torque loop a foot flagged while lighter than
  // SlipParams::min_estimate_force has no slope floor until it is loaded or lifts.
  double slope_floor_factor = 1.2;  // [-]
  // Each foot's cone is taken about the plane through all feet, unless the
  // foot's ground plane (TerrainEstimator::groundNormal) differs from it by
  // more than this: then about the ground plane, and its slope floor with
  // it. Where the slope changes between the front and hind feet (a ramp's
  // foot and top) the plane through all feet is wrong under both; on even
  // ground the per-foot planes' own noise (0.2 deg median, 0.45 deg worst
  // on flat) stays below 2 deg, and the cones are the global plane's
  // (docs/design-notes.md, "Each foot's cone about its own ground").
  double ground_plane_min_angle = 0.035;  // [rad] (2 deg)
  // The friction map (slip/friction_map.hpp): every slip's last estimate is
  // written into the cell under its foot; a foot that lands in an
  // estimated cell takes estimate_margin x the cell's mu (at most
  // mu_default) at once, and a slip of it with no estimate of its own
  // yet brakes toward brake_margin x the cell's mu, not toward the floor.
  FrictionMapParams map;
  // The friction probe (slip/friction_probe.hpp): in the crawl, with four
  // feet down at full load, a pair of opposite forces along the line
  // between two feet ramps the tangential force on a foot whose friction is
  // a guess until it breaks away (its mu) or holds max_ratio; the trunk's
  // wrench is unchanged. Its answer takes the foot's cone there at K_mu
  // (RecoveryInput::probe_mu, probe_held) and, with the map on, goes into
  // the map's cell.
  ProbeParams probe;
};

struct SafetyParams {
  double max_joint_velocity = 30.0;  // [rad/s] above: frame rejected as corrupt
  double max_joint_torque = 400.0;   // [N m] measured torque above: frame rejected
  double max_gyro = 20.0;            // [rad/s]
  double max_acc = 200.0;            // [m/s^2]
  double quat_norm_tol = 0.1;        // [-] | |q| - 1 | above: frame rejected
  double joint_range_margin = 0.3;   // [rad] encoder reading this far past a joint limit: rejected
};

struct Params {
  double dt = hal::kTickPeriod;     // [s] control period (1 kHz)
  QpParams qp;
  GaitParams gait;
  TrunkParams trunk;
  JointParams joint;
  StanceParams stance;
  EstimatorParams estimator;
  SlipParams slip;
  RecoveryParams recovery;
  SafetyParams safety;
};

}  // namespace hyq
