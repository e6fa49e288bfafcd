// HyQ on its terrain, stepped one 1 kHz tick at a time in lock-step with a
// controller: read sensorFrame(), ask the controller, then step(command).
#pragma once
#include <ode/ode.h>

#include <memory>

#include "hal/frames.hpp"
#include "sim_host/contact.hpp"
#include "sim_host/robot.hpp"
#include "sim_host/scenario.hpp"
#include "sim_host/sensors.hpp"
#include "sim_host/sim_params.hpp"
#include "sim_host/terrain.hpp"
#include "sim_host/tick_record.hpp"

namespace hyq::sim {

// ODE's one-time global set-up; safe to call any number of times.
void ensureOdeInitialised();

struct SimConfig {
  ContactParams contact;
  IntegrationParams integration;
  FallParams fall;
};

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
  const HyqRobot& robot() const { return *robot_; }
  const Terrain& terrain() const { return *terrain_; }
  const SimConfig& config() const { return config_; }

 private:
  void applyJointLoop(const hal::CommandFrame& command, std::array<double, 12>& tau_applied);
  Vec3 disturbanceAt(double t) const;
  void measure(const Vec3& base_acceleration);

  Scenario scenario_;
  SimConfig config_;
  dWorldID world_ = nullptr;
  std::unique_ptr<Terrain> terrain_;
  std::unique_ptr<HyqRobot> robot_;
  std::unique_ptr<ContactModel> contacts_;
  std::unique_ptr<SensorModel> sensor_model_;
  std::array<int, 4> foot_contact_{};
  std::array<double, 12> tau_applied_{};
  hal::SensorFrame sensors_{};
  uint32_t tick_ = 0;
};

}  // namespace hyq::sim
