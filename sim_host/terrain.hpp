// The ground: a height profile along x (flat, ramps, flat tops), extruded
// along y, plus friction patches. It answers ground-truth queries
// (height, normal, mu) and owns the ODE collision boxes of its surface.
#pragma once
#include <ode/ode.h>

#include <vector>

#include "firmware/controller/types.hpp"
#include "sim_host/scenario.hpp"

namespace hyq::sim {

class Terrain {
 public:
  explicit Terrain(const TerrainSpec& spec);
  ~Terrain();
  Terrain(const Terrain&) = delete;
  Terrain& operator=(const Terrain&) = delete;

  double height(double x) const;                  // [m] ground z at x
  Vec3 normal(double x) const;                    // [-] outward surface normal at x, W
  double mu(double x, double y) const;            // [-] friction coefficient at (x, y)

  // One collision box per straight piece of the profile; its top face is the piece.
  struct Piece {
    double x_begin, x_end;                        // [m]
    dGeomID box;
  };
  const std::vector<Piece>& pieces() const { return pieces_; }

 private:
  int pieceIndex(double x) const;
  TerrainSpec spec_;
  std::vector<double> xs_, zs_;                   // profile breakpoints
  std::vector<Piece> pieces_;
};

}  // namespace hyq::sim
