// A dense, strictly convex QP solver of fixed size, with no heap:
//
//   minimise 0.5 x'Hx + g'x   subject to   A_eq x = b_eq,   A_in x >= b_in,
//
// x in R^N, ME equalities, MI inequalities (compile-time sizes).
//
// Method: the dual active-set method of Goldfarb and Idnani (1983). It starts
// from the unconstrained minimum and adds the most violated constraint at a
// time, keeping the multipliers non-negative. Factors (H = L L', N_A the
// active rows as columns): U = H^-1 N_A, column by column, and the upper
// triangular R with R'R = N_A' H^-1 N_A, extended by a column per addition
// and re-triangularised by Givens rotations after a removal. The primal step
// direction is z = H^-1 n - U R^-1 R^-T N_A' H^-1 n, the dual one
// r = R^-1 R^-T N_A' H^-1 n. An iteration costs two triangular solves with L
// (O(N^2)), O(q N) for z and an O(MI) scan for the most violated constraint. Why this method: it
// needs no feasible starting point, detects infeasibility by itself, and its
// iterates are always minimisers over a subset of the constraints, which is a
// meaningful bounded answer when the iteration bound cuts it short.
//
// Cost: the unconstrained minimum takes the Cholesky factor L and two
// triangular solves (N^3/6 + N^2 multiply-adds). L is stored in both
// triangles (L and L'), so that every inner product of the factorisation and
// the solves runs over contiguous memory. Constraint rows are kept with the
// range of columns they may touch: the scans and the products with a row
// cost its width, not N. Rows three columns wide (a foot's forces) are kept
// compact only and take unrolled products; in a block layout of such rows
// the most-violated scan reads each block's three x entries once and skips
// blocks whose rows are all ignored (a swing foot's). Up to N = 12 the
// factorisation and the triangular solves run straight-line (every index a
// compile-time constant, the solution's entries in registers; the forward
// solve compiled once per block start, and for a narrow row reading its
// three entries alone), as are the step directions' two solves with R
// (compiled once per active count, 0 to N), in the plain loops' summation
// order: the same results, at two to three instructions a multiply-add on
// the Cortex-M7 instead of about six. In a block layout of narrow rows the
// rows are loaded and scaled block by block (loadNarrowBlocks).
//
// Why templated sizes: the GRF problem is QpSolver<12, 24> (3 forces per foot;
// 4 pyramid faces + min/max normal force per foot), while the unit tests run
// the same code on small sizes where every active set can be enumerated.
//
// Two entry points:
//  - solve(): any input. Checks every number, symmetrises H, optional warm
//    start (below).
//  - solveStructured(): for a caller that builds the problem itself (GrfQp)
//    and guarantees that H is exactly symmetric (only its lower triangle is
//    read), that the constraint matrices and bounds are finite, and that
//    inequality i has nonzeros only in the columns of its block
//    (QpBlockLayout: block i / rows, columns [cols * block, cols * block +
//    cols)); entries outside the blocks are not read. Non-finite H or g is
//    still detected (kInvalidInput). Always a cold start. Same method and
//    answer as solve() otherwise.
//
// Robustness (never NaN/Inf out):
//  - non-finite input: status kInvalidInput, x = 0;
//  - H not numerically positive definite: symmetrised, then shifted by a
//    growing multiple of the identity until its Cholesky factor exists
//    (hessianRegularised() says so);
//  - constraint rows are scaled to unit norm; a row of (near) zero norm is
//    ignored when it is satisfied (0 >= b, b <= tolerance) and makes the
//    problem infeasible otherwise;
//  - linearly dependent constraints are detected and never added (a row
//    whose part outside the active rows' span, in the H^-1 metric, is below
//    kDependent of its length);
//  - infeasible: status kInfeasible, x = minimiser of the cost subject to the
//    equalities and the inequalities accepted before the conflict (bounded,
//    satisfies those, may violate the rest);
//  - iteration bound hit: status kMaxIterations, x = the current iterate
//    (bounded, satisfies the constraints active so far, may violate others);
//  - a non-finite result (overflow): status kNumericalFailure, x = 0.
//
// Iteration bound: iterations count active-set changes (constraint additions
// and removals, warm-start additions included) and are bounded by
// max_iterations; each costs O(N^2), so the bound is the worst case's cost.
// QpParams::max_iterations explains the GRF problem's value.
//
// Warm start (solve() only): the inequality active set of the last successful
// solve is kept in the object. With warm_start = true it is imposed first
// (constraints whose multipliers come out negative are dropped again), then
// the method continues as usual; the answer is the same optimum.
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

// Block layout solveStructured() relies on: inequality i touches only the
// columns [cols * (i / rows), cols * (i / rows) + cols).
struct QpBlockLayout {
  int rows;  // [-] inequalities per block
  int cols;  // [-] variables per block
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

namespace qp_detail {

// Largest N whose triangular solves run straight-line (every index a
// constant, the solution's entries held in registers): the board's FPU has
// 16 double registers.
constexpr int kUnrolledMaxSize = 12;

// L y = b for rows F..N-1, y[i] = 0 for i < F. b's entries of rows F to
// F + Count - 1 are read from b[0], b[1], ...; the rest are zero and not
// read (Count = 3: a narrow row). lt: L stored column-major with L(i, k)
// also at lt[i N + k] (the factor kept in both triangles), so that row i's
// entries are contiguous. The summation order is the plain loop's (k
// ascending), whatever Count.
template <int N, int F, int Count>
__attribute__((always_inline)) inline void forwardSubstitute(const double* lt, const double* b,
                                                             double* y) {
  double t[N];
#pragma GCC unroll 16
  for (int i = 0; i < F; ++i) t[i] = 0.0;
#pragma GCC unroll 16
  for (int i = F; i < N; ++i) {
    double v = i < F + Count ? b[i - F] : 0.0;
#pragma GCC unroll 16
    for (int k = F; k < i; ++k) v -= lt[i * N + k] * t[k];
    t[i] = v / lt[i * N + i];
  }
#pragma GCC unroll 16
  for (int i = 0; i < N; ++i) y[i] = t[i];
}

// The same with the first row chosen at run time: straight-line for a
// multiple of Step (one copy of the code per such start); false, y
// untouched, for any other. Count = 0: b holds all N entries (b[i] for row
// i, from `first` on); otherwise b holds the Count entries from `first`.
template <int N, int Step, int Count, int F = 0>
inline bool forwardSubstituteFrom(int first, const double* lt, const double* b, double* y) {
  if (first == F) {
    if constexpr (Count == 0) {
      forwardSubstitute<N, F, N - F>(lt, b + F, y);
    } else {
      forwardSubstitute<N, F, Count>(lt, b, y);
    }
    return true;
  }
  if constexpr (F + Step < N) return forwardSubstituteFrom<N, Step, Count, F + Step>(first, lt, b, y);
  return false;
}

// L' u = y (lt as above: L(k, i) for k > i at lt[i N + k]).
template <int N>
inline void backSubstitute(const double* lt, const double* y, double* u) {
  double t[N];
#pragma GCC unroll 16
  for (int i = N - 1; i >= 0; --i) {
    double v = y[i];
#pragma GCC unroll 16
    for (int k = i + 1; k < N; ++k) v -= lt[i * N + k] * t[k];
    t[i] = v / lt[i * N + i];
  }
#pragma GCC unroll 16
  for (int i = 0; i < N; ++i) u[i] = t[i];
}

}  // namespace qp_detail

template <int N, int MI, int ME = 0>
class QpSolver {
 public:
  static constexpr int kNumConstraints = ME + MI;  // equalities first, then inequalities
  using VecN = Eigen::Matrix<double, N, 1>;
  using MatN = Eigen::Matrix<double, N, N>;
  using Problem = QpProblem<N, MI, ME>;

  // Solves the problem; x always receives finite values.
  QpStatus solve(const Problem& problem, const QpSettings& settings, bool warm_start, VecN& x);
  // The same for a problem with the guarantees listed at the top of this
  // file (a layout that does not fit the sizes falls back to solve(), cold).
  QpStatus solveStructured(const Problem& problem, const QpSettings& settings,
                           const QpBlockLayout& layout, VecN& x);

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
  // Dependency test on ||z||_H / ||n||_H^-1 = sqrt(n'z / n'H^-1 n): n'z is
  // a difference with round-off of 1e-16 n'H^-1 n, so the test sits well
  // above that (1e-6 on the norms, 1e-12 on their squares).
  static constexpr double kDependent = 1e-6;
  // Rows of this width (a foot's three forces in the GRF layout) take an
  // unrolled path in rowDot() and mostViolated(): the summation order is
  // the loop's, so the results are the same.
  static constexpr int kNarrowWidth = 3;

  void begin(const QpSettings& settings, VecN& x);
  // Cholesky factor of H (lower triangle read); false if a pivot fails.
  bool factorHessian(const MatN& hessian);
  // Symmetrised H shifted until it factors (hessianRegularised()).
  void factorShifted(const MatN& hessian);
  // layout == nullptr: every row spans all columns.
  void loadConstraints(const Problem& problem, double tolerance, const QpBlockLayout* layout);
  // The same for inequalities only (ME = 0), every one a narrow row of a
  // block layout of `rows` rows a block: the same numbers, in fewer
  // instructions.
  void loadNarrowBlocks(const Problem& problem, double tolerance, int rows);
  // Scaling of row c to unit norm (norm > zero_norm: enabled) or its
  // ignoring; returns whether it is enabled.
  __attribute__((always_inline)) bool scaleRow(int c, double norm, double zero_norm, double tolerance);
  QpStatus finish(const Problem& problem, bool warm_start, VecN& x);
  void resetToUnconstrained(const VecN& gradient, VecN& x);
  void solveHessian(int c, VecN& u) const;  // u = H^-1 n_c (n_c: row c, unit norm)
  void solveUpper(const VecN& y, VecN& u) const;  // L' u = y
  double rowDot(int c, const VecN& v) const {
    const int b = col_begin_[c];
    if (col_end_[c] - b == kNarrowWidth) {
      const double* a = &narrow_(0, c);
      return a[0] * v[b] + a[1] * v[b + 1] + a[2] * v[b + 2];
    }
    double s = 0.0;
    for (int k = b; k < col_end_[c]; ++k) s += rows_(c, k) * v[k];
    return s;
  }
  // From u = H^-1 n_c: w = R^-T N_A' u, r = R^-1 w (dual direction), z
  // (primal direction), nz = n_c'z; false if z is zero (n_c dependent).
  bool stepDirections(int c, const VecN& u, VecN& w, VecN& z, VecN& r, double& nz) const;
  // Its w and r for Q active constraints, straight-line (a copy of the code
  // per count, chosen by triangularSolvesFor), in the loops' order.
  template <int Q>
  void triangularSolves(const VecN& u, VecN& w, VecN& r) const;
  template <int Q = 0>
  void triangularSolvesFor(int q, const VecN& u, VecN& w, VecN& r) const {
    if (q == Q) {
      triangularSolves<Q>(u, w, r);
      return;
    }
    if constexpr (Q < N) triangularSolvesFor<Q + 1>(q, u, w, r);
  }
  bool appendToFactor(const VecN& u, const VecN& w, double nz);  // U and R gain a column
  void removeFromFactor(int position);
  // Adds constraint c with a full step regardless of the multipliers' signs
  // (for equalities and the warm-start set). Returns false if dependent.
  bool forceActive(int c, VecN& x);
  bool imposeWarmSet(const VecN& gradient, VecN& x);
  double violation(int c, const VecN& x) const { return rowDot(c, x) - bounds_[c]; }
  void setActive(int c, bool active) {
    scan_below_[c] = active ? -std::numeric_limits<double>::infinity() : violated_below_[c];
  }
  // The inactive inequality of largest violation beyond its tolerance
  // (measured on unit rows), -1 if none.
  int mostViolated(const VecN& x) const;

  MatN cholesky_{};        // L (H = L L') in the lower triangle, L' in the upper
  MatN u_{};               // U: column k = H^-1 n of the constraint at active position k
  MatN r_{};               // R (upper triangular q x q block): R'R = N_A' H^-1 N_A
  MatCN rows_{};           // constraint rows scaled to unit norm (read in their column range only)
  // Rows of width kNarrowWidth once more, compact: column c holds row c's
  // coefficients of columns col_begin_[c] + 0, 1, 2 (contiguous for rowDot).
  Eigen::Matrix<double, kNarrowWidth, kNumConstraints> narrow_{};
  int col_begin_[kNumConstraints] = {};  // row c may be nonzero in columns [begin, end)
  int col_end_[kNumConstraints] = {};
  VecC bounds_{};          // their bounds, scaled alike
  // Row c counts as violated when its violation is below this: -tolerance
  // (1 + |bound|), -infinity for ignored rows (never violated).
  VecC violated_below_{};
  // What mostViolated() compares with: violated_below_ for an inactive row,
  // -infinity for an active one (never violated).
  VecC scan_below_{};
  VecC row_scale_{};       // 1 / original row norm (0 for ignored rows)
  VecC multipliers_{};     // output, original scaling
  bool enabled_[kNumConstraints] = {};
  // Per block of a narrow block layout (block k: inequalities from ME + k *
  // narrow_block_rows_): false when all its rows are ignored.
  bool block_live_[kNumConstraints] = {};
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
  // Inequalities per block when every inequality is a narrow row of a block
  // layout (solveStructured() with layout.cols == kNarrowWidth), else 0.
  int narrow_block_rows_ = 0;
};

// ---------------------------------------------------------------------------
// Implementation (a template: sizes are fixed per instantiation). The GRF
// size QpSolver<12, 24> is instantiated once, in qp_solver.cpp.

template <int N, int MI, int ME>
void QpSolver<N, MI, ME>::begin(const QpSettings& settings, VecN& x) {
  iterations_ = 0;
  max_iterations_ = settings.max_iterations;
  tolerance_ = settings.feasibility_tolerance;
  hessian_regularised_ = false;
  num_active_ = 0;
  multipliers_.setZero();
  x.setZero();
}

template <int N, int MI, int ME>
bool QpSolver<N, MI, ME>::factorHessian(const MatN& hessian) {
  // Cholesky by hand so that a failing pivot is seen, not papered over. L is
  // written to both triangles (lt(k, i) = L(i, k)): the row products read
  // L's rows as contiguous columns of the upper triangle.
  double max_diag = 0.0;
  for (int i = 0; i < N; ++i) max_diag = std::fmax(max_diag, std::fabs(hessian(i, i)));
  const double pivot_floor = kRelativeZero * (max_diag > 0.0 ? max_diag : 1.0);
  MatN& lt = cholesky_;
  if constexpr (N <= qp_detail::kUnrolledMaxSize) {
    // Straight-line: every index a constant, row col of L held in registers
    // while the column below its pivot is computed.
    const double* h = hessian.data();
    double* l = lt.data();
#pragma GCC unroll 16
    for (int col = 0; col < N; ++col) {
      double pivot = h[col * N + col];
#pragma GCC unroll 16
      for (int k = 0; k < col; ++k) pivot -= l[col * N + k] * l[col * N + k];
      if (!(pivot > pivot_floor)) return false;  // also catches NaN
      const double diag = std::sqrt(pivot);
      l[col * N + col] = diag;
#pragma GCC unroll 16
      for (int row = col + 1; row < N; ++row) {
        double v = h[col * N + row];
#pragma GCC unroll 16
        for (int k = 0; k < col; ++k) v -= l[row * N + k] * l[col * N + k];
        v /= diag;
        l[row * N + col] = v;
        l[col * N + row] = v;
      }
    }
    return true;
  }
  for (int col = 0; col < N; ++col) {
    double pivot = hessian(col, col);
    for (int k = 0; k < col; ++k) pivot -= lt(k, col) * lt(k, col);
    if (!(pivot > pivot_floor)) return false;  // also catches NaN
    lt(col, col) = std::sqrt(pivot);
    for (int row = col + 1; row < N; ++row) {
      double v = hessian(row, col);
      for (int k = 0; k < col; ++k) v -= lt(k, row) * lt(k, col);
      lt(col, row) = v / lt(col, col);
      lt(row, col) = lt(col, row);
    }
  }
  return true;
}

template <int N, int MI, int ME>
void QpSolver<N, MI, ME>::factorShifted(const MatN& hessian_in) {
  // H symmetrised; if not numerically positive definite, shifted by
  // 1e-12, 1e-9, ... of its scale until it is (16 tries reach 1e33: always).
  MatN hessian = 0.5 * (hessian_in + hessian_in.transpose());
  const double scale = std::fmax(hessian.cwiseAbs().maxCoeff(), 1.0);
  double shift = kRelativeZero * scale;
  for (int attempt = 0; attempt < 16 && !factorHessian(hessian); ++attempt) {
    hessian.diagonal().array() += shift;
    shift *= 1e3;
    hessian_regularised_ = true;
  }
}

template <int N, int MI, int ME>
void QpSolver<N, MI, ME>::loadConstraints(const Problem& problem, double tolerance,
                                          const QpBlockLayout* layout) {
  narrow_block_rows_ = layout != nullptr && layout->cols == kNarrowWidth ? layout->rows : 0;
  double max_norm = 0.0;
  double norms[kNumConstraints];
  // Inequality c's block and its place in it, counted along the rows.
  int block = 0, in_block = 0;
  for (int c = 0; c < kNumConstraints; ++c) {
    int begin = 0, end = N;
    if (layout != nullptr && c >= ME) {
      begin = layout->cols * block;
      end = begin + layout->cols;
      if (++in_block == layout->rows) {
        in_block = 0;
        ++block;
      }
    }
    col_begin_[c] = begin;
    col_end_[c] = end;
    // Element-wise: Eigen rejects row blocks of a zero-row matrix (ME = 0).
    double sum = 0.0;
    if (end - begin == kNarrowWidth) {
      // Kept compact only: rowDot() and solveHessian() read narrow rows there.
      double* a = &narrow_(0, c);
      if (c < ME) {
        a[0] = problem.eq_matrix(c, begin);
        a[1] = problem.eq_matrix(c, begin + 1);
        a[2] = problem.eq_matrix(c, begin + 2);
      } else {
        a[0] = problem.ineq_matrix(c - ME, begin);
        a[1] = problem.ineq_matrix(c - ME, begin + 1);
        a[2] = problem.ineq_matrix(c - ME, begin + 2);
      }
      sum = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
    } else {
      for (int k = begin; k < end; ++k) {
        const double v = c < ME ? problem.eq_matrix(c, k) : problem.ineq_matrix(c - ME, k);
        rows_(c, k) = v;
        sum += v * v;
      }
    }
    bounds_[c] = c < ME ? problem.eq_bound[c] : problem.ineq_bound[c - ME];
    norms[c] = std::sqrt(sum);
    max_norm = std::fmax(max_norm, norms[c]);
  }
  trivially_infeasible_ = false;
  const double zero_norm = kRelativeZero * max_norm;
  // A block whose rows are all ignored (a swing foot's) is never violated.
  bool live = false;
  block = 0;
  in_block = 0;
  for (int c = 0; c < kNumConstraints; ++c) {
    const bool enabled = scaleRow(c, norms[c], zero_norm, tolerance);
    if (narrow_block_rows_ > 0 && c >= ME) {
      live = live || enabled;
      if (++in_block == narrow_block_rows_ || c + 1 == kNumConstraints) {
        block_live_[block++] = live;
        live = false;
        in_block = 0;
      }
    }
  }
}

template <int N, int MI, int ME>
inline bool QpSolver<N, MI, ME>::scaleRow(int c, double norm, double zero_norm, double tolerance) {
  const bool enabled = norm > zero_norm && norm > 0.0;
  enabled_[c] = enabled;
  if (enabled) {
    const double scale = 1.0 / norm;
    row_scale_[c] = scale;
    if (col_end_[c] - col_begin_[c] == kNarrowWidth) {
      double* a = &narrow_(0, c);
      a[0] *= scale;
      a[1] *= scale;
      a[2] *= scale;
    } else {
      for (int k = col_begin_[c]; k < col_end_[c]; ++k) rows_(c, k) *= scale;
    }
    const double bound = bounds_[c] * scale;
    bounds_[c] = bound;
    violated_below_[c] = -tolerance * (1.0 + std::fabs(bound));
    scan_below_[c] = violated_below_[c];
    return true;
  }
  // A zero row reads 0 >= b (or 0 = b): true or false whatever x is.
  row_scale_[c] = 0.0;
  violated_below_[c] = -std::numeric_limits<double>::infinity();
  scan_below_[c] = violated_below_[c];
  narrow_.col(c).setZero();
  const bool holds = c < ME ? std::fabs(bounds_[c]) <= tolerance : bounds_[c] <= tolerance;
  if (!holds) trivially_infeasible_ = true;
  return false;
}

template <int N, int MI, int ME>
void QpSolver<N, MI, ME>::loadNarrowBlocks(const Problem& problem, double tolerance, int rows) {
  narrow_block_rows_ = rows;
  double max_norm = 0.0;
  double norms[kNumConstraints];
  // The matrix is column-major: a block's three columns, row c of each.
  const double* m = problem.ineq_matrix.data();
  for (int first = 0, begin = 0; first < MI; first += rows, begin += kNarrowWidth) {
    const double* col = m + MI * begin;
    const int last = first + rows < MI ? first + rows : MI;
    for (int c = first; c < last; ++c) {
      col_begin_[c] = begin;
      col_end_[c] = begin + kNarrowWidth;
      const double a0 = col[c], a1 = col[MI + c], a2 = col[2 * MI + c];
      double* a = &narrow_(0, c);
      a[0] = a0;
      a[1] = a1;
      a[2] = a2;
      bounds_[c] = problem.ineq_bound[c];
      norms[c] = std::sqrt(a0 * a0 + a1 * a1 + a2 * a2);
      max_norm = std::fmax(max_norm, norms[c]);
    }
  }
  trivially_infeasible_ = false;
  const double zero_norm = kRelativeZero * max_norm;
  // A block whose rows are all ignored (a swing foot's) is never violated.
  for (int first = 0, block = 0; first < MI; first += rows, ++block) {
    const int last = first + rows < MI ? first + rows : MI;
    bool live = false;
    for (int c = first; c < last; ++c) live = scaleRow(c, norms[c], zero_norm, tolerance) || live;
    block_live_[block] = live;
  }
}

template <int N, int MI, int ME>
void QpSolver<N, MI, ME>::resetToUnconstrained(const VecN& gradient, VecN& x) {
  // x = -H^-1 g by two triangular solves with L; J waits for a constraint.
  VecN y;
  bool solved = false;
  if constexpr (N <= qp_detail::kUnrolledMaxSize) {
    solved = qp_detail::forwardSubstituteFrom<N, kNarrowWidth, 0>(0, cholesky_.data(), gradient.data(), y.data());
  }
  for (int i = 0; i < N && !solved; ++i) {
    double v = gradient[i];
    for (int k = 0; k < i; ++k) v -= cholesky_(k, i) * y[k];
    y[i] = v / cholesky_(i, i);
  }
  solveUpper(y, x);
  x = -x;
  num_active_ = 0;
  scan_below_ = violated_below_;
}

template <int N, int MI, int ME>
void QpSolver<N, MI, ME>::solveUpper(const VecN& y, VecN& u) const {
  if constexpr (N <= qp_detail::kUnrolledMaxSize) {
    qp_detail::backSubstitute<N>(cholesky_.data(), y.data(), u.data());
    return;
  }
  for (int i = N - 1; i >= 0; --i) {
    double v = y[i];
    for (int k = i + 1; k < N; ++k) v -= cholesky_(k, i) * u[k];
    u[i] = v / cholesky_(i, i);
  }
}

template <int N, int MI, int ME>
void QpSolver<N, MI, ME>::solveHessian(int c, VecN& u) const {
  // L y = n_c: y is zero before the row's first column.
  VecN y;
  const int first = col_begin_[c];
  const int end = col_end_[c];
  const bool narrow = end - first == kNarrowWidth;
  if constexpr (N <= qp_detail::kUnrolledMaxSize) {
    // A narrow row's three entries straight from its compact copy.
    if (narrow && first + kNarrowWidth <= N &&
        qp_detail::forwardSubstituteFrom<N, kNarrowWidth, kNarrowWidth>(first, cholesky_.data(),
                                                                        &narrow_(0, c), y.data())) {
      solveUpper(y, u);
      return;
    }
  }
  double n[N];
  for (int i = first; i < N; ++i) n[i] = i < end ? (narrow ? narrow_(i - first, c) : rows_(c, i)) : 0.0;
  bool solved = false;
  if constexpr (N <= qp_detail::kUnrolledMaxSize) {
    solved = qp_detail::forwardSubstituteFrom<N, kNarrowWidth, 0>(first, cholesky_.data(), n, y.data());
  }
  if (!solved) {
    for (int i = 0; i < first; ++i) y[i] = 0.0;
    for (int i = first; i < N; ++i) {
      double v = n[i];
      for (int k = first; k < i; ++k) v -= cholesky_(k, i) * y[k];
      y[i] = v / cholesky_(i, i);
    }
  }
  solveUpper(y, u);
}

template <int N, int MI, int ME>
int QpSolver<N, MI, ME>::mostViolated(const VecN& x) const {
  int p = -1;
  double worst = 0.0;
  if (narrow_block_rows_ > 0) {
    // Block layout of narrow rows: each block's three x entries are read once.
    for (int first = ME, block = 0; first < kNumConstraints; first += narrow_block_rows_, ++block) {
      if (!block_live_[block]) continue;
      const int b = col_begin_[first];
      const double x0 = x[b], x1 = x[b + 1], x2 = x[b + 2];
      const int last = first + narrow_block_rows_ < kNumConstraints ? first + narrow_block_rows_
                                                                    : kNumConstraints;
      for (int c = first; c < last; ++c) {
        const double s = narrow_(0, c) * x0 + narrow_(1, c) * x1 + narrow_(2, c) * x2 - bounds_[c];
        if (s < scan_below_[c] && s < worst) {
          worst = s;
          p = c;
        }
      }
    }
    return p;
  }
  for (int c = ME; c < kNumConstraints; ++c) {
    const double s = violation(c, x);
    if (s < scan_below_[c] && s < worst) {
      worst = s;
      p = c;
    }
  }
  return p;
}

template <int N, int MI, int ME>
bool QpSolver<N, MI, ME>::stepDirections(int c, const VecN& u, VecN& w, VecN& z, VecN& r,
                                         double& nz) const {
  const int q = num_active_;
  // w = R^-T N_A' u (forward), r = R^-1 w (backward).
  if constexpr (N <= qp_detail::kUnrolledMaxSize) {
    triangularSolvesFor(q, u, w, r);
  } else {
    for (int i = 0; i < q; ++i) {
      double v = rowDot(active_[i], u);
      for (int k = 0; k < i; ++k) v -= r_(k, i) * w[k];
      w[i] = v / r_(i, i);
    }
    for (int i = q - 1; i >= 0; --i) {
      double v = w[i];
      for (int k = i + 1; k < q; ++k) v -= r_(i, k) * r[k];
      r[i] = v / r_(i, i);
    }
  }
  // z = u - U r, entry by entry in registers (k ascending, as z -= r_k U_k).
  double t[N];
#pragma GCC unroll 16
  for (int j = 0; j < N; ++j) t[j] = u[j];
  for (int k = 0; k < q; ++k) {
    const double r_k = r[k];
    const double* u_k = &u_(0, k);
#pragma GCC unroll 16
    for (int j = 0; j < N; ++j) t[j] -= r_k * u_k[j];
  }
#pragma GCC unroll 16
  for (int j = 0; j < N; ++j) z[j] = t[j];
  // n'z = n'H^-1 n - |w|^2 >= 0: the part of n outside the active span.
  nz = std::fmax(rowDot(c, z), 0.0);
  const double nu = rowDot(c, u);
  return nz > kDependent * kDependent * nu;
}

template <int N, int MI, int ME>
template <int Q>
void QpSolver<N, MI, ME>::triangularSolves(const VecN& u, VecN& w, VecN& r) const {
  double wv[Q + 1], rv[Q + 1];
  for (int i = 0; i < Q; ++i) wv[i] = rowDot(active_[i], u);
#pragma GCC unroll 16
  for (int i = 0; i < Q; ++i) {
    double v = wv[i];
#pragma GCC unroll 16
    for (int k = 0; k < i; ++k) v -= r_(k, i) * wv[k];
    wv[i] = v / r_(i, i);
  }
#pragma GCC unroll 16
  for (int i = Q - 1; i >= 0; --i) {
    double v = wv[i];
#pragma GCC unroll 16
    for (int k = i + 1; k < Q; ++k) v -= r_(i, k) * rv[k];
    rv[i] = v / r_(i, i);
  }
#pragma GCC unroll 16
  for (int i = 0; i < Q; ++i) {
    w[i] = wv[i];
    r[i] = rv[i];
  }
}

template <int N, int MI, int ME>
bool QpSolver<N, MI, ME>::appendToFactor(const VecN& u, const VecN& w, double nz) {
  const int q = num_active_;
  if (q >= N || !(nz > 0.0)) return false;
  // Only R's upper triangle is read: the rows below the new diagonal stay as they are.
  for (int i = 0; i < q; ++i) r_(i, q) = w[i];
  r_(q, q) = std::sqrt(nz);
  u_.col(q) = u;
  num_active_ = q + 1;
  return true;
}

template <int N, int MI, int ME>
void QpSolver<N, MI, ME>::removeFromFactor(int position) {
  const int q = num_active_;
  setActive(active_[position], false);
  for (int k = position; k < q - 1; ++k) {
    active_[k] = active_[k + 1];
    dual_[k] = dual_[k + 1];
    r_.col(k) = r_.col(k + 1);
    u_.col(k) = u_.col(k + 1);
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
    r_(k + 1, k) = 0.0;
  }
  num_active_ = q - 1;
}

template <int N, int MI, int ME>
bool QpSolver<N, MI, ME>::forceActive(int c, VecN& x) {
  VecN u, w, z, r;
  double nz = 0.0;
  solveHessian(c, u);
  if (!stepDirections(c, u, w, z, r, nz)) return false;
  const double step = -violation(c, x) / nz;
  x += step * z;
  for (int k = 0; k < num_active_; ++k) dual_[k] -= step * r[k];
  const int q = num_active_;
  if (!appendToFactor(u, w, nz)) return false;
  active_[q] = c;
  dual_[q] = step;
  setActive(c, true);
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
  begin(settings, x);
  const bool finite = problem.hessian.allFinite() && problem.gradient.allFinite() &&
                      problem.ineq_matrix.allFinite() && problem.ineq_bound.allFinite() &&
                      problem.eq_matrix.allFinite() && problem.eq_bound.allFinite() &&
                      std::isfinite(tolerance_);
  if (!finite) {
    warm_count_ = 0;
    return QpStatus::kInvalidInput;
  }
  factorShifted(problem.hessian);
  loadConstraints(problem, tolerance_, nullptr);
  return finish(problem, warm_start, x);
}

template <int N, int MI, int ME>
QpStatus QpSolver<N, MI, ME>::solveStructured(const Problem& problem, const QpSettings& settings,
                                              const QpBlockLayout& layout, VecN& x) {
  const bool fits = layout.rows > 0 && layout.cols > 0 &&
                    layout.cols * ((MI + layout.rows - 1) / layout.rows) <= N;
  if (!fits) return solve(problem, settings, false, x);
  begin(settings, x);
  warm_count_ = 0;
  // H is exactly symmetric: its lower triangle is H. A failing pivot is a
  // non-finite or indefinite H: the former is refused, the latter shifted.
  if (!factorHessian(problem.hessian)) {
    if (!problem.hessian.allFinite()) return QpStatus::kInvalidInput;
    factorShifted(problem.hessian);
  }
  if (!std::isfinite(tolerance_)) return QpStatus::kInvalidInput;
  bool loaded = false;
  if constexpr (ME == 0) {
    if (layout.cols == kNarrowWidth) {
      loadNarrowBlocks(problem, tolerance_, layout.rows);
      loaded = true;
    }
  }
  if (!loaded) loadConstraints(problem, tolerance_, &layout);
  const QpStatus status = finish(problem, false, x);
  // A non-finite g passes the factorisation and makes x non-finite.
  if (status == QpStatus::kNumericalFailure && !problem.gradient.allFinite())
    return QpStatus::kInvalidInput;
  return status;
}

template <int N, int MI, int ME>
QpStatus QpSolver<N, MI, ME>::finish(const Problem& problem, bool warm_start, VecN& x) {
  // An unsatisfiable zero row is reported at the end; the rest is still solved.
  bool infeasible = false;
  if (!(warm_start && warm_count_ > 0)) warm_count_ = 0;
  if (!imposeWarmSet(problem.gradient, x)) infeasible = true;

  VecN u, w, z, r;
  double nz = 0.0;
  bool hit_bound = false;
  while (!infeasible) {
    const int p = mostViolated(x);
    if (p < 0) break;
    solveHessian(p, u);

    // Move from the current (dual feasible) point towards satisfying p,
    // dropping active inequalities whose multipliers would turn negative.
    double dual_p = 0.0;
    bool added = false;
    while (!added && !infeasible) {
      if (iterations_ >= max_iterations_) {
        hit_bound = true;
        break;
      }
      const bool primal_step = stepDirections(p, u, w, z, r, nz);
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
          primal_step ? -violation(p, x) / nz : std::numeric_limits<double>::infinity();
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
        if (!appendToFactor(u, w, nz)) {
          infeasible = true;
          break;
        }
        active_[q] = p;
        dual_[q] = dual_p;
        setActive(p, true);
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
