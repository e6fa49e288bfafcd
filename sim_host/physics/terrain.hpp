// The ground: a height profile along x (flat, ramps, flat tops), extruded
// along y, plus friction patches. It answers ground-truth queries
// (height, normal, mu) and lists the straight pieces of its surface, from
// which each engine builds its collision geometry.
#pragma once
#include <vector>

#include "firmware/controller/model/types.hpp"
#include "sim_host/scenario/scenario.hpp"

namespace hyq::sim {

class Terrain {
 public:
  explicit Terrain(const TerrainSpec& spec);
  Terrain(const Terrain&) = delete;
  Terrain& operator=(const Terrain&) = delete;

  double height(double x) const;                  // [m] ground z at x
  Vec3 normal(double x) const;                    // [-] outward surface normal at x, W
  // [-] friction coefficient at (x, y) at time t (a timed patch is there
  // only while t0 <= t < t1), and at the terrain's clock.
  double muAt(double x, double y, double t) const;
  double mu(double x, double y) const { return muAt(x, y, time_); }
  // The simulator sets the clock before each engine step; engines read the
  // friction at it.
  void setTime(double t) { time_ = t; }           // [s]
  double time() const { return time_; }          // [s]
  // The instants at which some patch appears or goes, sorted, each once.
  const std::vector<double>& frictionChanges() const { return changes_; }

  // The straight pieces of the profile, sorted along x; the first and last
  // reach kWorldHalfExtent. An engine's collision box per piece has the
  // piece as its top face and kBoxThickness below it.
  struct Piece {
    double x_begin, x_end;                        // [m]
    double z_begin, z_end;                        // [m]
  };
  const std::vector<Piece>& pieces() const { return pieces_; }
  const TerrainSpec& spec() const { return spec_; }
  static constexpr double kWorldHalfExtent = 500.0;  // [m] the ground's reach in x and y
  static constexpr double kBoxThickness = 2.0;       // [m] collision boxes below the surface

 private:
  int pieceIndex(double x) const;
  TerrainSpec spec_;
  double time_ = 0.0;             // [s]
  std::vector<double> changes_;   // [s]
  std::vector<double> xs_, zs_;                   // profile breakpoints
  std::vector<Piece> pieces_;
};

}  // namespace hyq::sim
