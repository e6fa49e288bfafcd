// A simulation scenario, read from a YAML file (documented in
// docs/scenarios.md). Parsing is strict: an unknown key, a wrong type or an
// out-of-range value is a ScenarioError naming the file and the key.
//
// Ranges of the keys ([a, b] inclusive, (a, b] excludes a). Numbers must be
// finite; kScenarioRanges below is this table in code.
//
//   key                          range
//   (the file)                   at most 256 KiB (kMaxScenarioFileBytes)
//   name                         1..64 characters, none a control character;
//                                where it names the output folder out/<name>
//                                (no --out): letters, digits, '_', '-', '.'
//                                only, and not "." or ".."
//   duration                     [0.01, 3600] s (at least one 1 ms tick);
//                                also hyq_sim's --duration
//   seed                         integer, 0..9999999999999999999 (at most 19 digits)
//   terrain.mu                   [0, 5]
//   terrain.patches              at most 1000 entries
//   terrain.patches[].x, .y      each bound in [-400, 400] m
//   terrain.patches[].mu         [0, 5]
//   terrain.patches[].t          each bound in [0, 1e4] s
//   terrain.generate.seed        integer, 1..1e12: a terrain drawn from the
//                                distribution of terrain_generator.hpp (its
//                                slopes, patches, start heading, gait, speed,
//                                pushes and duration replace the file's; no
//                                terrain.mu, patches or ramps beside it)
//   terrain.ramps                at most 100 entries
//   terrain.ramps[].x0           [-400, 400] m
//   terrain.ramps[].angle        (-1.2, 1.2) rad
//   terrain.ramps[].length       (0, 800] m, and x0 + length <= 400 m
//   robot.payload_kg             [0, 200] kg
//   robot.start.x, .y            [-400, 400] m (the ground reaches 500 m)
//   robot.start.yaw              [-pi, pi] rad
//   sensors.q                    [0, 0.01] rad        (100 x the default)
//   sensors.qd                   [0, 1] rad/s         (100 x)
//   sensors.tau, .tau_bias       [0, 50] N m          (100 x)
//   sensors.gyro                 [0, 0.2] rad/s       (100 x)
//   sensors.gyro_bias            [0, 0.1] rad/s       (100 x)
//   sensors.acc, .acc_bias       [0, 2] m/s^2         (100 x)
//   sensors.orientation          [0, 0.1] rad         (100 x)
//   disturbances                 at most 100 entries
//   disturbances[].t             [0, 3600] s
//   disturbances[].duration      (0, 3600] s
//   disturbances[].force         each component in [-5000, 5000] N, and the
//                                forces active at any one time add up to at
//                                most 5000 N (magnitude)
//   physics.engine               ode or mujoco (default ode); also hyq_sim's --engine
//   physics.ode.stiffness_scale  [0.1, 10]: the ODE contact's normal and
//                                tangential stiffness times this (above 1,
//                                at least ceil(sqrt(scale)) substeps a tick)
//   physics.mujoco.timeconst     [0.002, 0.1] s  (solref[0]; 2 ticks at least)
//   physics.mujoco.dampratio     [0.1, 10]       (solref[1])
//   physics.mujoco.solimp        [d0, dwidth, width]: d0, dwidth in [0.01, 0.9999],
//                                width in [0, 0.1] m
//   physics.mujoco.impratio      [1, 100]
//   physics.mujoco.noslip_iterations  integer in [0, 100]
//   physics.mujoco (together)    a contact that carries HyQ. The impedance d
//                                runs from d0 at the surface to dwidth at
//                                `width` deep; MuJoCo's contact is a spring-
//                                damper of time constant timeconst * dwidth / d,
//                                which must be at least 2 ms (2 ticks); at rest
//                                a foot sinks (1 - d) (dwidth / d)^2 timeconst^2
//                                dampratio^2 a, at most the foot's radius
//                                (21.75 mm), with a = 110 m/s^2 x (84.7 kg +
//                                payload) / 84.7 kg; and d at that depth is at
//                                least 0.5
//   plant.model                  ideal or hyq (default hyq): the preset of
//                                every plant.* key below (sim_host/physics/plant_params.hpp)
//   plant.actuator.model         ideal or hyq (the torque-loop model)
//   plant.actuator.pd_rate       [500, 10000] Hz
//   plant.actuator.bandwidth     [1, 500] Hz
//   plant.actuator.damping_ratio [0.1, 5]
//   plant.actuator.rate_limit    [100, 1e7] N m/s
//   plant.actuator.torque_sensor_cutoff  [1, 5000] Hz
//   plant.actuator.velocity_limit  [0, 100] rad/s (0: none)
//   plant.encoder.resolution     [0, 0.01] rad (0: not quantised)
//   plant.encoder.velocity       truth or differentiated
//   plant.encoder.velocity_cutoff  [1, 1000] Hz
//   plant.delay.sensor_ticks, .command_ticks, .imu_ticks  integers in [0, 10] ticks
//   plant.body                   nominal or published
//   plant.imu                    origin or mounted
//   plant.trunk_mass_scale       [0.5, 2] the simulated trunk's mass over its body model's
//   plant.trunk_inertia_scale    [0.5, 2] the simulated trunk's inertia tensor over its body model's
//   controller.joint.torque_bandwidth  0 or [1, 1000] Hz: the torque loop the controller's
//                                gains assume (0: ideal joints; plant.model hyq sets 40)
//   controller.joint.swing_kp, .swing_kd, .swing_crossover_fraction, controller.slip_damping,
//   controller.k_mu,
//   controller.estimator.com_offset_time, controller.estimator.imu_position [x, y, z]:
//                                params.hpp's, with their ranges
//   gait.*, controller.mu_default, controller.qp.*, controller.trunk.*
//                                the controller's own ranges
//                                (firmware/controller/params_check.cpp)
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "firmware/controller/params.hpp"
#include "sim_host/physics/sim_params.hpp"

namespace hyq::sim {

struct ScenarioError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The ranges of the table above, as the reader checks them.
struct KeyRange {
  const char* key;        // "[]" stands for a list index
  double min, max;
  bool min_open, max_open;  // the bound itself is outside the range
  const char* unit;       // "" for none
};

inline constexpr size_t kMaxScenarioFileBytes = 256 * 1024;
inline constexpr double kMaxForce = 5000.0;  // [N] of all disturbances at one time

inline constexpr KeyRange kScenarioRanges[] = {
    {"name", 1, 64, false, false, "characters"},
    {"duration", 0.01, 3600.0, false, false, "s"},
    {"terrain.mu", 0.0, 5.0, false, false, ""},
    {"terrain.patches", 0, 1000, false, false, "entries"},
    {"terrain.patches[].x", -400.0, 400.0, false, false, "m"},
    {"terrain.patches[].y", -400.0, 400.0, false, false, "m"},
    {"terrain.patches[].mu", 0.0, 5.0, false, false, ""},
    {"terrain.patches[].t", 0.0, 1e4, false, false, "s"},
    {"terrain.ramps", 0, 100, false, false, "entries"},
    {"terrain.generate.seed", 1.0, 1e12, false, false, ""},
    {"terrain.ramps[].x0", -400.0, 400.0, false, false, "m"},
    {"terrain.ramps[].angle", -1.2, 1.2, true, true, "rad"},
    {"terrain.ramps[].length", 0.0, 800.0, true, false, "m"},
    {"terrain.ramps[].end", -400.0, 400.0, false, false, "m"},  // x0 + length
    {"robot.payload_kg", 0.0, 200.0, false, false, "kg"},
    {"robot.start.x", -400.0, 400.0, false, false, "m"},
    {"robot.start.y", -400.0, 400.0, false, false, "m"},
    {"robot.start.yaw", -3.14159265358979323846, 3.14159265358979323846, false, false, "rad"},
    {"sensors.q", 0.0, 100 * SensorNoise{}.q, false, false, "rad"},
    {"sensors.qd", 0.0, 100 * SensorNoise{}.qd, false, false, "rad/s"},
    {"sensors.tau", 0.0, 100 * SensorNoise{}.tau, false, false, "N m"},
    {"sensors.tau_bias", 0.0, 100 * SensorNoise{}.tau_bias, false, false, "N m"},
    {"sensors.gyro", 0.0, 100 * SensorNoise{}.gyro, false, false, "rad/s"},
    {"sensors.gyro_bias", 0.0, 100 * SensorNoise{}.gyro_bias, false, false, "rad/s"},
    {"sensors.acc", 0.0, 100 * SensorNoise{}.acc, false, false, "m/s^2"},
    {"sensors.acc_bias", 0.0, 100 * SensorNoise{}.acc_bias, false, false, "m/s^2"},
    {"sensors.orientation", 0.0, 100 * SensorNoise{}.orientation, false, false, "rad"},
    {"disturbances", 0, 100, false, false, "entries"},
    {"disturbances[].t", 0.0, 3600.0, false, false, "s"},
    {"disturbances[].duration", 0.0, 3600.0, true, false, "s"},
    {"disturbances[].force", -kMaxForce, kMaxForce, false, false, "N"},
    {"physics.ode.stiffness_scale", 0.1, 10.0, false, false, ""},
    {"physics.mujoco.timeconst", 0.002, 0.1, false, false, "s"},
    {"physics.mujoco.dampratio", 0.1, 10.0, false, false, ""},
    {"physics.mujoco.solimp[0]", 0.01, 0.9999, false, false, ""},
    {"physics.mujoco.solimp[1]", 0.01, 0.9999, false, false, ""},
    {"physics.mujoco.solimp[2]", 0.0, 0.1, false, false, "m"},
    {"physics.mujoco.impratio", 1.0, 100.0, false, false, ""},
    {"physics.mujoco.noslip_iterations", 0.0, 100.0, false, false, ""},
    {"plant.actuator.pd_rate", 500.0, 10000.0, false, false, "Hz"},
    {"plant.actuator.bandwidth", 1.0, 500.0, false, false, "Hz"},
    {"plant.actuator.damping_ratio", 0.1, 5.0, false, false, ""},
    {"plant.actuator.rate_limit", 100.0, 1e7, false, false, "N m/s"},
    {"plant.actuator.torque_sensor_cutoff", 1.0, 5000.0, false, false, "Hz"},
    {"plant.actuator.velocity_limit", 0.0, 100.0, false, false, "rad/s"},
    {"plant.encoder.resolution", 0.0, 0.01, false, false, "rad"},
    {"plant.encoder.velocity_cutoff", 1.0, 1000.0, false, false, "Hz"},
    {"plant.delay.sensor_ticks", 0.0, kMaxDelayTicks, false, false, "ticks"},
    {"plant.delay.command_ticks", 0.0, kMaxDelayTicks, false, false, "ticks"},
    {"plant.delay.imu_ticks", 0.0, kMaxDelayTicks, false, false, "ticks"},
    {"plant.trunk_mass_scale", 0.5, 2.0, false, false, ""},
    {"plant.trunk_inertia_scale", 0.5, 2.0, false, false, ""},
};

// MuJoCo's contact, all its settings together (the table above).
// [s] the least time constant of the contact's spring-damper: MuJoCo's own
// rule, timeconst at least twice the 1 ms step.
inline constexpr double kMujocoMinTimeConstant = 0.002;
// [m/s^2] a quarter of HyQ's weight over a foot's effective mass along the
// contact normal (about 1.9 kg) in the start posture: measured, the trunk's
// sink at rest on softened contacts (MujocoEngine::staticSink) against the
// sink formula of the table gives 107..112 m/s^2. A payload adds in
// proportion to the robot's mass.
inline constexpr double kMujocoFootLoadAcceleration = 110.0;
// The least impedance where the feet carry the robot: below it the
// regularised contact leaves most of each change of force to the spring, and
// the feet sink and creep (measured on MuJoCo with solimp [d, d, 0.001]: the
// trot falls at d = 0.1, the crawl at 0.05; both walk at 0.2).
inline constexpr double kMujocoMinImpedance = 0.5;

// The entry of kScenarioRanges for `key` (throws std::logic_error if none).
const KeyRange& scenarioRange(std::string_view key);
// True when v lies in the range.
bool inRange(const KeyRange& range, double v);
// "in [0.01, 3600] s", for messages.
std::string rangeText(const KeyRange& range);

// `text` as a finite decimal number: an optional sign, digits with an
// optional fraction, an optional exponent, the whole text and nothing else
// (no spaces, no hexadecimal, no inf or nan). nullopt otherwise.
std::optional<double> parseDecimal(std::string_view text);

// `s` fit for a one-line message: control characters as '?', and cut to
// `max_chars` characters followed by "..." when longer.
std::string clipForMessage(std::string_view s, size_t max_chars = 80);

// True when `name` can name a folder: 1..64 letters, digits, '_', '-' or
// '.', and not "." or "..".
bool isPlainFileName(std::string_view name);

struct FrictionPatch {
  double x0, x1;    // [m] extent along x, W
  double y0, y1;    // [m] extent along y, W
  double mu;        // [-]
  // [s] there only while t0 <= t < t1 (a sudden oil patch); always by default
  double t0 = -std::numeric_limits<double>::infinity();
  double t1 = std::numeric_limits<double>::infinity();
};

// Flat ground at z = 0 up to x0, a slope rising at `angle` for `length`
// (measured along x), then flat again. Ramps follow each other along +x.
struct Ramp {
  double x0;        // [m] foot of the slope
  double angle;     // [rad] slope angle, positive uphill towards +x
  double length;    // [m] horizontal extent of the slope
};

struct TerrainSpec {
  double mu = 0.8;                       // [-] everywhere not covered by a patch
  std::vector<FrictionPatch> patches;    // later entries win where they overlap
  std::vector<Ramp> ramps;               // sorted by x0, not overlapping
  uint64_t generated_seed = 0;           // terrain.generate.seed the terrain was drawn from; 0: the file's
};

struct Disturbance {
  double t;                              // [s] start
  double duration;                       // [s]
  std::array<double, 3> force;           // [N] at the trunk CoM, W
};

struct SensorSpec {
  bool noise = true;
  // false: each constant bias is drawn from a normal distribution with its
  // magnitude as standard deviation; true: each is exactly its magnitude,
  // with a random sign per axis or joint (the worst case of a specified
  // bias, on every axis and joint at once).
  bool biases_at_magnitude = false;
  SensorNoise magnitudes;
};

struct Scenario {
  std::string name;
  std::string source_file;               // where it came from ("" if built in code)
  double duration = 10.0;                // [s] simulated
  uint64_t seed = 1;
  TerrainSpec terrain;
  double payload_kg = 0.0;               // [kg] extra trunk mass unknown to the controller
  double start_x = 0.0, start_y = 0.0, start_yaw = 0.0;  // [m], [m], [rad]
  std::string controller_kind = "wbc";
  hyq::Params controller_params;         // params.hpp defaults + scenario overrides
  SensorSpec sensors;
  std::vector<Disturbance> disturbances;
  PhysicsSpec physics;                   // engine and contact settings
  PlantSpec plant;                       // actuators, encoders, delays, IMU mount, bodies (plant.*)
};

// Puts `s` on the hyq plant with the controller configured for HyQ, as
// `plant: {model: hyq}` does: the joint gains for their torque loop
// (kHyqControllerTorqueBandwidth); unless `s` sets them already, the
// crawl's body shift bounded (kHyqShiftAcceleration), the crawl's (hind
// feet's) step height (kHyqCrawlStepHeight), the trot's duty factor (kHyqTrotDutyFactor)
// and guess delay (kHyqTrotGuessDelay), and the IMU's lever arm taken out where the
// robot has its IMU (EstimatorParams::imu_position).
void putOnHyqPlant(Scenario& s);

// Reads and checks a scenario file. Throws ScenarioError. The plant is
// `default_plant` with its preset where the file names none (`plant.model`):
// the robot's own, hyq, unless the caller asks for the ideal plant.
Scenario loadScenario(const std::string& path, PlantModel default_plant = PlantModel::hyq);
// Same, from YAML text; `origin` names the source in messages.
Scenario parseScenario(const std::string& yaml_text, const std::string& origin,
                       PlantModel default_plant = PlantModel::hyq);
// The text of the regular file `path`, at most max_bytes + 1 bytes (more is
// left unread, so that a caller can tell the file is too long). Throws
// ScenarioError, one line naming the file, when it cannot be opened or read
// or is not a regular file (a FIFO, a device, a directory), which is never
// waited on.
std::string readRegularFile(const std::string& path, size_t max_bytes);
// readRegularFile with kMaxScenarioFileBytes: parseScenario refuses a text
// that long.
std::string readScenarioFile(const std::string& path);

// Throws ScenarioError (naming the scenario's file and the key `name`)
// unless the scenario's name can name its default output folder out/<name>.
void checkOutputFolderName(const Scenario& scenario);

}  // namespace hyq::sim
