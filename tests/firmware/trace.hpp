// Sensor traces for the firmware replay tests.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "hal/frames.hpp"

namespace hyq::test {

// HyQ standing (robot_params stand posture) with small deterministic sway,
// encoder noise, load torques and IMU noise: `ticks` frames from `seed`.
std::vector<hal::SensorFrame> synthesiseStandTrace(int ticks, uint32_t seed);

// A trace recorded from the simulator: a file of wire-format sensor
// messages (hal/wire.hpp encodeSensor, back to back). Empty on failure.
std::vector<hal::SensorFrame> loadWireTrace(const std::string& path);

// Sensor frames recorded from the simulator, closed loop with the host
// controller: the start of ice_patches (standing, the first body shifts and
// swings, the front feet onto the first low-friction patch).
std::vector<hal::SensorFrame> recordSimTrace(int ticks);

}  // namespace hyq::test
