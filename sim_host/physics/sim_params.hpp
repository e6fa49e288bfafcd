// The simulator's own numbers (contact model, integration, sensor noise,
// fall criterion), each with its unit. Robot numbers are in
// firmware/controller/model/robot_params.hpp; controller tuning in params.hpp.
#pragma once
#include <string>

#include "hal/frames.hpp"
#include "sim_host/physics/plant_params.hpp"

namespace hyq::sim {

// The contact forces are explicit (computed before each ODE step), so their
// damping is bounded by the lightest mass they push: a foot moving across the
// shank swings only the lower leg about the knee, m = I_knee / L^2 ~ 0.29 kg,
// and explicit damping is stable for c h / m < 2. The values below keep
// c h / m <= ~0.7 at h = 1 ms (docs/performance.md has the measurements).
struct ContactParams {
  // Normal: penalty spring-damper on the penetration depth, never pulling.
  // ~1 mm static sink per foot under HyQ's weight.
  double normal_stiffness = 2.0e5;    // [N/m]
  double normal_damping = 500.0;      // [N s/m]
  // Tangential stick: a stiff bristle spring on the foot's material point
  // at the contact; a loaded foot's contact point stays within ~1 mm of
  // where it touched down and does not creep.
  double tangent_stiffness = 1.0e5;   // [N/m]
  double tangent_damping = 150.0;     // [N s/m]
  // The published body's lower leg is lighter at the foot (0.0262 kg m^2
  // about the knee over 0.346^2: 0.219 kg, against the nominal 0.295 kg):
  // 500 N s/m is c h / m = 2.3 there, beyond explicit damping's bound, and
  // the feet's forces rang between 500 and 1700 N with the robot at rest
  // (ice_patches, 30 s, seed 1: the crawl fell on flat ground). 250 N s/m
  // (c h / m = 1.14) holds them at the weight (+-5 N at rest) on that body;
  // the nominal body keeps normal_damping (c h / m = 1.7).
  double published_normal_damping = 250.0;  // [N s/m]
  // Spheres at the trunk box's 8 corners stand for the trunk in a fall.
  double trunk_corner_radius = 0.01;  // [m]
};

struct IntegrationParams {
  double tick = hal::kTickPeriod;     // [s] control period seen by the controller
  // One exact (dWorldStep) ODE step per tick is stable with the contact
  // numbers above and keeps HyQ at ~55x real time; 2 or 4 substeps cost
  // 2x or 4x and change the standing forces by < 0.1 %.
  int substeps = 1;                   // [-] ODE steps per tick
  bool quick_step = false;            // [-] dWorldQuickStep instead of the exact dWorldStep
  int quick_step_iterations = 20;     // [-] its solver iterations
  double joint_stop_erp = 0.2;        // [-] joint-limit error reduction
  double joint_stop_cfm = 1e-9;       // [m/N] joint-limit softness
};

// Sensor noise (standard deviations) and constant biases (drawn once per run,
// standard deviation of the draw). Magnitudes documented in docs/scenarios.md.
struct SensorNoise {
  double q = 1e-4;                    // [rad] encoder noise
  double qd = 1e-2;                   // [rad/s] differentiated-encoder noise
  double tau = 0.5;                   // [N m] torque-sensor noise
  double tau_bias = 0.5;              // [N m] torque-sensor offset
  double gyro = 2e-3;                 // [rad/s]
  double gyro_bias = 1e-3;            // [rad/s]
  double acc = 2e-2;                  // [m/s^2]
  double acc_bias = 2e-2;             // [m/s^2]
  double orientation = 1e-3;          // [rad] small-angle noise on the IMU attitude
};

struct FallParams {
  double min_height = 0.25;           // [m] base origin above the local ground
  double max_tilt = 0.7853981633974483;  // [rad] angle between z_B and the world z (45 deg)
  double stop_after = 0.5;            // [s] simulated time kept after a fall
};

struct SimConfig {
  ContactParams contact;
  IntegrationParams integration;
  FallParams fall;
};

enum class EngineKind { ode, mujoco };

// MuJoCo's contact: soft constraints with elliptic friction cones.
// solref = (timeconst, dampratio): the contact behaves as a mass-spring-
// damper of that time constant and damping ratio; solimp = (d0, dwidth,
// width): the constraint's impedance from d0 at zero penetration to dwidth
// at `width` of it. impratio > 1 makes friction harder than the normal (less
// creep inside the cone); noslip iterations remove creep altogether.
//
// Defaults: timeconst 5 ms (2.5x the 2 ms MuJoCo asks as the least at a
// 1 ms step; its own default, 20 ms, is a softer contact), critical damping,
// MuJoCo's default impedance, no noslip. impratio 10: a soft friction
// constraint creeps inside the cone at a speed proportional to its force;
// HyQ standing on a 0.2 rad slope (tangential force a fifth of the normal)
// creeps 5.3 mm/s per foot at impratio 1, 1.8 at 3, 0.53 at 10, 0.18 at 30.
// A rubber foot on firm ground does not creep measurably there, and 5 mm/s
// over a crawl's 4-8 s stance moves a foot centimetres; 0.5 mm/s is left
// as the creep the controller must live with (docs/scenarios.md).
struct MujocoParams {
  double timeconst = 0.005;           // [s] solref[0]
  double dampratio = 1.0;             // [-] solref[1]
  double solimp_d0 = 0.9;             // [-] solimp[0]
  double solimp_dwidth = 0.95;        // [-] solimp[1]
  double solimp_width = 0.001;        // [m] solimp[2]
  double impratio = 10.0;             // [-] friction-to-normal impedance ratio
  int noslip_iterations = 0;          // [-]
  int solver_iterations = 100;        // [-] Newton solver's bound
  double solver_tolerance = 1e-10;    // [-]
};

// Which engine runs the scenario, and its contact settings (scenario keys
// physics.*; docs/scenarios.md).
struct PhysicsSpec {
  EngineKind engine = EngineKind::ode;
  double ode_stiffness_scale = 1.0;   // [-] ODE contact's normal and tangential stiffness factor
  MujocoParams mujoco;
};

const char* engineName(EngineKind e);
// "ode" or "mujoco" into `out`; false for any other name.
bool parseEngineName(const std::string& name, EngineKind& out);

}  // namespace hyq::sim
