// The delay line that pairs a tick's GRF parts and slip velocity with the
// joint and base accelerations centred on that tick: exact replay D ticks later,
// readiness, reset, and the delay clamped to its storage.
#include "firmware/controller/state/grf_delay.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace hyq {
namespace {

// A tick's parts: arbitrary, but each tick's and each leg's its own.
Mat3 jtInverse(int tick, int leg) {
  Mat3 j;
  j << 1.0 + 0.1 * tick, 0.2, -0.3 * leg, 0.4, -2.0, 0.05 * tick, 0.0, 0.7, 3.0 + leg;
  return j;
}
Vec3 staticPart(int tick, int leg) { return Vec3(tick, 2.0 * tick + leg, -3.0 * tick); }
Mat3 massPart(int tick, int leg) {  // a leg's mass matrix: no HAA coupling
  Mat3 m;
  const double m12 = 0.02 * tick - 0.1 * leg;
  m << 0.5 + 0.01 * tick, 0.0, 0.0, 0.0, 1.0 + leg, m12, 0.0, m12, 0.3;
  return m;
}
Mat3 alphaTorque(int tick, int leg) {
  Mat3 b;
  b << 0.0, -0.4 * leg, 0.02 * tick, 0.6, 0.0, -0.1, -0.05 * tick, 0.3, 0.0;
  return b;
}
Mat3 attitude(int tick) {
  return Eigen::AngleAxisd(0.1 * tick, Vec3(1.0, -2.0, 0.5).normalized()).toRotationMatrix();
}
Vec3 slipVelocity(int tick, int leg) { return Vec3(0.01 * tick, -0.02 * leg, 0.001); }
bool slipValid(int tick) { return tick % 3 != 0; }

void pushTick(GrfDelayLine& line, int tick) {
  for (int leg = 0; leg < 4; ++leg) {
    GrfParts& p = line.parts(leg);
    p.jt_inverse = jtInverse(tick, leg);
    p.u_static = staticPart(tick, leg);
    p.setMass(massPart(tick, leg));
    p.alpha_torque = alphaTorque(tick, leg);
    line.pushSlipVelocity(leg, slipVelocity(tick, leg), slipValid(tick));
  }
  line.pushAttitude(attitude(tick));
  line.advance();
}

TEST(GrfDelayLineTest, ReturnsTheTickDTicksBackWithTheGivenAcceleration) {
  for (int delay : {0, 1, 4, 5, kMaxGrfDelay}) {
    GrfDelayLine line;
    line.reset(delay);
    EXPECT_EQ(line.delay(), delay);
    const Vec3 qdd(3.0, -7.0, 11.0);     // [rad/s^2]
    const Vec3 alpha(-20.0, 4.0, 9.0);   // [rad/s^2]
    for (int tick = 0; tick < 3 * (kMaxGrfDelay + 1) + 2; ++tick) {
      pushTick(line, tick);
      EXPECT_EQ(line.ready(), tick >= delay) << "delay " << delay << " tick " << tick;
      if (tick < delay) {
        for (int leg = 0; leg < 4; ++leg) EXPECT_FALSE(line.slipVelocityValid(leg));
        continue;
      }
      const int then = tick - delay;
      for (int leg = 0; leg < 4; ++leg) {
        // f = R J^-T (u + M qdd + K alpha), the maps of that tick as full products.
        const Mat3 to_world = attitude(then) * jtInverse(then, leg);
        const Vec3 expected = to_world * staticPart(then, leg) + (to_world * massPart(then, leg)) * qdd +
                              (to_world * alphaTorque(then, leg)) * alpha;
        const Vec3 got = line.force(leg, qdd, alpha);
        EXPECT_LT((got - expected).norm(), 1e-12 * expected.norm()) << "delay " << delay << " tick " << tick;
        EXPECT_EQ(line.slipVelocity(leg), slipVelocity(then, leg));
        EXPECT_EQ(line.slipVelocityValid(leg), slipValid(then));
      }
    }
  }
}

TEST(GrfDelayLineTest, ForceSigmaIsTheAccelerationErrorsThroughThatTicksMaps) {
  const int delay = 4;
  GrfDelayLine line;
  line.reset(delay);
  for (int tick = 0; tick < 12; ++tick) pushTick(line, tick);
  const int then = 11 - delay;
  const Vec3 sigma(2.0, 0.5, 3.0);        // [rad/s^2] joints
  const Vec3 alpha_sigma(1.0, 0.0, 2.0);  // [rad/s^2] base
  for (int leg = 0; leg < 4; ++leg) {
    const Mat3 to_world = attitude(then) * jtInverse(then, leg);
    const Mat3 a = to_world * massPart(then, leg), b = to_world * alphaTorque(then, leg);
    // Independent errors: the variances of the columns' images add.
    const double joints = a.col(0).squaredNorm() * 4.0 + a.col(1).squaredNorm() * 0.25 + a.col(2).squaredNorm() * 9.0;
    const double base = b.col(0).squaredNorm() * 1.0 + b.col(2).squaredNorm() * 4.0;
    const double expected = std::sqrt(joints + base);
    EXPECT_NEAR(line.forceSigma(leg, sigma, alpha_sigma), expected, 1e-12 * expected);
    EXPECT_NEAR(line.forceSigma(leg, sigma, Vec3::Zero()), std::sqrt(joints), 1e-12 * expected);
    EXPECT_EQ(line.forceSigma(leg, Vec3::Zero(), Vec3::Zero()), 0.0);
  }
}

TEST(GrfDelayLineTest, ASingularLegsZeroInverseGivesNoForce) {
  GrfDelayLine line;
  line.reset(0);
  GrfParts& p = line.parts(2);
  p.u_static = Vec3(5.0, -3.0, 40.0);
  p.setMass(massPart(1, 2));
  p.alpha_torque = alphaTorque(1, 2);
  line.pushAttitude(attitude(3));
  line.advance();
  EXPECT_EQ(line.force(2, Vec3(1.0, 2.0, 3.0), Vec3(4.0, 5.0, 6.0)), Vec3::Zero());
  EXPECT_EQ(line.forceSigma(2, Vec3(1.0, 2.0, 3.0), Vec3(4.0, 5.0, 6.0)), 0.0);
}

TEST(GrfDelayLineTest, ResetEmptiesTheLine) {
  GrfDelayLine line;
  line.reset(2);
  for (int tick = 1; tick < 10; ++tick) pushTick(line, tick);  // reads tick 7: valid
  ASSERT_TRUE(line.ready());
  ASSERT_TRUE(line.slipVelocityValid(0));
  line.reset(2);
  EXPECT_FALSE(line.ready());
  for (int leg = 0; leg < 4; ++leg) {
    EXPECT_FALSE(line.slipVelocityValid(leg));
    EXPECT_EQ(line.force(leg, Vec3(1.0, 1.0, 1.0), Vec3(1.0, 1.0, 1.0)), Vec3::Zero());
  }
}

TEST(GrfDelayLineTest, DelayIsClampedToItsStorage) {
  GrfDelayLine line;
  line.reset(kMaxGrfDelay + 7);
  EXPECT_EQ(line.delay(), kMaxGrfDelay);
  line.reset(-3);
  EXPECT_EQ(line.delay(), 0);
}

}  // namespace
}  // namespace hyq
