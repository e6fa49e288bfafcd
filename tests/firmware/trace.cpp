#include "trace.hpp"

#include <cmath>
#include <fstream>
#include <iterator>
#include <random>

#include "firmware/controller/model/robot_params.hpp"
#include "hal/wire.hpp"
#include "sim_host/loop/run.hpp"
#include "sim_host/scenario/scenario.hpp"

namespace hyq::test {

std::vector<hal::SensorFrame> synthesiseStandTrace(int ticks, uint32_t seed) {
  std::mt19937 rng(seed);
  // Uniform from raw mt19937 output: the same numbers with every standard library.
  auto noise = [&rng](double amplitude) {
    return amplitude * (2.0 * (static_cast<double>(rng()) / 4294967295.0) - 1.0);
  };
  const double dt = 0.001;
  const double sway_hz = 0.7;
  std::vector<hal::SensorFrame> trace(ticks);
  for (int k = 0; k < ticks; ++k) {
    hal::SensorFrame& s = trace[k];
    s = {};
    s.tick = static_cast<uint32_t>(k + 1);
    const double t = k * dt;
    const double w = 2.0 * M_PI * sway_hz;
    for (int leg = 0; leg < hal::kNumLegs; ++leg) {
      for (int joint = 0; joint < hal::kJointsPerLeg; ++joint) {
        const int j = 3 * leg + joint;
        const double phase = 0.4 * j;
        const double amplitude = 0.03 + 0.01 * joint;
        s.q[j] = robot::standAngle(leg, joint) + amplitude * std::sin(w * t + phase) + noise(2e-4);
        s.qd[j] = amplitude * w * std::cos(w * t + phase) + noise(5e-3);
        // Gravity load of an 85 kg robot on four legs, mostly on HFE and KFE.
        const double load[3] = {4.0, 22.0, -38.0};
        const double sign = robot::isFront(leg) ? 1.0 : -1.0;
        s.tau[j] = (joint == 0 ? load[0] : sign * load[joint]) * (1.0 + 0.1 * std::sin(w * t)) + noise(0.5);
      }
    }
    const double roll = 0.02 * std::sin(w * t), pitch = 0.015 * std::cos(w * t + 0.3);
    s.imu_quat[0] = std::cos(roll / 2) * std::cos(pitch / 2);
    s.imu_quat[1] = std::sin(roll / 2) * std::cos(pitch / 2);
    s.imu_quat[2] = std::cos(roll / 2) * std::sin(pitch / 2);
    s.imu_quat[3] = -std::sin(roll / 2) * std::sin(pitch / 2);
    s.imu_gyro[0] = 0.02 * w * std::cos(w * t) + noise(2e-3);
    s.imu_gyro[1] = -0.015 * w * std::sin(w * t + 0.3) + noise(2e-3);
    s.imu_gyro[2] = noise(2e-3);
    s.imu_acc[0] = -robot::kGravity * pitch + noise(0.05);
    s.imu_acc[1] = robot::kGravity * roll + noise(0.05);
    s.imu_acc[2] = robot::kGravity + noise(0.05);
  }
  return trace;
}

std::vector<hal::SensorFrame> loadWireTrace(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<hal::SensorFrame> trace;
  hal::wire::Decoder decoder;
  static hal::wire::Message message;
  for (uint8_t b : bytes)
    if (decoder.push(b, message) && message.type == hal::wire::MessageType::kSensor)
      trace.push_back(message.sensor);
  return trace;
}

std::vector<hal::SensorFrame> recordSimTrace(int ticks) {
  return sim::recordSensorFrames(
      sim::loadScenario(std::string(HYQ_SOURCE_DIR) + "/sim_host/scenarios/ice_patches.yaml"), ticks);
}

}  // namespace hyq::test
