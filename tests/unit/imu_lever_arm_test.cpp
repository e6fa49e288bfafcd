// The accelerometer's reading moved from the IMU's mount to B's origin:
// exact for a steady angular acceleration (at once with the bare difference,
// after the low-pass's first-order convergence with kImuAlphaTime), nothing
// taken out when the IMU is at the origin, the difference's noise cut by the
// low-pass as designed, and not accumulating in the reading's integral.
#include "firmware/controller/state/imu_lever_arm.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "firmware/controller/params.hpp"

namespace hyq {
namespace {

constexpr double kDt = 0.001;                        // [s]
constexpr double kMount[3] = {0.290, 0.0, 0.0999};  // [m] HyQ's IMU in B

// What an accelerometer at r reads on a trunk whose origin feels f0.
Vec3 reading(const Vec3& f0, const Vec3& omega, const Vec3& alpha, const Vec3& r) {
  return f0 + alpha.cross(r) + omega.cross(omega.cross(r));
}

TEST(ImuLeverArm, AtTheOriginTheReadingPassesUnchanged) {
  ImuLeverArm arm;
  const double origin[3] = {0.0, 0.0, 0.0};
  arm.reset(origin, kDt, kImuAlphaTime);
  EXPECT_FALSE(arm.enabled());
  const Vec3 f(0.3, -0.2, 9.81);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(arm.atOrigin(f, Vec3(1.0 * k, -2.0, 0.5)), f);
}

TEST(ImuLeverArm, ASteadyAngularAccelerationIsTakenOutExactly) {
  const Vec3 r(kMount[0], kMount[1], kMount[2]);
  const Vec3 f0(0.4, -0.1, 9.7);                  // [m/s^2] at the origin
  const Vec3 omega0(0.2, -0.5, 0.1), alpha(30.0, -45.0, 5.0);  // [rad/s], [rad/s^2]: a trot's pitch and roll
  for (const double alpha_time : {0.0, kImuAlphaTime}) {
    ImuLeverArm arm;
    arm.reset(kMount, kDt, alpha_time);
    ASSERT_TRUE(arm.enabled());
    // The low-pass's share of the step it takes each tick.
    const double gain = kDt / (alpha_time + kDt);
    for (int k = 0; k < 50; ++k) {
      const Vec3 omega = omega0 + alpha * (k * kDt);
      const Vec3 at_origin = arm.atOrigin(reading(f0, omega, alpha, r), omega);
      // No difference yet at k = 0: only the centripetal term comes out;
      // then alpha x r's share not yet taken out is (1 - gain)^k.
      const double left = std::pow(1.0 - gain, k);
      // The difference's rounding: 1e-16 / 1e-3 x 0.3.
      EXPECT_LT((at_origin - (f0 + left * alpha.cross(r))).norm(), 1e-9) << "T " << alpha_time << " tick " << k;
    }
    // After a gap the next reading has no difference again, and alpha starts from 0.
    arm.restart();
    const Vec3 omega = omega0 + alpha * 0.2;
    EXPECT_LT((arm.atOrigin(reading(f0, omega, alpha, r), omega) - (f0 + alpha.cross(r))).norm(), 1e-12);
  }
}

// The gyro's noise reaches the reading through the difference: per axis
// sqrt(2) sigma / dt, and |alpha x r| has sqrt(2) |r| times that, 1.23 m/s^2
// at HyQ's mount with the simulator's 2e-3 rad/s. The low-pass (gain g =
// dt / (T + dt)) of a differenced white noise keeps g / sqrt(2 - g) of it:
// 0.26 at 2 ms.
TEST(ImuLeverArm, TheLowPassCutsTheDifferencesNoise) {
  const Vec3 r(kMount[0], kMount[1], kMount[2]);
  const Vec3 f0(0.0, 0.0, 9.81);
  const Vec3 omega(0.1, -0.2, 0.05);  // [rad/s] steady
  double rms[2] = {0.0, 0.0};
  const double times[2] = {0.0, kImuAlphaTime};
  for (int i = 0; i < 2; ++i) {
    ImuLeverArm arm;
    arm.reset(kMount, kDt, times[i]);
    std::mt19937 rng(11);
    std::normal_distribution<double> noise(0.0, 2e-3);  // [rad/s] per tick
    double sum = 0.0;
    const int n = 20000;
    for (int k = 0; k < n; ++k) {
      const Vec3 measured = omega + Vec3(noise(rng), noise(rng), noise(rng));
      // The centripetal term's own noise (omega x (omega x r) from the noisy
      // rate) is 1e-4 of the difference's: the error is the difference's.
      const Vec3 error = arm.atOrigin(reading(f0, omega, Vec3::Zero(), r), measured) - f0;
      if (k > 100) sum += error.squaredNorm();
    }
    rms[i] = std::sqrt(sum / (n - 101));
  }
  std::printf("reading's noise: bare difference %.3f m/s^2, low-passed %.3f m/s^2\n", rms[0], rms[1]);
  const double bare = std::sqrt(2.0) * 2e-3 / kDt * std::sqrt(2.0) * r.norm();
  EXPECT_NEAR(rms[0], bare, 0.05 * bare);
  const double g = kDt / (kImuAlphaTime + kDt);
  const double cut = g / std::sqrt(2.0 - g);
  EXPECT_NEAR(rms[1] / rms[0], cut, 0.05 * cut);
}

TEST(ImuLeverArm, TheDifferencesNoiseDoesNotAccumulateInTheIntegral) {
  ImuLeverArm arm;
  arm.reset(kMount, kDt, kImuAlphaTime);
  const Vec3 r(kMount[0], kMount[1], kMount[2]);
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 2e-3);  // [rad/s] per tick, the simulator's gyro
  const Vec3 f0(0.0, 0.0, 9.81);
  Vec3 integral = Vec3::Zero();  // [m/s] of (corrected - f0): the velocity error
  double worst = 0.0;
  for (int k = 0; k < 5000; ++k) {
    const Vec3 omega_true(0.3 * std::sin(20.0 * k * kDt), 0.2 * std::cos(15.0 * k * kDt), 0.05);
    const Vec3 alpha_true(6.0 * std::cos(20.0 * k * kDt), -3.0 * std::sin(15.0 * k * kDt), 0.0);
    const Vec3 measured = omega_true + Vec3(noise(rng), noise(rng), noise(rng));
    integral += kDt * (arm.atOrigin(reading(f0, omega_true, alpha_true, r), measured) - f0);
    worst = std::max(worst, integral.norm());
  }
  // Per tick the difference's noise is 2.8e-3 / 1e-3 x 0.3 = 0.85 m/s^2; over
  // 5 s its integral stays near one tick's gyro noise times |r| (6e-4 m/s),
  // plus the difference's half-tick lag and the low-pass's 2 ms on a 6 rad/s^2
  // swing, where a random walk of 5000 ticks would reach 0.06 m/s.
  EXPECT_LT(worst, 5e-3);
}

}  // namespace
}  // namespace hyq
