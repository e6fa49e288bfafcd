#include "firmware/controller/force/grf_qp.hpp"

#include <cmath>

namespace hyq {
namespace {

constexpr int kFeet = kNumLegs;

// Below this |n x x_hat| the x-based tangent is ill-defined (n nearly along x).
constexpr double kTangentDegenerate = 1e-6;

Vec3 usableNormal(const Vec3& n) {
  const double length = n.norm();
  if (!std::isfinite(length) || length < 0.5) return Vec3::UnitZ();
  return n / length;
}

double usableMu(double mu) { return std::isfinite(mu) && mu > 0.0 ? mu : 0.0; }

// A = [I I I I; [p_i]x ...]: force and moment about the CoM of the 4 forces.
Mat6x12 wrenchMap(const Mat3x4& foot_from_com) {
  Mat6x12 a;
  for (int foot = 0; foot < kFeet; ++foot) {
    a.block<3, 3>(0, 3 * foot).setIdentity();
    a.block<3, 3>(3, 3 * foot) = skew(foot_from_com.col(foot));
  }
  return a;
}

// Below this |z - (z.n) n| a normal has no fall line (level ground).
constexpr double kLevelNormal = 1e-6;

// A foot's pyramid narrowed across its normal's fall line (GrfInput::
// mu_across below mu): t2 up the fall line, t1 across it. False on a level
// normal (no fall line): the square pyramid of contactTangents.
bool fallLineTangents(const Vec3& n, Vec3& t1, Vec3& t2) {
  const Vec3 up = Vec3::UnitZ() - n.z() * n;
  const double up_norm = up.norm();
  if (!(up_norm > kLevelNormal)) return false;
  t2 = up / up_norm;
  t1 = t2.cross(n);
  return true;
}

// A foot's pyramid: its tangents, and the half-width along t1 it returns;
// along t2 it is mu_p (usableMu(mu) * pyramid_scale). Square unless
// mu_across * pyramid_scale < mu_p on a normal with a fall line.
double pyramidAxes(const Vec3& n, double mu_p, double mu_across, double pyramid_scale, Vec3& t1, Vec3& t2) {
  const double across_p = mu_across * pyramid_scale;
  if (across_p < mu_p && fallLineTangents(n, t1, t2)) return usableMu(across_p);
  contactTangents(n, t1, t2);
  return mu_p;
}

// Per-foot admissible force nearest in the contact's own coordinates: normal
// component clamped to [f_min, f_max], tangential ones to
// +/- mu_i (f_n - offset) along the pyramid's axes.
Vec3 projectIntoPyramid(const Vec3& f, const Vec3& n, double mu_p, double mu_across, double pyramid_scale,
                        double f_min, double f_max, double offset) {
  Vec3 t1, t2;
  const double mu_1 = pyramidAxes(n, mu_p, mu_across, pyramid_scale, t1, t2);
  const double fn = std::fmin(std::fmax(n.dot(f), f_min), f_max);
  const double room = std::fmax(fn - offset, 0.0);
  const double ft1 = std::fmin(std::fmax(t1.dot(f), -mu_1 * room), mu_1 * room);
  const double ft2 = std::fmin(std::fmax(t2.dot(f), -mu_p * room), mu_p * room);
  return fn * n + ft1 * t1 + ft2 * t2;
}

}  // namespace

void contactTangents(const Vec3& normal, Vec3& t1, Vec3& t2) {
  t1 = normal.cross(Vec3::UnitX());
  if (t1.norm() < kTangentDegenerate) t1 = normal.cross(Vec3::UnitY());
  t1.normalize();
  t2 = t1.cross(normal);
}

void GrfQp::init(const QpParams& params, double pyramid_scale) {
  params_ = params;
  pyramid_scale_ = pyramid_scale;
  settings_.max_iterations = params.max_iterations;
  settings_.feasibility_tolerance = params.feasibility_tolerance;
}

namespace {

// The foot's normal-force ceiling [N]: the lower of the global one and the
// controller's per-foot ramp; never negative, NaN treated as no ramp.
double footMaxNormalForce(const GrfInput& input, const QpParams& params, int foot) {
  const double cap = input.max_normal_force[foot];
  if (!(cap < params.f_normal_max)) return params.f_normal_max;
  return cap > 0.0 ? cap : 0.0;
}

// [N] The foot's normal-force floor: f_normal_min, lowered to its ceiling
// where the ramp caps it below that (a foot being unloaded must reach its cap).
double footMinNormalForce(const QpParams& params, double f_max) {
  return params.f_normal_min < f_max ? params.f_normal_min : f_max;
}

// [N] The normal force a foot's pyramid is shifted by (GrfInput::
// cone_offset), at most its lower normal bound f_low; 0 if not positive or NaN.
double coneOffset(double cone_offset, double f_low) {
  if (!(cone_offset > 0.0)) return 0.0;
  const double offset = cone_offset < f_low ? cone_offset : f_low;
  return offset > 0.0 ? offset : 0.0;
}

}  // namespace

void GrfQp::buildProblem(const GrfInput& input, const QpParams& params, double pyramid_scale,
                         GrfProblem& problem) {
  // H = A' W^2 A + reg I and g = -A' W^2 w_des, block by block: with
  // [a]x' [b]x = (a.b) I - b a', foot pair (i, j) gives
  //   H_ij = w_lin^2 I + w_ang^2 ((p_i.p_j) I - p_j p_i'),
  // and foot i  g_i = -w_lin^2 f_des + w_ang^2 p_i x m_des.
  // (Swing feet are decoupled below.)
  const double w_lin2 = params.wrench_weight_lin * params.wrench_weight_lin;
  const double w_ang2 = params.wrench_weight_ang * params.wrench_weight_ang;
  const Vec3 force_des = input.wrench_des.head<3>(), moment_des = input.wrench_des.tail<3>();
  for (int i = 0; i < kFeet; ++i) {
    const Vec3 p_i = input.foot_from_com.col(i);
    for (int j = 0; j <= i; ++j) {
      const Vec3 p_j = input.foot_from_com.col(j);
      Mat3 block = (-w_ang2 * p_j) * p_i.transpose();
      block.diagonal().array() += w_lin2 + w_ang2 * p_i.dot(p_j);
      problem.hessian.block<3, 3>(3 * i, 3 * j) = block;
      problem.hessian.block<3, 3>(3 * j, 3 * i) = block.transpose();
    }
    problem.gradient.segment<3>(3 * i) = -w_lin2 * force_des + w_ang2 * p_i.cross(moment_des);
  }
  problem.hessian.diagonal().array() += params.regularisation;
  problem.ineq_matrix.setZero();
  problem.ineq_bound.setZero();

  for (int foot = 0; foot < kFeet; ++foot) {
    const int col = 3 * foot;
    if (!input.stance[foot]) {
      // Decoupled unit rows with zero gradient: the optimum is exactly f = 0.
      problem.hessian.middleRows<3>(col).setZero();
      problem.hessian.middleCols<3>(col).setZero();
      problem.hessian.block<3, 3>(col, col).setIdentity();
      problem.gradient.segment<3>(col).setZero();
      continue;
    }
    if (input.smoothing > 0.0 && input.force_previous.col(foot).allFinite()) {
      problem.hessian.block<3, 3>(col, col).diagonal().array() += input.smoothing;
      problem.gradient.segment<3>(col) -= input.smoothing * input.force_previous.col(foot);
    }
    const Vec3 n = usableNormal(input.normal.col(foot));
    // Tangential forces cost extra (in this foot's cone frame): internal
    // forces between the feet do not change the wrench, so against the
    // smoothing term only this lets them die out (QpParams).
    if (params.tangential_weight > 0.0)
      problem.hessian.block<3, 3>(col, col) +=
          params.tangential_weight * (Mat3::Identity() - n * n.transpose());
    const double mu_p = usableMu(input.mu[foot]) * pyramid_scale;  // along t2
    Vec3 t1, t2;
    const double mu_1 = pyramidAxes(n, mu_p, input.mu_across[foot], pyramid_scale, t1, t2);
    const int row = kGrfConstraintsPerFoot * foot;
    const double f_max = footMaxNormalForce(input, params, foot);
    problem.ineq_matrix.block<1, 3>(row + 0, col) = n.transpose();
    const double f_low = footMinNormalForce(params, f_max);
    problem.ineq_bound[row + 0] = f_low;
    problem.ineq_matrix.block<1, 3>(row + 1, col) = -n.transpose();
    problem.ineq_bound[row + 1] = -f_max;
    problem.ineq_matrix.block<1, 3>(row + 2, col) = (mu_1 * n - t1).transpose();
    problem.ineq_matrix.block<1, 3>(row + 3, col) = (mu_1 * n + t1).transpose();
    problem.ineq_matrix.block<1, 3>(row + 4, col) = (mu_p * n - t2).transpose();
    problem.ineq_matrix.block<1, 3>(row + 5, col) = (mu_p * n + t2).transpose();
    // |t_i.f| <= mu_i (n.f - offset), with offset <= f_low: f = f_low n stays feasible.
    const double offset = coneOffset(input.cone_offset, f_low);
    problem.ineq_bound.segment<2>(row + 2).setConstant(mu_1 * offset);
    problem.ineq_bound.segment<2>(row + 4).setConstant(mu_p * offset);
  }
}

QpStatus GrfQp::solveProblem(const GrfProblem& problem, Vec12& forces) {
  return solver_.solveStructured(problem, settings_, kGrfLayout, forces);
}

void GrfQp::solve(const GrfInput& input, GrfOutput& output, StageTimer* timer) {
  buildProblem(input, params_, pyramid_scale_, problem_);
  if (timer != nullptr) timer->mark(Stage::kQpBuild);
  Vec12 f;
  output.status = solveProblem(problem_, f);
  if (timer != nullptr) timer->mark(Stage::kQpSolve);
  output.iterations = solver_.iterations();
  output.infeasible = output.status == QpStatus::kInfeasible ||
                      output.status == QpStatus::kInvalidInput ||
                      output.status == QpStatus::kNumericalFailure;
  output.hit_iteration_limit = output.status == QpStatus::kMaxIterations;

  const bool fallback = output.status == QpStatus::kInfeasible ||
                        output.status == QpStatus::kMaxIterations;
  for (int foot = 0; foot < kFeet; ++foot) {
    Vec3 force = f.segment<3>(3 * foot);
    if (!input.stance[foot]) {
      force.setZero();
    } else if (fallback) {
      const double f_max = footMaxNormalForce(input, params_, foot);
      const double f_low = footMinNormalForce(params_, f_max);
      force = projectIntoPyramid(force, usableNormal(input.normal.col(foot)),
                                 usableMu(input.mu[foot]) * pyramid_scale_, input.mu_across[foot],
                                 pyramid_scale_, f_low, f_max,
                                 coneOffset(input.cone_offset, f_low));
    }
    output.forces.col(foot) = force;
  }
  const Mat6x12 a = wrenchMap(input.foot_from_com);
  Vec12 stacked;
  for (int foot = 0; foot < kFeet; ++foot) stacked.segment<3>(3 * foot) = output.forces.col(foot);
  output.wrench = a * stacked;
  if (!output.wrench.allFinite()) output.wrench.setZero();  // foot_from_com not finite
}

}  // namespace hyq
