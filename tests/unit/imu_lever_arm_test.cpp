// The accelerometer's reading moved from the IMU's mount to B's origin:
// exact for a steady angular acceleration, nothing taken out when the IMU is
// at the origin, and the one-tick difference's noise not accumulating in the
// reading's integral.
#include "firmware/controller/state/imu_lever_arm.hpp"

#include <gtest/gtest.h>

#include <random>

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
  arm.reset(origin, kDt);
  EXPECT_FALSE(arm.enabled());
  const Vec3 f(0.3, -0.2, 9.81);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(arm.atOrigin(f, Vec3(1.0 * k, -2.0, 0.5)), f);
}

TEST(ImuLeverArm, ASteadyAngularAccelerationIsTakenOutExactly) {
  ImuLeverArm arm;
  arm.reset(kMount, kDt);
  ASSERT_TRUE(arm.enabled());
  const Vec3 r(kMount[0], kMount[1], kMount[2]);
  const Vec3 f0(0.4, -0.1, 9.7);                  // [m/s^2] at the origin
  const Vec3 omega0(0.2, -0.5, 0.1), alpha(30.0, -45.0, 5.0);  // [rad/s], [rad/s^2]: a trot's pitch and roll
  for (int k = 0; k < 50; ++k) {
    const Vec3 omega = omega0 + alpha * (k * kDt);
    const Vec3 at_origin = arm.atOrigin(reading(f0, omega, alpha, r), omega);
    if (k == 0) {
      // No difference yet: only the centripetal term comes out.
      EXPECT_LT((at_origin - (f0 + alpha.cross(r))).norm(), 1e-12);
    } else {
      EXPECT_LT((at_origin - f0).norm(), 1e-9) << "tick " << k;  // the difference's rounding: 1e-16 / 1e-3 x 0.3
    }
  }
  // After a gap the next reading has no difference again.
  arm.restart();
  const Vec3 omega = omega0 + alpha * 0.2;
  EXPECT_LT((arm.atOrigin(reading(f0, omega, alpha, r), omega) - (f0 + alpha.cross(r))).norm(), 1e-12);
}

TEST(ImuLeverArm, TheDifferencesNoiseDoesNotAccumulateInTheIntegral) {
  ImuLeverArm arm;
  arm.reset(kMount, kDt);
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
  // plus the difference's half-tick lag on a 6 rad/s^2 swing, where a random
  // walk of 5000 ticks would reach 0.06 m/s.
  EXPECT_LT(worst, 5e-3);
}

}  // namespace
}  // namespace hyq
