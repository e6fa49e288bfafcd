#include "firmware/controller/terrain_estimator.hpp"

#include <cmath>

namespace hyq {

void TerrainEstimator::reset(double height) {
  a_ = 0.0;
  b_ = 0.0;
  c_ = height;
  normal_ = Vec3::UnitZ();
}

bool TerrainEstimator::fit(const Mat3x4& feet_world, uint32_t mask) {
  // Normal equations of z = a x + b y + c, centred for conditioning.
  int count = 0;
  Vec3 mean = Vec3::Zero();
  for (int i = 0; i < 4; ++i) {
    if (mask & (1u << i)) {
      mean += feet_world.col(i);
      ++count;
    }
  }
  if (count < 3) return false;
  mean /= count;
  double sxx = 0.0, sxy = 0.0, syy = 0.0, sxz = 0.0, syz = 0.0;
  for (int i = 0; i < 4; ++i) {
    if (!(mask & (1u << i))) continue;
    const Vec3 d = feet_world.col(i) - mean;
    sxx += d.x() * d.x();
    sxy += d.x() * d.y();
    syy += d.y() * d.y();
    sxz += d.x() * d.z();
    syz += d.y() * d.z();
  }
  const double det = sxx * syy - sxy * sxy;
  // Collinear feet (or all at one point): the plane is not defined.
  const double scale = sxx + syy;
  if (!(scale > 1e-8) || std::fabs(det) < 1e-6 * scale * scale) return false;
  const double a = (syy * sxz - sxy * syz) / det;
  const double b = (sxx * syz - sxy * sxz) / det;
  if (!std::isfinite(a) || !std::isfinite(b)) return false;
  a_ = a;
  b_ = b;
  c_ = mean.z() - a * mean.x() - b * mean.y();
  normal_ = Vec3(-a, -b, 1.0).normalized();
  return true;
}

}  // namespace hyq
