// Joint accelerations for the GRF estimate's leg-inertia term: the slope of
// the last N joint velocities (exact on ramps, sqrt(12 / (N (N^2 - 1))) of the
// velocity noise over dt, restart after a bad sample), and its standard error
// (zero on ramps, the slope's error under noise, large across a kink).
#include "firmware/controller/state/joint_acceleration.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace hyq {
namespace {

constexpr double kDt = 0.001;

Vec12 ramp(const Vec12& slope, const Vec12& start, int k) {
  return start + slope * (k * kDt);
}

TEST(JointAccelerationTest, ExactOnAVelocityRampFromTheSecondSample) {
  JointAccelerationFilter filter;
  filter.reset(10, kDt);
  Vec12 slope, start;
  for (int j = 0; j < 12; ++j) {
    slope[j] = -20.0 + 3.5 * j;  // [rad/s^2]
    start[j] = 0.1 * j;
  }
  EXPECT_EQ(filter.update(ramp(slope, start, 0)), Vec12::Zero());
  for (int k = 1; k < 40; ++k) {
    const Vec12 qdd = filter.update(ramp(slope, start, k));
    EXPECT_LT((qdd - slope).cwiseAbs().maxCoeff(), 1e-6) << "tick " << k;
    // On a line there is no scatter; two samples fit any line, so with
    // them the slope's error is unknown.
    if (k >= 2) {
      EXPECT_LT(filter.accelerationSigma().maxCoeff(), 1e-6) << "tick " << k;
    } else {
      EXPECT_TRUE(std::isinf(filter.accelerationSigma().minCoeff()));
    }
  }
}

TEST(JointAccelerationTest, NoiseShrinksAsTheWindowTheory) {
  const int n = 10;
  const double sigma_v = 0.01;  // [rad/s], the simulator's joint velocity noise
  JointAccelerationFilter filter;
  filter.reset(n, kDt);
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, sigma_v);
  double sum_sq = 0.0, sigma_sq = 0.0;
  int count = 0;
  for (int k = 0; k < 20000; ++k) {
    Vec12 qd;
    for (int j = 0; j < 12; ++j) qd[j] = noise(rng);
    const Vec12 qdd = filter.update(qd);
    if (k >= n) {
      sum_sq += qdd.squaredNorm();
      sigma_sq += filter.accelerationSigma().squaredNorm();
      count += 12;
    }
  }
  const double expected = sigma_v / (kDt * std::sqrt(n * (n * n - 1) / 12.0));  // 1.10 rad/s^2
  EXPECT_NEAR(std::sqrt(sum_sq / count), expected, 0.03 * expected);
  // The filter's own standard error, from each window's scatter, says the same.
  EXPECT_NEAR(std::sqrt(sigma_sq / count), expected, 0.03 * expected);
}

TEST(JointAccelerationTest, SigmaFlagsAKinkInTheWindow) {
  // A joint that stops dead (a foot's impact): 0.5 rad/s, then 0. Inside the
  // window the samples lie on no line, and sigma says so; a window wholly
  // after the kink is exact again.
  const int n = 10;
  JointAccelerationFilter filter;
  filter.reset(n, kDt);
  double peak = 0.0;
  for (int k = 0; k < 3 * n; ++k) {
    Vec12 qd = Vec12::Zero();
    if (k < n) qd[4] = 0.5;
    filter.update(qd);
    if (k >= n && k < 2 * n - 1) peak = std::fmax(peak, filter.accelerationSigma()[4]);
    if (k >= 2 * n - 1) {
      EXPECT_LT(filter.accelerationSigma()[4], 1e-9) << "tick " << k;
    }
    if (k >= 2) {
      EXPECT_EQ(filter.accelerationSigma()[3], 0.0);  // the other joints never moved
    }
  }
  // 0.5 rad/s of step: 17.7 rad/s^2 at worst, against the 1.1 rad/s^2 that
  // the simulator's velocity noise gives (the test above).
  EXPECT_GT(peak, 10.0 * 1.1);
}

TEST(JointAccelerationTest, ABadSampleRestartsTheHistory) {
  JointAccelerationFilter filter;
  filter.reset(8, kDt);
  const Vec12 slope = Vec12::Constant(5.0);
  for (int k = 0; k < 20; ++k) filter.update(ramp(slope, Vec12::Zero(), k));
  Vec12 bad = Vec12::Zero();
  bad[4] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_LT(filter.accelerationSigma().maxCoeff(), 1e-6);  // on the ramp
  EXPECT_EQ(filter.update(bad), Vec12::Zero());
  // After the gap the old samples are gone: a new ramp is exact at once.
  // Its error is unknown (infinite) until three samples show a scatter.
  EXPECT_TRUE(std::isinf(filter.accelerationSigma().minCoeff()));
  EXPECT_EQ(filter.update(Vec12::Constant(3.0)), Vec12::Zero());
  EXPECT_TRUE(std::isinf(filter.accelerationSigma().minCoeff()));
  const Vec12 qdd = filter.update(Vec12::Constant(3.0) + slope * kDt);
  EXPECT_LT((qdd - slope).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_TRUE(std::isinf(filter.accelerationSigma().minCoeff()));
  filter.update(Vec12::Constant(3.0) + slope * (2.0 * kDt));
  EXPECT_LT(filter.accelerationSigma().maxCoeff(), 1e-6);
  EXPECT_TRUE(filter.acceleration().allFinite());
}

TEST(JointAccelerationTest, WindowIsClampedToItsStorage) {
  // On qd = c t^2 the slope over n samples is the derivative at the window's
  // middle, 2 c (t_now - (n - 1) dt / 2): it tells the window length used.
  JointAccelerationFilter filter;
  filter.reset(1000, kDt);
  const double c = 50.0;  // [rad/s^3]
  const int ticks = 3 * kMaxAccelWindow;
  Vec12 qdd;
  for (int k = 0; k < ticks; ++k) {
    const double t = k * kDt;
    qdd = filter.update(Vec12::Constant(c * t * t));
  }
  const double t_now = (ticks - 1) * kDt;
  const double expected = 2.0 * c * (t_now - 0.5 * (kMaxAccelWindow - 1) * kDt);
  EXPECT_NEAR(qdd[0], expected, 1e-9);
  EXPECT_GT(std::fabs(qdd[0] - 2.0 * c * (t_now - 0.5 * (10 - 1) * kDt)), 0.5);  // not 10
}

TEST(JointAccelerationTest, CentreLagIsWhereTheSlopeIsExact) {
  // On qd = c t^2 the slope is the true acceleration (N - 1) / 2 ticks back:
  // for odd N exactly centreLag() ticks, for even N half a tick further.
  const double c = 50.0;  // [rad/s^3]
  for (int window : {9, 10, 11}) {
    JointAccelerationFilter filter;
    filter.reset(window, kDt);
    EXPECT_EQ(filter.centreLag(), (window - 1) / 2);
    Vec12 qdd;
    const int ticks = 40;
    for (int k = 0; k < ticks; ++k) qdd = filter.update(Vec12::Constant(c * (k * kDt) * (k * kDt)));
    const double lag_ticks = ((ticks - 1) * kDt - qdd[0] / (2.0 * c)) / kDt;
    EXPECT_NEAR(lag_ticks - filter.centreLag(), window % 2 ? 0.0 : 0.5, 1e-6) << window;
  }
  JointAccelerationFilter clamped;
  clamped.reset(1000, kDt);
  EXPECT_EQ(clamped.centreLag(), (kMaxAccelWindow - 1) / 2);
}

}  // namespace
}  // namespace hyq
