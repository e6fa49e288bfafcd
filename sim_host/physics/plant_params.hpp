// The simulated plant between the controller's command frame and its sensor
// frame: the joints' actuators, the encoders, the transport delays, the IMU's
// mounting and the bodies the engines simulate (scenario keys plant.*;
// docs/scenarios.md, "The plant").
//
// `ideal` is the plant the controller's model assumes: the joint PD applied
// exactly at every engine step on the true state, the torque sensor reading
// that torque, true joint velocities plus noise, no delays, the IMU at the
// base origin and the controller's own nominal bodies. `hyq` is HyQ as
// published; every default below names its source, and those that are
// assumptions say so.
#pragma once
#include <string>

namespace hyq::sim {

enum class PlantModel { ideal, hyq };
enum class BodyModel { nominal, published };
enum class ImuMount { origin, mounted };
enum class VelocitySource { truth, differentiated };

// One joint's low-level loop (HyQ's joint board): the command frame's PD at
// `pd_rate`, a closed torque loop tracking the PD's torque as a second-order
// lag, a torque rate limit and saturation, and a torque sensor behind a
// first-order filter.
struct ActuatorParams {
  bool model = false;                 // [-] false: the ideal joint loop (exact PD torque every engine step)
  // HyQ's low-level control runs at 1 kHz ("the frequency of the low level
  // controller in the real platform", Focchi et al., Sec. 5).
  double pd_rate = 1000.0;            // [Hz]
  // Closed torque loop: natural frequency and damping ratio of the lag. At
  // damping 1/sqrt(2) the loop's -3 dB bandwidth equals the natural
  // frequency. HyQ's hydraulic joints close their torque loop in the tens of
  // Hz (Boaventura et al., "Dynamic torque control of a hydraulic quadruped
  // robot", ICRA 2012; Focchi et al., "Robot impedance control and
  // passivity analysis with inner torque and velocity feedback loops",
  // 2016); the servo valves' flow bandwidth, about 250 Hz (Moog E024,
  // Semini et al., "Design of HyQ", 2011), bounds it from above. 40 Hz and
  // 1/sqrt(2) are this project's choice inside that range, not a measured
  // figure of one joint.
  double bandwidth = 40.0;            // [Hz]
  double damping_ratio = 0.70710678118654752;  // [-]
  // Torque rate limit: an estimate, not a published figure. A valve's rated
  // flow (~4e-5 m^3/s) into a cylinder chamber and hose (~1e-5 m^3) of oil
  // at an effective bulk modulus ~1e9 Pa raises its pressure at ~4e9 Pa/s;
  // on a 16 mm bore (2.0e-4 m^2) at a ~0.05 m lever that is ~4e4 N m/s. Half
  // of it, 2e4 N m/s, allows for the opposite chamber and the valve's
  // pressure drop: a 150 N m swing takes at least 7.5 ms.
  double rate_limit = 2.0e4;          // [N m/s]
  // Torque sensor (load cells on the cylinders, a strain-gauge sensor on
  // HAA) read through a first-order anti-alias filter: assumed at 200 Hz,
  // under the 500 Hz Nyquist frequency of the 1 kHz loop; no published
  // figure at hand.
  double torque_sensor_cutoff = 200.0;  // [Hz]
  // The servo valves' flow saturation: driving a joint along its motion, the
  // actuator has the supply pressure less the valve's drop, which grows with
  // the flow squared, so the torque it can deliver that way falls from the
  // effort limit at rest to none at this velocity, as (1 - (qd / limit)^2);
  // against the motion it has all of it. 0: no limit (the ideal plant's).
  double velocity_limit = 0.0;        // [rad/s]
};

// HyQ's joint velocity limit, the servo valves' flow: 12 rad/s on every joint
// in the published description (HAA, HFE and KFE alike).
inline constexpr double kHyqJointVelocityLimit = 12.0;  // [rad/s]

// HyQ's joint encoders: high-resolution relative optical encoders (Avago
// AEDA-3300, Semini et al., "Design of HyQ", 2011). At 80 000 counts per
// revolution after quadrature decoding (assumed) a count is
// 2 pi / 80 000 = 7.854e-5 rad.
inline constexpr double kHyqEncoderResolution = 2.0 * 3.14159265358979323846 / 80000.0;  // [rad]

// Joint encoders and the velocity the robot computes from them.
struct EncoderParams {
  // Quantisation step; 0: none (the reading is the true angle plus the
  // sensors.q noise). With quantisation on the reading has no further noise.
  double resolution = 0.0;            // [rad]
  // truth: the true velocity plus the sensors.qd noise. differentiated:
  // the backward difference of the (quantised) encoder readings at each
  // sample, through a first-order low-pass of `velocity_cutoff`, and no
  // further noise. Its lag to a steady acceleration is
  // T/2 + T/(exp(2 pi fc T) - 1) (T the sample period; ~1/(2 pi fc)):
  // 1.64 ms at 100 Hz and 1 kHz.
  VelocitySource velocity = VelocitySource::truth;
  // Assumed, no published figure at hand: 100 Hz brings the differentiated
  // quantisation (one count in one tick is 0.079 rad/s) to a few hundredths
  // of a rad/s once filtered, near the ideal plant's 0.01 rad/s noise.
  double velocity_cutoff = 100.0;     // [Hz]
};

// Transport delays in whole 1 ms ticks. A frame read at tick k carries the
// joints' state of tick k - sensor_ticks and the IMU's of tick
// k - sensor_ticks - imu_ticks; the command the controller answers at tick k
// reaches the joints at tick k + command_ticks.
struct DelayParams {
  int sensor_ticks = 0;               // [ticks]
  int command_ticks = 0;              // [ticks]
  int imu_ticks = 0;                  // [ticks]
};
inline constexpr int kMaxDelayTicks = 10;  // [ticks] each delay's bound
// HyQ's control computer exchanges one frame per 1 ms cycle with the joint
// boards: one tick each way is this project's assumption of that cycle. The
// IMU's own filtering and serial link add 2 ticks (assumed).
inline constexpr DelayParams kHyqDelays{1, 1, 2};

struct PlantSpec {
  PlantModel model = PlantModel::ideal;  // the preset the values below came from
  ActuatorParams actuator;
  EncoderParams encoder;
  DelayParams delay;
  // The bodies the engines simulate: the controller's nominal model
  // (robot_params.hpp) or the published description's inertial parameters
  // (body_model.hpp).
  BodyModel body = BodyModel::nominal;
  // Where the IMU sits: at the base origin, or where HyQ has it (0.290, 0,
  // 0.0999) m in B, upside down (body_model.hpp).
  ImuMount imu = ImuMount::origin;
  // The simulated trunk's mass and inertia tensor over the body model's
  // (the margin map's "model error" axes); the controller keeps its own.
  double trunk_mass_scale = 1.0;      // [-]
  double trunk_inertia_scale = 1.0;   // [-]

  // True when every part is the ideal one (the simulator then runs the
  // ideal plant's code path exactly).
  bool isIdeal() const {
    return !actuator.model && encoder.resolution == 0.0 && encoder.velocity == VelocitySource::truth &&
           delay.sensor_ticks == 0 && delay.command_ticks == 0 && delay.imu_ticks == 0 &&
           body == BodyModel::nominal && imu == ImuMount::origin && trunk_mass_scale == 1.0 &&
           trunk_inertia_scale == 1.0;
  }
};

// The presets: every part ideal, or every part HyQ's (the defaults above
// with the models switched on, and kHyqJointVelocityLimit).
PlantSpec idealPlant();
// The torque-loop bandwidth the controller's joint gains assume on HyQ
// (JointParams::torque_bandwidth), which a scenario on the hyq plant gets
// unless it sets controller.joint.torque_bandwidth: the robot's
// configuration, fixed while the margin map varies the plant's own.
inline constexpr double kHyqControllerTorqueBandwidth = 40.0;  // [Hz]
// The crawl's body shift on HyQ, its peak acceleration bounded
// (GaitParams::max_shift_acceleration), which a scenario on the hyq plant
// gets unless it sets gait.max_shift_acceleration. Behind the torque loop,
// with the published body's CoM 3 cm off the model's, the unbounded shift's
// 2.9 m/s^2 put the crawl's feet on the ice's limit: hyq plant, seeds 1-4,
// recovery on, longest slip after detection, unbounded -> 1 m/s^2, ODE:
// ramp 61 -> 31 ms, ice_010 66 -> 49, ramp_035 59 -> 38, ice_to_grip 53 ->
// 33; MuJoCo: ice_patches 148 -> 28, ice_010 119 -> 44, ramp_035 176 -> 26.
// The drawn validation crawls: falls 19 -> 12 of 201 (docs/design-notes.md,
// "The crawl's margin against a CoM the model misplaces"). A crawl that
// hands over to the trot mid-stride leaves its CoM off the diagonals, which
// the trot's start shift takes back before its first lift-off. The ideal plant
// keeps it off: there it costs the ramps their estimates ("A gentler body
// shift").
inline constexpr double kHyqShiftAcceleration = 1.0;  // [m/s^2]
// The trot's duty factor on HyQ (TrotParams::duty_factor), which a scenario
// on the hyq plant gets unless it sets gait.trot.duty_factor: its swing
// 0.18 s instead of 0.24, its four-foot hand-overs 0.12 s instead of 0.06,
// twice a 0.6 s cycle. Behind the torque loop a pair's stance is where the
// trunk tips about the line between its feet; the longer it lasts the
// further (docs/design-notes.md, "The trot's diagonal stance behind the
// torque loop").
inline constexpr double kHyqTrotDutyFactor = 0.7;  // [-]
// The trot's guess delay on HyQ (TrotParams::guess_delay), which a scenario
// on the hyq plant gets unless it sets gait.trot.guess_delay: none. A flag
// on a landing foot starts its guess toward the floor at once. Behind the
// torque loop a foot takes 25-30 ms to stop once its cone is narrowed; a
// 30 ms wait before the guess doubled the trot's slides after detection
// (trot_ice_patches, seeds 1-8, longest: ODE 83 -> 51 ms, MuJoCo 78 -> 20;
// trot_push_ice 173 -> 54 and 89 -> 58). The cost: the trot's landings on
// good ground are flagged too, and its feet's mu in use sits at the floor
// (0.07 on level ground) as on ice (docs/design-notes.md, "The trot's guess
// delay on the hyq plant").
inline constexpr double kHyqTrotGuessDelay = 0.0;  // [s]
// The crawl's swing apex on HyQ (GaitParams::step_height: the hind feet's;
// the front feet keep kFrontStepHeight), which a scenario on the hyq plant
// gets unless it sets gait.step_height. Behind the torque
// loop a foot lags its swing and lands as the reference brakes: from a
// 10 cm apex the hind feet met the ground at 0.2 m/s and bounced three or
// four times, and those bounces were 12 of the 20 slips that lasted more
// than 40 ms after detection (hyq plant, 8 crawl scenarios, ODE seeds 1-8);
// from 6 cm none did. The drawn validation set, recovery on: falls 16 ->
// 12, got through 231 -> 241 (docs/design-notes.md, "A crawl's landing
// behind the torque loop").
inline constexpr double kHyqCrawlStepHeight = 0.06;  // [m]
PlantSpec hyqPlant();

const char* plantModelName(PlantModel m);
bool parsePlantModelName(const std::string& name, PlantModel& out);
// summary.json's "plant" value: the preset, the actuator model, the delays,
// the encoders, the IMU mount and the body model in use.
std::string plantJson(const PlantSpec& plant);

}  // namespace hyq::sim
