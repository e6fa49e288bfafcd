// The whole body's CoM offset from the ground forces: standing on four feet
// whose vertical forces balance about a CoM 3 cm ahead of and 1 cm left of
// the model's, the estimate reads that offset; it learns nothing while the
// trunk moves or turns (kComOffsetRestSpeed, kComOffsetRestRate), nor from
// forces that do not carry the weight, nor when switched off.
#include "firmware/controller/state/com_offset.hpp"

#include <gtest/gtest.h>

namespace hyq {
namespace {

constexpr double kDt = 0.001;
constexpr double kWeight = 850.0;         // [N]
constexpr double kHalfLength = 0.37;      // [m] feet ahead of and behind the model's CoM
constexpr double kHalfWidth = 0.20;       // [m] feet left and right of it
const Vec3 kModelCom(0.0, 0.0, 0.6);      // [m] W
const Vec3 kTrueOffset(0.03, 0.01, 0.0);  // [m] the real CoM minus the model's

// Four feet on level ground (LF, RF, LH, RH) and vertical forces whose
// moments balance about kModelCom + kTrueOffset, carrying `weight`.
void standingFeet(Mat3x4& feet, Mat3x4& forces, double weight) {
  const double x[4] = {kHalfLength, kHalfLength, -kHalfLength, -kHalfLength};
  const double y[4] = {kHalfWidth, -kHalfWidth, kHalfWidth, -kHalfWidth};
  // f_i = W/4 (1 + a x_i + b y_i): sum x f = W a L^2, sum y f = W b w^2.
  const double a = kTrueOffset.x() / (kHalfLength * kHalfLength);
  const double b = kTrueOffset.y() / (kHalfWidth * kHalfWidth);
  for (int i = 0; i < 4; ++i) {
    feet.col(i) = Vec3(x[i], y[i], 0.0);
    forces.col(i) = Vec3(0.0, 0.0, weight / 4.0 * (1.0 + a * x[i] + b * y[i]));
  }
}

// The estimate a plain running mean over its whole time constant
// (com_offset_start_time 0): at rest it reads the offset from the first
// tick on.
ComOffsetEstimator makeEstimator(double time) {
  EstimatorParams params;
  params.com_offset_time = time;
  params.com_offset_start_time = 0.0;
  ComOffsetEstimator est;
  est.reset(params, kDt);
  return est;
}

// Feeds `ticks` ticks of the standing feet with the trunk's CoM velocity
// `com_vel` and angular velocity `omega`.
void feed(ComOffsetEstimator& est, int ticks, const Vec3& com_vel, const Vec3& omega, double weight = kWeight) {
  Mat3x4 feet, forces;
  standingFeet(feet, forces, weight);
  for (int k = 0; k < ticks; ++k)
    est.update(feet, forces, 0xFu, kModelCom, Mat3::Identity(), kWeight, com_vel, omega);
}

TEST(ComOffset, StandingStillItReadsTheOffsetOfTheRealCoM) {
  ComOffsetEstimator est = makeEstimator(1.0);
  ASSERT_TRUE(est.enabled());
  feed(est, 2000, Vec3::Zero(), Vec3::Zero());
  EXPECT_NEAR(est.offsetBase().x(), kTrueOffset.x(), 1e-6);
  EXPECT_NEAR(est.offsetBase().y(), kTrueOffset.y(), 1e-6);
  EXPECT_EQ(est.offsetBase().z(), 0.0);
}

TEST(ComOffset, ItLearnsNothingWhileTheTrunkMovesOrTurns) {
  ComOffsetEstimator moving = makeEstimator(1.0), turning = makeEstimator(1.0), slow = makeEstimator(1.0);
  feed(moving, 2000, Vec3(kComOffsetRestSpeed * 1.01, 0.0, 0.0), Vec3::Zero());
  feed(turning, 2000, Vec3::Zero(), Vec3(0.0, kComOffsetRestRate * 1.01, 0.0));
  EXPECT_EQ(moving.offsetBase().norm(), 0.0);
  EXPECT_EQ(turning.offsetBase().norm(), 0.0);
  // Just under both limits it is still at rest.
  feed(slow, 2000, Vec3(kComOffsetRestSpeed * 0.99, 0.0, 0.0), Vec3(0.0, kComOffsetRestRate * 0.99, 0.0));
  EXPECT_NEAR(slow.offsetBase().x(), kTrueOffset.x(), 1e-6);
}

TEST(ComOffset, ForcesThatDoNotCarryTheWeightAndASwitchedOffEstimateLearnNothing) {
  ComOffsetEstimator light = makeEstimator(1.0), off = makeEstimator(0.0);
  // 20 % short of the weight: beyond com_offset_weight_tolerance (15 %).
  feed(light, 2000, Vec3::Zero(), Vec3::Zero(), 0.8 * kWeight);
  EXPECT_EQ(light.offsetBase().norm(), 0.0);
  EXPECT_FALSE(off.enabled());
  feed(off, 2000, Vec3::Zero(), Vec3::Zero());
  EXPECT_EQ(off.offsetBase().norm(), 0.0);
}

}  // namespace
}  // namespace hyq
