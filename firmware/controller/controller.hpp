// The slip-aware locomotion controller: one call per 1 kHz tick.
// Inputs in, outputs out: no I/O, no heap, no globals; all state is a member.
//
// step() is the paper's Fig. 1 as a pipeline of named stages, each a
// function with this tick's plain structs in and out:
//
//   frame check -> leg state -> contact and slip -> state estimate ->
//   surface estimate -> recovery and freeze supervisor -> motion reference ->
//   trunk wrench -> GRF QP -> friction probe -> joint commands -> freezing ->
//   output check ->
//   telemetry
//
// One rule for time: a stage reads this tick's outputs of the stages before
// it, and what it needs of the previous tick from `previous_` alone, which
// step() writes once, at its end (and start() fills for the first tick, as
// the standing robot it starts from). A stage's own state (the estimators,
// filters and gaits it updates) is read by other stages only after its
// update in the same tick.
//
// Every choice that depends on the gait in use is in `profile_`
// (GaitProfile), filled once when a gait is picked.
#pragma once
#include <cstdint>

#include "firmware/controller/state/com_offset.hpp"
#include "firmware/controller/gait/crawl_gait.hpp"
#include "firmware/controller/gait/gait_profile.hpp"
#include "firmware/controller/state/grf_delay.hpp"
#include "firmware/controller/force/grf_qp.hpp"
#include "firmware/controller/state/gyro_bias.hpp"
#include "firmware/controller/state/imu_lever_arm.hpp"
#include "firmware/controller/state/joint_acceleration.hpp"
#include "firmware/controller/force/joint_commands.hpp"
#include "firmware/controller/model/kinematics.hpp"
#include "firmware/controller/params.hpp"
#include "firmware/controller/slip/friction_map.hpp"
#include "firmware/controller/slip/friction_probe.hpp"
#include "firmware/controller/slip/slip_detector.hpp"
#include "firmware/controller/stage_clock.hpp"
#include "firmware/controller/state/state_estimator.hpp"
#include "firmware/controller/slip/surface_estimator.hpp"
#include "firmware/controller/state/terrain_estimator.hpp"
#include "firmware/controller/state/torque_bias.hpp"
#include "firmware/controller/gait/trot_gait.hpp"
#include "firmware/controller/slip/traction_recovery.hpp"
#include "firmware/controller/model/types.hpp"
#include "hal/frames.hpp"

namespace hyq {

// True when every field is finite and within the plausible ranges of `limits`.
bool sensorFrameValid(const hal::SensorFrame& frame, const SafetyParams& limits);

class Controller {
 public:
  // Checks the parameters (params_check.hpp) and resets all state. With
  // parameters out of range it refuses them and returns false: every step()
  // then answers the safe hold with kFlagBadParams until init() succeeds.
  bool init(const Params& params);
  // One control tick: sensor frame in, command frame out. Never allocates.
  void step(const hal::SensorFrame& sensors, hal::CommandFrame& command);

  // Ticks whose command was not finite and was replaced by the safe hold.
  uint32_t badCommandCount() const { return bad_command_count_; }
  // Frames whose tick number did not follow the previous frame's.
  uint32_t tickGapCount() const { return tick_gap_count_; }
  // Fault injection, for tests and bring-up: the next command's first
  // feed-forward torque is made NaN before the output check, which must
  // then answer the safe hold with kFlagBadCommand.
  void injectCommandFault() { inject_command_fault_ = true; }
  // Per-stage timing: with a clock set, stageCounts() holds the counts each
  // stage of the last step() took (stage_clock.hpp).
  void setStageClock(const StageClock& clock) { stage_timer_.setClock(clock); }
  const StageCounts& stageCounts() const { return stage_timer_.counts(); }
  // The force distribution QP (its last problem: the QP recorder, tests/bench/qp_record.cpp).
  const GrfQp& grfQp() const { return grf_qp_; }

 private:
  // This tick's IMU readings, less their estimated biases.
  struct Imu {
    Mat3 R_wb;                // [-] orientation of B in W
    Vec3 omega_base;          // [rad/s] angular velocity, B
    Vec3 specific_force;      // [m/s^2] accelerometer, B
  };
  // This tick's leg quantities, leg i in column i.
  struct Legs {
    Mat3x4 q, qd, tau;        // tau less the learnt torque offsets
    Mat3x4 foot_base;         // [m] B
    Mat3x4 foot_vel_base;     // [m/s] u_i = J qd + w x p of the contact point (grf_contact_point) or the centre, B
    Mat3x4 grf_world;         // [N] estimated from joint torques, W
    Vec12 qdd;                // [rad/s^2] joint accelerations, centred (N - 1) / 2 ticks back
    Vec3 alpha_base;          // [rad/s^2] the base's angular acceleration in B, centred alike (zero when unused, and in the crawl below kCrawlTurnAlphaMin)
    // The Jacobian forces go through: the contact point's
    // (EstimatorParams::grf_contact_point), else the foot centre's.
    Mat3 jacobian[kNumLegs];
    Vec3 gravity_torque[kNumLegs];  // [N m]
    LegTrig trig[kNumLegs];   // each leg's joint-angle sines and cosines
    Mat3 mass[kNumLegs];      // [kg m^2] legMassMatrix (EstimatorParams::grf_leg_dynamics; else zero)
    Vec3 com_base;            // [m] whole-body CoM, B
    LegMask at_stop;          // legs with a joint within StanceParams::joint_stop_margin of a limit
  };
  // Which feet stand, which the detector watches, which slip.
  struct Contact {
    LegMask stance;           // the gait's stance set (its plan of last tick)
    LegMask watched;          // stance feet and landing feet that already push
    LegMask held;             // landing feet watched before whose force dipped: detection holds
    LegMask slipping;         // watched and flagged
    LegMask untrusted;        // left out of odometry and plane fits (slipping, recovery on)
    SlipResult slip;          // the detector's answer: flags, slip velocities
  };
  // The estimated body, W.
  struct Body {
    Vec3 base;                // [m] base origin
    Vec3 com;                 // [m]
    Vec3 com_vel;             // [m/s]
    Vec3 omega;               // [rad/s] the trunk's angular velocity
    Mat3x4 feet_world;        // [m] foot centres
    Vec3 foothold_origin;     // [m] the base moved by the CoM offset estimate (GaitInput)
  };
  // What a stage reads of the previous tick: the values at its end.
  struct PreviousTick {
    // The gait's plans (stance set, swing phases, events): last tick's is
    // read while this tick's is written into the other slot, in place, and
    // the two swap at the tick's end (no copy of the plan each tick).
    GaitOutput plans[2];
    int last = 0;
    const GaitOutput& gait() const { return plans[last]; }
    GaitOutput& next() { return plans[last ^ 1]; }
    SlipResult slip;          // base velocity from the legs that anchors the IMU; slip velocities (slip damping)
    LegMask watched;          // feet slip detection watched or held
    LegMask slipping;         // watched feet flagged (telemetry)
    Mat3x4 grf_des_world = Mat3x4::Zero();  // [N] the QP's forces (force continuity)
    Vec3 ground_normal = Vec3::UnitZ();  // [-] the terrain plane's normal, W (contact points, landing forces)
    Vec12 torque_bias = Vec12::Zero();   // [N m] the learnt joint-torque offsets
    Vec3 acc_bias = Vec3::Zero();        // [m/s^2] the accelerometer's estimated bias, B
    Vec3 base_position = Vec3::Zero();   // [m] the estimated base origin, W (re-plan after bad frames)
    Vec3 normal_in_use[kNumLegs] = {Vec3::UnitZ(), Vec3::UnitZ(), Vec3::UnitZ(), Vec3::UnitZ()};  // cones' normals, W
    bool freezing = false;               // the recovery's freeze call
    // [ticks] since each leg's lift-off (counted up to settle_ticks_), 0
    // outside swing: the torque offsets are learnt in a settled swing.
    int swing_ticks[kNumLegs] = {};
  };

  // The stages, in the order step() calls them.
  bool checkFrame(const hal::SensorFrame& s, hal::CommandFrame& command);
  Imu readImu(const hal::SensorFrame& s);
  void computeLegs(const hal::SensorFrame& s, const Imu& imu, Legs& legs);
  void start(const Imu& imu, const Legs& legs);
  Contact detectSlip(const Imu& imu, const Legs& legs);
  Body estimateState(const Imu& imu, const Legs& legs, const Contact& contact);
  RecoveryInput estimateSurfaces(const Imu& imu, const Legs& legs, const Contact& contact,
                                 const Mat3x4& feet_world);
  // A friction probe's answers into the recovery's input (the probe's mu
  // and the normal it was read about, for the rest of the foothold).
  void takeProbeAnswers(const Contact& contact, RecoveryInput& rin);
  void useFrictionMap(const Contact& contact, const Mat3x4& feet_world, RecoveryInput& rin);
  bool superviseRecovery(const RecoveryInput& estimates);
  // The friction probe (RecoveryParams::probe): its pair added to `forces`
  // (the QP's, W) in place; its answers kept for the next tick's recovery.
  void probeFriction(const Legs& legs, const Body& body, const Contact& contact, const GaitOutput& plan,
                     Mat3x4& forces);
  const GaitOutput& planMotion(const Imu& imu, const Legs& legs, const Body& body, const Contact& contact,
                                bool freezing);
  Vec6 trunkWrench(const Imu& imu, const Legs& legs, const Body& body, const GaitOutput& plan) const;
  GrfOutput distributeForces(const Vec6& wrench, const Legs& legs, const Body& body, const GaitOutput& plan);
  void jointCommands(const Imu& imu, const Legs& legs, const Body& body, const Contact& contact,
                     const GaitOutput& plan, const Mat3x4& grf_des, hal::CommandFrame& command) const;
  Vec3 dampedSlipVelocity(int leg, const SlipResult& slip, const GaitOutput& plan) const;
  // The crawl hands over to the trot (GaitSchedule) when its time has come,
  // the last plan had four feet down, none loading or unloading, and the CoM
  // is nearly still (GaitSchedule::max_com_speed).
  void switchGaitIfDue(const Body& body);
  // Picks the gait: its profile, and the stages' settings that follow from it.
  void useGait(GaitKind kind);
  // A watched landing foot's swing PD reference, kept to its press along the ground's normal.
  void pressAlongNormal(int leg, const Imu& imu, const Legs& legs, const Vec3& kp, Vec3& q_ref, Vec3& qd_ref) const;
  // A crawl's stance leg's damping [N m s/rad] and joint velocity
  // reference [rad/s] toward a holding foot (joints behind a torque loop).
  void stanceHold(int leg, const Legs& legs, const SlipResult& slip, Vec3& kd, Vec3& qd_ref) const;
  // A flagged stance foot's slip damping [N s/m] (RecoveryParams::slip_damping, bounded).
  double slipDampingGain(int leg, const Legs& legs) const;
  // A swinging leg's PD gains [N m/rad], [N m s/rad] per joint (JointParams).
  void swingGains(int leg, const Legs& legs, Vec3& kp, Vec3& kd) const;
  // [N m] a swinging leg's inertia feed-forward for its reference's acceleration (the trot's).
  Vec3 swingInertiaTorque(int leg, const Imu& imu, const Legs& legs, const GaitOutput& plan) const;
  // map_writes false: the telemetry of a repeated tick, with no write into
  // the friction map.
  void fillTelemetry(const Legs& legs, const GaitOutput& plan, LegMask slipping, const Mat3x4& grf_des,
                     bool map_writes, hal::Telemetry& t) const;

  // Writes `previous_` from this tick's values.
  void endTick(const Contact& contact, const Mat3x4& grf_des);
  // A bad frame's telemetry: the last good tick's.
  void repeatTelemetry(hal::Telemetry& telemetry) const;
  // Empties the joint-acceleration history and the GRF delay line, and what
  // else assumes one tick between samples.
  void restartFilters();
  void safeHold(hal::CommandFrame& command, uint32_t flags) const;

  Params params_{};
  bool initialised_ = false;
  bool params_refused_ = false;
  bool started_ = false;      // first good frame seen: estimator and gait set up
  double last_good_q_[kNumJoints] = {};  // [rad] the last good frame's joint angles
  bool have_good_ = false;
  bool was_bad_ = false;
  bool have_tick_ = false;
  uint32_t last_tick_ = 0;    // [-] the previous frame's tick number
  uint32_t bad_command_count_ = 0;
  uint32_t tick_gap_count_ = 0;
  bool inject_command_fault_ = false;
  StageTimer stage_timer_;

  StateEstimator estimator_;
  GyroBiasEstimator gyro_bias_;
  ImuLeverArm imu_lever_arm_;  // the accelerometer moved to B's origin (EstimatorParams::imu_position)
  TorqueBiasEstimator torque_bias_;
  ComOffsetEstimator com_offset_;   // the CoM's offset from the model's, added to Legs::com_base
  int settle_ticks_ = 0;            // [ticks] EstimatorParams::torque_bias_settle
  TerrainEstimator terrain_;
  LegMask refit_pending_;  // touched down, the plane not yet refit through them (trot)
  // Both gaits are members (no heap); GaitParams::kind picks the one at
  // start, GaitParams::schedule a switch from the crawl to the trot.
  CrawlGait crawl_;
  TrotGait trot_;
  GaitProfile profile_;                    // the gait in use and what differs with it
  uint32_t run_ticks_ = 0;                 // [-] good frames since the first one (saturates)
  Gait& gait() {  // the gait in use, behind its interface
    if (profile_.kind == GaitKind::kTrot) return trot_;
    return crawl_;
  }
  ImuVelocityIntegrator imu_velocity_;
  SlipDetector slip_detector_;
  JointAccelerationFilter joint_accel_;
  AngularAccelerationFilter base_alpha_;  // the gyro's slope: the base's angular acceleration, B
  // The crawl's fast-turn term (GaitProfile::grf_fast_turn): each leg's
  // torque per base angular acceleration [kg m^2], one leg refreshed a tick.
  Mat3 turn_maps_[kNumLegs] = {Mat3::Zero(), Mat3::Zero(), Mat3::Zero(), Mat3::Zero()};
  int turn_map_leg_ = 0;  // the leg whose map this tick refreshes
  GrfDelayLine grf_delay_;
  SurfaceEstimator surface_[kNumLegs];
  TractionRecovery recovery_;
  FrictionMap friction_map_;        // RecoveryParams::map
  double map_estimate_[kNumLegs] = {0.0, 0.0, 0.0, 0.0};  // [-] each flagged foot's latest mu estimate, for the map
  double map_written_[kNumLegs] = {0.0, 0.0, 0.0, 0.0};  // [-] the last estimate each foot wrote into the map
  double map_mu_[kNumLegs] = {0.0, 0.0, 0.0, 0.0};  // [-] the map's mu under each foot, 0: unknown
  hal::MapWrite map_writes_[kNumLegs] = {};  // this tick's writes into the map, for the telemetry
  FrictionProbe probe_;             // RecoveryParams::probe
  ProbeOutput probe_out_;           // its last tick's answer (read by the next tick's recovery)
  double probe_cos_normal_ = 1.0;   // [-] cos(ProbeParams::max_normal_angle), taken at init
  Mat3x4 grf_sample_ = Mat3x4::Zero();  // [N] this tick's GRF samples aligned with their accelerations (estimateSurfaces), W
  double probe_mu_[kNumLegs] = {0.0, 0.0, 0.0, 0.0};  // [-] a probe's mu for the foot on this foothold, 0: none
  // [-] unit, W: the cone normal that probe's mu was read about (with probe_mu_)
  Vec3 probe_normal_[kNumLegs] = {Vec3::UnitZ(), Vec3::UnitZ(), Vec3::UnitZ(), Vec3::UnitZ()};
  FreezeMode freeze_;
  GrfQp grf_qp_;
  PreviousTick previous_;
  Legs legs_;  // this tick's; a member, so that the tick's largest struct is not on the stack
  // The trot's row split (TrotParams::prior_row_split), its sines taken at init.
  TerrainEstimator::RowSplit row_split_;
  // [m] The stand posture's foot centres in B, the gaits' foothold pattern:
  // a constant, computed at init (24 sines and cosines).
  Mat3x4 stand_feet_ = Mat3x4::Zero();
};

}  // namespace hyq
