// What HyQ's own sensors report, from the simulator's ground truth: joint
// encoders and torque sensors, and an IMU at the base origin or where the
// robot has it (PlantSpec::imu). Noise is white Gaussian; biases are drawn
// once per run; all from a seeded generator.
#pragma once
#include <array>
#include <cstdint>
#include <random>

#include "firmware/controller/model/types.hpp"
#include "hal/frames.hpp"
#include "sim_host/physics/body_model.hpp"
#include "sim_host/scenario/scenario.hpp"

namespace hyq::sim {

struct TrueProprioception {
  std::array<double, 12> q{}, qd{}, tau{};  // [rad], [rad/s], [N m]
  Quat base_orientation = Quat::Identity(); // B in W
  Vec3 base_omega = Vec3::Zero();           // [rad/s] W
  Vec3 base_acceleration = Vec3::Zero();    // [m/s^2] of the base origin, W
  Vec3 base_alpha = Vec3::Zero();           // [rad/s^2] angular acceleration of B, W
};

class SensorModel {
 public:
  // `plant`: the IMU's mount, and which joint readings carry white noise
  // (a quantised encoder's angle and a differentiated velocity do not).
  SensorModel(const SensorSpec& spec, uint64_t seed, const PlantSpec& plant = PlantSpec{});
  void measure(uint32_t tick, const TrueProprioception& truth, hal::SensorFrame& frame);

 private:
  double noise(double sigma);
  double bias(double magnitude);  // a constant bias (SensorSpec::biases_at_magnitude)
  // The IMU at its mount: its own readings (noise and biases in its own
  // frame) turned into B by the robot's driver; the lever arm's
  // acceleration stays in the reading.
  void measureMountedImu(const TrueProprioception& truth, hal::SensorFrame& frame);
  SensorSpec spec_;
  bool q_noise_ = true, qd_noise_ = true;
  bool imu_mounted_ = false;
  ImuPlacement imu_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  std::array<double, 12> tau_bias_{};
  Vec3 gyro_bias_ = Vec3::Zero(), acc_bias_ = Vec3::Zero();
};

}  // namespace hyq::sim
