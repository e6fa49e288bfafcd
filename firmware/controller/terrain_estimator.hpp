// Terrain estimation from the feet alone: a least-squares plane through the
// stance feet, refit at every touch-down (paper Fig. 1 "terrain estimation").
// Its normal is the n0 the controller uses for every stance foot until slip
// recovery corrects a foot's own normal.
#pragma once
#include <cstdint>

#include "firmware/controller/types.hpp"

namespace hyq {

class TerrainEstimator {
 public:
  // Flat ground through `height` [m].
  void reset(double height);
  // Fit z = a x + b y + c through the feet in `mask` (W positions, columns).
  // Needs >= 3 feet that are not collinear; otherwise keeps the last plane
  // and returns false.
  bool fit(const Mat3x4& feet_world, uint32_t mask);
  const Vec3& normal() const { return normal_; }
  // Plane height [m] under (x, y).
  double heightAt(double x, double y) const { return a_ * x + b_ * y + c_; }

 private:
  double a_ = 0.0, b_ = 0.0, c_ = 0.0;
  Vec3 normal_ = Vec3::UnitZ();
};

}  // namespace hyq
