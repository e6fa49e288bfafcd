// The GRF distribution: standing weight support without friction use, exact
// zero on swing feet, pyramids respected for random normals and mu, wrenches
// beyond friction tracked as well as the pyramids allow, fallbacks flagged.
#include "firmware/controller/force/grf_qp.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>
#include <random>

#include "firmware/controller/model/kinematics.hpp"
#include "firmware/controller/model/robot_params.hpp"

// Every heap allocation of this test binary is counted: malloc (what Eigen's
// dynamic matrices use) through glibc's own entry point, and operator new.
namespace {
std::atomic<long> g_allocations{0};
}  // namespace
extern "C" void* __libc_malloc(size_t size);
extern "C" void* malloc(size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_malloc(size);
}
void* operator new(size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, size_t) noexcept { std::free(p); }

namespace hyq {
namespace {

constexpr double kPyramidScale = 0.70710678118654752;
const double kWeight = robot::kTotalMass * robot::kGravity;

// HyQ standing on flat ground at the stand posture, CoM at the base origin.
GrfInput standingInput() {
  GrfInput in;
  for (int leg = 0; leg < 4; ++leg) {
    const Vec3 q(robot::standAngle(leg, 0), robot::standAngle(leg, 1), robot::standAngle(leg, 2));
    in.stance[leg] = true;
    in.foot_from_com.col(leg) = footPositionBase(leg, q);
    in.normal.col(leg) = Vec3::UnitZ();
    in.mu[leg] = 0.6;
  }
  in.wrench_des << 0.0, 0.0, kWeight, 0.0, 0.0, 0.0;
  return in;
}

// Standing on mu 0.3 under a forward wrench of 400 N, beyond what friction
// allows (mu_p * weight = 0.212 * 831 = 176 N).
GrfInput pushedBeyondFriction() {
  GrfInput in = standingInput();
  for (int leg = 0; leg < 4; ++leg) in.mu[leg] = 0.3;
  in.wrench_des[0] = 400.0;
  return in;
}

// Violation of foot i's normal bounds and pyramid faces [N] (0 when inside).
double pyramidViolation(const Vec3& f, const Vec3& n, double mu, const QpParams& params) {
  Vec3 t1, t2;
  contactTangents(n, t1, t2);
  const double fn = n.dot(f), mu_p = mu * kPyramidScale;
  double worst = std::fmax(params.f_normal_min - fn, fn - params.f_normal_max);
  worst = std::fmax(worst, std::fabs(t1.dot(f)) - mu_p * fn);
  worst = std::fmax(worst, std::fabs(t2.dot(f)) - mu_p * fn);
  return std::fmax(worst, 0.0);
}

TEST(GrfQp, StandingRobotCarriesItsWeightWithoutFriction) {
  GrfQp qp;
  const QpParams params;
  qp.init(params, kPyramidScale);
  GrfOutput out;
  qp.solve(standingInput(), out);
  ASSERT_EQ(out.status, QpStatus::kOptimal);
  EXPECT_FALSE(out.infeasible);
  EXPECT_FALSE(out.hit_iteration_limit);
  // Regularisation costs only reg/(1 + reg) of the weight: well under 0.1 N.
  EXPECT_NEAR(out.forces.row(2).sum(), kWeight, 0.1);
  EXPECT_NEAR(out.wrench[2], kWeight, 0.1);
  for (int leg = 0; leg < 4; ++leg) {
    EXPECT_NEAR(out.forces(0, leg), 0.0, 1e-9) << robot::kLegNames[leg];
    EXPECT_NEAR(out.forces(1, leg), 0.0, 1e-9) << robot::kLegNames[leg];
    EXPECT_GT(out.forces(2, leg), params.f_normal_min);
  }
  EXPECT_LT(out.wrench.tail<3>().norm(), 1e-6);
}

// Sum over stance feet of |tangential force| [N].
double tangentialSum(const Mat3x4& forces, const GrfInput& in) {
  double sum = 0.0;
  for (int leg = 0; leg < 4; ++leg) {
    if (!in.stance[leg]) continue;
    const Vec3 f = forces.col(leg), n = in.normal.col(leg);
    sum += (f - f.dot(n) * n).norm();
  }
  return sum;
}

TEST(GrfQp, TangentialWeightLetsInternalTangentialForcesDieOut) {
  // The front feet pushing each other apart sideways (+-30 N) is an internal
  // force: it changes neither the net force nor the moment about the CoM.
  // With force smoothing (each tick starts from last tick's forces, as in the
  // controller, where a foot joins with the force it lands with), the wrench
  // error cannot remove it; only the weights on the forces themselves can.
  // Regularisation alone (1e-4 against smoothing 0.5) takes seconds; the
  // tangential weight tens of ticks.
  GrfInput in = standingInput();
  in.smoothing = 0.5;
  GrfQp qp_plain, qp_weighted;
  QpParams plain;
  plain.tangential_weight = 0.0;
  const QpParams weighted;  // the default is on
  ASSERT_GT(weighted.tangential_weight, 0.0);
  qp_plain.init(plain, kPyramidScale);
  qp_weighted.init(weighted, kPyramidScale);
  Mat3x4 start = Mat3x4::Zero();
  start.row(2).setConstant(kWeight / 4.0);
  start(1, 0) = 30.0;   // LF pushed to +y
  start(1, 1) = -30.0;  // RF pushed to -y
  const double initial = tangentialSum(start, in);
  ASSERT_NEAR(initial, 60.0, 1e-12);
  Mat3x4 f_plain = start, f_weighted = start;
  const int ticks = 100;  // [ms]
  for (int k = 0; k < ticks; ++k) {
    GrfOutput out;
    in.force_previous = f_plain;
    qp_plain.solve(in, out);
    ASSERT_EQ(out.status, QpStatus::kOptimal);
    f_plain = out.forces;
    in.force_previous = f_weighted;
    qp_weighted.solve(in, out);
    ASSERT_EQ(out.status, QpStatus::kOptimal);
    f_weighted = out.forces;
    EXPECT_LT((out.wrench - in.wrench_des).norm(), 0.5);
  }
  // Per tick the internal part shrinks by the factor s / (s + w): w = 1e-4
  // keeps 98 % after 100 ticks, w = 1e-4 + 0.01 keeps ~13 %.
  const double keep_plain = std::pow(0.5 / (0.5 + plain.regularisation), ticks);
  const double keep_weighted =
      std::pow(0.5 / (0.5 + weighted.regularisation + weighted.tangential_weight), ticks);
  EXPECT_NEAR(tangentialSum(f_plain, in), initial * keep_plain, 0.5);
  EXPECT_NEAR(tangentialSum(f_weighted, in), initial * keep_weighted, 0.5);
  EXPECT_LT(tangentialSum(f_weighted, in), 0.2 * initial);
  EXPECT_GT(tangentialSum(f_plain, in), 0.9 * initial);
}

// The cost's Hessian and gradient, built block by block, against the
// dense A' W^2 A + reg I and -A' W^2 w_des on random feet and wrenches
// (no smoothing, no tangential weight: only the wrench term and reg).
TEST(GrfQp, BlockBuiltCostEqualsTheDenseWrenchCost) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.6, 0.6);
  QpParams params;
  params.tangential_weight = 0.0;
  for (int trial = 0; trial < 50; ++trial) {
    GrfInput in = standingInput();
    Eigen::Matrix<double, 6, 12> a;
    for (int foot = 0; foot < 4; ++foot) {
      in.foot_from_com.col(foot) = Vec3(u(rng), u(rng), u(rng) - 0.6);
      a.block<3, 3>(0, 3 * foot).setIdentity();
      a.block<3, 3>(3, 3 * foot) = skew(in.foot_from_com.col(foot));
    }
    for (int k = 0; k < 6; ++k) in.wrench_des[k] = 200.0 * u(rng);
    GrfProblem problem;
    GrfQp::buildProblem(in, params, kPyramidScale, problem);
    Eigen::Matrix<double, 6, 1> w2;
    w2 << Vec3::Constant(params.wrench_weight_lin * params.wrench_weight_lin),
        Vec3::Constant(params.wrench_weight_ang * params.wrench_weight_ang);
    Eigen::Matrix<double, 12, 12> h = a.transpose() * w2.asDiagonal() * a;
    h.diagonal().array() += params.regularisation;
    const Eigen::Matrix<double, 12, 1> g = -a.transpose() * (w2.asDiagonal() * in.wrench_des);
    EXPECT_LT((problem.hessian - h).cwiseAbs().maxCoeff(), 1e-12 * h.cwiseAbs().maxCoeff()) << trial;
    EXPECT_LT((problem.gradient - g).cwiseAbs().maxCoeff(), 1e-12 * g.cwiseAbs().maxCoeff()) << trial;
    EXPECT_EQ(problem.hessian, problem.hessian.transpose()) << trial;
  }
}

TEST(GrfQp, SwingFootGetsExactlyZero) {
  GrfQp qp;
  const QpParams params;
  qp.init(params, kPyramidScale);
  for (int swing = 0; swing < 4; ++swing) {
    GrfInput in = standingInput();
    in.stance[swing] = false;
    // The CoM over the centroid of the three stance feet: weight is carried.
    Vec3 centroid = Vec3::Zero();
    for (int leg = 0; leg < 4; ++leg) {
      if (leg != swing) centroid += in.foot_from_com.col(leg) / 3.0;
    }
    for (int leg = 0; leg < 4; ++leg) in.foot_from_com.col(leg) -= Vec3(centroid.x(), centroid.y(), 0.0);
    GrfOutput out;
    qp.solve(in, out);
    ASSERT_EQ(out.status, QpStatus::kOptimal);
    EXPECT_EQ(out.forces(0, swing), 0.0);
    EXPECT_EQ(out.forces(1, swing), 0.0);
    EXPECT_EQ(out.forces(2, swing), 0.0);
    EXPECT_NEAR(out.wrench[2], kWeight, 0.1);
    EXPECT_LT(out.wrench.tail<3>().norm(), 0.05);
  }
}

TEST(GrfQp, ForcesRespectPyramidsForRandomNormalsAndMu) {
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  GrfQp qp;
  const QpParams params;
  qp.init(params, kPyramidScale);
  int friction_limited = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    GrfInput in = standingInput();
    in.stance[trial % 4] = trial % 3 != 0;  // mixes 3- and 4-foot stances
    for (int leg = 0; leg < 4; ++leg) {
      const double tilt = 0.6 * uniform(rng), heading = 6.283 * uniform(rng);
      in.normal.col(leg) << std::sin(tilt) * std::cos(heading), std::sin(tilt) * std::sin(heading),
          std::cos(tilt);
      in.mu[leg] = 0.05 + 0.95 * uniform(rng);
    }
    in.wrench_des << 200.0 * normal(rng), 200.0 * normal(rng), kWeight * (1.0 + 0.2 * normal(rng)),
        50.0 * normal(rng), 50.0 * normal(rng), 30.0 * normal(rng);
    GrfOutput out;
    qp.solve(in, out);
    ASSERT_EQ(out.status, QpStatus::kOptimal) << trial;
    bool on_boundary = false;
    for (int leg = 0; leg < 4; ++leg) {
      if (!in.stance[leg]) {
        ASSERT_TRUE(out.forces.col(leg).isZero(0.0));
        continue;
      }
      const Vec3 f = out.forces.col(leg);
      ASSERT_LT(pyramidViolation(f, in.normal.col(leg), in.mu[leg], params), 1e-6)
          << "trial " << trial << " leg " << leg;
      on_boundary = on_boundary || pyramidViolation(f, in.normal.col(leg), 0.99 * in.mu[leg],
                                                    params) > 1e-3;
    }
    friction_limited += on_boundary ? 1 : 0;
  }
  EXPECT_GT(friction_limited, 100);  // the pyramids were really in play
}

TEST(GrfQp, WrenchBeyondFrictionIsTrackedAsFarAsAllowedAndNotFlagged) {
  GrfQp qp;
  // The closed form below is for the wrench error and the plain
  // regularisation alone (the tangential weight adds its own term).
  QpParams params;
  params.tangential_weight = 0.0;
  qp.init(params, kPyramidScale);
  GrfInput in = pushedBeyondFriction();
  GrfOutput out;
  qp.solve(in, out);
  EXPECT_EQ(out.status, QpStatus::kOptimal);
  EXPECT_FALSE(out.infeasible);
  EXPECT_FALSE(out.hit_iteration_limit);
  const double mu_p = 0.3 * kPyramidScale;
  double normal_sum = 0.0;
  for (int leg = 0; leg < 4; ++leg) {
    // Every foot pushes forward as hard as its pyramid allows.
    EXPECT_NEAR(out.forces(0, leg), mu_p * out.forces(2, leg), 1e-6);
    normal_sum += out.forces(2, leg);
  }
  EXPECT_NEAR(out.wrench[0], mu_p * normal_sum, 1e-6);
  EXPECT_LT(out.wrench[0], 400.0);
  // Best tracking with equal weights: more normal force buys mu_p more
  // traction, so the optimum balances the errors at e_z = mu_p * e_x.
  const double error_x = 400.0 - out.wrench[0], error_z = out.wrench[2] - kWeight;
  EXPECT_GT(error_z, 10.0);
  EXPECT_NEAR(error_z, mu_p * error_x, 0.1);
  EXPECT_LT(out.wrench.tail<3>().norm(), 0.1);  // moments still met by redistribution
}

TEST(GrfQp, ARectangularPyramidLimitsTheForceAcrossTheFallLineOnly) {
  // All four feet on a 0.35 rad slope rising along x, asked for a sideways
  // force as well as the weight: the along-slope part (gravity's) is
  // carried within mu, the sideways part only within mu_across.
  const double tilt = 0.35, mu = 0.62, mu_across = 0.3;
  const Vec3 n(-std::sin(tilt), 0.0, std::cos(tilt));
  const Vec3 up(std::cos(tilt), 0.0, std::sin(tilt));  // the fall line, uphill
  const Vec3 side = up.cross(n);
  QpParams params;
  params.tangential_weight = 0.0;
  GrfQp qp;
  qp.init(params, kPyramidScale);
  GrfInput in = standingInput();
  for (int leg = 0; leg < 4; ++leg) {
    in.normal.col(leg) = n;
    in.mu[leg] = mu;
  }
  in.wrench_des << 0.0, 250.0, kWeight, 0.0, 0.0, 0.0;
  GrfOutput square, rectangle;
  qp.solve(in, square);
  for (int leg = 0; leg < 4; ++leg) in.mu_across[leg] = mu_across;
  qp.solve(in, rectangle);
  ASSERT_EQ(square.status, QpStatus::kOptimal);
  ASSERT_EQ(rectangle.status, QpStatus::kOptimal);
  double side_square = 0.0, side_rectangle = 0.0;
  for (int leg = 0; leg < 4; ++leg) {
    const Vec3 f = rectangle.forces.col(leg);
    const double fn = n.dot(f);
    EXPECT_LE(std::fabs(side.dot(f)), mu_across * kPyramidScale * fn + 1e-6) << leg;
    EXPECT_LE(std::fabs(up.dot(f)), mu * kPyramidScale * fn + 1e-6) << leg;
    side_square += side.dot(square.forces.col(leg));
    side_rectangle += side.dot(rectangle.forces.col(leg));
    // Sideways at its limit, and the weight's pull down the slope still held.
    EXPECT_NEAR(std::fabs(side.dot(f)), mu_across * kPyramidScale * fn, 1e-6) << leg;
  }
  EXPECT_LT(std::fabs(side_rectangle), std::fabs(side_square) - 20.0);
  // The slope still held: the QP leans on the normal force for sideways
  // traction, which costs a few N of the wrench along x, nothing like the
  // weight's pull down the slope (0.34 kWeight = 282 N).
  EXPECT_LT(std::fabs(rectangle.wrench[0]), 10.0);
  // mu_across at or above mu, or a level normal: the square pyramid, bit for bit.
  for (int leg = 0; leg < 4; ++leg) in.mu_across[leg] = mu;
  GrfOutput same;
  qp.solve(in, same);
  EXPECT_TRUE(same.forces == square.forces);
  GrfInput flat = standingInput();
  GrfOutput flat_square, flat_narrow;
  flat.wrench_des[1] = 250.0;
  qp.solve(flat, flat_square);
  for (int leg = 0; leg < 4; ++leg) flat.mu_across[leg] = 0.1;
  qp.solve(flat, flat_narrow);
  EXPECT_TRUE(flat_narrow.forces == flat_square.forces);
}

TEST(GrfQp, ConeOffsetLeavesALightFootNoTangentialForce) {
  // A forward wrench beyond friction, with every pyramid shifted by 10 N:
  // each foot pushes forward mu_p (f_n - 10) at most; a foot capped at its
  // least normal force (f_normal_min = 10 N) pushes with none; a foot capped
  // below the offset (5 N) keeps a feasible problem (the offset falls to 5).
  GrfQp qp;
  QpParams params;
  params.tangential_weight = 0.0;
  qp.init(params, kPyramidScale);
  GrfInput in = pushedBeyondFriction();
  in.cone_offset = 10.0;
  in.max_normal_force[robot::LF] = params.f_normal_min;
  in.max_normal_force[robot::RF] = 5.0;
  GrfOutput out;
  qp.solve(in, out);
  ASSERT_EQ(out.status, QpStatus::kOptimal);
  const double mu_p = 0.3 * kPyramidScale;
  EXPECT_NEAR(out.forces(2, robot::LF), 10.0, 1e-6);
  EXPECT_NEAR(out.forces.col(robot::LF).head<2>().norm(), 0.0, 1e-6);
  EXPECT_NEAR(out.forces(2, robot::RF), 5.0, 1e-6);
  EXPECT_NEAR(out.forces.col(robot::RF).head<2>().norm(), 0.0, 1e-6);
  for (int leg : {robot::LH, robot::RH}) {
    EXPECT_GT(out.forces(2, leg), 100.0);
    EXPECT_NEAR(out.forces(0, leg), mu_p * (out.forces(2, leg) - 10.0), 1e-6);
  }
  // Without the offset the same feet push mu_p f_n.
  in.cone_offset = 0.0;
  qp.solve(in, out);
  ASSERT_EQ(out.status, QpStatus::kOptimal);
  EXPECT_NEAR(out.forces(0, robot::LF), mu_p * out.forces(2, robot::LF), 1e-6);
  EXPECT_GT(out.forces(0, robot::LF), 1.0);
  // A NaN offset is no offset.
  const Mat3x4 plain = out.forces;
  in.cone_offset = std::nan("");
  qp.solve(in, out);
  ASSERT_EQ(out.status, QpStatus::kOptimal);
  EXPECT_NEAR((out.forces - plain).norm(), 0.0, 1e-9);
}

TEST(GrfQp, CrossedNormalBoundsFollowTheCeiling) {
  // f_min above f_max: the minimum is lowered to the ceiling (a foot being
  // unloaded must be able to reach its cap), so the problem stays feasible.
  GrfQp qp;
  QpParams params;
  params.f_normal_min = 300.0;
  params.f_normal_max = 100.0;
  qp.init(params, kPyramidScale);
  GrfOutput out;
  qp.solve(standingInput(), out);
  EXPECT_EQ(out.status, QpStatus::kOptimal);
  EXPECT_FALSE(out.infeasible);
  for (int leg = 0; leg < 4; ++leg) EXPECT_NEAR(out.forces(2, leg), 100.0, 1e-6);
}

TEST(GrfQp, PerFootNormalForceCapIsRespected) {
  GrfQp qp;
  const QpParams params;
  qp.init(params, kPyramidScale);
  GrfInput in = standingInput();
  in.max_normal_force[robot::RH] = 40.0;
  GrfOutput out;
  qp.solve(in, out);
  ASSERT_EQ(out.status, QpStatus::kOptimal);
  EXPECT_NEAR(out.forces(2, robot::RH), 40.0, 1e-6);  // it would carry ~208 N uncapped
  EXPECT_NEAR(out.wrench[2], kWeight, 1.0);           // the others take the rest
}

TEST(GrfQp, IterationLimitGivesAdmissibleForcesAndFlag) {
  GrfQp qp;
  QpParams params;
  params.max_iterations = 2;  // the friction-limited case needs more
  qp.init(params, kPyramidScale);
  GrfInput in = standingInput();
  for (int leg = 0; leg < 4; ++leg) in.mu[leg] = 0.3;
  in.wrench_des[0] = 400.0;
  in.wrench_des[1] = -150.0;
  GrfOutput out;
  qp.solve(in, out);
  EXPECT_TRUE(out.hit_iteration_limit);
  EXPECT_FALSE(out.infeasible);
  EXPECT_EQ(out.iterations, 2);
  ASSERT_TRUE(out.forces.allFinite());
  for (int leg = 0; leg < 4; ++leg) {
    // Projected into the foot's own bounds and pyramid.
    EXPECT_LT(pyramidViolation(out.forces.col(leg), Vec3::UnitZ(), 0.3, params), 1e-9);
  }
}

TEST(GrfQp, NonFiniteInputGivesZeroForcesAndFlag) {
  GrfQp qp;
  qp.init(QpParams{}, kPyramidScale);
  GrfOutput out;
  GrfInput in = standingInput();
  in.wrench_des[3] = std::nan("");
  qp.solve(in, out);
  EXPECT_TRUE(out.infeasible);
  EXPECT_TRUE(out.forces.isZero(0.0));
  EXPECT_TRUE(out.wrench.allFinite());

  in = standingInput();
  in.foot_from_com(0, 2) = std::numeric_limits<double>::infinity();
  qp.solve(in, out);
  EXPECT_TRUE(out.infeasible);
  EXPECT_TRUE(out.forces.allFinite());
  EXPECT_TRUE(out.wrench.allFinite());

  // Good input afterwards: back to normal.
  qp.solve(standingInput(), out);
  EXPECT_EQ(out.status, QpStatus::kOptimal);
  EXPECT_NEAR(out.wrench[2], kWeight, 0.1);
}

TEST(GrfQp, BadNormalOrMuIsReplacedNotPropagated) {
  GrfQp qp;
  const QpParams params;
  qp.init(params, kPyramidScale);
  GrfInput in = standingInput();
  in.normal.col(1) = Vec3(std::nan(""), 0.0, 1.0);
  in.normal.col(2) = Vec3::Zero();
  in.mu[3] = -1.0;
  in.wrench_des[0] = 100.0;
  GrfOutput out;
  qp.solve(in, out);
  ASSERT_EQ(out.status, QpStatus::kOptimal);
  ASSERT_TRUE(out.forces.allFinite());
  // Negative mu became 0: that foot pushes straight along its normal (+z).
  EXPECT_NEAR(out.forces(0, 3), 0.0, 1e-9);
  EXPECT_NEAR(out.forces(1, 3), 0.0, 1e-9);
  // The replaced normals are +z: those feet stay in the flat mu = 0.6 pyramid.
  EXPECT_LT(pyramidViolation(out.forces.col(1), Vec3::UnitZ(), 0.6, params), 1e-6);
  EXPECT_LT(pyramidViolation(out.forces.col(2), Vec3::UnitZ(), 0.6, params), 1e-6);
}

TEST(GrfQp, TangentsAreOrthonormalEvenForNormalsAlongX) {
  const Vec3 normals[] = {Vec3::UnitZ(), Vec3::UnitX(), -Vec3::UnitX(),
                          Vec3(1.0, 1e-9, 0.0).normalized(), Vec3(0.3, -0.2, 0.9).normalized()};
  for (const Vec3& n : normals) {
    Vec3 t1, t2;
    contactTangents(n, t1, t2);
    EXPECT_NEAR(t1.norm(), 1.0, 1e-12);
    EXPECT_NEAR(t2.norm(), 1.0, 1e-12);
    EXPECT_NEAR(t1.dot(n), 0.0, 1e-12);
    EXPECT_NEAR(t2.dot(n), 0.0, 1e-12);
    EXPECT_NEAR(t1.dot(t2), 0.0, 1e-12);
  }
  // Flat ground: t1 = z x x = y, t2 = y x z = x (as in the lab's code).
  Vec3 t1, t2;
  contactTangents(Vec3::UnitZ(), t1, t2);
  EXPECT_LT((t1 - Vec3::UnitY()).norm(), 1e-15);
  EXPECT_LT((t2 - Vec3::UnitX()).norm(), 1e-15);
}

TEST(GrfQp, RepeatedTicksGiveTheSameAnswerAndIterations) {
  GrfQp qp;
  qp.init(QpParams{}, kPyramidScale);
  GrfInput in = standingInput();
  for (int leg = 0; leg < 4; ++leg) in.mu[leg] = 0.3;
  in.wrench_des[0] = 400.0;  // friction-limited: 4+ active constraints
  GrfOutput first, again;
  qp.solve(in, first);
  ASSERT_GE(first.iterations, 4);
  qp.solve(in, again);
  EXPECT_EQ(again.iterations, first.iterations);
  EXPECT_EQ(again.forces, first.forces);
}

TEST(GrfQp, SolvingAndTheLegModelNeverAllocate) {
  GrfQp qp;
  qp.init(QpParams{}, kPyramidScale);
  GrfInput in = standingInput();
  GrfOutput out;
  Vec3 sink = Vec3::Zero();
  const long before = g_allocations.load();
  for (int tick = 0; tick < 10000; ++tick) {
    // Vary the problem so that active sets, fallbacks and guards all run.
    in.wrench_des[0] = 600.0 * std::sin(0.01 * tick);
    in.mu[tick % 4] = 0.1 + 0.5 * ((tick / 7) % 3);
    in.stance[(tick / 500) % 4] = tick % 1000 < 500;
    if (tick % 997 == 0) in.wrench_des[4] = std::nan("");
    qp.solve(in, out);
    in.wrench_des[4] = 0.0;
    const int leg = tick % 4;
    const Vec3 q(-0.2, 0.7, robot::isFront(leg) ? -1.4 : 1.4);
    Vec3 q_ik;
    legInverseKinematics(leg, footPositionBase(leg, q), q_ik);
    sink += footJacobianBase(leg, q_ik) * legGravityTorque(leg, q_ik, Vec3(0.0, 0.0, -9.81));
  }
  const long allocations = g_allocations.load() - before;
  EXPECT_EQ(allocations, 0);
  EXPECT_TRUE(sink.allFinite());
  EXPECT_TRUE(out.forces.allFinite());
}

}  // namespace
}  // namespace hyq
