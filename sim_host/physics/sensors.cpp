#include "sim_host/physics/sensors.hpp"

#include "firmware/controller/model/robot_params.hpp"

namespace hyq::sim {

SensorModel::SensorModel(const SensorSpec& spec, uint64_t seed) : spec_(spec), rng_(seed) {
  for (double& b : tau_bias_) b = bias(spec_.magnitudes.tau_bias);
  for (int i = 0; i < 3; ++i) gyro_bias_[i] = bias(spec_.magnitudes.gyro_bias);
  for (int i = 0; i < 3; ++i) acc_bias_[i] = bias(spec_.magnitudes.acc_bias);
}

double SensorModel::bias(double magnitude) {
  const double drawn = noise(magnitude);  // 0 with the noise off: biases off too
  if (!spec_.biases_at_magnitude || drawn == 0.0) return drawn;
  return drawn < 0.0 ? -magnitude : magnitude;
}

double SensorModel::noise(double sigma) {
  return spec_.noise ? sigma * normal_(rng_) : 0.0;
}

void SensorModel::measure(uint32_t tick, const TrueProprioception& truth, hal::SensorFrame& f) {
  const SensorNoise& m = spec_.magnitudes;
  f.tick = tick;
  for (int j = 0; j < hal::kNumJoints; ++j) {
    f.q[j] = truth.q[j] + noise(m.q);
    f.qd[j] = truth.qd[j] + noise(m.qd);
    f.tau[j] = truth.tau[j] + tau_bias_[j] + noise(m.tau);
  }
  const Vec3 tilt(noise(m.orientation), noise(m.orientation), noise(m.orientation));
  Quat q = truth.base_orientation;
  if (tilt.norm() > 0.0) q = q * Quat(Eigen::AngleAxisd(tilt.norm(), tilt.normalized()));
  q.normalize();
  f.imu_quat[0] = q.w();
  f.imu_quat[1] = q.x();
  f.imu_quat[2] = q.y();
  f.imu_quat[3] = q.z();
  const Mat3 rt = truth.base_orientation.toRotationMatrix().transpose();
  const Vec3 gyro = rt * truth.base_omega + gyro_bias_;
  const Vec3 specific_force =
      rt * (truth.base_acceleration + Vec3(0.0, 0.0, hyq::robot::kGravity)) + acc_bias_;
  for (int i = 0; i < 3; ++i) {
    f.imu_gyro[i] = gyro[i] + noise(m.gyro);
    f.imu_acc[i] = specific_force[i] + noise(m.acc);
  }
}

}  // namespace hyq::sim
