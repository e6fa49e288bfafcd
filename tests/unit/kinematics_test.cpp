// Leg model: Jacobians and gravity torques against finite differences, IK
// round trips, and the stand posture against the published HyQ foot positions.
#include "firmware/controller/model/kinematics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <Eigen/Eigenvalues>

#include "firmware/controller/model/robot_params.hpp"

namespace hyq {
namespace {

using robot::kNumLegs;

// A joint configuration drawn uniformly inside the leg's limits.
Vec3 randomJoints(int leg, std::mt19937_64& rng) {
  Vec3 q;
  for (int j = 0; j < 3; ++j) {
    double lo, hi;
    robot::jointLimits(leg, j, lo, hi);
    q[j] = std::uniform_real_distribution<double>(lo, hi)(rng);
  }
  return q;
}

Vec3 standJoints(int leg) {
  return Vec3(robot::standAngle(leg, 0), robot::standAngle(leg, 1), robot::standAngle(leg, 2));
}

// Central difference of a vector function of q, column per joint.
template <typename F>
Mat3 centralDifference(F f, const Vec3& q, double h) {
  Mat3 d;
  for (int j = 0; j < 3; ++j) {
    Vec3 qp = q, qm = q;
    qp[j] += h;
    qm[j] -= h;
    d.col(j) = (f(qp) - f(qm)) / (2.0 * h);
  }
  return d;
}

TEST(Kinematics, StandPostureFeetWhereHyqDocSaysTheyAre) {
  for (int leg = 0; leg < kNumLegs; ++leg) {
    const Vec3 p = footPositionBase(leg, standJoints(leg));
    const double sx = robot::isFront(leg) ? 1.0 : -1.0;
    const double sy = robot::isLeft(leg) ? 1.0 : -1.0;
    EXPECT_NEAR(p.x(), sx * 0.37, 0.01) << robot::kLegNames[leg];
    EXPECT_NEAR(p.y(), sy * 0.33, 0.01) << robot::kLegNames[leg];
    EXPECT_NEAR(p.z(), -0.60, 0.01) << robot::kLegNames[leg];
  }
}

TEST(Kinematics, ZeroPostureHangsStraightDown) {
  const double length = robot::kHipLength + robot::kUpperLength + robot::kLowerLength;
  for (int leg = 0; leg < kNumLegs; ++leg) {
    const Vec3 p = footPositionBase(leg, Vec3::Zero());
    EXPECT_NEAR(p.x(), robot::kHaaPos[leg][0], 1e-12);
    EXPECT_NEAR(p.y(), robot::kHaaPos[leg][1], 1e-12);
    EXPECT_NEAR(p.z(), -length, 1e-12);
  }
}

TEST(Kinematics, ConventionSigns) {
  for (int leg = 0; leg < kNumLegs; ++leg) {
    const Vec3 p0 = footPositionBase(leg, Vec3::Zero());
    // Negative HAA swings the foot outward (away from the body's mid-plane).
    const Vec3 p_haa = footPositionBase(leg, Vec3(-0.3, 0.0, 0.0));
    const double outward = robot::isLeft(leg) ? 1.0 : -1.0;
    EXPECT_GT(outward * (p_haa.y() - p0.y()), 0.05) << robot::kLegNames[leg];
    // Positive HFE moves the foot backwards.
    EXPECT_LT(footPositionBase(leg, Vec3(0.0, 0.3, 0.0)).x(), p0.x() - 0.1);
    // The HFE joint sits kHipLength below the HAA joint at q = 0.
    EXPECT_NEAR(hfePositionBase(leg, Vec3::Zero()).z(), -robot::kHipLength, 1e-12);
  }
}

// The knee from kfePositionBase is the far end of the upper link and the
// near end of the lower one, each link's midpoint halfway along it.
TEST(Kinematics, KneeJoinsUpperAndLowerLinks) {
  std::mt19937_64 rng(5);
  for (int leg = 0; leg < kNumLegs; ++leg) {
    for (int trial = 0; trial < 50; ++trial) {
      const Vec3 q = randomJoints(leg, rng);
      const Vec3 knee = kfePositionBase(leg, q);
      const Vec3 from_upper = 2.0 * linkComPositionBase(leg, kUpperLink, q) - hfePositionBase(leg, q);
      const Vec3 from_lower = 2.0 * linkComPositionBase(leg, kLowerLink, q) - footPositionBase(leg, q);
      EXPECT_LT((knee - from_upper).norm(), 1e-12) << robot::kLegNames[leg];
      EXPECT_LT((knee - from_lower).norm(), 1e-12) << robot::kLegNames[leg];
      EXPECT_NEAR((knee - hfePositionBase(leg, q)).norm(), robot::kUpperLength, 1e-12);
    }
  }
}

TEST(Kinematics, FootJacobianMatchesFiniteDifferences) {
  std::mt19937_64 rng(7);
  for (int leg = 0; leg < kNumLegs; ++leg) {
    for (int trial = 0; trial < 500; ++trial) {
      const Vec3 q = randomJoints(leg, rng);
      const Mat3 numeric = centralDifference(
          [leg](const Vec3& x) { return footPositionBase(leg, x); }, q, 1e-6);
      const Mat3 analytic = footJacobianBase(leg, q);
      ASSERT_LT((analytic - numeric).cwiseAbs().maxCoeff(), 1e-6)
          << robot::kLegNames[leg] << " q = " << q.transpose();
    }
  }
}

// The ground touches the foot sphere kFootRadius below its centre. Taken as
// a point of the lower link, that point's motion is found here from the
// link's own geometry (its midpoint, the foot centre, and the leg plane
// through HFE, knee and foot): components fixed in the link's frame at q0,
// then differenced.
TEST(Kinematics, ContactPointJacobianIsThatOfALowerLinkPoint) {
  std::mt19937_64 rng(13);
  const auto linkFrame = [](int leg, const Vec3& q) {
    const Vec3 foot = footPositionBase(leg, q);
    const Vec3 mid = linkComPositionBase(leg, kLowerLink, q);
    const Vec3 knee = 2.0 * mid - foot;
    const Vec3 hfe = hfePositionBase(leg, q);
    Mat3 frame;
    frame.col(0) = (foot - knee).normalized();
    frame.col(1) = (knee - hfe).cross(foot - knee).normalized();
    frame.col(2) = frame.col(0).cross(frame.col(1));
    return frame;
  };
  for (int leg = 0; leg < kNumLegs; ++leg) {
    for (int trial = 0; trial < 200; ++trial) {
      const Vec3 q = randomJoints(leg, rng);
      // Skip poses whose knee is nearly straight: the plane is undefined.
      const Vec3 foot = footPositionBase(leg, q);
      const Vec3 knee = 2.0 * linkComPositionBase(leg, kLowerLink, q) - foot;
      if ((knee - hfePositionBase(leg, q)).normalized().cross((foot - knee).normalized()).norm() < 0.2)
        continue;
      Vec3 normal = Vec3(std::uniform_real_distribution<double>(-0.4, 0.4)(rng),
                         std::uniform_real_distribution<double>(-0.4, 0.4)(rng), 1.0);
      normal.normalize();
      const Vec3 d_in_link = linkFrame(leg, q).transpose() * (-robot::kFootRadius * normal);
      const Mat3 numeric = centralDifference(
          [&](const Vec3& x) { return Vec3(footPositionBase(leg, x) + linkFrame(leg, x) * d_in_link); }, q, 1e-6);
      const Mat3 analytic = footContactJacobianBase(leg, q, normal);
      ASSERT_LT((analytic - numeric).cwiseAbs().maxCoeff(), 1e-6)
          << robot::kLegNames[leg] << " q = " << q.transpose();
    }
  }
  // Hanging straight down on level ground, the contact point is r further
  // from the HFE and KFE axes than the centre: its levers are longer by r.
  for (int leg = 0; leg < kNumLegs; ++leg) {
    const Mat3 centre = footJacobianBase(leg, Vec3::Zero());
    const Mat3 contact = footContactJacobianBase(leg, Vec3::Zero(), Vec3::UnitZ());
    EXPECT_NEAR(contact(0, 1), -(robot::kUpperLength + robot::kLowerLength + robot::kFootRadius), 1e-12);
    EXPECT_NEAR(contact(0, 2), -(robot::kLowerLength + robot::kFootRadius), 1e-12);
    EXPECT_NEAR(contact(0, 1) - centre(0, 1), -robot::kFootRadius, 1e-12);
  }
}

TEST(Kinematics, LinkComJacobiansMatchFiniteDifferences) {
  std::mt19937_64 rng(11);
  for (int leg = 0; leg < kNumLegs; ++leg) {
    for (int link = 0; link < kLinksPerLeg; ++link) {
      for (int trial = 0; trial < 100; ++trial) {
        const Vec3 q = randomJoints(leg, rng);
        const Mat3 numeric = centralDifference(
            [leg, link](const Vec3& x) { return linkComPositionBase(leg, link, x); }, q, 1e-6);
        ASSERT_LT((linkComJacobianBase(leg, link, q) - numeric).cwiseAbs().maxCoeff(), 1e-6);
      }
    }
  }
}

TEST(Kinematics, LinkComsAreLinkMidpoints) {
  std::mt19937_64 rng(3);
  for (int leg = 0; leg < kNumLegs; ++leg) {
    const Vec3 q = randomJoints(leg, rng);
    const Vec3 haa(robot::kHaaPos[leg][0], robot::kHaaPos[leg][1], robot::kHaaPos[leg][2]);
    const Vec3 hfe = hfePositionBase(leg, q);
    const Vec3 foot = footPositionBase(leg, q);
    EXPECT_LT((linkComPositionBase(leg, kHipLink, q) - 0.5 * (haa + hfe)).norm(), 1e-12);
    const Vec3 upper_com = linkComPositionBase(leg, kUpperLink, q);
    const Vec3 lower_com = linkComPositionBase(leg, kLowerLink, q);
    // Knee = 2 * upper CoM - HFE = 2 * lower CoM - foot.
    EXPECT_LT(((2.0 * upper_com - hfe) - (2.0 * lower_com - foot)).norm(), 1e-12);
    EXPECT_NEAR((2.0 * upper_com - hfe - hfe).norm(), robot::kUpperLength, 1e-12);
    EXPECT_NEAR((foot - (2.0 * lower_com - foot)).norm(), robot::kLowerLength, 1e-12);
  }
}

// The HAA column of a link's CoM Jacobian is normal to the leg plane, the
// HFE and KFE columns in it: the mass matrix couples HAA with neither
// (Controller::computeLegs multiplies by it skipping those entries).
TEST(Kinematics, LegMassMatrixHasNoHaaCoupling) {
  std::mt19937_64 rng(5);
  for (int leg = 0; leg < kNumLegs; ++leg)
    for (int trial = 0; trial < 20; ++trial) {
      const Mat3 m = legMassMatrix(leg, randomJoints(leg, rng));
      EXPECT_EQ(m(0, 1), 0.0);
      EXPECT_EQ(m(0, 2), 0.0);
      EXPECT_EQ(m(1, 0), 0.0);
      EXPECT_EQ(m(2, 0), 0.0);
      EXPECT_GT(m(0, 0), 0.0);
    }
}

TEST(Kinematics, LegMassMomentIsTheLinksMassesTimesTheirComs) {
  std::mt19937_64 rng(4);
  const double masses[kLinksPerLeg] = {robot::kHipMass, robot::kUpperMass, robot::kLowerMass};
  for (int leg = 0; leg < kNumLegs; ++leg)
    for (int trial = 0; trial < 20; ++trial) {
      const Vec3 q = randomJoints(leg, rng);
      Vec3 expected = Vec3::Zero();
      for (int link = 0; link < kLinksPerLeg; ++link) expected += masses[link] * linkComPositionBase(leg, link, q);
      EXPECT_LT((legMassMoment(leg, legTrig(leg, q)) - expected).norm(), 1e-12) << "leg " << leg;
    }
}

// Potential energy of the leg's links, V = -sum m g.p_com; the holding torque
// is its gradient.
double legPotential(int leg, const Vec3& q, const Vec3& g) {
  const double masses[kLinksPerLeg] = {robot::kHipMass, robot::kUpperMass, robot::kLowerMass};
  double v = 0.0;
  for (int link = 0; link < kLinksPerLeg; ++link) {
    v -= masses[link] * g.dot(linkComPositionBase(leg, link, q));
  }
  return v;
}

TEST(Kinematics, GravityTorqueIsGradientOfPotentialEnergy) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int leg = 0; leg < kNumLegs; ++leg) {
    for (int trial = 0; trial < 200; ++trial) {
      const Vec3 q = randomJoints(leg, rng);
      const Vec3 g = robot::kGravity * Vec3(normal(rng), normal(rng), normal(rng)).normalized();
      const Vec3 tau = legGravityTorque(leg, q, g);
      const double h = 1e-6;
      for (int j = 0; j < 3; ++j) {
        Vec3 qp = q, qm = q;
        qp[j] += h;
        qm[j] -= h;
        const double numeric = (legPotential(leg, qp, g) - legPotential(leg, qm, g)) / (2.0 * h);
        ASSERT_NEAR(tau[j], numeric, 1e-6) << robot::kLegNames[leg] << " joint " << j;
      }
    }
  }
}

TEST(Kinematics, KneeGravityTorqueEqualsLowerLegMomentAboutKneeAxis) {
  // An independent check of the sign: the KFE holding torque is minus the
  // moment of the lower leg's weight about the KFE axis, and that axis is the
  // HAA-rotated y_B, i.e. (0, cos a, sin a) with a = kHaaAxisSign * q_haa.
  const Vec3 g(0.0, 0.0, -robot::kGravity);
  std::mt19937_64 rng(17);
  for (int leg = 0; leg < kNumLegs; ++leg) {
    const Vec3 q = randomJoints(leg, rng);
    const double a = robot::kHaaAxisSign[leg] * q[0];
    const Vec3 kfe_axis(0.0, std::cos(a), std::sin(a));
    const Vec3 knee = 2.0 * linkComPositionBase(leg, kUpperLink, q) - hfePositionBase(leg, q);
    const Vec3 lever = linkComPositionBase(leg, kLowerLink, q) - knee;
    const double gravity_moment = lever.cross(robot::kLowerMass * g).dot(kfe_axis);
    EXPECT_NEAR(legGravityTorque(leg, q, g)[2], -gravity_moment, 1e-9) << robot::kLegNames[leg];
  }
}

TEST(Kinematics, StanceTorqueSignSupportsTheBody) {
  // A leg pushing the trunk up (ground force +z on the foot) needs torques
  // whose power against the foot motion is consistent: tau = -J^T f means a
  // virtual foot displacement dq moves the foot by J dq and the ground does
  // work f.(J dq) = -tau.dq. Check that for the stand posture, a pure vertical
  // GRF of the body weight share yields a KFE torque that extends the knee.
  const Vec3 f(0.0, 0.0, robot::kTotalMass * robot::kGravity / 4.0);
  for (int leg = 0; leg < kNumLegs; ++leg) {
    const Vec3 q = standJoints(leg);
    const Vec3 tau = -footJacobianBase(leg, q).transpose() * f;
    // Extending the knee (|KFE| decreasing) lowers the foot relative to the hip,
    // so the actuator must push towards extension: sign opposite to KFE's.
    EXPECT_LT(tau[2] * q[2], 0.0) << robot::kLegNames[leg];
  }
}

TEST(Kinematics, LegMassMatrixIsSymmetricPositiveDefinite) {
  std::mt19937_64 rng(11);
  for (int leg = 0; leg < kNumLegs; ++leg)
    for (int trial = 0; trial < 50; ++trial) {
      const Mat3 m = legMassMatrix(leg, randomJoints(leg, rng));
      EXPECT_LT((m - m.transpose()).cwiseAbs().maxCoeff(), 1e-12);
      EXPECT_GT(Eigen::SelfAdjointEigenSolver<Mat3>(m).eigenvalues().minCoeff(), 1e-4);
    }
}

TEST(Kinematics, LegMassMatrixDiagonalIsTheRodsAboutEachJointAxis) {
  // KFE turns only the lower link: a thin rod about its end, m L^2 / 3.
  // HFE turns the upper rod about its end and the lower one about the HFE
  // axis: m_l (r^2 + L_l^2 / 12), r = HFE to the lower link's midpoint, whose
  // square is Lu^2 + (Ll/2)^2 + Lu Ll cos(q_kfe) (law of cosines).
  // HAA (x_B through the HAA joint) turns all three: each link's mass at its
  // midpoint's distance from the axis, plus its rod inertia about a parallel
  // axis through the midpoint, m L^2 / 12 (1 - (d . x)^2).
  using namespace robot;
  std::mt19937_64 rng(12);
  for (int leg = 0; leg < kNumLegs; ++leg)
    for (int trial = 0; trial < 20; ++trial) {
      const Vec3 q = randomJoints(leg, rng);
      const Mat3 m = legMassMatrix(leg, q);
      EXPECT_NEAR(m(2, 2), kLowerMass * kLowerLength * kLowerLength / 3.0, 1e-12);
      const double r2 = kUpperLength * kUpperLength + 0.25 * kLowerLength * kLowerLength +
                        kUpperLength * kLowerLength * std::cos(q[2]);
      const double hfe = kUpperMass * kUpperLength * kUpperLength / 3.0 +
                         kLowerMass * (r2 + kLowerLength * kLowerLength / 12.0);
      EXPECT_NEAR(m(1, 1), hfe, 1e-12);

      const Vec3 haa(kHaaPos[leg][0], kHaaPos[leg][1], kHaaPos[leg][2]);
      const Vec3 hfe_joint = hfePositionBase(leg, q);
      const Vec3 knee = 2.0 * linkComPositionBase(leg, kUpperLink, q) - hfe_joint;
      const Vec3 starts[3] = {haa, hfe_joint, knee};
      const Vec3 ends[3] = {hfe_joint, knee, footPositionBase(leg, q)};
      const double masses[3] = {kHipMass, kUpperMass, kLowerMass};
      double about_haa = 0.0;
      for (int link = 0; link < 3; ++link) {
        const Vec3 r = linkComPositionBase(leg, link, q) - haa;
        const Vec3 d = ends[link] - starts[link];
        const double length = d.norm(), along_x = d.x() / length;
        about_haa += masses[link] * (r.y() * r.y() + r.z() * r.z()) +
                     masses[link] * length * length / 12.0 * (1.0 - along_x * along_x);
      }
      EXPECT_NEAR(m(0, 0), about_haa, 1e-12) << "leg " << leg;
    }
}

TEST(Kinematics, LegInertiaIsTheSeparateCallsInOnePass) {
  std::mt19937_64 rng(14);
  const Vec3 gravity_a(0.3, -0.2, -9.81), gravity_b(1.5, 0.4, -12.0);
  for (int leg = 0; leg < kNumLegs; ++leg)
    for (int trial = 0; trial < 20; ++trial) {
      const Vec3 q = randomJoints(leg, rng);
      const LegInertia model = legInertia(leg, q, gravity_a, gravity_b);
      // Bit for bit: the controller's torques must not change with the pass.
      EXPECT_EQ(model.holding_a, legGravityTorque(leg, q, gravity_a));
      EXPECT_EQ(model.holding_b, legGravityTorque(leg, q, gravity_b));
      EXPECT_EQ(model.mass, legMassMatrix(leg, q));
    }
}

// The joint torques sum_k m_k Jc_k^T a_k that give each link CoM the
// acceleration a_k of its path at qdd = 0, by finite differences: the joints
// move at qd while the base turns by exp([w t + alpha t^2 / 2]x) (`turning`)
// or stays still (Jc by finite differences too).
Vec3 linkPathTorque(int leg, const Vec3& q, const Vec3& qd, const Vec3& omega, const Vec3& alpha, bool turning) {
  const double h = 1e-4;  // [s] time step of the differences
  auto turn = [](const Vec3& theta) {
    const double angle = theta.norm();
    return angle > 0.0 ? Mat3(Eigen::AngleAxisd(angle, theta / angle).toRotationMatrix()) : Mat3(Mat3::Identity());
  };
  const double mass[3] = {robot::kHipMass, robot::kUpperMass, robot::kLowerMass};
  Vec3 torque = Vec3::Zero();
  for (int link = 0; link < 3; ++link) {
    auto com = [&](const Vec3& qq) { return linkComPositionBase(leg, link, qq); };
    auto world = [&](double t) {
      const Mat3 r = turning ? turn(omega * t + 0.5 * alpha * t * t) : Mat3(Mat3::Identity());
      return Vec3(r * com(q + qd * t));
    };
    const Vec3 accel = (world(h) - 2.0 * world(0.0) + world(-h)) / (h * h);
    torque += mass[link] * (centralDifference(com, q, 1e-6).transpose() * accel);
  }
  return torque;
}

// The links' share of the base's rotation: the base's part of each CoM's
// acceleration is the difference between its path on the turning base and
// on a still one.
TEST(Kinematics, BaseRotationTorqueMatchesTheLinksAccelerationsByFiniteDifferences) {
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int leg = 0; leg < kNumLegs; ++leg)
    for (int trial = 0; trial < 10; ++trial) {
      const Vec3 q = standJoints(leg) + 0.3 * Vec3(u(rng), u(rng), u(rng));
      const Vec3 qd = 3.0 * Vec3(u(rng), u(rng), u(rng));       // [rad/s]
      const Vec3 omega = 2.0 * Vec3(u(rng), u(rng), u(rng));    // [rad/s]
      const Vec3 alpha = 30.0 * Vec3(u(rng), u(rng), u(rng));   // [rad/s^2]
      const Vec3 expected = linkPathTorque(leg, q, qd, omega, alpha, true) -
                            linkPathTorque(leg, q, qd, omega, alpha, false);
      const LegBaseRotation model = legBaseRotation(leg, legTrig(leg, q), qd, omega, false);
      const Vec3 got = model.alpha_map * alpha + model.rate_torque;
      EXPECT_LT((got - expected).norm(), 1e-4 * (1.0 + expected.norm()))
          << "leg " << leg << " got " << got.transpose() << " expected " << expected.transpose();
    }
}

// With the leg's own motion: the whole acceleration of each link CoM's path
// on the turning base, so that C(q, qd) qd of the fixed-base dynamics (the
// path on a still base) is in too.
TEST(Kinematics, LegMotionTorqueMatchesTheLinksWholeAccelerationsByFiniteDifferences) {
  std::mt19937_64 rng(22);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int leg = 0; leg < kNumLegs; ++leg)
    for (int trial = 0; trial < 10; ++trial) {
      const Vec3 q = standJoints(leg) + 0.3 * Vec3(u(rng), u(rng), u(rng));
      const Vec3 qd = 3.0 * Vec3(u(rng), u(rng), u(rng));                       // [rad/s]
      const Vec3 omega = trial < 5 ? Vec3(Vec3::Zero()) : Vec3(2.0 * Vec3(u(rng), u(rng), u(rng)));  // [rad/s]
      const Vec3 alpha = 30.0 * Vec3(u(rng), u(rng), u(rng));                   // [rad/s^2]
      const Vec3 expected = linkPathTorque(leg, q, qd, omega, alpha, true);
      const Vec3 own = linkPathTorque(leg, q, qd, omega, alpha, false);
      const LegBaseRotation with = legBaseRotation(leg, legTrig(leg, q), qd, omega, true);
      const LegBaseRotation without = legBaseRotation(leg, legTrig(leg, q), qd, omega, false);
      const Vec3 got = with.alpha_map * alpha + with.rate_torque;
      EXPECT_LT((got - expected).norm(), 1e-4 * (1.0 + expected.norm()))
          << "leg " << leg << " got " << got.transpose() << " expected " << expected.transpose();
      // The leg's own part is what the flag adds, and it is not small at 3 rad/s.
      EXPECT_LT((with.rate_torque - without.rate_torque - own).norm(), 1e-4 * (1.0 + own.norm())) << "leg " << leg;
      EXPECT_GT(own.norm(), 0.05) << "leg " << leg;
      // The map alone (the crawl's fast-turn term) is the same, bit for bit.
      EXPECT_EQ(legBaseAlphaMap(leg, legTrig(leg, q)), with.alpha_map) << "leg " << leg;
      EXPECT_EQ(legBaseAlphaMap(leg, legTrig(leg, q)), without.alpha_map) << "leg " << leg;
    }
}

// A base turning about the HAA axis itself at constant rate flings each
// link straight out from that axis: no moment about it, so no HAA torque.
TEST(Kinematics, SpinAboutTheHaaAxisNeedsNoHaaTorque) {
  for (int leg = 0; leg < kNumLegs; ++leg) {
    const Vec3 q = standJoints(leg);
    const Vec3 omega(3.0, 0.0, 0.0);  // [rad/s] about x_B, through B's origin
    const LegBaseRotation model = legBaseRotation(leg, legTrig(leg, q), Vec3::Zero(), omega, true);
    // About the parallel axis through the HAA joint h, the centrifugal
    // acceleration differs by the constant w x (w x h), which the leg
    // carries like a gravity: take it back out.
    const Vec3 haa(robot::kHaaPos[leg][0], robot::kHaaPos[leg][1], robot::kHaaPos[leg][2]);
    const Vec3 offset_accel = omega.cross(omega.cross(haa));
    const Vec3 about_haa = model.rate_torque + legGravityTorque(leg, q, offset_accel);
    EXPECT_NEAR(about_haa[0], 0.0, 1e-12) << "leg " << leg;
  }
}

TEST(Kinematics, InverseKinematicsRoundTrip) {
  std::mt19937_64 rng(13);
  for (int leg = 0; leg < kNumLegs; ++leg) {
    for (int trial = 0; trial < 1000; ++trial) {
      const Vec3 q = randomJoints(leg, rng);
      Vec3 q_ik;
      ASSERT_TRUE(legInverseKinematics(leg, footPositionBase(leg, q), q_ik))
          << robot::kLegNames[leg] << " q = " << q.transpose();
      ASSERT_LT((q_ik - q).cwiseAbs().maxCoeff(), 1e-9) << robot::kLegNames[leg];
    }
  }
}

TEST(Kinematics, InverseKinematicsChoosesTheRobotsKneeBranch) {
  for (int leg = 0; leg < kNumLegs; ++leg) {
    Vec3 q;
    ASSERT_TRUE(legInverseKinematics(leg, footPositionBase(leg, standJoints(leg)), q));
    EXPECT_LT((q - standJoints(leg)).norm(), 1e-9);
    EXPECT_EQ(q[2] < 0.0, robot::isFront(leg));
  }
}

TEST(Kinematics, UnreachableTargetIsFlaggedAndClamped) {
  for (int leg = 0; leg < kNumLegs; ++leg) {
    const Vec3 haa(robot::kHaaPos[leg][0], robot::kHaaPos[leg][1], robot::kHaaPos[leg][2]);
    const Vec3 targets[] = {haa + Vec3(0.0, 0.0, -2.0),   // beyond full stretch
                            haa + Vec3(0.0, 0.0, -0.1),   // inside the hip
                            haa + Vec3(0.0, 0.0, 0.6),    // above the trunk
                            haa};                          // on the HAA axis
    for (const Vec3& target : targets) {
      Vec3 q;
      EXPECT_FALSE(legInverseKinematics(leg, target, q));
      for (int j = 0; j < 3; ++j) {
        double lo, hi;
        robot::jointLimits(leg, j, lo, hi);
        ASSERT_TRUE(std::isfinite(q[j]));
        EXPECT_GE(q[j], lo);
        EXPECT_LE(q[j], hi);
      }
    }
    // Beyond full stretch straight down: closest answer is the most extended knee.
    Vec3 q;
    legInverseKinematics(leg, haa + Vec3(0.0, 0.0, -2.0), q);
    double lo, hi;
    robot::jointLimits(leg, 2, lo, hi);
    EXPECT_DOUBLE_EQ(q[2], robot::isFront(leg) ? hi : lo);
  }
}

TEST(Kinematics, NonFiniteTargetGivesStandPosture) {
  Vec3 q;
  EXPECT_FALSE(legInverseKinematics(robot::LH, Vec3(NAN, 0.0, -0.6), q));
  EXPECT_LT((q - standJoints(robot::LH)).norm(), 1e-15);
}

}  // namespace
}  // namespace hyq
