// HyQ on its terrain, stepped one 1 kHz tick at a time in lock-step with a
// controller: read sensorFrame(), ask the controller, then step(command).
// The physics engine under it is the scenario's (physics.engine: ODE or
// MuJoCo); the joint loop, disturbances, sensors and records are the same
// for both.
#pragma once
#include <memory>

#include "hal/frames.hpp"
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

 private:
  // The drives' torques for `command` at the engine's present state, after
  // saturation (`tau_applied`), and what the joints receive: those minus
  // the joints' viscous damping.
  void jointLoop(const hal::CommandFrame& command, std::array<double, 12>& tau_applied,
                 std::array<double, 12>& tau_joint) const;
  Vec3 disturbanceAt(double t) const;
  void measure(const Vec3& base_acceleration);

  Scenario scenario_;
  SimConfig config_;
  std::unique_ptr<Terrain> terrain_;
  std::unique_ptr<PhysicsEngine> engine_;
  std::unique_ptr<SensorModel> sensor_model_;
  std::array<double, 12> tau_applied_{};
  hal::SensorFrame sensors_{};
  uint32_t tick_ = 0;
};

}  // namespace hyq::sim
