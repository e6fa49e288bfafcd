// What the simulator knows at the end of one 1 kHz tick: ground truth,
// the sensor frame the controller saw, and the command it answered with.
// The logger (log.csv) and the metrics both consume these records.
#pragma once
#include <array>
#include <cstdint>

#include "hal/frames.hpp"

namespace hyq::sim {

struct PlantSpec;  // sim_host/physics/plant_params.hpp

struct FootTruth {
  bool in_contact = false;             // sphere touching the terrain
  std::array<double, 3> position{};    // [m] foot centre, W
  std::array<double, 3> velocity{};    // [m/s] foot centre, W
  std::array<double, 3> force{};       // [N] contact force on the foot, W
  std::array<double, 3> normal{0, 0, 1};  // [-] true surface normal at the contact point, W
  double mu = 0.0;                     // [-] true friction coefficient at the contact point (the centre in the air)
  std::array<double, 3> slip_velocity{};  // [m/s] tangential velocity of the contact point, W
  double slip_speed = 0.0;             // [m/s] |slip_velocity| (0 when not in contact)
};

struct TickRecord {
  uint32_t tick = 0;
  double time = 0.0;                   // [s] simulated time at the end of the tick
  // Trunk ground truth
  std::array<double, 3> base_pos{};    // [m] base frame origin, W
  std::array<double, 4> base_quat{1, 0, 0, 0};  // [-] (w,x,y,z), B in W
  std::array<double, 3> base_vel{};    // [m/s] base origin velocity, W
  std::array<double, 3> base_omega{};  // [rad/s] angular velocity, W
  std::array<FootTruth, 4> feet{};
  std::array<double, 3> disturbance{}; // [N] external force applied this tick, W
  hal::SensorFrame sensors{};          // what the controller received
  hal::CommandFrame command{};         // what it answered (incl. telemetry)
  std::array<double, 12> tau_applied{};  // [N m] torque the joint loop applied (after saturation)
  const PlantSpec* plant = nullptr;    // the simulated plant (summary.json's "plant"); null: not known
};

}  // namespace hyq::sim
