#include "firmware/controller/slip/friction_map.hpp"

#include <cmath>

namespace hyq {

namespace {
constexpr double kMaxCellIndex = 1.0e9;  // [-] |floor(x / size)| clamped here: far from int32's ends
}  // namespace

void FrictionMap::reset(const FrictionMapParams& params) {
  params_ = params;
  for (FrictionCell& c : cells_) c = FrictionCell();
}

void FrictionMap::cellOf(double x, double y, int32_t& ix, int32_t& iy) const {
  double fx = std::floor(x / params_.cell_size), fy = std::floor(y / params_.cell_size);
  if (!(fx > -kMaxCellIndex)) fx = -kMaxCellIndex;  // NaN too
  if (fx > kMaxCellIndex) fx = kMaxCellIndex;
  if (!(fy > -kMaxCellIndex)) fy = -kMaxCellIndex;
  if (fy > kMaxCellIndex) fy = kMaxCellIndex;
  ix = static_cast<int32_t>(fx);
  iy = static_cast<int32_t>(fy);
}

int FrictionMap::slotOf(int32_t ix, int32_t iy) {
  int sx = static_cast<int>(ix % kFrictionMapSide), sy = static_cast<int>(iy % kFrictionMapSide);
  if (sx < 0) sx += kFrictionMapSide;
  if (sy < 0) sy += kFrictionMapSide;
  return sy * kFrictionMapSide + sx;
}

FrictionLookup FrictionMap::summary(const FrictionCell& c) {
  FrictionLookup out;
  out.known = true;
  out.mu = c.mean;
  out.count = c.count;
  out.spread = c.count > 1 ? std::sqrt(c.m2 / static_cast<double>(c.count - 1)) : 0.0;
  return out;
}

FrictionWrite FrictionMap::add(double x, double y, double mu, double time) {
  FrictionWrite out;
  if (!params_.enabled || !(mu > 0.0) || !std::isfinite(mu) || !std::isfinite(x) || !std::isfinite(y)) return out;
  int32_t ix, iy;
  cellOf(x, y, ix, iy);
  FrictionCell& c = cells_[slotOf(ix, iy)];
  const bool same_cell = c.ix == ix && c.iy == iy && fresh(c, time);
  if (!same_cell || std::fabs(mu - c.mean) > params_.disagreement * c.mean) {
    c = FrictionCell();
    c.ix = ix;
    c.iy = iy;
  }
  // Welford's running mean and sum of squared deviations.
  ++c.count;
  const double delta = mu - c.mean;
  c.mean += delta / static_cast<double>(c.count);
  c.m2 += delta * (mu - c.mean);
  c.time = time;
  out.written = true;
  out.ix = ix;
  out.iy = iy;
  out.cell = summary(c);
  return out;
}

FrictionLookup FrictionMap::lookup(double x, double y, double time) const {
  FrictionLookup out;
  if (!params_.enabled) return out;
  int32_t ix, iy;
  cellOf(x, y, ix, iy);
  const FrictionCell& c = cells_[slotOf(ix, iy)];
  if (c.ix != ix || c.iy != iy || !fresh(c, time)) return out;
  return summary(c);
}

int FrictionMap::knownCells(double time) const {
  int n = 0;
  for (const FrictionCell& c : cells_)
    if (fresh(c, time)) ++n;
  return n;
}

}  // namespace hyq
