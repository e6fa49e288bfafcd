// Ground reaction force distribution: the stance feet's forces that best
// realise the desired body wrench, inside each foot's friction pyramid.
//
//   minimise  || W (A f - w_des) ||^2 + regularisation ||f||^2
//             + tangential_weight sum_i ||(I - n_i n_i^T) f_i||^2
//   A = [ I  I  I  I ; [p_0]x [p_1]x [p_2]x [p_3]x ],  p_i = foot_i - CoM (W)
//
// subject to, per stance foot (normal n, tangents t1, t2, mu_p = mu * scale):
//   f_normal_min <= n.f <= f_normal_max,   |t_k.f| <= mu_p n.f   (k = 1, 2)
// (t1 across the fall line with mu_across * scale instead, where a foot's
// mu_across is below its mu: GrfInput::mu_across)
// and f = 0 for swing feet. Sizes stay fixed (12 forces, 24 inequalities): a
// swing foot's forces get identity Hessian rows, zero gradient and zero
// constraint rows, so the solver returns exactly 0 for them.
#pragma once
#include "firmware/controller/params.hpp"
#include "firmware/controller/force/qp_solver.hpp"
#include "firmware/controller/stage_clock.hpp"
#include "firmware/controller/model/types.hpp"

namespace hyq {

constexpr int kGrfVariables = 12;
constexpr int kGrfConstraintsPerFoot = 6;  // min/max normal force + 4 pyramid faces
constexpr int kGrfConstraints = 4 * kGrfConstraintsPerFoot;
// Foot i's inequalities (rows 6i..6i+5) touch only its forces (columns 3i..3i+2).
constexpr QpBlockLayout kGrfLayout{kGrfConstraintsPerFoot, 3};
using GrfSolver = QpSolver<kGrfVariables, kGrfConstraints>;
using GrfProblem = QpProblem<kGrfVariables, kGrfConstraints>;

// GrfInput::mu_across's default: no foot's pyramid narrowed across its fall line.
constexpr double kNoAcrossLimit = 1e9;

struct GrfInput {
  bool stance[4];           // [-] leg in stance (LF, RF, LH, RH)
  Mat3x4 foot_from_com;     // [m] foot position minus CoM position, W
  Mat3x4 normal;            // [-] surface normal under each foot, W (unit)
  Vec4 mu;                  // [-] friction coefficient of each foot's cone
  // [-] Where below mu, the foot's pyramid is a rectangle about the fall line
  // of its normal (its steepest direction): mu along it, mu_across across
  // it (TractionRecovery::muAcross). On a level normal, or at mu and above:
  // the square pyramid of contactTangents.
  Vec4 mu_across = Vec4::Constant(kNoAcrossLimit);
  Vec6 wrench_des;          // [N, N m] force and moment about the CoM, W
  // [N] per-foot cap on the normal force, below QpParams.f_normal_max: the
  // controller ramps it after touch-down and before lift-off so that no
  // foot's force steps. The minimum normal force is lowered with it.
  Vec4 max_normal_force = Vec4::Constant(1e9);
  // [N] each stance foot's tangential force is bounded by
  // mu_p (f_n - cone_offset), the offset at most the foot's lower normal
  // bound (min(f_normal_min, its cap)); 0: the plain pyramid.
  double cone_offset = 0.0;
  // Force continuity: adds smoothing * ||f_i - force_previous_i||^2 per
  // stance foot to the cost [-, relative to the wrench error in N^2], so
  // that a foot joining the support or a change of the stance set does not
  // step the other feet's forces. 0 disables it.
  double smoothing = 0.0;
  Mat3x4 force_previous = Mat3x4::Zero();  // [N] W
};

struct GrfOutput {
  Mat3x4 forces;            // [N] force from the ground on each foot, W
  Vec6 wrench;              // [N, N m] wrench the forces realise, about the CoM, W
  QpStatus status;          // solver outcome (see qp_solver.hpp)
  bool infeasible;          // no feasible point (or invalid input): fallback forces
  bool hit_iteration_limit; // iteration bound reached: fallback forces
  int iterations;           // [-] active-set changes used this call
};

// Tangent directions of a contact: t1 = normalize(n x x_hat) (n x y_hat when
// n is nearly along x_hat), t2 = t1 x n.
void contactTangents(const Vec3& normal, Vec3& t1, Vec3& t2);

class GrfQp {
 public:
  // pyramid_scale: RecoveryParams::pyramid_scale (cone -> inscribed pyramid).
  void init(const QpParams& params, double pyramid_scale);

  // One tick, solved from scratch (the solver's structured entry point,
  // cold: the last tick's active set saves no iteration on the recorded
  // runs, tests/bench/qp_replay). Never produces NaN/Inf. When the solver
  // stops short (infeasible, iteration bound), each stance force is
  // projected into its own normal-force bounds and pyramid, so the answer is
  // still physically admissible per foot; on invalid input (NaN/Inf) all
  // forces are zero. With a timer, the problem's build is marked as
  // Stage::kQpBuild and the solver's call as Stage::kQpSolve.
  void solve(const GrfInput& input, GrfOutput& output, StageTimer* timer = nullptr);

  // The QP that solve() builds (exposed for tests and diagnostics). Normals
  // that are not finite or have near-zero length are replaced by +z_W,
  // friction coefficients that are negative or not finite by 0.
  static void buildProblem(const GrfInput& input, const QpParams& params, double pyramid_scale,
                           GrfProblem& problem);

  // The solver call solve() makes on the problem it built; the raw solution
  // (no fallback projection). The QP replay benchmark (tests/bench/qp_replay.cpp)
  // runs recorded problems through it.
  QpStatus solveProblem(const GrfProblem& problem, Vec12& forces);
  // The problem of the last solve() (diagnostics and the QP recorder).
  const GrfProblem& lastProblem() const { return problem_; }
  const GrfSolver& solver() const { return solver_; }

 private:
  QpParams params_{};
  double pyramid_scale_ = 0.70710678118654752;
  QpSettings settings_{};
  GrfSolver solver_{};
  GrfProblem problem_{};
};

}  // namespace hyq
