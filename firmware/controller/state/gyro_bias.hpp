// The gyro's bias, estimated from the IMU's own attitude.
//
// A gyro bias b biases every rate the controller uses: the foot velocities
// u_i = J qd + w x x_i, and so the leg odometry, by b x (mean foot position),
// about 0.6 mm/s per 1e-3 rad/s of roll or pitch bias at HyQ's standing
// height: 5 cm over a 90 s walk. Standing still does not calibrate it (the
// base rocks at about 1e-3 rad/s while the legs settle), but the attitude
// does: integrated, the gyro's rate must reproduce the IMU's orientation.
//
// A second-order complementary filter on SO(3) (Mahony's passive filter with
// the measured attitude as the reference): an attitude R_hat propagated by
// the corrected rate w - b_hat plus k_p e, where e = log(R_hat^T R) in B is
// its error, and b_hat -= k_i e dt. The error dynamics are
// s^2 + k_p s + k_i, critically damped at natural frequency 1 / time:
// k_p = 2 / time, k_i = 1 / time^2. Every attitude sample counts: with the
// simulator's noise (attitude 1e-3 rad, gyro 2e-3 rad/s per tick) a few
// 1e-5 rad/s are left on the bias, where averaging the rate difference over
// T leaves 1.4e-3 / T rad/s.
//
// The reference must not drift with the gyro. The simulator's attitude is
// the truth plus white noise. A real IMU's attitude comes from its own
// filter: roll and pitch are held by gravity, so their biases are
// observable this way; yaw is only if the IMU has a heading reference
// (magnetometer, or an external one).
#pragma once

#include "firmware/controller/params.hpp"
#include "firmware/controller/model/types.hpp"

namespace hyq {

class GyroBiasEstimator {
 public:
  void reset(const EstimatorParams& params, double dt);
  // After a gap in the frames: the attitude filter starts again from the
  // next attitude; the bias is kept.
  void restart() { have_attitude_ = false; }
  // attitude: the IMU's this tick, a unit quaternion (B to W); gyro: its
  // raw rate (B) [rad/s]. Returns the rate with the bias estimate removed.
  Vec3 update(const Quat& attitude, const Vec3& gyro);
  const Vec3& bias() const { return bias_; }  // [rad/s] in B

 private:
  bool enabled_ = false;
  double k_p_ = 0.0;      // [1/s]
  double k_i_ = 0.0;      // [1/s^2]
  double limit_ = 0.0;    // [rad/s]
  double dt_ = kTickPeriod;  // [s]
  Quat attitude_ = Quat::Identity();
  Vec3 bias_ = Vec3::Zero();
  bool have_attitude_ = false;
};

}  // namespace hyq
