#include "sim_host/physics/sensors.hpp"

#include "firmware/controller/model/robot_params.hpp"

namespace hyq::sim {

SensorModel::SensorModel(const SensorSpec& spec, uint64_t seed, const PlantSpec& plant)
    : spec_(spec),
      q_noise_(plant.encoder.resolution == 0.0),
      qd_noise_(plant.encoder.velocity == VelocitySource::truth),
      imu_mounted_(plant.imu == ImuMount::mounted),
      imu_(imuPlacement(plant.imu)),
      rng_(seed) {
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
    f.q[j] = q_noise_ ? truth.q[j] + noise(m.q) : truth.q[j];
    f.qd[j] = qd_noise_ ? truth.qd[j] + noise(m.qd) : truth.qd[j];
    f.tau[j] = truth.tau[j] + tau_bias_[j] + noise(m.tau);
  }
  if (imu_mounted_) {
    measureMountedImu(truth, f);
    return;
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

void SensorModel::measureMountedImu(const TrueProprioception& truth, hal::SensorFrame& f) {
  const SensorNoise& m = spec_.magnitudes;
  const Mat3 r_wb = truth.base_orientation.toRotationMatrix();
  const Mat3& r_bi = imu_.rotation;
  // The attitude the IMU reports is its own frame's, I in W; the driver
  // turns it back into B's.
  const Vec3 tilt(noise(m.orientation), noise(m.orientation), noise(m.orientation));
  Quat q_wi = truth.base_orientation * Quat(r_bi);
  if (tilt.norm() > 0.0) q_wi = q_wi * Quat(Eigen::AngleAxisd(tilt.norm(), tilt.normalized()));
  Quat q = q_wi * Quat(r_bi).conjugate();
  q.normalize();
  f.imu_quat[0] = q.w();
  f.imu_quat[1] = q.x();
  f.imu_quat[2] = q.y();
  f.imu_quat[3] = q.z();
  // At the mount, r in W: a = a_origin + alpha x r + omega x (omega x r).
  const Vec3 r = r_wb * imu_.position, w = truth.base_omega;
  const Vec3 a_imu = truth.base_acceleration + truth.base_alpha.cross(r) + w.cross(w.cross(r));
  const Mat3 r_iw = (r_wb * r_bi).transpose();
  const Vec3 gyro = r_iw * w + gyro_bias_;
  const Vec3 specific_force = r_iw * (a_imu + Vec3(0.0, 0.0, hyq::robot::kGravity)) + acc_bias_;
  Vec3 gyro_i, acc_i;
  for (int i = 0; i < 3; ++i) {
    gyro_i[i] = gyro[i] + noise(m.gyro);
    acc_i[i] = specific_force[i] + noise(m.acc);
  }
  const Vec3 gyro_b = r_bi * gyro_i, acc_b = r_bi * acc_i;
  for (int i = 0; i < 3; ++i) {
    f.imu_gyro[i] = gyro_b[i];
    f.imu_acc[i] = acc_b[i];
  }
}

}  // namespace hyq::sim
