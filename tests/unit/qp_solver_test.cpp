// The QP solver against the KKT conditions and against brute-force
// enumeration of active sets, on seeded random problems; infeasible,
// degenerate and invalid inputs; warm start; the iteration bound.
#include "firmware/controller/force/qp_solver.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "firmware/controller/force/grf_qp.hpp"

namespace hyq {
namespace {

constexpr double kKktTol = 1e-8;  // relative to the size of the terms compared

// Row i as a column vector, element-wise: Eigen rejects row blocks of the
// zero-row matrices a problem without equalities carries.
template <typename Matrix>
Eigen::Matrix<double, Matrix::ColsAtCompileTime, 1> rowOf(const Matrix& m, int i) {
  Eigen::Matrix<double, Matrix::ColsAtCompileTime, 1> v;
  for (int k = 0; k < v.size(); ++k) v[k] = m(i, k);
  return v;
}

template <int N, int MI, int ME>
double objective(const QpProblem<N, MI, ME>& p, const Eigen::Matrix<double, N, 1>& x) {
  return 0.5 * x.dot(p.hessian * x) + p.gradient.dot(x);
}

// Checks stationarity, primal and dual feasibility and complementarity, each
// relative to the magnitude of the terms involved. Returns "" when they hold.
template <int N, int MI, int ME>
std::string kktViolation(const QpProblem<N, MI, ME>& p, const QpSolver<N, MI, ME>& solver,
                         const Eigen::Matrix<double, N, 1>& x) {
  Eigen::Matrix<double, MI, 1> lambda;
  for (int i = 0; i < MI; ++i) lambda[i] = solver.ineqMultiplier(i);
  Eigen::Matrix<double, ME, 1> nu;
  for (int e = 0; e < ME; ++e) nu[e] = solver.eqMultiplier(e);

  const Eigen::Matrix<double, N, 1> hx = p.hessian * x;
  Eigen::Matrix<double, N, 1> residual = hx + p.gradient;
  double scale = hx.norm() + p.gradient.norm();
  for (int i = 0; i < MI; ++i) {
    residual -= lambda[i] * rowOf(p.ineq_matrix, i);
    scale += std::fabs(lambda[i]) * rowOf(p.ineq_matrix, i).norm();
  }
  for (int e = 0; e < ME; ++e) {
    residual -= nu[e] * rowOf(p.eq_matrix, e);
    scale += std::fabs(nu[e]) * rowOf(p.eq_matrix, e).norm();
  }
  if (residual.norm() > kKktTol * (1.0 + scale)) {
    return "stationarity " + std::to_string(residual.norm()) + " scale " + std::to_string(scale);
  }
  for (int i = 0; i < MI; ++i) {
    const double row_scale = rowOf(p.ineq_matrix, i).norm() * x.norm() + std::fabs(p.ineq_bound[i]);
    const double slack = rowOf(p.ineq_matrix, i).dot(x) - p.ineq_bound[i];
    if (slack < -kKktTol * (1.0 + row_scale)) return "primal " + std::to_string(i);
    if (lambda[i] < 0.0) return "dual sign " + std::to_string(i);
    if (std::fabs(lambda[i] * slack) > kKktTol * (1.0 + row_scale) * (1.0 + lambda[i])) {
      return "complementarity " + std::to_string(i);
    }
  }
  for (int e = 0; e < ME; ++e) {
    const double row_scale = rowOf(p.eq_matrix, e).norm() * x.norm() + std::fabs(p.eq_bound[e]);
    if (std::fabs(rowOf(p.eq_matrix, e).dot(x) - p.eq_bound[e]) > kKktTol * (1.0 + row_scale)) {
      return "equality " + std::to_string(e);
    }
  }
  return "";
}

// Brute force: the optimum of a strictly convex QP is the lowest-cost
// feasible point among the minimisers with some subset S of inequalities
// held as equalities (with the equalities always held). `allowed` filters
// the subsets tried (all of them when it accepts everything).
template <int N, int MI, int ME, typename Allowed>
bool enumerateActiveSets(const QpProblem<N, MI, ME>& p, Allowed allowed,
                         Eigen::Matrix<double, N, 1>& best_x, double tol = 1e-9) {
  double best = std::numeric_limits<double>::infinity();
  for (unsigned mask = 0; mask < (1u << MI); ++mask) {
    const int active = __builtin_popcount(mask);
    if (active + ME > N || !allowed(mask)) continue;
    const int m = active + ME;
    Eigen::MatrixXd kkt = Eigen::MatrixXd::Zero(N + m, N + m);
    Eigen::VectorXd rhs(N + m);
    kkt.topLeftCorner(N, N) = p.hessian;
    rhs.head(N) = -p.gradient;
    int row = N;
    for (int e = 0; e < ME; ++e, ++row) {
      kkt.block(row, 0, 1, N) = rowOf(p.eq_matrix, e).transpose();
      kkt.block(0, row, N, 1) = rowOf(p.eq_matrix, e);
      rhs[row] = p.eq_bound[e];
    }
    for (int i = 0; i < MI; ++i) {
      if (!(mask & (1u << i))) continue;
      kkt.block(row, 0, 1, N) = rowOf(p.ineq_matrix, i).transpose();
      kkt.block(0, row, N, 1) = rowOf(p.ineq_matrix, i);
      rhs[row++] = p.ineq_bound[i];
    }
    Eigen::FullPivLU<Eigen::MatrixXd> lu(kkt);
    if (lu.rank() < N + m) continue;  // dependent rows: covered by a smaller set
    const Eigen::VectorXd sol = lu.solve(rhs);
    const Eigen::Matrix<double, N, 1> x = sol.head(N);
    bool feasible = true;
    for (int i = 0; i < MI && feasible; ++i) {
      const double scale = 1.0 + rowOf(p.ineq_matrix, i).norm() * x.norm() + std::fabs(p.ineq_bound[i]);
      feasible = rowOf(p.ineq_matrix, i).dot(x) - p.ineq_bound[i] >= -tol * scale;
    }
    if (feasible && objective(p, x) < best) {
      best = objective(p, x);
      best_x = x;
    }
  }
  return std::isfinite(best);
}

// A strictly convex problem with a known feasible point x_feas: some rows are
// tight at it, the others have random slack, so many constraints end active.
template <int N, int MI, int ME>
QpProblem<N, MI, ME> randomFeasibleProblem(std::mt19937_64& rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  QpProblem<N, MI, ME> p;
  Eigen::Matrix<double, N, N> m;
  for (int i = 0; i < N; ++i)
    for (int j = 0; j < N; ++j) m(i, j) = normal(rng);
  p.hessian = m * m.transpose() + 0.1 * Eigen::Matrix<double, N, N>::Identity();
  for (int i = 0; i < N; ++i) p.gradient[i] = 5.0 * normal(rng);
  Eigen::Matrix<double, N, 1> x_feas;
  for (int i = 0; i < N; ++i) x_feas[i] = normal(rng);
  for (int i = 0; i < MI; ++i) {
    for (int j = 0; j < N; ++j) p.ineq_matrix(i, j) = normal(rng);
    const double slack = uniform(rng) < 0.3 ? 0.0 : uniform(rng);
    p.ineq_bound[i] = rowOf(p.ineq_matrix, i).dot(x_feas) - slack;
  }
  for (int e = 0; e < ME; ++e) {
    for (int j = 0; j < N; ++j) p.eq_matrix(e, j) = normal(rng);
    p.eq_bound[e] = rowOf(p.eq_matrix, e).dot(x_feas);
  }
  return p;
}

template <int N, int MI, int ME>
void checkAgainstEnumeration(int problems, uint64_t seed) {
  std::mt19937_64 rng(seed);
  QpSolver<N, MI, ME> solver;
  QpSettings settings;
  int with_active = 0;
  for (int trial = 0; trial < problems; ++trial) {
    const QpProblem<N, MI, ME> p = randomFeasibleProblem<N, MI, ME>(rng);
    Eigen::Matrix<double, N, 1> x, x_ref = Eigen::Matrix<double, N, 1>::Zero();
    ASSERT_EQ(solver.solve(p, settings, false, x), QpStatus::kOptimal) << "trial " << trial;
    ASSERT_EQ(kktViolation(p, solver, x), "") << "trial " << trial;
    ASSERT_TRUE(enumerateActiveSets(p, [](unsigned) { return true; }, x_ref));
    ASSERT_LT((x - x_ref).norm(), 1e-7 * (1.0 + x_ref.norm())) << "trial " << trial;
    with_active += solver.activeCount() > ME ? 1 : 0;
  }
  // The generator must exercise the active-set logic, not only interior optima.
  EXPECT_GT(with_active, problems / 2);
}

TEST(QpSolver, RandomProblemsMatchEnumerationAndKkt) {
  checkAgainstEnumeration<4, 8, 0>(1000, 1);
  checkAgainstEnumeration<3, 10, 0>(500, 2);
}

TEST(QpSolver, RandomProblemsWithEqualitiesMatchEnumerationAndKkt) {
  checkAgainstEnumeration<5, 8, 2>(500, 3);
}

// GRF-shaped problems from the real builder, random stance, normals, mu,
// wrench and foot positions.
GrfInput randomGrfInput(std::mt19937_64& rng, int min_stance) {
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  GrfInput in;
  int stance = 0;
  do {
    stance = 0;
    for (int leg = 0; leg < 4; ++leg) {
      in.stance[leg] = uniform(rng) < 0.8;
      stance += in.stance[leg] ? 1 : 0;
    }
  } while (stance < min_stance);
  const double sx[4] = {1, 1, -1, -1}, sy[4] = {1, -1, 1, -1};
  for (int leg = 0; leg < 4; ++leg) {
    in.foot_from_com.col(leg) =
        Vec3(0.37 * sx[leg], 0.33 * sy[leg], -0.6) + 0.08 * Vec3(normal(rng), normal(rng), normal(rng));
    const double tilt = 0.5 * uniform(rng), heading = 6.283 * uniform(rng);
    in.normal.col(leg) = Vec3(std::sin(tilt) * std::cos(heading), std::sin(tilt) * std::sin(heading),
                              std::cos(tilt));
    in.mu[leg] = 0.1 + 0.9 * uniform(rng);
  }
  const double weight = 84.748 * 9.81;
  in.wrench_des << 150.0 * normal(rng), 150.0 * normal(rng), weight * (1.0 + 0.3 * normal(rng)),
      40.0 * normal(rng), 40.0 * normal(rng), 20.0 * normal(rng);
  return in;
}

TEST(QpSolver, GrfShapedProblemsSatisfyKkt) {
  std::mt19937_64 rng(4);
  const QpParams params;
  GrfSolver solver;
  QpSettings settings;
  int with_active = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    GrfProblem p;
    GrfQp::buildProblem(randomGrfInput(rng, 3), params, 0.70710678118654752, p);
    Vec12 x;
    ASSERT_EQ(solver.solve(p, settings, trial % 2 == 1, x), QpStatus::kOptimal) << trial;
    ASSERT_EQ(kktViolation(p, solver, x), "") << "trial " << trial;
    with_active += solver.activeCount() > 0 ? 1 : 0;
  }
  EXPECT_GT(with_active, 200);
}

TEST(QpSolver, GrfShapedTwoFootProblemsMatchEnumeration) {
  // Two stance feet (12 live constraint rows). Per foot, only these active
  // subsets can be feasible: {none, min, max normal force} x {no face, one of
  // the 4 faces, two adjacent faces}; both normal bounds, or two opposite
  // faces, force f.n = 0 < f_min. The enumeration walks exactly those.
  std::mt19937_64 rng(5);
  const QpParams params;
  GrfSolver solver;
  QpSettings settings;
  const unsigned face_sets[9] = {0, 1, 2, 4, 8, 1 | 4, 1 | 8, 2 | 4, 2 | 8};
  int checked = 0, with_active = 0;
  while (checked < 1000) {
    GrfInput in = randomGrfInput(rng, 0);
    int stance_legs[2], count = 0;
    for (int leg = 0; leg < 4 && count < 2; ++leg) {
      if (in.stance[leg]) stance_legs[count++] = leg;
    }
    if (count < 2) continue;
    for (int leg = 0; leg < 4; ++leg) {
      in.stance[leg] = leg == stance_legs[0] || leg == stance_legs[1];
    }
    GrfProblem full;
    GrfQp::buildProblem(in, params, 0.70710678118654752, full);
    // Reduced problem: the 6 forces and 12 rows of the two stance feet.
    QpProblem<6, 12, 0> p;
    for (int a = 0; a < 2; ++a) {
      for (int b = 0; b < 2; ++b) {
        p.hessian.block<3, 3>(3 * a, 3 * b) =
            full.hessian.block<3, 3>(3 * stance_legs[a], 3 * stance_legs[b]);
      }
      p.gradient.segment<3>(3 * a) = full.gradient.segment<3>(3 * stance_legs[a]);
      p.ineq_matrix.block<6, 3>(6 * a, 3 * a) =
          full.ineq_matrix.block<6, 3>(6 * stance_legs[a], 3 * stance_legs[a]);
      p.ineq_matrix.block<6, 3>(6 * a, 3 * (1 - a)).setZero();
      p.ineq_bound.segment<6>(6 * a) = full.ineq_bound.segment<6>(6 * stance_legs[a]);
    }
    auto allowed = [&face_sets](unsigned mask) {
      for (int a = 0; a < 2; ++a) {
        const unsigned foot = (mask >> (6 * a)) & 0x3f;
        if ((foot & 3u) == 3u) return false;
        bool face_ok = false;
        for (unsigned f : face_sets) face_ok = face_ok || (foot >> 2) == f;
        if (!face_ok) return false;
      }
      return true;
    };
    Vec12 x;
    ASSERT_EQ(solver.solve(full, settings, false, x), QpStatus::kOptimal);
    Eigen::Matrix<double, 6, 1> x_ref = Eigen::Matrix<double, 6, 1>::Zero();
    ASSERT_TRUE(enumerateActiveSets(p, allowed, x_ref, 1e-9));
    for (int a = 0; a < 2; ++a) {
      ASSERT_LT((x.segment<3>(3 * stance_legs[a]) - x_ref.segment<3>(3 * a)).norm(),
                1e-7 * (1.0 + x_ref.norm()))
          << "problem " << checked;
    }
    with_active += solver.activeCount() > 0 ? 1 : 0;
    ++checked;
  }
  EXPECT_GT(with_active, 100);
}

TEST(QpSolver, WarmStartSameAnswerInFewerOrEqualIterations) {
  std::mt19937_64 rng(6);
  QpSettings settings;
  QpSolver<6, 12> solver;
  for (int trial = 0; trial < 500; ++trial) {
    const QpProblem<6, 12, 0> p = randomFeasibleProblem<6, 12, 0>(rng);
    Eigen::Matrix<double, 6, 1> cold, warm;
    ASSERT_EQ(solver.solve(p, settings, false, cold), QpStatus::kOptimal);
    const int cold_iterations = solver.iterations();
    ASSERT_EQ(solver.solve(p, settings, true, warm), QpStatus::kOptimal);
    EXPECT_LE(solver.iterations(), cold_iterations);
    EXPECT_LT((warm - cold).norm(), 1e-9 * (1.0 + cold.norm()));
  }
}

TEST(QpSolver, WarmStartAcrossSlowlyChangingGrfProblems) {
  // A wrench that rotates slowly, tick after tick, like a controller's.
  std::mt19937_64 rng(8);
  const QpParams params;
  QpSettings settings;
  GrfSolver warm_solver, cold_solver;
  GrfInput in = randomGrfInput(rng, 4);
  for (int leg = 0; leg < 4; ++leg) in.mu[leg] = 0.3;
  long warm_total = 0, cold_total = 0;
  for (int tick = 0; tick < 2000; ++tick) {
    const double phase = 0.005 * tick;
    in.wrench_des << 250.0 * std::cos(phase), 250.0 * std::sin(phase), 830.0, 10.0, 0.0, 0.0;
    GrfProblem p;
    GrfQp::buildProblem(in, params, 0.70710678118654752, p);
    Vec12 warm, cold;
    ASSERT_EQ(warm_solver.solve(p, settings, true, warm), QpStatus::kOptimal);
    ASSERT_EQ(cold_solver.solve(p, settings, false, cold), QpStatus::kOptimal);
    ASSERT_LT((warm - cold).norm(), 1e-8 * (1.0 + cold.norm())) << tick;
    ASSERT_EQ(kktViolation(p, warm_solver, warm), "") << tick;
    warm_total += warm_solver.iterations();
    cold_total += cold_solver.iterations();
  }
  EXPECT_LE(warm_total, cold_total);
}

TEST(QpSolver, InfeasibleBoundsAreFlaggedWithFiniteAnswer) {
  // x0 >= 1 and x0 <= 0.
  QpProblem<2, 2> p;
  p.hessian = Eigen::Matrix2d::Identity();
  p.gradient << 0.0, -1.0;
  p.ineq_matrix << 1.0, 0.0, -1.0, 0.0;
  p.ineq_bound << 1.0, 0.0;
  QpSolver<2, 2> solver;
  Eigen::Vector2d x;
  EXPECT_EQ(solver.solve(p, QpSettings{}, false, x), QpStatus::kInfeasible);
  EXPECT_TRUE(x.allFinite());
  // The documented answer: minimiser over the constraints accepted so far;
  // the free coordinate is still optimal.
  EXPECT_NEAR(x[1], 1.0, 1e-12);
}

TEST(QpSolver, InconsistentEqualitiesAreFlagged) {
  QpProblem<2, 1, 2> p;
  p.hessian = Eigen::Matrix2d::Identity();
  p.gradient.setZero();
  p.eq_matrix << 1.0, 1.0, 2.0, 2.0;
  p.eq_bound << 1.0, 3.0;
  p.ineq_matrix << 1.0, 0.0;
  p.ineq_bound << -10.0;
  QpSolver<2, 1, 2> solver;
  Eigen::Vector2d x;
  EXPECT_EQ(solver.solve(p, QpSettings{}, false, x), QpStatus::kInfeasible);
  EXPECT_TRUE(x.allFinite());
}

TEST(QpSolver, ZeroRowWithPositiveBoundIsInfeasibleButRestIsSolved) {
  QpProblem<2, 2> p;
  p.hessian = Eigen::Matrix2d::Identity();
  p.gradient << -1.0, -1.0;
  p.ineq_matrix << 0.0, 0.0, -1.0, 0.0;  // 0 >= 1 (impossible), x0 <= 0.5
  p.ineq_bound << 1.0, -0.5;
  QpSolver<2, 2> solver;
  Eigen::Vector2d x;
  EXPECT_EQ(solver.solve(p, QpSettings{}, false, x), QpStatus::kInfeasible);
  EXPECT_NEAR(x[0], 0.5, 1e-12);
  EXPECT_NEAR(x[1], 1.0, 1e-12);
}

TEST(QpSolver, DegenerateConstraintsStillGiveTheOptimum) {
  // Duplicate active rows, a scaled copy, a zero row that always holds, and
  // three constraints through one vertex in 2D (more than N active-capable).
  QpProblem<2, 6> p;
  p.hessian = Eigen::Matrix2d::Identity();
  p.gradient << 3.0, 3.0;  // unconstrained minimum (-3, -3)
  p.ineq_matrix << 1.0, 0.0,  //
      1.0, 0.0,               // duplicate
      4.0, 0.0,               // scaled duplicate
      0.0, 0.0,               // zero row, 0 >= -1 holds
      0.0, 1.0,               //
      1.0, 1.0;               // through the same vertex (0, 0)
  p.ineq_bound << 0.0, 0.0, 0.0, -1.0, 0.0, 0.0;
  QpSolver<2, 6> solver;
  Eigen::Vector2d x;
  ASSERT_EQ(solver.solve(p, QpSettings{}, false, x), QpStatus::kOptimal);
  EXPECT_LT(x.norm(), 1e-12);
  EXPECT_EQ(kktViolation(p, solver, x), "");
}

TEST(QpSolver, SingularAndIllConditionedHessiansGiveFiniteAnswers) {
  QpSolver<3, 6> solver;
  QpProblem<3, 6> p;
  p.ineq_matrix << Eigen::Matrix3d::Identity(), -Eigen::Matrix3d::Identity();
  p.ineq_bound << -1.0, -1.0, -1.0, -1.0, -1.0, -1.0;  // box |x_i| <= 1
  p.gradient << 1.0, -2.0, 0.5;
  Eigen::Vector3d x;

  p.hessian.setZero();  // an LP over the box: the shift makes it solvable
  EXPECT_EQ(solver.solve(p, QpSettings{}, false, x), QpStatus::kOptimal);
  EXPECT_TRUE(solver.hessianRegularised());
  EXPECT_LT((x - Eigen::Vector3d(-1.0, 1.0, -1.0)).norm(), 1e-9);

  p.hessian = Eigen::Vector3d(1.0, 1e-14, 1e-15).asDiagonal();  // nearly singular
  EXPECT_EQ(solver.solve(p, QpSettings{}, false, x), QpStatus::kOptimal);
  EXPECT_TRUE(x.allFinite());
  EXPECT_LE(x.cwiseAbs().maxCoeff(), 1.0 + 1e-9);

  p.hessian << 1.0, 2.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, -1.0;  // indefinite
  EXPECT_NE(solver.solve(p, QpSettings{}, false, x), QpStatus::kInvalidInput);
  EXPECT_TRUE(x.allFinite());
  EXPECT_LE(x.cwiseAbs().maxCoeff(), 1.0 + 1e-9);

  // Without constraints to bound it, a nearly singular H still gives finite x.
  QpSolver<2, 1> free_solver;
  QpProblem<2, 1> q;
  q.hessian = Eigen::Vector2d(1.0, 0.0).asDiagonal();
  q.gradient << 1.0, 1e300;
  q.ineq_matrix.setZero();
  q.ineq_bound << 0.0;
  Eigen::Vector2d y;
  const QpStatus status = free_solver.solve(q, QpSettings{}, false, y);
  EXPECT_TRUE(status == QpStatus::kOptimal || status == QpStatus::kNumericalFailure);
  EXPECT_TRUE(y.allFinite());
}

TEST(QpSolver, NonFiniteInputIsFlaggedAndAnswerIsZero) {
  std::mt19937_64 rng(9);
  QpSolver<4, 8> solver;
  Eigen::Vector4d x;
  const double bad[3] = {std::nan(""), std::numeric_limits<double>::infinity(),
                         -std::numeric_limits<double>::infinity()};
  for (double value : bad) {
    for (int where = 0; where < 4; ++where) {
      QpProblem<4, 8> p = randomFeasibleProblem<4, 8, 0>(rng);
      if (where == 0) p.hessian(1, 2) = value;
      if (where == 1) p.gradient[3] = value;
      if (where == 2) p.ineq_matrix(5, 0) = value;
      if (where == 3) p.ineq_bound[7] = value;
      EXPECT_EQ(solver.solve(p, QpSettings{}, true, x), QpStatus::kInvalidInput);
      EXPECT_TRUE(x.isZero(0.0));
    }
  }
  // A good problem afterwards is solved normally (warm start was dropped).
  const QpProblem<4, 8> p = randomFeasibleProblem<4, 8, 0>(rng);
  EXPECT_EQ(solver.solve(p, QpSettings{}, true, x), QpStatus::kOptimal);
  EXPECT_EQ(kktViolation(p, solver, x), "");
}

TEST(QpSolver, IterationBoundIsRespectedAndReported) {
  std::mt19937_64 rng(10);
  QpSolver<6, 12> solver;
  QpSettings settings;
  int bounded = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const QpProblem<6, 12> p = randomFeasibleProblem<6, 12, 0>(rng);
    Eigen::Matrix<double, 6, 1> x;
    settings.max_iterations = 64;
    ASSERT_EQ(solver.solve(p, settings, false, x), QpStatus::kOptimal);
    const int needed = solver.iterations();
    if (needed < 2) continue;
    settings.max_iterations = needed - 1;
    EXPECT_EQ(solver.solve(p, settings, false, x), QpStatus::kMaxIterations);
    EXPECT_EQ(solver.iterations(), needed - 1);
    EXPECT_TRUE(x.allFinite());
    ++bounded;
  }
  EXPECT_GT(bounded, 50);
}

}  // namespace
}  // namespace hyq
