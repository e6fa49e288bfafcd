// A dense, strictly convex QP solver of fixed size, with no heap:
//
//   minimise 0.5 x'Hx + g'x   subject to   A_eq x = b_eq,   A_in x >= b_in,
//
// x in R^N, ME equalities, MI inequalities (compile-time sizes).
//
// Method: the dual active-set method of Goldfarb and Idnani (1983). It starts
// from the unconstrained minimum and adds the most violated constraint at a
// time, keeping the multipliers non-negative; the factors J = L^-T Q and R
// (H = L L') are updated by Givens rotations, so an iteration costs O(N^2)
// plus an O(MI N) scan for the most violated constraint. Why this method: it
// needs no feasible starting point, detects infeasibility by itself, and its
// iterates are always minimisers over a subset of the constraints, which is a
// meaningful bounded answer when the iteration bound cuts it short.
//
// Why templated sizes: the GRF problem is QpSolver<12, 24> (3 forces per foot;
// 4 pyramid faces + min/max normal force per foot), while the unit tests run
// the same code on small sizes where every active set can be enumerated.
//
// Robustness (never NaN/Inf out):
//  - non-finite input: status kInvalidInput, x = 0;
//  - H not numerically positive definite: symmetrised, then shifted by a
//    growing multiple of the identity until its Cholesky factor exists
//    (hessianRegularised() says so);
//  - constraint rows are scaled to unit norm; a row of (near) zero norm is
//    ignored when it is satisfied (0 >= b, b <= tolerance) and makes the
//    problem infeasible otherwise;
//  - linearly dependent constraints are detected and never added;
//  - infeasible: status kInfeasible, x = minimiser of the cost subject to the
//    equalities and the inequalities accepted before the conflict (bounded,
//    satisfies those, may violate the rest);
//  - iteration bound hit: status kMaxIterations, x = the current iterate
//    (bounded, satisfies the constraints active so far, may violate others);
//  - a non-finite result (overflow): status kNumericalFailure, x = 0.
//
// Warm start: the inequality active set of the last successful solve is kept
// in the object. With warm_start = true it is imposed first (constraints whose
// multipliers come out negative are dropped again), then the method continues
// as usual; the answer is the same optimum, usually with fewer iterations.
// Iterations count active-set changes (constraint additions and removals,
// warm-start additions included) and are bounded by max_iterations.
#pragma once
#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <limits>

#include "firmware/controller/params.hpp"

namespace hyq {

enum class QpStatus : uint8_t {
  kOptimal = 0,
  kInfeasible,
  kMaxIterations,
  kInvalidInput,
  kNumericalFailure,
};

// Defaults are the GRF problem's (QpParams, the one place for the numbers).
struct QpSettings {
  int max_iterations = QpParams{}.max_iterations;  // [-] bound on active-set changes
  double feasibility_tolerance = QpParams{}.feasibility_tolerance;  // [units of x] on unit-norm rows
};

template <int N, int MI, int ME = 0>
struct QpProblem {
  Eigen::Matrix<double, N, N> hessian;
  Eigen::Matrix<double, N, 1> gradient;
  Eigen::Matrix<double, MI, N> ineq_matrix;  // rows a_i: a_i x >= b_i
  Eigen::Matrix<double, MI, 1> ineq_bound;
  Eigen::Matrix<double, ME, N> eq_matrix;    // rows a_e: a_e x = b_e
  Eigen::Matrix<double, ME, 1> eq_bound;
};

template <int N, int MI, int ME = 0>
class QpSolver {
 public:
  static constexpr int kNumConstraints = ME + MI;  // equalities first, then inequalities
  using VecN = Eigen::Matrix<double, N, 1>;
  using MatN = Eigen::Matrix<double, N, N>;
  using Problem = QpProblem<N, MI, ME>;

  // Solves the problem; x always receives finite values.
  QpStatus solve(const Problem& problem, const QpSettings& settings, bool warm_start, VecN& x);

  // Forget the stored active set (next warm start is a cold start).
  void resetWarmStart() { warm_count_ = 0; }

  int iterations() const { return iterations_; }
  bool hessianRegularised() const { return hessian_regularised_; }
  int activeCount() const { return num_active_; }
  // Multiplier of inequality i (>= 0; 0 when inactive), in the problem's
  // own scaling: H x + g = A_eq' eqMultiplier + A_in' ineqMultiplier.
  double ineqMultiplier(int i) const { return multipliers_[ME + i]; }
  double eqMultiplier(int e) const { return multipliers_[e]; }

 private:
  using VecC = Eigen::Matrix<double, kNumConstraints, 1>;
  using MatCN = Eigen::Matrix<double, kNumConstraints, N>;

  // Scale of "numerically zero" for row norms and dependency tests, relative
  // to the quantities compared; far above round-off, far below real data.
  static constexpr double kRelativeZero = 1e-12;

  bool factorHessian(const MatN& hessian);
  void loadConstraints(const Problem& problem, double tolerance);
  void resetToUnconstrained(const VecN& gradient, VecN& x);
  // d = J' n_c, z = step direction, r = R^-1 d(0:q); false if z is zero.
  bool stepDirections(int c, VecN& d, VecN& z, VecN& r) const;
  bool appendToFactor(VecN& d);  // Givens update of J and R for a new column
  void removeFromFactor(int position);
  // Adds constraint c with a full step regardless of the multipliers' signs
  // (for equalities and the warm-start set). Returns false if dependent.
  bool forceActive(int c, VecN& x);
  bool imposeWarmSet(const VecN& gradient, VecN& x);
  double violation(int c, const VecN& x) const { return rows_.row(c).dot(x) - bounds_[c]; }

  MatN cholesky_{};        // L, H = L L'
  MatN j_{};               // J: J J' = H^-1, first q columns span the active rows
  MatN r_{};               // R (upper triangular q x q block): J(:,0:q)' N_active
  MatCN rows_{};           // constraint rows scaled to unit norm
  VecC bounds_{};          // their bounds, scaled alike
  VecC row_scale_{};       // 1 / original row norm (0 for ignored rows)
  VecC multipliers_{};     // output, original scaling
  bool enabled_[kNumConstraints] = {};
  bool is_active_[kNumConstraints] = {};
  int active_[N] = {};     // constraint index per active position
  double dual_[N] = {};    // multiplier per active position (unit-norm rows)
  int num_active_ = 0;
  int warm_set_[N] = {};
  int warm_count_ = 0;
  int iterations_ = 0;
  int max_iterations_ = 0;
  double tolerance_ = 0.0;
  bool hessian_regularised_ = false;
  bool trivially_infeasible_ = false;
};

// ---------------------------------------------------------------------------
// Implementation (a template: sizes are fixed per instantiation). The GRF
// size QpSolver<12, 24> is instantiated once, in qp_solver.cpp.

template <int N, int MI, int ME>
bool QpSolver<N, MI, ME>::factorHessian(const MatN& hessian) {
  // Cholesky by hand so that a failing pivot is seen, not papered over.
  double max_diag = 0.0;
  for (int i = 0; i < N; ++i) max_diag = std::fmax(max_diag, std::fabs(hessian(i, i)));
  const double pivot_floor = kRelativeZero * (max_diag > 0.0 ? max_diag : 1.0);
  MatN& l = cholesky_;
  l.setZero();
  for (int col = 0; col < N; ++col) {
    double pivot = hessian(col, col);
    for (int k = 0; k < col; ++k) pivot -= l(col, k) * l(col, k);
    if (!(pivot > pivot_floor)) return false;  // also catches NaN
    l(col, col) = std::sqrt(pivot);
    for (int row = col + 1; row < N; ++row) {
      double v = hessian(row, col);
      for (int k = 0; k < col; ++k) v -= l(row, k) * l(col, k);
      l(row, col) = v / l(col, col);
    }
  }
  return true;
}

template <int N, int MI, int ME>
void QpSolver<N, MI, ME>::loadConstraints(const Problem& problem, double tolerance) {
  double max_norm = 0.0;
  double norms[kNumConstraints];
  for (int c = 0; c < kNumConstraints; ++c) {
    // Element-wise: Eigen rejects row blocks of a zero-row matrix (ME = 0).
    for (int k = 0; k < N; ++k) {
      rows_(c, k) = c < ME ? problem.eq_matrix(c, k) : problem.ineq_matrix(c - ME, k);
    }
    bounds_[c] = c < ME ? problem.eq_bound[c] : problem.ineq_bound[c - ME];
    norms[c] = rows_.row(c).norm();
    max_norm = std::fmax(max_norm, norms[c]);
  }
  trivially_infeasible_ = false;
  for (int c = 0; c < kNumConstraints; ++c) {
    const double norm = norms[c];
    enabled_[c] = norm > kRelativeZero * max_norm && norm > 0.0;
    if (enabled_[c]) {
      row_scale_[c] = 1.0 / norm;
      rows_.row(c) *= row_scale_[c];
      bounds_[c] *= row_scale_[c];
      continue;
    }
    // A zero row reads 0 >= b (or 0 = b): true or false whatever x is.
    row_scale_[c] = 0.0;
    const bool holds = c < ME ? std::fabs(bounds_[c]) <= tolerance : bounds_[c] <= tolerance;
    if (!holds) trivially_infeasible_ = true;
  }
}

template <int N, int MI, int ME>
void QpSolver<N, MI, ME>::resetToUnconstrained(const VecN& gradient, VecN& x) {
  // J = L^-T, so that J J' = H^-1; x = -H^-1 g. J is upper triangular:
  // column i of L^-1 by forward substitution is row i of J.
  j_.setZero();
  for (int col = 0; col < N; ++col) {
    for (int row = col; row < N; ++row) {
      double v = row == col ? 1.0 : 0.0;
      for (int k = col; k < row; ++k) v -= cholesky_(row, k) * j_(col, k);
      j_(col, row) = v / cholesky_(row, row);
    }
  }
  r_.setZero();
  num_active_ = 0;
  for (int c = 0; c < kNumConstraints; ++c) is_active_[c] = false;
  x = -(j_ * (j_.transpose() * gradient));
}

template <int N, int MI, int ME>
bool QpSolver<N, MI, ME>::stepDirections(int c, VecN& d, VecN& z, VecN& r) const {
  const int q = num_active_;
  d = j_.transpose() * rows_.row(c).transpose();
  z.setZero();
  for (int k = q; k < N; ++k) z += d[k] * j_.col(k);
  r.setZero();
  for (int i = q - 1; i >= 0; --i) {
    double v = d[i];
    for (int k = i + 1; k < q; ++k) v -= r_(i, k) * r[k];
    r[i] = v / r_(i, i);
  }
  // z = 0 exactly when n_c lies in the span of the active rows.
  double null_part = 0.0;
  for (int k = q; k < N; ++k) null_part += d[k] * d[k];
  return std::sqrt(null_part) > kRelativeZero * 1e2 * d.norm();
}

template <int N, int MI, int ME>
bool QpSolver<N, MI, ME>::appendToFactor(VecN& d) {
  const int q = num_active_;
  if (q >= N) return false;
  // Rotate d(q+1..N-1) into d(q), carrying the same rotations into J's columns.
  for (int k = N - 1; k > q; --k) {
    const double h = std::sqrt(d[k - 1] * d[k - 1] + d[k] * d[k]);
    if (h == 0.0) continue;
    const double cs = d[k - 1] / h, sn = d[k] / h;
    d[k - 1] = h;
    d[k] = 0.0;
    for (int row = 0; row < N; ++row) {
      const double a = j_(row, k - 1), b = j_(row, k);
      j_(row, k - 1) = cs * a + sn * b;
      j_(row, k) = -sn * a + cs * b;
    }
  }
  if (!(std::fabs(d[q]) > kRelativeZero * 1e2 * d.norm())) return false;
  for (int i = 0; i <= q; ++i) r_(i, q) = d[i];
  num_active_ = q + 1;
  return true;
}

template <int N, int MI, int ME>
void QpSolver<N, MI, ME>::removeFromFactor(int position) {
  const int q = num_active_;
  is_active_[active_[position]] = false;
  for (int k = position; k < q - 1; ++k) {
    active_[k] = active_[k + 1];
    dual_[k] = dual_[k + 1];
    r_.col(k) = r_.col(k + 1);
  }
  r_.col(q - 1).setZero();
  // R is now upper Hessenberg from `position` on: rotate its subdiagonal away.
  for (int k = position; k < q - 1; ++k) {
    const double h = std::sqrt(r_(k, k) * r_(k, k) + r_(k + 1, k) * r_(k + 1, k));
    if (h == 0.0) continue;
    const double cs = r_(k, k) / h, sn = r_(k + 1, k) / h;
    for (int col = k; col < q - 1; ++col) {
      const double a = r_(k, col), b = r_(k + 1, col);
      r_(k, col) = cs * a + sn * b;
      r_(k + 1, col) = -sn * a + cs * b;
    }
    for (int row = 0; row < N; ++row) {
      const double a = j_(row, k), b = j_(row, k + 1);
      j_(row, k) = cs * a + sn * b;
      j_(row, k + 1) = -sn * a + cs * b;
    }
  }
  num_active_ = q - 1;
}

template <int N, int MI, int ME>
bool QpSolver<N, MI, ME>::forceActive(int c, VecN& x) {
  VecN d, z, r;
  if (!stepDirections(c, d, z, r)) return false;
  const double step = -violation(c, x) / z.dot(rows_.row(c).transpose());
  x += step * z;
  for (int k = 0; k < num_active_; ++k) dual_[k] -= step * r[k];
  const int q = num_active_;
  if (!appendToFactor(d)) return false;
  active_[q] = c;
  dual_[q] = step;
  is_active_[c] = true;
  return true;
}

template <int N, int MI, int ME>
bool QpSolver<N, MI, ME>::imposeWarmSet(const VecN& gradient, VecN& x) {
  // Impose the stored set as equalities; a negative multiplier means that
  // constraint does not belong to this problem's solution: drop it and redo.
  // Each pass removes at least one, so at most warm_count_ + 1 passes.
  for (int pass = 0; pass <= N; ++pass) {
    resetToUnconstrained(gradient, x);
    for (int e = 0; e < ME; ++e) {
      if (enabled_[e] && !forceActive(e, x) && std::fabs(violation(e, x)) > tolerance_) {
        return false;  // an inconsistent dependent equality
      }
    }
    int kept = 0;
    for (int k = 0; k < warm_count_; ++k) {
      const int c = warm_set_[k];
      if (!enabled_[c] || iterations_ >= max_iterations_) continue;
      if (forceActive(c, x)) {
        warm_set_[kept++] = c;
        ++iterations_;
      }
    }
    warm_count_ = kept;
    double max_dual = 0.0;
    for (int k = 0; k < num_active_; ++k) max_dual = std::fmax(max_dual, std::fabs(dual_[k]));
    int dropped = 0;
    kept = 0;
    for (int k = 0; k < num_active_; ++k) {
      const int c = active_[k];
      if (c < ME) continue;
      if (dual_[k] < -kRelativeZero * (1.0 + max_dual)) {
        ++dropped;
      } else {
        warm_set_[kept++] = c;
      }
    }
    if (dropped == 0) return true;
    warm_count_ = kept;
  }
  return true;
}

template <int N, int MI, int ME>
QpStatus QpSolver<N, MI, ME>::solve(const Problem& problem, const QpSettings& settings,
                                    bool warm_start, VecN& x) {
  iterations_ = 0;
  max_iterations_ = settings.max_iterations;
  tolerance_ = settings.feasibility_tolerance;
  hessian_regularised_ = false;
  num_active_ = 0;
  multipliers_.setZero();
  for (int c = 0; c < kNumConstraints; ++c) is_active_[c] = false;
  x.setZero();

  const bool finite = problem.hessian.allFinite() && problem.gradient.allFinite() &&
                      problem.ineq_matrix.allFinite() && problem.ineq_bound.allFinite() &&
                      problem.eq_matrix.allFinite() && problem.eq_bound.allFinite() &&
                      std::isfinite(tolerance_);
  if (!finite) {
    warm_count_ = 0;
    return QpStatus::kInvalidInput;
  }

  // H symmetrised; if not numerically positive definite, shifted by
  // 1e-12, 1e-9, ... of its scale until it is (16 tries reach 1e33: always).
  MatN hessian = 0.5 * (problem.hessian + problem.hessian.transpose());
  const double scale = std::fmax(hessian.cwiseAbs().maxCoeff(), 1.0);
  double shift = kRelativeZero * scale;
  for (int attempt = 0; attempt < 16 && !factorHessian(hessian); ++attempt) {
    hessian.diagonal().array() += shift;
    shift *= 1e3;
    hessian_regularised_ = true;
  }

  // An unsatisfiable zero row is reported at the end; the rest is still solved.
  loadConstraints(problem, tolerance_);
  bool infeasible = false;
  if (!(warm_start && warm_count_ > 0)) warm_count_ = 0;
  if (!imposeWarmSet(problem.gradient, x)) infeasible = true;

  VecN d, z, r;
  bool hit_bound = false;
  while (!infeasible) {
    // Most violated inactive inequality (violation measured on unit rows).
    int p = -1;
    double worst = 0.0;
    for (int c = ME; c < kNumConstraints; ++c) {
      if (!enabled_[c] || is_active_[c]) continue;
      const double s = violation(c, x);
      if (s < -tolerance_ * (1.0 + std::fabs(bounds_[c])) && s < worst) {
        worst = s;
        p = c;
      }
    }
    if (p < 0) break;

    // Move from the current (dual feasible) point towards satisfying p,
    // dropping active inequalities whose multipliers would turn negative.
    double dual_p = 0.0;
    bool added = false;
    while (!added && !infeasible) {
      if (iterations_ >= max_iterations_) {
        hit_bound = true;
        break;
      }
      const bool primal_step = stepDirections(p, d, z, r);
      double dual_limit = std::numeric_limits<double>::infinity();
      int block = -1;
      for (int k = 0; k < num_active_; ++k) {
        if (active_[k] < ME || !(r[k] > 0.0)) continue;
        const double ratio = dual_[k] / r[k];
        if (ratio < dual_limit) {
          dual_limit = ratio;
          block = k;
        }
      }
      const double full_step =
          primal_step ? -violation(p, x) / z.dot(rows_.row(p).transpose())
                      : std::numeric_limits<double>::infinity();
      const double step = std::fmin(dual_limit, full_step);
      if (!std::isfinite(step)) {
        infeasible = true;  // p conflicts with the equalities / accepted set
        break;
      }
      if (primal_step) x += step * z;
      for (int k = 0; k < num_active_; ++k) dual_[k] -= step * r[k];
      dual_p += step;
      ++iterations_;
      if (primal_step && full_step <= dual_limit) {
        const int q = num_active_;
        if (!appendToFactor(d)) {
          infeasible = true;
          break;
        }
        active_[q] = p;
        dual_[q] = dual_p;
        is_active_[p] = true;
        added = true;
      } else {
        dual_[block] = 0.0;
        removeFromFactor(block);
      }
    }
    if (hit_bound) break;
  }

  for (int k = 0; k < num_active_; ++k) {
    multipliers_[active_[k]] = dual_[k] * row_scale_[active_[k]];
  }
  if (!x.allFinite() || !multipliers_.allFinite()) {
    x.setZero();
    multipliers_.setZero();
    warm_count_ = 0;
    return QpStatus::kNumericalFailure;
  }
  if (infeasible) return QpStatus::kInfeasible;  // keep the previous warm set
  warm_count_ = 0;
  for (int k = 0; k < num_active_; ++k) {
    if (active_[k] >= ME) warm_set_[warm_count_++] = active_[k];
  }
  if (trivially_infeasible_) return QpStatus::kInfeasible;
  return hit_bound ? QpStatus::kMaxIterations : QpStatus::kOptimal;
}

}  // namespace hyq
