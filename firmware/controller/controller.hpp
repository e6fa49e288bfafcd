// The slip-aware locomotion controller: one call per 1 kHz tick.
// Inputs in, outputs out: no I/O, no heap, no globals; all state is a member.
//
// Each tick (paper Fig. 1): check the frame -> leg kinematics, GRFs from joint
// torques -> slip detection -> odometry over the non-slipping stance feet ->
// terrain plane at touch-downs -> n, mu estimation and smooth correction (or
// freezing) -> crawl references -> trunk wrench -> GRF QP -> joint commands.
#pragma once
#include <cstdint>

#include "firmware/controller/crawl_gait.hpp"
#include "firmware/controller/grf_delay.hpp"
#include "firmware/controller/gyro_bias.hpp"
#include "firmware/controller/grf_qp.hpp"
#include "firmware/controller/joint_acceleration.hpp"
#include "firmware/controller/params.hpp"
#include "firmware/controller/slip_detector.hpp"
#include "firmware/controller/state_estimator.hpp"
#include "firmware/controller/surface_estimator.hpp"
#include "firmware/controller/terrain_estimator.hpp"
#include "firmware/controller/torque_bias.hpp"
#include "firmware/controller/traction_recovery.hpp"
#include "firmware/controller/types.hpp"
#include "hal/frames.hpp"

namespace hyq {

// True when every field is finite and within the plausible ranges of `limits`.
bool sensorFrameValid(const hal::SensorFrame& frame, const SafetyParams& limits);

class Controller {
 public:
  // Sets parameters and resets all state. The only place that may be slow.
  void init(const Params& params);
  // One control tick: sensor frame in, command frame out. Never allocates.
  void step(const hal::SensorFrame& sensors, hal::CommandFrame& command);

  const Params& params() const { return params_; }

 private:
  struct Legs {  // this tick's leg quantities, leg i in column i
    Mat3x4 q, qd, tau;
    Mat3x4 foot_base;       // [m] B
    Mat3x4 foot_vel_base;   // [m/s] u_i = J qd + w x p, B
    Mat3x4 grf_world;       // [N] estimated from joint torques, W
    Vec12 qdd;              // [rad/s^2] joint accelerations, centred (N - 1) / 2 ticks back
    // The Jacobian forces go through: the contact point's
    // (EstimatorParams::grf_contact_point), else the foot centre's.
    Mat3 jacobian[4];
    Vec3 gravity_torque[4];
  };

  void start();
  // Empties the joint-acceleration history and the GRF delay line.
  void restartAccelerations();
  void computeLegs(const hal::SensorFrame& sensors, const Mat3& R_wb, const Vec3& specific_force);
  void safeHold(hal::CommandFrame& command, uint32_t flags) const;
  void freezeCommand(hal::CommandFrame& command);
  // Replaces `to` by alpha * to + (1 - alpha) * from, in applied torque.
  static void blendCommands(const hal::CommandFrame& from, double alpha, hal::CommandFrame& to);
  void fillTelemetry(hal::CommandFrame& command, uint32_t slip_mask) const;
  Vec3 comBase() const;

  Params params_{};
  bool initialised_ = false;
  bool started_ = false;      // first good frame seen: estimator and gait set up
  hal::SensorFrame last_good_{};
  bool have_good_ = false;
  bool was_bad_ = false;

  StateEstimator estimator_;
  GyroBiasEstimator gyro_bias_;
  TorqueBiasEstimator torque_bias_;
  int swing_ticks_[4] = {0, 0, 0, 0};  // [ticks] since lift-off (counted up to the settle time), 0 outside swing
  TerrainEstimator terrain_;
  CrawlGait gait_;
  GaitOutput gait_out_;
  ImuVelocityIntegrator imu_velocity_;
  SlipDetector slip_detector_;
  JointAccelerationFilter joint_accel_;
  GrfDelayLine grf_delay_;
  SlipResult slip_;
  SurfaceEstimator surface_[4];
  TractionRecovery recovery_;
  GrfQp grf_qp_;
  Legs legs_;
  Mat3 R_wb_ = Mat3::Identity();
  Vec3 com_base_ = Vec3::Zero();     // [m] whole-body CoM in B, this tick
  Vec3 omega_base_ = Vec3::Zero();
  Mat3x4 grf_des_world_ = Mat3x4::Zero();
  bool frozen_ = false;
  Vec12 freeze_q_ = Vec12::Zero();
  Vec12 freeze_tau_ = Vec12::Zero();
  Vec12 last_tau_ = Vec12::Zero();   // [N m] what the joint loop applied last tick
  double unfreeze_time_ = 1e9;       // [s] since freezing ended
  uint32_t qp_flags_ = 0;
  double touchdown_force_[4] = {0, 0, 0, 0};  // [N] normal force when the foot touched down
};

}  // namespace hyq
