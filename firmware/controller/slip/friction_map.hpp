// The friction map: what the robot has learnt of the ground's friction
// around it, in a fixed grid of cells in the world's x-y plane. Each cell
// holds the mean of the estimates taken in it (one per slip, at the slip's
// end), their spread and their count. A foot that lands in an estimated
// cell takes that cell's friction before its own slip says anything, so a
// hind foot steps onto ice that a front foot has slid on.
//
// Static memory and constant work: kFrictionMapSide^2 slots addressed by
// the cell's integer coordinates modulo the side (a torus), so the map
// covers any ground with the cells near the robot: a slot is taken over by
// the next cell that maps onto it, which is how the map forgets ground
// the robot has left (kFrictionMapSide x cell_size behind it). A cell is
// also forgotten once its last estimate is older than max_age, and starts
// again from a new estimate that disagrees with its mean by more than the
// disagreement (the ground changed: oil spilt, or ice melted).
#pragma once
#include <cstdint>

namespace hyq {

inline constexpr int kFrictionMapSide = 12;  // slots per side of the torus

struct FrictionMapParams {
  bool enabled = false;         // [-] false: no cell is written or read
  double cell_size = 0.25;      // [m] side of a cell
  double max_age = 60.0;        // [s] a cell's estimate is forgotten this long after its last one
  double disagreement = 0.3;    // [-] a new estimate off the mean by more than this share restarts the cell
};

// One cell's record.
struct FrictionCell {
  int32_t ix = 0, iy = 0;       // [-] the cell's coordinates: floor(x / cell_size), floor(y / cell_size)
  int32_t count = 0;            // [-] estimates in it; 0: the slot is empty
  double mean = 0.0;            // [-] their mean mu
  double m2 = 0.0;              // [-] sum of squared deviations (Welford)
  double time = 0.0;            // [s] of the last one
};

// What a lookup finds.
struct FrictionLookup {
  bool known = false;           // the cell has an estimate, not older than max_age
  double mu = 0.0;              // [-] its mean
  double spread = 0.0;          // [-] standard deviation of its estimates (0 for one)
  int32_t count = 0;            // [-] its estimates
};

// What a write left in its cell.
struct FrictionWrite {
  bool written = false;         // false: the estimate was ignored (map off, or mu not a positive finite number)
  int32_t ix = 0, iy = 0;       // [-] the cell's coordinates
  FrictionLookup cell;          // the cell after the write
};

class FrictionMap {
 public:
  void reset(const FrictionMapParams& params);
  // One estimate `mu` at world (x, y) [m], at `time` [s]. Ignored when the
  // map is off or mu is not a positive finite number. Returns the cell
  // as the write left it.
  FrictionWrite add(double x, double y, double mu, double time);
  FrictionLookup lookup(double x, double y, double time) const;
  // Slots holding a cell whose last estimate is not older than max_age.
  int knownCells(double time) const;
  bool enabled() const { return params_.enabled; }

 private:
  // The cell coordinates of (x, y), clamped far from int32's ends.
  void cellOf(double x, double y, int32_t& ix, int32_t& iy) const;
  static int slotOf(int32_t ix, int32_t iy);
  bool fresh(const FrictionCell& c, double time) const { return c.count > 0 && time - c.time <= params_.max_age; }
  static FrictionLookup summary(const FrictionCell& c);

  FrictionMapParams params_;
  FrictionCell cells_[kFrictionMapSide * kFrictionMapSide];
};

}  // namespace hyq
