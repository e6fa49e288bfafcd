#include "firmware/controller/terrain_estimator.hpp"

#include <cmath>

namespace hyq {

namespace {

constexpr int kMaxPoints = 4 + 4 * TerrainEstimator::kFootholdHistory;

// Weighted least-squares plane z = a x + b y + c through `n` points
// (normal equations, centred for conditioning). False when the points are
// (nearly) collinear or the weights vanish.
bool fitPlane(const Vec3* points, const double* weights, int n, double& a, double& b, double& c) {
  double w_sum = 0.0;
  Vec3 mean = Vec3::Zero();
  for (int k = 0; k < n; ++k) {
    w_sum += weights[k];
    mean += weights[k] * points[k];
  }
  if (!(w_sum > 0.0)) return false;
  mean /= w_sum;
  double sxx = 0.0, sxy = 0.0, syy = 0.0, sxz = 0.0, syz = 0.0;
  for (int k = 0; k < n; ++k) {
    const Vec3 d = points[k] - mean;
    const double w = weights[k];
    sxx += w * d.x() * d.x();
    sxy += w * d.x() * d.y();
    syy += w * d.y() * d.y();
    sxz += w * d.x() * d.z();
    syz += w * d.y() * d.z();
  }
  const double det = sxx * syy - sxy * sxy;
  // Collinear points (or all at one point): the plane is not defined.
  const double scale = sxx + syy;
  if (!(scale > 1e-8 * w_sum) || std::fabs(det) < 1e-6 * scale * scale) return false;
  const double a_new = (syy * sxz - sxy * syz) / det;
  const double b_new = (sxx * syz - sxy * sxz) / det;
  if (!std::isfinite(a_new) || !std::isfinite(b_new)) return false;
  a = a_new;
  b = b_new;
  c = mean.z() - a_new * mean.x() - b_new * mean.y();
  return true;
}

}  // namespace

void TerrainEstimator::reset(double height) {
  a_ = 0.0;
  b_ = 0.0;
  c_ = height;
  normal_ = Vec3::UnitZ();
  for (int i = 0; i < 4; ++i) {
    local_normal_[i] = normal_;
    for (int k = 0; k < kFootholdHistory; ++k) history_[i][k].setZero();
    history_count_[i] = 0;
  }
}

void TerrainEstimator::recordLiftoff(int leg, const Vec3& foot_world) {
  if (leg < 0 || leg >= 4 || !foot_world.allFinite()) return;
  for (int k = kFootholdHistory - 1; k > 0; --k) history_[leg][k] = history_[leg][k - 1];
  history_[leg][0] = foot_world;
  if (history_count_[leg] < kFootholdHistory) ++history_count_[leg];
}

bool TerrainEstimator::fit(const Mat3x4& feet_world, uint32_t mask, double local_length) {
  Vec3 points[kMaxPoints];
  double weights[kMaxPoints];
  int n = 0;
  for (int i = 0; i < 4; ++i) {
    if (!(mask & (1u << i))) continue;
    points[n] = feet_world.col(i);
    weights[n] = 1.0;
    ++n;
  }
  if (n < 3) return false;
  double a = 0.0, b = 0.0, c = 0.0;
  if (!fitPlane(points, weights, n, a, b, c)) return false;
  a_ = a;
  b_ = b;
  c_ = c;
  normal_ = Vec3(-a, -b, 1.0).normalized();
  // Local planes: the feet above and every recorded foothold, weighted by
  // their horizontal distance from each foot in turn.
  for (int i = 0; i < 4; ++i)
    for (int k = 0; k < history_count_[i]; ++k) points[n++] = history_[i][k];
  for (int leg = 0; leg < 4; ++leg) {
    local_normal_[leg] = normal_;
    if (!(local_length > 0.0)) continue;
    const Vec3& at = feet_world.col(leg);
    for (int k = 0; k < n; ++k) {
      const double dx = points[k].x() - at.x(), dy = points[k].y() - at.y();
      weights[k] = std::exp(-(dx * dx + dy * dy) / (2.0 * local_length * local_length));
    }
    double al = 0.0, bl = 0.0, cl = 0.0;
    if (fitPlane(points, weights, n, al, bl, cl)) local_normal_[leg] = Vec3(-al, -bl, 1.0).normalized();
  }
  return true;
}

}  // namespace hyq
