// What HyQ's own sensors report, from the simulator's ground truth: joint
// encoders and torque sensors, and an IMU at the base origin. Noise is white
// Gaussian; biases are drawn once per run; all from a seeded generator.
#pragma once
#include <array>
#include <cstdint>
#include <random>

#include "firmware/controller/model/types.hpp"
#include "hal/frames.hpp"
#include "sim_host/scenario/scenario.hpp"

namespace hyq::sim {

struct TrueProprioception {
  std::array<double, 12> q{}, qd{}, tau{};  // [rad], [rad/s], [N m]
  Quat base_orientation = Quat::Identity(); // B in W
  Vec3 base_omega = Vec3::Zero();           // [rad/s] W
  Vec3 base_acceleration = Vec3::Zero();    // [m/s^2] of the base origin, W
};

class SensorModel {
 public:
  SensorModel(const SensorSpec& spec, uint64_t seed);
  void measure(uint32_t tick, const TrueProprioception& truth, hal::SensorFrame& frame);

 private:
  double noise(double sigma);
  double bias(double magnitude);  // a constant bias (SensorSpec::biases_at_magnitude)
  SensorSpec spec_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  std::array<double, 12> tau_bias_{};
  Vec3 gyro_bias_ = Vec3::Zero(), acc_bias_ = Vec3::Zero();
};

}  // namespace hyq::sim
