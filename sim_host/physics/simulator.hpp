// HyQ on its terrain, stepped one 1 kHz tick at a time in lock-step with a
// controller: read sensorFrame(), ask the controller, then step(command).
// The physics engine under it is the scenario's (physics.engine: ODE or
// MuJoCo); the joint loop, disturbances, sensors and records are the same
// for both. The plant between the frames is the scenario's (plant.*,
// plant_params.hpp): the ideal one, or HyQ's actuators, encoders, delays,
// IMU mount and bodies.
#pragma once
#include <array>
#include <memory>

#include "hal/frames.hpp"
#include "sim_host/physics/actuator.hpp"
#include "sim_host/physics/physics_engine.hpp"
#include "sim_host/scenario/scenario.hpp"
#include "sim_host/physics/sensors.hpp"
#include "sim_host/physics/sim_params.hpp"
#include "sim_host/physics/terrain.hpp"
#include "sim_host/records/tick_record.hpp"

namespace hyq::sim {

class Simulator {
 public:
  explicit Simulator(const Scenario& scenario, const SimConfig& config = SimConfig{});
  ~Simulator();
  Simulator(const Simulator&) = delete;
  Simulator& operator=(const Simulator&) = delete;

  // What the controller reads for the coming tick.
  const hal::SensorFrame& sensorFrame() const { return sensors_; }
  // Applies `command` through the joint loop for one tick; `record` gets the
  // state at the end of the tick. The next sensorFrame() is ready afterwards.
  void step(const hal::CommandFrame& command, TickRecord& record);

  uint32_t tick() const { return tick_; }
  double time() const { return tick_ * config_.integration.tick; }  // [s]
  // Trunk below FallParams::min_height above the local ground, or tilted
  // past FallParams::max_tilt.
  bool fallen() const;
  const PhysicsEngine& engine() const { return *engine_; }
  const Terrain& terrain() const { return *terrain_; }
  const SimConfig& config() const { return config_; }
  const PlantSpec& plant() const { return scenario_.plant; }
  const JointActuator& actuator(int j) const { return actuators_[j]; }

  // Ring buffers of the transport delays: room for the longest delay of
  // each kind, and of the IMU's behind the frame's.
  static constexpr int kCommandRing = kMaxDelayTicks + 1;
  static constexpr int kFrameRing = 2 * kMaxDelayTicks + 1;

 private:
  // The drives' torques for `command` at the engine's present state, after
  // saturation (`tau_applied`), and what the joints receive: those minus
  // the joints' viscous damping.
  void jointLoop(const hal::CommandFrame& command, std::array<double, 12>& tau_applied,
                 std::array<double, 12>& tau_joint) const;
  // The same through the joints' actuators, over an engine step of `h` [s]:
  // `tau_applied` the torques they deliver (mean over the step).
  void actuatorLoop(const hal::CommandFrame& command, double h, std::array<double, 12>& tau_applied,
                    std::array<double, 12>& tau_joint);
  // The command the joints act on this tick: the one answered
  // delay.command_ticks ticks ago (the first command before there was one).
  const hal::CommandFrame& delayedCommand(const hal::CommandFrame& command);
  // Before the first tick, each actuator holds the torque `command` asks
  // for at rest: the robot starts loaded, as with the ideal joint loop.
  void primeActuators(const hal::CommandFrame& command);
  // The joints' angles and rates from the engine into joint_q_, joint_qd_:
  // after each engine step, the state the next one starts from.
  void readJoints();
  // After an engine step: the boards' or the tick's encoder samples.
  void sampleEncoders(bool tick_end);
  Vec3 disturbanceAt(double t) const;
  void measure(const Vec3& base_acceleration, const Vec3& base_alpha);
  // The frame from the latest measurement and the delays.
  void deliver(const hal::SensorFrame& fresh);

  Scenario scenario_;
  SimConfig config_;
  std::unique_ptr<Terrain> terrain_;
  std::unique_ptr<PhysicsEngine> engine_;
  std::unique_ptr<SensorModel> sensor_model_;
  std::array<double, 12> tau_applied_{};
  hal::SensorFrame sensors_{};
  uint32_t tick_ = 0;
  // The plant's state (unused by the ideal plant).
  bool ideal_plant_ = true;
  std::array<double, 12> joint_q_{}, joint_qd_{};  // [rad], [rad/s] (readJoints)
  std::array<JointActuator, 12> actuators_{};
  std::array<JointEncoder, 12> tick_encoders_{};  // sampled each tick when no actuator is modelled
  std::array<hal::CommandFrame, kCommandRing> commands_{};
  uint32_t commands_received_ = 0;
  std::array<hal::SensorFrame, kFrameRing> frames_{};  // the latest measurement at frames_[tick % kFrameRing]
};

}  // namespace hyq::sim
