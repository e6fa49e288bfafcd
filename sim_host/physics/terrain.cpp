#include "sim_host/physics/terrain.hpp"

#include <algorithm>
#include <cmath>

namespace hyq::sim {

Terrain::Terrain(const TerrainSpec& spec) : spec_(spec) {
  xs_.push_back(-kWorldHalfExtent);
  zs_.push_back(0.0);
  for (const Ramp& r : spec_.ramps) {
    const double z0 = zs_.back();
    xs_.push_back(r.x0);
    zs_.push_back(z0);
    xs_.push_back(r.x0 + r.length);
    zs_.push_back(z0 + r.length * std::tan(r.angle));
  }
  xs_.push_back(kWorldHalfExtent);
  zs_.push_back(zs_.back());

  for (size_t i = 0; i + 1 < xs_.size(); ++i) {
    const double dx = xs_[i + 1] - xs_[i];
    if (dx <= 0.0) continue;  // a ramp starting where the previous one ends
    pieces_.push_back({xs_[i], xs_[i + 1], zs_[i], zs_[i + 1]});
  }

  for (const FrictionPatch& p : spec_.patches)
    for (double t : {p.t0, p.t1})
      if (std::isfinite(t)) changes_.push_back(t);
  std::sort(changes_.begin(), changes_.end());
  changes_.erase(std::unique(changes_.begin(), changes_.end()), changes_.end());
}

int Terrain::pieceIndex(double x) const {
  int i = 0;
  while (i + 1 < static_cast<int>(xs_.size()) - 1 && x >= xs_[i + 1]) ++i;
  return i;
}

double Terrain::height(double x) const {
  if (x <= xs_.front()) return zs_.front();
  if (x >= xs_.back()) return zs_.back();
  const int i = pieceIndex(x);
  const double dx = xs_[i + 1] - xs_[i];
  if (dx <= 0.0) return zs_[i + 1];
  return zs_[i] + (x - xs_[i]) / dx * (zs_[i + 1] - zs_[i]);
}

Vec3 Terrain::normal(double x) const {
  const int i = pieceIndex(x);
  const double angle = std::atan2(zs_[i + 1] - zs_[i], xs_[i + 1] - xs_[i]);
  return Vec3(-std::sin(angle), 0.0, std::cos(angle));
}

double Terrain::muAt(double x, double y, double t) const {
  double mu = spec_.mu;
  for (const FrictionPatch& p : spec_.patches)
    if (x >= p.x0 && x <= p.x1 && y >= p.y0 && y <= p.y1 && t >= p.t0 && t < p.t1) mu = p.mu;
  return mu;
}

}  // namespace hyq::sim
