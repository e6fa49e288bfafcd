// The friction map: cells, their statistics, forgetting (age, a cell that
// takes the slot over, a disagreeing estimate), its bounds (the full grid,
// far coordinates, bad numbers), switched off; and the recovery's use of it
// at touch-down and as a guess's target.
#include "firmware/controller/slip/friction_map.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "firmware/controller/slip/traction_recovery.hpp"

namespace hyq {
namespace {

FrictionMapParams on() {
  FrictionMapParams p;
  p.enabled = true;
  p.cell_size = 0.25;
  p.max_age = 10.0;
  p.disagreement = 0.3;
  return p;
}

TEST(FrictionMap, ACellHoldsTheMeanSpreadAndCountOfItsEstimates) {
  FrictionMap map;
  map.reset(on());
  map.add(1.01, 2.01, 0.20, 1.0);
  map.add(1.20, 2.24, 0.22, 2.0);  // same cell: [1.0, 1.25) x [2.0, 2.25)
  map.add(1.10, 2.10, 0.24, 3.0);
  const FrictionLookup c = map.lookup(1.24, 2.0, 3.5);
  ASSERT_TRUE(c.known);
  EXPECT_EQ(c.count, 3);
  EXPECT_NEAR(c.mu, 0.22, 1e-15);
  EXPECT_NEAR(c.spread, 0.02, 1e-12);  // sample standard deviation of 0.20, 0.22, 0.24
  EXPECT_FALSE(map.lookup(1.25, 2.0, 3.5).known);   // the next cell along x
  EXPECT_FALSE(map.lookup(1.0, 1.999, 3.5).known);  // and along -y
  EXPECT_EQ(map.knownCells(3.5), 1);
}

TEST(FrictionMap, AWriteReturnsItsCellAsItLeftIt) {
  FrictionMap map;
  map.reset(on());
  const FrictionWrite first = map.add(-0.30, 0.10, 0.20, 1.0);
  ASSERT_TRUE(first.written);
  EXPECT_EQ(first.ix, -2);  // floor(-0.30 / 0.25)
  EXPECT_EQ(first.iy, 0);
  EXPECT_EQ(first.cell.count, 1);
  EXPECT_DOUBLE_EQ(first.cell.mu, 0.20);
  EXPECT_EQ(first.cell.spread, 0.0);
  const FrictionWrite second = map.add(-0.26, 0.24, 0.24, 2.0);
  EXPECT_EQ(second.ix, -2);
  EXPECT_EQ(second.cell.count, 2);
  EXPECT_NEAR(second.cell.mu, 0.22, 1e-15);
  EXPECT_NEAR(second.cell.spread, std::sqrt(0.0008), 1e-12);  // sample standard deviation of 0.20, 0.24
  const FrictionWrite restarted = map.add(-0.26, 0.24, 0.60, 3.0);  // off the mean by more than 30 %
  EXPECT_EQ(restarted.cell.count, 1);
  EXPECT_DOUBLE_EQ(restarted.cell.mu, 0.60);
  EXPECT_FALSE(map.add(-0.26, 0.24, std::nan(""), 4.0).written);
  map.reset(FrictionMapParams{});  // off
  EXPECT_FALSE(map.add(-0.26, 0.24, 0.2, 4.0).written);
}

TEST(FrictionMap, NegativeCoordinatesHaveTheirOwnCells) {
  FrictionMap map;
  map.reset(on());
  map.add(-0.01, -0.01, 0.1, 0.0);  // cell (-1, -1)
  map.add(0.01, 0.01, 0.5, 0.0);    // cell (0, 0)
  EXPECT_NEAR(map.lookup(-0.2, -0.2, 0.0).mu, 0.1, 1e-15);
  EXPECT_NEAR(map.lookup(0.2, 0.2, 0.0).mu, 0.5, 1e-15);
  EXPECT_FALSE(map.lookup(-0.2, 0.2, 0.0).known);
}

TEST(FrictionMap, AnEstimateIsForgottenAfterMaxAge) {
  FrictionMap map;
  map.reset(on());
  map.add(0.1, 0.1, 0.3, 5.0);
  EXPECT_TRUE(map.lookup(0.1, 0.1, 15.0).known);   // exactly max_age old
  EXPECT_FALSE(map.lookup(0.1, 0.1, 15.001).known);
  EXPECT_EQ(map.knownCells(15.001), 0);
  // A stale cell starts again from its next estimate.
  map.add(0.1, 0.1, 0.6, 20.0);
  EXPECT_EQ(map.lookup(0.1, 0.1, 20.0).count, 1);
  EXPECT_NEAR(map.lookup(0.1, 0.1, 20.0).mu, 0.6, 1e-15);
}

TEST(FrictionMap, AGroundThatChangedRestartsItsCell) {
  FrictionMap map;
  map.reset(on());
  map.add(0.1, 0.1, 0.5, 0.0);
  map.add(0.1, 0.1, 0.55, 1.0);  // within 30 %: averaged
  EXPECT_EQ(map.lookup(0.1, 0.1, 1.0).count, 2);
  map.add(0.1, 0.1, 0.1, 2.0);   // oil spilt: off by far more than 30 %
  const FrictionLookup c = map.lookup(0.1, 0.1, 2.0);
  EXPECT_EQ(c.count, 1);
  EXPECT_NEAR(c.mu, 0.1, 1e-15);
}

// The grid is a torus of kFrictionMapSide^2 slots: a cell that maps onto a
// taken slot takes it over, and the one it replaced is forgotten.
TEST(FrictionMap, TheFullGridForgetsTheCellsTheRobotHasLeft) {
  FrictionMap map;
  map.reset(on());
  const double size = 0.25;
  for (int ix = 0; ix < kFrictionMapSide; ++ix)
    for (int iy = 0; iy < kFrictionMapSide; ++iy)
      map.add((ix + 0.5) * size, (iy + 0.5) * size, 0.1 + 0.001 * (ix * kFrictionMapSide + iy), 1.0);
  EXPECT_EQ(map.knownCells(1.0), kFrictionMapSide * kFrictionMapSide);
  for (int ix = 0; ix < kFrictionMapSide; ++ix)
    for (int iy = 0; iy < kFrictionMapSide; ++iy)
      ASSERT_NEAR(map.lookup((ix + 0.5) * size, (iy + 0.5) * size, 1.0).mu,
                  0.1 + 0.001 * (ix * kFrictionMapSide + iy), 1e-15);
  // One grid further along x: the same slot.
  const double ahead = (kFrictionMapSide + 0.5) * size;
  map.add(ahead, 0.5 * size, 0.9, 2.0);
  EXPECT_NEAR(map.lookup(ahead, 0.5 * size, 2.0).mu, 0.9, 1e-15);
  EXPECT_EQ(map.lookup(ahead, 0.5 * size, 2.0).count, 1);
  EXPECT_FALSE(map.lookup(0.5 * size, 0.5 * size, 2.0).known);
  EXPECT_EQ(map.knownCells(2.0), kFrictionMapSide * kFrictionMapSide);
}

TEST(FrictionMap, BadNumbersAndFarCoordinatesStayInBounds) {
  FrictionMap map;
  map.reset(on());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  map.add(0.1, 0.1, nan, 0.0);
  map.add(0.1, 0.1, -0.2, 0.0);
  map.add(0.1, 0.1, 0.0, 0.0);
  map.add(0.1, 0.1, inf, 0.0);
  map.add(nan, 0.1, 0.3, 0.0);
  map.add(inf, 0.1, 0.3, 0.0);
  EXPECT_EQ(map.knownCells(0.0), 0);
  // Far away (clamped cell coordinates): written and read, no overflow.
  map.add(1e300, -1e300, 0.4, 0.0);
  EXPECT_TRUE(map.lookup(1e300, -1e300, 0.0).known);
  EXPECT_FALSE(map.lookup(nan, nan, 0.0).known);
}

TEST(FrictionMap, SwitchedOffItNeitherWritesNorReads) {
  FrictionMap map;
  FrictionMapParams p = on();
  p.enabled = false;
  map.reset(p);
  map.add(0.1, 0.1, 0.3, 0.0);
  EXPECT_EQ(map.knownCells(0.0), 0);
  EXPECT_FALSE(map.lookup(0.1, 0.1, 0.0).known);
}

// The recovery: a foot that lands on known ground takes estimate_margin x
// the map's mu at once, down or up; a slip of it with no estimate of its
// own brakes toward brake_margin x that mu, not toward the floor.
TEST(FrictionMap, AFootLandingOnKnownGroundTakesItsFriction) {
  RecoveryParams params;
  TractionRecovery recovery;
  recovery.reset(params);
  RecoveryInput swing;
  swing.stance_mask = 0xE;  // leg 0 in the air
  recovery.update(swing, 0.001);
  EXPECT_DOUBLE_EQ(recovery.muInUse(0), params.mu_default);
  RecoveryInput land;
  land.stance_mask = 0xF;
  land.map_mu[0] = 0.2;
  recovery.update(land, 0.001);
  EXPECT_NEAR(recovery.muInUse(0), params.estimate_margin * 0.2, 1e-12);
  // A slip with no estimate yet: toward brake_margin x 0.2 (0.1), never the floor.
  RecoveryInput slip = land;
  slip.slip_mask = 1u;
  for (int k = 0; k < 1000; ++k) recovery.update(slip, 0.001);
  EXPECT_NEAR(recovery.muInUse(0), params.brake_margin * 0.2, 1e-6);
  EXPECT_GT(recovery.muInUse(0), params.mu_floor + 0.02);
  // Lifted and landed on ground the map knows to be good: up at once, to at
  // most mu_default.
  recovery.update(swing, 0.001);
  RecoveryInput good;
  good.stance_mask = 0xF;
  good.map_mu[0] = 0.9;
  recovery.update(good, 0.001);
  EXPECT_DOUBLE_EQ(recovery.muInUse(0), params.mu_default);
  // Unknown ground: the foot keeps what it had.
  recovery.update(swing, 0.001);
  RecoveryInput unknown;
  unknown.stance_mask = 0xF;
  recovery.update(unknown, 0.001);
  EXPECT_DOUBLE_EQ(recovery.muInUse(0), params.mu_default);
}

}  // namespace
}  // namespace hyq
