// One joint's low-level loop, as HyQ's joint board runs it: it samples its
// encoder, runs the command frame's PD at its own rate (PlantSpec's
// actuator.pd_rate), and its closed torque loop delivers the PD's torque as
// a second-order lag, rate-limited and saturated; its torque sensor reads
// the delivered torque through a first-order filter. The simulator runs one
// per joint on either engine (simulator.cpp). Nothing here allocates.
#pragma once
#include "sim_host/physics/plant_params.hpp"

namespace hyq::sim {

// A joint encoder as the board reads it: the angle quantised to the
// encoder's step, and the velocity as the backward difference of those
// readings through a first-order low-pass (or the true velocity, with
// VelocitySource::truth).
class JointEncoder {
 public:
  JointEncoder() = default;
  explicit JointEncoder(const EncoderParams& params);
  // At rest at `q` [rad]: the reading, the previous one and the velocity.
  void reset(double q);
  // A reading of the joint at angle `q` [rad] and velocity `qd` [rad/s],
  // `elapsed` [s] after the previous one.
  void sample(double q, double qd, double elapsed);
  double position() const { return position_; }  // [rad]
  double velocity() const { return velocity_; }  // [rad/s]

  // `q` to the nearest multiple of `step` (q itself for step 0).
  static double quantise(double q, double step);
  // The low-pass's lag behind a steady acceleration [s], for a sample
  // period `period` [s]: the backward difference's period / 2 and the
  // filter's period / (exp(2 pi fc period) - 1).
  static double velocityLag(double cutoff, double period);

 private:
  EncoderParams params_;
  double position_ = 0.0, velocity_ = 0.0;
  double alpha_period_ = -1.0, alpha_ = 1.0;  // the filter gain for that period
};

// The command frame's PD terms for one joint.
struct JointCommand {
  double tau_ff = 0.0;   // [N m]
  double q_ref = 0.0;    // [rad]
  double qd_ref = 0.0;   // [rad/s]
  double kp = 0.0;       // [N m/rad]
  double kd = 0.0;       // [N m s/rad]
};

class JointActuator {
 public:
  // The torque loop integrates in steps of at most this [s] (10 kHz).
  static constexpr double kMaxIntegrationStep = 1e-4;

  JointActuator() = default;
  JointActuator(const ActuatorParams& actuator, const EncoderParams& encoder, double effort_limit);
  // At rest at `q` [rad], delivering `tau` [N m] (its sensor reading it).
  void reset(double q, double tau = 0.0);

  // One engine step of `h` [s] from the joint's state at its start, (q0
  // [rad], qd0 [rad/s]): the PD on the board's latest encoder sample and
  // `command` when the step begins, again at each PD sample inside the
  // step (the joint's state taken as q0 + qd0 t there), the torque loop
  // integrated over the step. Returns the mean torque delivered over the
  // step [N m] (what the engine applies).
  double step(const JointCommand& command, double q0, double qd0, double h);
  // After the engine step, the joint at its end (q1, qd1): the board reads
  // its encoder when a PD period ends there.
  void finishStep(double q1, double qd1);

  // The PD's output [N m], non-finite as 0, saturated.
  double pd(const JointCommand& command) const;

  double demanded() const { return demand_; }   // [N m] the PD's latest output
  double delivered() const { return torque_; }  // [N m] at the end of the last step
  double measured() const { return sensor_; }   // [N m] the torque sensor's filtered reading
  const JointEncoder& encoder() const { return encoder_; }

 private:
  // Discrete torque loop for an integration step `dt` [s]: the exact
  // zero-order-hold update of the lag, x+ = phi x + gamma u, x = (torque,
  // its rate), and the sensor filter's gain.
  void discretise(double dt);
  // One integration step toward demand_, the joint moving at qd [rad/s].
  void integrate(double qd);

  ActuatorParams params_;
  double effort_limit_ = 0.0;        // [N m]
  double pd_period_ = 1e-3;          // [s]
  JointEncoder encoder_;
  double since_sample_ = 0.0;        // [s] since the encoder's last sample
  double demand_ = 0.0;              // [N m]
  double torque_ = 0.0, rate_ = 0.0; // [N m], [N m/s] delivered torque and its rate
  double sensor_ = 0.0;              // [N m]
  // The discretisation for dt_ [s].
  double dt_ = -1.0;
  double phi_[2][2] = {{1.0, 0.0}, {0.0, 1.0}};
  double gamma_[2] = {0.0, 0.0};
  double sensor_alpha_ = 1.0;
};

}  // namespace hyq::sim
