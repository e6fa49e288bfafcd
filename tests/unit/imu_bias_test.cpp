// IMU bias estimation: the gyro's bias from the IMU's own (noisy) attitude
// while the body rocks, and the accelerometer's from the leg odometry, with
// the leg odometry's drift measured with and without the estimates.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "firmware/controller/state/gyro_bias.hpp"
#include "firmware/controller/model/robot_params.hpp"
#include "firmware/controller/state/state_estimator.hpp"

namespace hyq {
namespace {

constexpr double kDt = 0.001;

// A body rocking in roll, pitch and yaw like a walking trunk (about 0.02 rad,
// 0.1-0.5 Hz): its rate in B and its attitude, integrated exactly enough.
struct RockingBody {
  Quat attitude = Quat::Identity();
  Vec3 rate(double t) const {
    const double w = 2.0 * M_PI;
    return Vec3(0.02 * 0.25 * w * std::cos(0.25 * w * t), 0.015 * 0.5 * w * std::cos(0.5 * w * t + 1.0),
                0.01 * 0.1 * w * std::cos(0.1 * w * t));
  }
  void advance(double t) {
    // Midpoint rate over the tick.
    const Vec3 step = kDt * rate(t + 0.5 * kDt);
    attitude = (attitude * Quat(Eigen::AngleAxisd(step.norm(), step.normalized()))).normalized();
  }
};

// The IMU's attitude with white small-angle noise of `sigma` per tick.
Quat noisyAttitude(const Quat& q, double sigma, std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, sigma);
  const Vec3 tilt(n(rng), n(rng), n(rng));
  return (q * Quat(Eigen::AngleAxisd(tilt.norm(), tilt.normalized()))).normalized();
}

// Runs the gyro-bias filter for `seconds` on a rocking body with the
// simulator's noise (attitude 1e-3 rad, gyro 2e-3 rad/s per tick).
Vec3 runGyro(GyroBiasEstimator& est, const Vec3& true_bias, double seconds, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> gyro_noise(0.0, 2e-3);
  RockingBody body;
  const int n = static_cast<int>(std::lround(seconds / kDt));
  for (int k = 0; k < n; ++k) {
    const double t = k * kDt;
    const Vec3 truth = body.rate(t);
    const Vec3 gyro = truth + true_bias + Vec3(gyro_noise(rng), gyro_noise(rng), gyro_noise(rng));
    est.update(noisyAttitude(body.attitude, 1e-3, rng), gyro);
    body.advance(t);
  }
  return est.bias();
}

TEST(GyroBias, ConvergesOnTheBiasWhileTheBodyRocks) {
  EstimatorParams p;
  const Vec3 bias(2e-3, -1.5e-3, 1e-3);
  for (uint32_t seed = 1; seed <= 4; ++seed) {
    GyroBiasEstimator est;
    est.reset(p, kDt);
    const Vec3 b = runGyro(est, bias, 10.0, seed);
    // The attitude's and the gyro's noise leave a few 1e-5 rad/s per axis.
    EXPECT_LT((b - bias).cwiseAbs().maxCoeff(), 1e-4) << "seed " << seed;
    // What the filter returns is the reading less its (updated) estimate.
    const Vec3 reading(0.01, -0.02, 0.03);
    const Vec3 rate = est.update(Quat::Identity(), reading);
    EXPECT_EQ(rate, reading - est.bias());
  }
}

TEST(GyroBias, SettlesWithinSecondsOfTheStart) {
  // Critically damped at 1 rad/s: e^-t (1 + t) of the bias is left after t
  // seconds, 4 % at 5 s.
  EstimatorParams p;
  const Vec3 bias(2e-3, -2e-3, 2e-3);
  GyroBiasEstimator est;
  est.reset(p, kDt);
  const Vec3 b = runGyro(est, bias, 5.0, 7);
  EXPECT_LT((b - bias).cwiseAbs().maxCoeff(), 0.1 * 2e-3);
}

TEST(GyroBias, OffReturnsTheRawRate) {
  EstimatorParams p;
  p.gyro_bias_time = 0.0;
  GyroBiasEstimator est;
  est.reset(p, kDt);
  const Vec3 b = runGyro(est, Vec3(2e-3, 0.0, 0.0), 2.0, 3);
  EXPECT_EQ(b, Vec3::Zero());
  EXPECT_EQ(est.update(Quat::Identity(), Vec3(0.1, 0.2, 0.3)), Vec3(0.1, 0.2, 0.3));
}

TEST(GyroBias, AnImplausibleBiasIsClampedToTheLimit) {
  EstimatorParams p;
  GyroBiasEstimator est;
  est.reset(p, kDt);
  const Vec3 b = runGyro(est, Vec3(0.1, -0.1, 0.0), 10.0, 5);
  EXPECT_NEAR(b.x(), p.gyro_bias_limit, 1e-12);
  EXPECT_NEAR(b.y(), -p.gyro_bias_limit, 1e-12);
}

TEST(GyroBias, RestartTakesTheNextAttitudeAndKeepsTheBias) {
  EstimatorParams p;
  GyroBiasEstimator est;
  est.reset(p, kDt);
  const Vec3 bias(1e-3, 1e-3, -1e-3);
  const Vec3 before = runGyro(est, bias, 10.0, 9);
  // A gap in the frames during which the body turned by 0.5 rad: without the
  // restart, the filter would read that turn as an attitude error and wind
  // it into the bias.
  est.restart();
  const Quat turned(Eigen::AngleAxisd(0.5, Vec3::UnitZ()));
  est.update(turned, bias);
  for (int k = 0; k < 100; ++k) est.update(turned, bias);
  EXPECT_LT((est.bias() - before).norm(), 1e-5);
}

// Walks a body in a straight line at 0.05 m/s on four stance feet, tilted by
// 0.1 rad, with an accelerometer bias, and returns the horizontal odometry
// error after `seconds`.
double odometryDrift(const EstimatorParams& p, const Vec3& acc_bias, double seconds, Vec3* estimate) {
  StateEstimator est;
  est.reset(p, kDt);
  const Mat3 R = Eigen::AngleAxisd(0.1, Vec3(1.0, 1.0, 0.0).normalized()).toRotationMatrix();
  Mat3x4 feet;
  feet << 0.37, 0.37, -0.37, -0.37, 0.21, -0.21, 0.21, -0.21, -0.6, -0.6, -0.6, -0.6;
  est.initialise(R, feet);
  const Vec3 v_world(0.05, 0.0, 0.0);
  Mat3x4 foot_vel;
  for (int i = 0; i < 4; ++i) foot_vel.col(i) = -(R.transpose() * v_world);
  const Vec3 reading = R.transpose() * Vec3(0.0, 0.0, robot::kGravity) + acc_bias;
  const int n = static_cast<int>(std::lround(seconds / kDt));
  for (int k = 0; k < n; ++k) est.update(R, reading - est.accBias(), foot_vel, 0xF);
  if (estimate) *estimate = est.accBias();
  const Vec3 truth = v_world * (n * kDt);
  return std::hypot(est.position().x() - truth.x(), est.position().y() - truth.y());
}

TEST(AccelerometerBias, TheVelocityFilterLearnsItAndTheOdometryStopsDrifting) {
  EstimatorParams p;
  const Vec3 bias(0.04, -0.03, 0.02);
  Vec3 estimate;
  const double with = odometryDrift(p, bias, 60.0, &estimate);
  EXPECT_LT((estimate - bias).cwiseAbs().maxCoeff(), 1e-6);
  // The lead tau |b| decays with acc_bias_time: about tau |b| acc_bias_time
  // of position, 3 mm here.
  EXPECT_LT(with, 4e-3);
  p.acc_bias_time = 0.0;
  const double without = odometryDrift(p, bias, 60.0, &estimate);
  EXPECT_EQ(estimate, Vec3::Zero());
  // tau |b_horizontal| t: 0.02 s * 0.05 m/s^2 * 60 s = 6 cm.
  EXPECT_GT(without, 0.04);
}

// Stands still on four feet for `seconds` with an accelerometer bias and
// returns the largest error of the height estimate.
double standingHeightDrift(const EstimatorParams& p, const Vec3& acc_bias, double seconds) {
  StateEstimator est;
  est.reset(p, kDt);
  const Mat3 R = Mat3::Identity();
  Mat3x4 feet;
  feet << 0.37, 0.37, -0.37, -0.37, 0.21, -0.21, 0.21, -0.21, -0.6, -0.6, -0.6, -0.6;
  est.initialise(R, feet);
  const Vec3 reading = Vec3(0.0, 0.0, robot::kGravity) + acc_bias;
  const int n = static_cast<int>(std::lround(seconds / kDt));
  double worst = 0.0;
  for (int k = 0; k < n; ++k) {
    est.update(R, reading - est.accBias(), Mat3x4::Zero(), 0xF);
    worst = std::max(worst, std::fabs(est.position().z() - 0.6));
  }
  return worst;
}

TEST(AccelerometerBias, AtTheStartItIsLearntFastEnoughToHoldTheHeight) {
  // 2 m/s^2 vertical (the specified worst): learnt from the start at
  // acc_bias_time, the height estimate runs off by tau |b| acc_bias_time,
  // 12 cm; as a running mean from acc_bias_start_time, by a few mm.
  EstimatorParams p;
  const Vec3 bias(0.0, 0.0, -2.0);
  EXPECT_LT(standingHeightDrift(p, bias, 10.0), 0.01);
  p.acc_bias_start_time = p.acc_bias_time;
  EXPECT_GT(standingHeightDrift(p, bias, 10.0), 0.08);
}

TEST(AccelerometerBias, AnImplausibleBiasIsClampedToTheLimit) {
  EstimatorParams p;
  Vec3 estimate;
  odometryDrift(p, Vec3(2.0 * p.acc_bias_limit, 0.0, 0.0), 30.0, &estimate);
  EXPECT_NEAR(estimate.x(), p.acc_bias_limit, 1e-12);
}

}  // namespace
}  // namespace hyq
