// Plain-data frames exchanged between the robot (or the simulator) and the
// controller board, once per 1 kHz tick. These are the exact structs the
// firmware reads and writes: no pointers, no virtuals, fixed size, doubles.
//
// Conventions (used across the project):
//   legs   LF=0, RF=1, LH=2, RH=3
//   joints per leg HAA=0, HFE=1, KFE=2; joint index j = 3*leg + joint
//   W: world frame, z up.  B: base (trunk) frame, x forward, y left, z up.
#pragma once
#include <cstdint>

namespace hyq::hal {

constexpr int kNumLegs = 4;
constexpr int kJointsPerLeg = 3;
constexpr int kNumJoints = kNumLegs * kJointsPerLeg;
constexpr uint32_t kTicksPerSecond = 1000;  // [1/s] frames come at 1 kHz
constexpr double kTickPeriod = 1.0 / kTicksPerSecond;  // [s] one tick

// What the robot's sensors deliver each tick (proprioception only).
struct SensorFrame {
  uint32_t tick;                  // [-] monotonic tick counter, 1 tick = 1 ms
  double q[kNumJoints];           // [rad] joint positions (encoders)
  double qd[kNumJoints];          // [rad/s] joint velocities
  double tau[kNumJoints];         // [N m] measured joint torques
  double imu_quat[4];             // [-] orientation of B in W, (w, x, y, z)
  double imu_gyro[3];             // [rad/s] angular velocity of B, in B
  double imu_acc[3];              // [m/s^2] specific force (accelerometer), in B
};

// Command-frame status bits (CommandFrame::flags).
enum CommandFlag : uint32_t {
  kFlagBadSensorFrame = 1u << 0,  // NaN/Inf/out of range input: safe hold active
  kFlagQpInfeasible = 1u << 1,    // GRF QP had no feasible point: best bounded answer
  kFlagQpMaxIter = 1u << 2,       // GRF QP hit its iteration bound
  kFlagFreeze = 1u << 3,          // freezing mode ("wooden chair") active
  kFlagNotInitialised = 1u << 4,  // step() called before init()
  kFlagLinkLost = 1u << 5,        // board: link to robot lost, safe state
  kFlagBadCommand = 1u << 6,      // the controller's command was not finite: safe hold instead
  kFlagBadParams = 1u << 7,       // init() refused its parameters: safe hold until valid ones come
  kFlagTickGap = 1u << 8,         // frames were missed before this one: filters restarted
};

// The friction map's cell a foot's estimate went into on one tick, as the
// write left the cell; count 0: no write by that foot.
struct MapWrite {
  int32_t cell[2];                // [-] the cell: floor(x / cell_size), floor(y / cell_size) of the foot, W
  uint32_t count;                 // [-] the cell's estimates after the write
  double mu;                      // [-] their mean
  double spread;                  // [-] their standard deviation (0 for one)
};

// Controller internals that travel with the command so that a host run and
// a run on the board log the same things. Not used by the joint loop.
struct Telemetry {
  uint32_t stance_mask;           // bit i: leg i in stance (controller's view)
  uint32_t slip_mask;             // bit i: leg i flagged slipping
  uint32_t swing_leg;             // [-] leg in swing, or 4 when none
  double gait_phase;              // [-] 0..1 within the crawl cycle
  double base_pos_est[3];         // [m] estimated base position, W
  double base_vel_est[3];         // [m/s] estimated base velocity, W
  double foot_vel_base[kNumLegs][3];  // [m/s] u_i = bv_fi + bw x bx_fi, in B, of the foot's contact point (grf_contact_point) or centre
  double grf_est[kNumLegs][3];    // [N] GRF estimated from joint torques, W
  double grf_des[kNumLegs][3];    // [N] GRF from the QP, W
  double mu_used[kNumLegs];       // [-] friction coefficient used in the QP
  double normal_used[kNumLegs][3];  // [-] surface normal used in the QP, W
  double mu_hat[kNumLegs];        // [-] friction estimate: a probe's on this foothold, else the slips' filtered one (0 if none yet)
  double normal_hat[kNumLegs][3]; // [-] filtered normal estimate, W (zero if none yet, as mu_hat)
  uint32_t probe_leg;             // [-] the foot a friction probe ramps its pair on, 4 when none
  uint32_t probe_partner;         // [-] the pair's other foot, 4 when none
  uint32_t probe_counts[3];       // [-] friction probes started, ended in a break-away (a friction found), ended held
  MapWrite map_writes[kNumLegs];  // each foot's write into the friction map on this tick
};

// What the controller asks the joint loop to do. The low-level joint loop
// (motor-driver bridge, or the simulator's actuator model) applies, per joint,
//   tau = tau_ff + kp * (q_ref - q) + kd * (qd_ref - qd),
// saturated to the joint's effort limit.
struct CommandFrame {
  uint32_t tick;                  // [-] tick of the sensor frame this answers
  uint32_t flags;                 // [-] CommandFlag bits
  double tau_ff[kNumJoints];      // [N m] feed-forward torque
  double q_ref[kNumJoints];       // [rad] position reference
  double qd_ref[kNumJoints];      // [rad/s] velocity reference
  double kp[kNumJoints];          // [N m/rad] joint stiffness
  double kd[kNumJoints];          // [N m s/rad] joint damping
  Telemetry telemetry;
};

}  // namespace hyq::hal
