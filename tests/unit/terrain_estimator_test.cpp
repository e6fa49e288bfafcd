// The terrain plane through the feet, and each foot's local plane through the
// feet and the recorded footholds (the surface estimate's prior).
#include "firmware/controller/state/terrain_estimator.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace hyq {
namespace {

constexpr double kPi = 3.14159265358979323846;

double angleDeg(const Vec3& a, const Vec3& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / kPi;
}

// HyQ's stance footprint: LF, RF, LH, RH at (+-0.37, +-0.33).
const double kFootX[4] = {0.37, 0.37, -0.37, -0.37};
const double kFootY[4] = {0.33, -0.33, 0.33, -0.33};

// A 0.25 rad slope rising along x up to a flat top that starts at x = 0.1.
double rampTopHeight(double x) { return x < 0.1 ? -std::tan(0.25) * (0.1 - x) : 0.0; }

// Flat up to x = 0.1, then a 0.25 rad slope rising along x.
double rampFootHeight(double x) { return x > 0.1 ? std::tan(0.25) * (x - 0.1) : 0.0; }

Mat3x4 feetOn(double (*height)(double), double dx) {
  Mat3x4 feet;
  for (int i = 0; i < 4; ++i) feet.col(i) = Vec3(kFootX[i] + dx, kFootY[i], height(kFootX[i] + dx));
  return feet;
}

// A reset estimator whose four feet lifted off where feetOn(height, dx)
// puts them: each leg's last foothold recorded, no plane fitted yet.
TerrainEstimator afterAStride(double (*height)(double), double dx) {
  TerrainEstimator terrain;
  terrain.reset(0.0);
  const Mat3x4 before = feetOn(height, dx);
  for (int i = 0; i < 4; ++i) terrain.recordLiftoff(i, before.col(i));
  return terrain;
}

// A reset estimator whose four feet lifted off at `footholds`.
TerrainEstimator afterFootholds(const Vec3 (&footholds)[4]) {
  TerrainEstimator terrain;
  terrain.reset(0.0);
  for (int i = 0; i < 4; ++i) terrain.recordLiftoff(i, footholds[i]);
  return terrain;
}

// One fit with the preset's prior parameters (SlipParams: local planes,
// inliers, the row turn and its ground).
bool fitPreset(TerrainEstimator& terrain, const Mat3x4& feet, uint32_t mask = 0xF, uint32_t refit_legs = 0xF) {
  const SlipParams slip;
  return terrain.fit(feet, mask, slip.prior_local_length, slip.prior_inlier_distance, refit_legs,
                     slip.prior_turn_margin, slip.turn_sets_ground);
}

TEST(TerrainEstimator, FitsTheTiltedPlaneThroughTheFeet) {
  TerrainEstimator terrain;
  terrain.reset(0.0);
  // z = 0.1 x - 0.05 y + 0.2: the normal is (-0.1, 0.05, 1) normalised.
  Mat3x4 feet;
  for (int i = 0; i < 4; ++i)
    feet.col(i) = Vec3(kFootX[i], kFootY[i], 0.1 * kFootX[i] - 0.05 * kFootY[i] + 0.2);
  ASSERT_TRUE(terrain.fit(feet, 0xF));
  EXPECT_LT((terrain.normal() - Vec3(-0.1, 0.05, 1.0).normalized()).norm(), 1e-12);
  EXPECT_NEAR(terrain.heightAt(1.0, 1.0), 0.25, 1e-12);
  // Without a local length every foot's local plane is the global one.
  for (int i = 0; i < 4; ++i) EXPECT_EQ(terrain.localNormal(i), terrain.normal());
}

TEST(TerrainEstimator, KeepsTheLastPlaneWhenTheFeetAreCollinear) {
  TerrainEstimator terrain;
  terrain.reset(0.0);
  Mat3x4 feet;
  for (int i = 0; i < 4; ++i) feet.col(i) = Vec3(0.2 * i, 0.0, 0.05 * i);
  EXPECT_FALSE(terrain.fit(feet, 0xF, 0.4));
  EXPECT_EQ(terrain.normal(), Vec3::UnitZ());
  EXPECT_FALSE(terrain.fit(feetOn(rampTopHeight, 0.0), 0x3, 0.4));  // two feet
  EXPECT_EQ(terrain.normal(), Vec3::UnitZ());
  for (int i = 0; i < 4; ++i) EXPECT_EQ(terrain.localNormal(i), Vec3::UnitZ());
  // A failed fit after a good one keeps the good one's planes, local ones too.
  const Mat3x4 ramp_top = feetOn(rampTopHeight, 0.0);
  for (int i = 0; i < 4; ++i) terrain.recordLiftoff(i, feetOn(rampTopHeight, -0.4).col(i));
  ASSERT_TRUE(terrain.fit(ramp_top, 0xF, 0.4));
  const Vec3 global = terrain.normal(), local_lh = terrain.localNormal(2);
  EXPECT_GT(angleDeg(global, local_lh), 1.0);
  EXPECT_FALSE(terrain.fit(feet, 0xF, 0.4));
  EXPECT_EQ(terrain.normal(), global);
  EXPECT_EQ(terrain.localNormal(2), local_lh);
}

TEST(TerrainEstimator, OnAPlaneTheLocalPlanesAreTheGlobalOne) {
  TerrainEstimator terrain;
  terrain.reset(0.0);
  auto plane = [](double x, double y) { return 0.2 * x + 0.1 * y; };
  Mat3x4 feet;
  for (int i = 0; i < 4; ++i) {
    terrain.recordLiftoff(i, Vec3(kFootX[i] - 0.4, kFootY[i], plane(kFootX[i] - 0.4, kFootY[i])));
    feet.col(i) = Vec3(kFootX[i], kFootY[i], plane(kFootX[i], kFootY[i]));
  }
  ASSERT_TRUE(terrain.fit(feet, 0xF, 0.4));
  for (int i = 0; i < 4; ++i) EXPECT_LT(angleDeg(terrain.localNormal(i), terrain.normal()), 1e-9);
}

TEST(TerrainEstimator, AtARampsTopTheHindFeetKeepTheSlope) {
  // The front feet have reached the flat top, the hind feet and every
  // earlier foothold (one stride, 0.4 m, back) are on the slope. The plane
  // through the four feet is 5.1 deg off the slope under the hind feet;
  // their local planes, their row's plane, lie on it exactly (a plane
  // weighted by distance from each foot: 1.7 deg off).
  TerrainEstimator terrain = afterAStride(rampTopHeight, -0.4);
  ASSERT_TRUE(terrain.fit(feetOn(rampTopHeight, 0.0), 0xF, 0.4));
  const Vec3 slope = Vec3(-std::tan(0.25), 0.0, 1.0).normalized();
  EXPECT_NEAR(angleDeg(terrain.normal(), slope), 5.11, 0.01);
  for (int hind = 2; hind < 4; ++hind) EXPECT_LT(angleDeg(terrain.localNormal(hind), slope), 1e-9);
  // The front row has two feet on the top and two footholds on the slope:
  // no plane holds more than three of them, and the one through both feet
  // and a foothold is 4.7 deg off the flat top (the weighted plane: 8.0 deg;
  // the global one 9.2 deg).
  for (int front = 0; front < 2; ++front) {
    EXPECT_NEAR(angleDeg(terrain.localNormal(front), Vec3::UnitZ()), 4.74, 0.01);
    EXPECT_NEAR(angleDeg(terrain.normal(), Vec3::UnitZ()), 9.21, 0.01);
  }
}

TEST(TerrainEstimator, AtARampsFootTheFrontFeetSeeTheSlope) {
  // The front row on a 0.25 rad ramp rising from x = 1 m, as leg odometry
  // put it in a closed-loop run (MuJoCo, seed 2, 26 s): both front feet on
  // the slope, RF's last foothold too, LF's last foothold 4 cm before the
  // ramp's foot and both rows' earlier ones on the flat. The hind feet are
  // on the flat. A plane weighted by distance from LF (L = 0.4 m) is 5.2 deg
  // off the slope; the plane of the most points of LF's row, 1.4 deg.
  const Vec3 lf(1.374, 0.328, 0.0947), rf(1.574, -0.329, 0.1452);
  const Vec3 lh(0.636, 0.330, 0.0), rh(0.836, -0.329, 0.0);
  TerrainEstimator terrain;
  terrain.reset(0.0);
  for (const Vec3& p : {Vec3(0.582, 0.329, 0.0002), Vec3(0.962, 0.329, -0.0001)}) terrain.recordLiftoff(0, p);
  for (const Vec3& p : {Vec3(0.745, -0.328, 0.0002), Vec3(1.165, -0.328, 0.0420)}) terrain.recordLiftoff(1, p);
  Mat3x4 feet;
  feet << lf, rf, lh, rh;
  ASSERT_TRUE(terrain.fit(feet, 0xF, 0.4, 0.005));
  const Vec3 slope = Vec3(-std::tan(0.25), 0.0, 1.0).normalized();
  EXPECT_NEAR(angleDeg(terrain.localNormal(0), slope), 1.42, 0.01);
  EXPECT_LT(angleDeg(terrain.localNormal(1), slope), 1.5);
  // The hind row has no footholds yet: fewer than 3 points, its planes
  // are the weighted ones, pulled up the slope by the front feet (LH 4.77,
  // RH 7.84 deg from the flat they stand on).
  EXPECT_NEAR(angleDeg(terrain.localNormal(2), Vec3::UnitZ()), 4.77, 0.01);
  EXPECT_NEAR(angleDeg(terrain.localNormal(3), Vec3::UnitZ()), 7.84, 0.01);
}

// The prior of a foot just past a ramp's foot (SlipParams::
// prior_agreed_ground). RH is 15 cm up the slope (3.8 cm high), LH on the
// flat 1.5 cm before the ramp's foot, their last footholds on the flat
// (staggered, as the crawl leaves them); the front feet further up the
// slope. The hind row's four points lie on no one plane, and the three
// that the plane through RH holds are a blend of the two slopes. RH and
// both front feet lie on the slope, and LH within the 5 mm band of its
// plane extended (3.8 mm above it): four points agree on the ground plane,
// the slope. RH lies 3.8 cm off its footholds' plane, outside its 5 mm
// band: its prior is that ground plane. LH lies on its footholds' plane:
// it keeps its row's plane.
namespace {

struct PastARampsFoot {
  Vec3 footholds[4];
  Mat3x4 feet;
};

PastARampsFoot pastARampsFoot(double rh_x) {
  const double lh_x = 0.085, lf_x = 0.65, rf_x = 0.55;
  PastARampsFoot c{{Vec3(0.45, 0.33, rampFootHeight(0.45)), Vec3(0.35, -0.33, rampFootHeight(0.35)),
                    Vec3(-0.25, 0.33, 0.0), Vec3(-0.05, -0.33, 0.0)},
                   Mat3x4::Zero()};
  c.feet << Vec3(lf_x, 0.33, rampFootHeight(lf_x)), Vec3(rf_x, -0.33, rampFootHeight(rf_x)),
      Vec3(lh_x, 0.33, rampFootHeight(lh_x)), Vec3(rh_x, -0.33, rampFootHeight(rh_x));
  return c;
}

}  // namespace

TEST(TerrainEstimator, JustPastARampsFootTheHindPriorIsTheGroundFourPointsAgreeOn) {
  const Vec3 slope = Vec3(-std::tan(0.25), 0.0, 1.0).normalized();
  {
    const PastARampsFoot c = pastARampsFoot(0.25);
    TerrainEstimator terrain = afterFootholds(c.footholds);
    ASSERT_TRUE(fitPreset(terrain, c.feet));
    EXPECT_LT(angleDeg(terrain.groundNormal(3), slope), 1.0);
    EXPECT_GT(angleDeg(terrain.localNormal(3), slope), 3.0);  // the blend
    EXPECT_EQ(terrain.priorNormal(3), terrain.groundNormal(3));
    EXPECT_GT(angleDeg(terrain.groundNormal(2), terrain.localNormal(2)), 3.0);
    EXPECT_EQ(terrain.priorNormal(2), terrain.localNormal(2));
    // The front row's four points lie on the slope: its own plane is kept.
    for (int front = 0; front < 2; ++front) {
      EXPECT_LT(angleDeg(terrain.localNormal(front), slope), 1e-9) << front;
      EXPECT_EQ(terrain.priorNormal(front), terrain.localNormal(front)) << front;
    }
  }
  // RH 1 cm up the slope (4 cm past the ramp's foot): off its footholds'
  // plane by more than the 5 mm band, inside the row turn's 1.5 cm. Its
  // row's plane leans 11 deg off the slope; the ground plane is its prior.
  {
    const PastARampsFoot c = pastARampsFoot(0.14);
    TerrainEstimator terrain = afterFootholds(c.footholds);
    ASSERT_TRUE(fitPreset(terrain, c.feet));
    EXPECT_GT(angleDeg(terrain.localNormal(3), slope), 5.0);
    EXPECT_LT(angleDeg(terrain.groundNormal(3), slope), 1.0);
    EXPECT_EQ(terrain.priorNormal(3), terrain.groundNormal(3));
  }
  // The same ground on a hillside (all of it turned 0.1 rad about the
  // walk): the footholds' plane, which holds the horizontal square to the
  // walk, reads the slope across as slope along, and every foot lies off
  // it. The rule then rests on its other conditions: RH takes the ground
  // plane four points agree on.
  {
    PastARampsFoot c = pastARampsFoot(0.25);
    const Mat3 hillside = Eigen::AngleAxisd(0.1, Vec3::UnitX()).toRotationMatrix();
    for (Vec3& p : c.footholds) p = hillside * p;
    c.feet = hillside * c.feet;
    TerrainEstimator terrain = afterFootholds(c.footholds);
    ASSERT_TRUE(fitPreset(terrain, c.feet));
    EXPECT_GT(angleDeg(terrain.groundNormal(3), terrain.localNormal(3)), 3.0);
    EXPECT_EQ(terrain.priorNormal(3), terrain.groundNormal(3));
  }
}

// A row across a slope change (SlipParams::prior_turn_margin): both feet
// of the row off the plane of their footholds, on the same side, give the
// plane through the two feet that holds the horizontal square to the walk.
TEST(TerrainEstimator, ARowAcrossASlopeChangeTakesTheNewSlope) {
  constexpr double kMargin = SlipParams{}.prior_turn_margin;
  ASSERT_GT(kMargin, 0.0);
  const Vec3 slope = Vec3(-std::tan(0.25), 0.0, 1.0).normalized();
  auto onRampFoot = [](double x, double y) { return Vec3(x, y, x > 1.0 ? std::tan(0.25) * (x - 1.0) : 0.0); };
  // Fits the same feet and footholds with and without the turn; returns
  // the local normals of both fits.
  auto fitBoth = [](const Mat3x4& feet, const Vec3 (&footholds)[4], Vec3 (&with)[4], Vec3 (&without)[4]) {
    for (int pass = 0; pass < 2; ++pass) {
      TerrainEstimator terrain;
      terrain.reset(0.0);
      for (int i = 0; i < 4; ++i) terrain.recordLiftoff(i, footholds[i]);
      ASSERT_TRUE(terrain.fit(feet, 0xF, 0.4, 0.005, 0xF, pass == 0 ? kMargin : 0.0));
      for (int i = 0; i < 4; ++i) (pass == 0 ? with : without)[i] = terrain.localNormal(i);
    }
  };
  Vec3 with[4], without[4];
  // The front feet's first steps onto a 0.25 rad ramp rising from x = 1 m,
  // staggered as the crawl places them (a closed-loop run on MuJoCo at
  // contact time constant 0.01 s, seed 2, 21.58 s): LF 0.35 m and RF 0.15 m
  // up the slope, their last footholds on the flat. Every plane through
  // three of the row's points holds a flat foothold: the consensus plane is
  // 1.8 deg off the slope under LF (under RF, 9.3 deg); the turn gives the
  // slope.
  {
    Mat3x4 feet;
    feet << onRampFoot(1.35, 0.33), onRampFoot(1.15, -0.33), onRampFoot(0.55, 0.33), onRampFoot(0.75, -0.33);
    const Vec3 footholds[4] = {onRampFoot(0.95, 0.33), onRampFoot(0.75, -0.33), onRampFoot(0.15, 0.33),
                               onRampFoot(0.35, -0.33)};
    fitBoth(feet, footholds, with, without);
    EXPECT_GT(angleDeg(without[0], slope), 1.5);
    for (int front = 0; front < 2; ++front) EXPECT_LT(angleDeg(with[front], slope), 1e-9) << front;
    // The hind row, on the flat with its footholds, is as it was.
    for (int hind = 2; hind < 4; ++hind) EXPECT_EQ(with[hind], without[hind]) << hind;
  }
  // At the top of a ramp (rampTopHeight: the flat top from x = 0.1 m), the
  // hind row crossing it: both feet on the top (0.1 and 0.3 m past the
  // crest), footholds on the slope: the top.
  {
    Mat3x4 feet = feetOn(rampTopHeight, 0.0);
    feet.col(2) = Vec3(0.4, 0.33, rampTopHeight(0.4));
    feet.col(3) = Vec3(0.2, -0.33, rampTopHeight(0.2));
    const Vec3 footholds[4] = {feetOn(rampTopHeight, -0.4).col(0), feetOn(rampTopHeight, -0.4).col(1),
                               Vec3(0.0, 0.33, rampTopHeight(0.0)), Vec3(-0.2, -0.33, rampTopHeight(-0.2))};
    fitBoth(feet, footholds, with, without);
    EXPECT_GT(angleDeg(without[2], Vec3::UnitZ()), 1.0);
    for (int hind = 2; hind < 4; ++hind) EXPECT_LT(angleDeg(with[hind], Vec3::UnitZ()), 1e-9) << hind;
  }
  // Not a turn: one foot past the crest, its partner still on the slope
  // with the footholds; one foot 1 cm past it (2.5 mm off the slope's
  // plane, under the margin); the feet tilted to either side of the
  // footholds' plane (a sideways slope); the feet side by side across the
  // walk. Each fit is the consensus plane alone.
  const Vec3 hind_footholds[4] = {feetOn(rampTopHeight, -0.4).col(0), feetOn(rampTopHeight, -0.4).col(1),
                                  Vec3(-0.3, 0.33, rampTopHeight(-0.3)), Vec3(-0.5, -0.33, rampTopHeight(-0.5))};
  for (const double rh_x : {0.0, 0.11}) {
    Mat3x4 feet = feetOn(rampTopHeight, 0.0);
    feet.col(2) = Vec3(rh_x > 0.05 ? 0.31 : 0.2, 0.33, 0.0);
    feet.col(3) = Vec3(rh_x, -0.33, rampTopHeight(rh_x));
    fitBoth(feet, hind_footholds, with, without);
    for (int i = 0; i < 4; ++i) EXPECT_EQ(with[i], without[i]) << rh_x << " " << i;
  }
  {
    Mat3x4 feet;
    feet << Vec3(0.47, 0.33, 0.033), Vec3(0.27, -0.33, -0.033), Vec3(-0.27, 0.33, 0.0), Vec3(-0.47, -0.33, 0.0);
    const Vec3 footholds[4] = {Vec3(0.07, 0.33, 0.0), Vec3(-0.13, -0.33, 0.0), Vec3(-0.67, 0.33, 0.0),
                               Vec3(-0.87, -0.33, 0.0)};
    fitBoth(feet, footholds, with, without);
    for (int i = 0; i < 4; ++i) EXPECT_EQ(with[i], without[i]) << "sideways " << i;
  }
  {
    const Mat3x4 feet = feetOn(rampTopHeight, 0.0);
    const Vec3 footholds[4] = {feetOn(rampTopHeight, -0.4).col(0), feetOn(rampTopHeight, -0.4).col(1),
                               feetOn(rampTopHeight, -0.4).col(2), feetOn(rampTopHeight, -0.4).col(3)};
    fitBoth(feet, footholds, with, without);
    for (int i = 0; i < 4; ++i) EXPECT_EQ(with[i], without[i]) << "side by side " << i;
    EXPECT_NEAR(angleDeg(with[0], Vec3::UnitZ()), 4.74, 0.01);
  }
}

// A foot's ground where no four points agree on one (fit's
// turn_sets_ground): a row that turned takes the new slope, and a row whose
// standing feet still lie on its last own ground keeps it; otherwise the
// plane through all feet. Four points of which all but the foot lie on a
// line do not agree on a plane.
TEST(TerrainEstimator, ATurnedRowsPlaneIsItsFeetsGround) {
  constexpr double kMargin = SlipParams{}.prior_turn_margin;
  ASSERT_TRUE(SlipParams{}.turn_sets_ground);
  // A 0.35 rad ramp rising from x = 1 m; the feet and footholds where a
  // closed-loop crawl placed them (MuJoCo, seed 1, LF's first touch-down on
  // the slope).
  const Vec3 slope = Vec3(-std::tan(0.35), 0.0, 1.0).normalized();
  auto onRamp = [](double x, double y) { return Vec3(x, y, x > 1.0 ? std::tan(0.35) * (x - 1.0) : 0.0); };
  // Fits with the turned plane as the ground and without; returns both
  // fits' ground normals and the plane through all feet.
  struct Fits {
    Vec3 with[4], without[4], feet_plane;
  };
  auto fitBoth = [&](const Mat3x4& feet, const Vec3 (&footholds)[4]) {
    Fits fits;
    for (int pass = 0; pass < 2; ++pass) {
      TerrainEstimator terrain;
      terrain.reset(0.0);
      for (int i = 0; i < 4; ++i) terrain.recordLiftoff(i, footholds[i]);
      EXPECT_TRUE(terrain.fit(feet, 0xF, 0.4, 0.005, 0xF, kMargin, pass == 0));
      for (int i = 0; i < 4; ++i) (pass == 0 ? fits.with : fits.without)[i] = terrain.groundNormal(i);
      fits.feet_plane = terrain.normal();
    }
    return fits;
  };
  const Vec3 hind_footholds[2] = {onRamp(0.117, 0.33), onRamp(-0.09, -0.33)};
  // Both front feet on the slope, their footholds and the hind feet on the
  // flat. No plane through a front foot holds four points: without the
  // turn its cone is about the plane through all feet, more than 10 deg off
  // the slope's 20.1; with it, about the slope.
  {
    Mat3x4 feet;
    feet << onRamp(1.345, 0.33), onRamp(1.148, -0.33), onRamp(0.514, 0.33), onRamp(0.317, -0.33);
    const Vec3 footholds[4] = {onRamp(0.943, 0.33), onRamp(0.737, -0.33), hind_footholds[0], hind_footholds[1]};
    const Fits fits = fitBoth(feet, footholds);
    for (int front = 0; front < 2; ++front) {
      EXPECT_EQ(fits.without[front], fits.feet_plane) << front;
      EXPECT_GT(angleDeg(fits.without[front], slope), 10.0) << front;
      EXPECT_LT(angleDeg(fits.with[front], slope), 1e-9) << front;
    }
    // The hind row stands on the flat with its footholds: four points agree.
    for (int hind = 2; hind < 4; ++hind) {
      EXPECT_EQ(fits.with[hind], fits.without[hind]) << hind;
      EXPECT_LT(angleDeg(fits.with[hind], Vec3::UnitZ()), 1e-9) << hind;
    }
  }
  // A step earlier: only RF on the slope, LF and every foothold on the flat
  // (no turn). RF's cone is about the plane through all feet either way;
  // LF's about the flat its row agrees on. (LF, its foothold and LH lie on
  // one line along the walk: the plane through it and RF holds four points,
  // and was RF's ground, rolled 4.7 deg toward the left, before a line and a
  // point stopped counting as four agreeing points.)
  {
    Mat3x4 feet;
    feet << onRamp(0.943, 0.33), onRamp(1.148, -0.33), onRamp(0.514, 0.33), onRamp(0.317, -0.33);
    const Vec3 footholds[4] = {onRamp(0.55, 0.33), onRamp(0.737, -0.33), hind_footholds[0], hind_footholds[1]};
    const Fits fits = fitBoth(feet, footholds);
    EXPECT_EQ(fits.with[1], fits.feet_plane);
    EXPECT_EQ(fits.with[1], fits.without[1]);
    EXPECT_LT(angleDeg(fits.with[0], Vec3::UnitZ()), 1e-9);
  }
  // A step later: RF lands further up the slope (its foothold now on it,
  // LF's still on the flat, 3 cm before the ramp's foot). LF lies 12 mm off
  // the plane of the two footholds, under the margin: no turn, and no four
  // points agree. A row whose feet both stand on its last ground keeps it;
  // fitted afresh, the same points give the plane through all feet.
  {
    Mat3x4 first, next;
    first << onRamp(1.345, 0.33), onRamp(1.148, -0.33), onRamp(0.514, 0.33), onRamp(0.317, -0.33);
    next << onRamp(1.345, 0.33), onRamp(1.561, -0.33), onRamp(0.514, 0.33), onRamp(0.317, -0.33);
    const Vec3 footholds[4] = {onRamp(0.97, 0.33), onRamp(0.737, -0.33), hind_footholds[0], hind_footholds[1]};
    for (const bool keep : {true, false}) {
      TerrainEstimator walked, fresh;
      walked.reset(0.0);
      fresh.reset(0.0);
      for (int i = 0; i < 4; ++i) walked.recordLiftoff(i, footholds[i]);
      ASSERT_TRUE(walked.fit(first, 0xF, 0.4, 0.005, 0xF, kMargin, keep));
      walked.recordLiftoff(1, first.col(1));
      ASSERT_TRUE(walked.fit(next, 0xF, 0.4, 0.005, 0x2, kMargin, keep));
      for (int i = 0; i < 4; ++i) fresh.recordLiftoff(i, i == 1 ? first.col(1) : footholds[i]);
      ASSERT_TRUE(fresh.fit(next, 0xF, 0.4, 0.005, 0xF, kMargin, keep));
      for (int front = 0; front < 2; ++front) {
        EXPECT_EQ(fresh.groundNormal(front), fresh.normal()) << front;
        if (keep)
          EXPECT_LT(angleDeg(walked.groundNormal(front), slope), 1e-9) << front;
        else
          EXPECT_EQ(walked.groundNormal(front), walked.normal()) << front;
      }
    }
  }
  // Off the last ground: RF lands on a steeper stretch, 2 cm above that
  // plane. Not kept: the plane through all feet.
  {
    Mat3x4 first, next;
    first << onRamp(1.345, 0.33), onRamp(1.148, -0.33), onRamp(0.514, 0.33), onRamp(0.317, -0.33);
    next = first;
    next.col(1) = onRamp(1.561, -0.33) + Vec3(0.0, 0.0, 0.02);
    const Vec3 footholds[4] = {onRamp(0.97, 0.33), onRamp(0.737, -0.33), hind_footholds[0], hind_footholds[1]};
    TerrainEstimator walked;
    walked.reset(0.0);
    for (int i = 0; i < 4; ++i) walked.recordLiftoff(i, footholds[i]);
    ASSERT_TRUE(walked.fit(first, 0xF, 0.4, 0.005, 0xF, kMargin, true));
    walked.recordLiftoff(1, first.col(1));
    ASSERT_TRUE(walked.fit(next, 0xF, 0.4, 0.005, 0x2, kMargin, true));
    EXPECT_EQ(walked.groundNormal(1), walked.normal());
  }
}

TEST(TerrainEstimator, ARowThatCrossesASlopeChangeAtAnAngleDoesNotTurn) {
  EXPECT_DOUBLE_EQ(kCosMaxGroundTilt, std::cos(kMaxGroundTilt));
  EXPECT_DOUBLE_EQ(kSinMaxGroundTilt, std::sin(kMaxGroundTilt));
  // A 0.24 rad ramp rising along W x from x = 2.39 m, walked at a heading
  // of -55 deg: the change is crossed 55 deg off square. The feet and
  // footholds as a closed-loop crawl's leg odometry placed them (a drawn
  // validation terrain, hyq plant, LH in swing): both front feet on the
  // slope, RF's foothold and RH on the flat. RF stands 11 cm below LF and
  // 0.10 m ahead of it along the walk: the square-on plane through them
  // (their line and the horizontal across the walk) is 47 deg steep, 56 deg
  // off the slope. Either guard refuses it: the plane through all feet
  // slopes across the walk, and 47 deg is steeper than kMaxGroundTilt.
  // With RF and its foothold 0.15 m further ahead along the walk, the same
  // plane is 24 deg steep and 34 deg off: the cross-slope test alone
  // refuses it.
  const Vec3 slope = Vec3(-std::tan(0.24), 0.0, 1.0).normalized();
  const Vec3 walk(0.572, -0.820, 0.0);
  for (const double ahead : {0.0, 0.15}) {
    Mat3x4 feet;
    feet.col(0) = Vec3(2.896, -3.710, 0.122);
    feet.col(1) = Vec3(2.434, -4.157, 0.011) + ahead * walk;
    feet.col(2) = Vec3(2.2, -3.2, 0.0);  // in swing: not in the mask
    feet.col(3) = Vec3(1.949, -3.480, -0.013);
    TerrainEstimator terrain;
    terrain.reset(0.0);
    terrain.recordLiftoff(0, Vec3(2.776, -3.530, 0.096));
    terrain.recordLiftoff(1, Vec3(2.298, -3.970, -0.011) + ahead * walk);
    ASSERT_TRUE(fitPreset(terrain, feet, 0b1011u, 0b0011u));
    // The front feet's ground and prior: within the plane through the
    // feet's own error (6.4-6.6 deg) and a fraction of a degree.
    const double feet_plane_error = angleDeg(terrain.normal(), slope);
    EXPECT_LT(feet_plane_error, 7.0) << ahead;
    for (int front = 0; front < 2; ++front) {
      EXPECT_GE(terrain.groundNormal(front).z(), kCosMaxGroundTilt) << ahead << " " << front;
      EXPECT_LT(angleDeg(terrain.groundNormal(front), slope), feet_plane_error + 0.5) << ahead << " " << front;
      EXPECT_LT(angleDeg(terrain.localNormal(front), slope), feet_plane_error + 0.5) << ahead << " " << front;
    }
  }
}

TEST(TerrainEstimator, NoGroundSteeperThanTheCrawlIsSpecifiedFor) {
  // The feet and footholds of ATurnedRowsPlaneIsItsFeetsGround's first
  // steps onto a ramp, crossed square-on, the ramp 0.35 rad and 0.6 rad
  // steep. The row turns onto the first; the second is steeper than
  // kMaxGroundTilt, and the front feet keep a ground no steeper than that.
  for (const double angle : {0.35, 0.6}) {
    auto onRamp = [angle](double x, double y) {
      return Vec3(x, y, x > 1.0 ? std::tan(angle) * (x - 1.0) : 0.0);
    };
    Mat3x4 feet;
    feet << onRamp(1.345, 0.33), onRamp(1.148, -0.33), onRamp(0.514, 0.33), onRamp(0.317, -0.33);
    const Vec3 footholds[4] = {onRamp(0.943, 0.33), onRamp(0.737, -0.33), onRamp(0.117, 0.33), onRamp(-0.09, -0.33)};
    TerrainEstimator terrain = afterFootholds(footholds);
    ASSERT_TRUE(fitPreset(terrain, feet));
    const Vec3 slope = Vec3(-std::tan(angle), 0.0, 1.0).normalized();
    for (int front = 0; front < 2; ++front) {
      if (angle < kMaxGroundTilt) {
        EXPECT_LT(angleDeg(terrain.groundNormal(front), slope), 1e-9) << front;
      } else {
        EXPECT_GE(terrain.groundNormal(front).z(), kCosMaxGroundTilt) << front;
      }
    }
  }
}

TEST(TerrainEstimator, TheGroundPlaneIsTheOneFourPointsAgreeOn) {
  const Vec3 slope = Vec3(-std::tan(0.25), 0.0, 1.0).normalized();
  // On one plane the ground planes are that plane.
  {
    TerrainEstimator terrain = afterAStride(rampTopHeight, -1.0);
    ASSERT_TRUE(terrain.fit(feetOn(rampTopHeight, -0.6), 0xF, 0.4));
    for (int i = 0; i < 4; ++i) EXPECT_LT(angleDeg(terrain.groundNormal(i), slope), 1e-9) << i;
    for (int i = 0; i < 4; ++i) EXPECT_FALSE(terrain.groundStandsIn(i)) << i;
  }
  // At a ramp's top (front feet on the top, hind feet and all footholds on
  // the slope): the hind feet's ground is the slope (their row's four
  // points), 5.1 deg from the plane through the four feet. The front row's
  // four points lie on one plane only because its feet and footholds form
  // two parallel lines here (a crawl staggers them): 4.74 deg off the top
  // they stand on (atan(0.0332 / 0.4): 3.3 cm of rise over the stride), the
  // global plane 9.2 deg.
  {
    TerrainEstimator terrain = afterAStride(rampTopHeight, -0.4);
    ASSERT_TRUE(terrain.fit(feetOn(rampTopHeight, 0.0), 0xF, 0.4));
    for (int hind = 2; hind < 4; ++hind) EXPECT_LT(angleDeg(terrain.groundNormal(hind), slope), 1e-9);
    for (int front = 0; front < 2; ++front)
      EXPECT_NEAR(angleDeg(terrain.groundNormal(front), Vec3::UnitZ()), 4.74, 0.01);
    EXPECT_NEAR(angleDeg(terrain.normal(), slope), 5.11, 0.01);
    // Stagger the front row (LF a quarter stride ahead, as in the crawl):
    // no four points agree through a front foot, and its ground plane is
    // the global plane of this fit.
    Mat3x4 staggered = feetOn(rampTopHeight, 0.0);
    staggered.col(0) = Vec3(kFootX[0] + 0.1, kFootY[0], rampTopHeight(kFootX[0] + 0.1));
    ASSERT_TRUE(terrain.fit(staggered, 0xF, 0.4));
    for (int front = 0; front < 2; ++front)
      EXPECT_LT(angleDeg(terrain.groundNormal(front), terrain.normal()), 1e-12) << front;
    for (int hind = 2; hind < 4; ++hind) EXPECT_LT(angleDeg(terrain.groundNormal(hind), slope), 1e-9);
    // ... and says so (the friction probe reads no friction about it).
    for (int front = 0; front < 2; ++front) EXPECT_TRUE(terrain.groundStandsIn(front)) << front;
    for (int hind = 2; hind < 4; ++hind) EXPECT_FALSE(terrain.groundStandsIn(hind)) << hind;
  }
  // At a ramp's foot (front feet on the slope, hind feet and all footholds
  // on the flat): the hind feet's ground is the flat. The front row's
  // points again form two parallel lines: atan(0.0689 / 0.4) = 9.78 deg,
  // 4.54 deg off the slope.
  {
    TerrainEstimator terrain = afterAStride(rampFootHeight, -0.4);
    ASSERT_TRUE(terrain.fit(feetOn(rampFootHeight, 0.0), 0xF, 0.4));
    for (int hind = 2; hind < 4; ++hind) EXPECT_LT(angleDeg(terrain.groundNormal(hind), Vec3::UnitZ()), 1e-9);
    for (int front = 0; front < 2; ++front) EXPECT_NEAR(angleDeg(terrain.groundNormal(front), slope), 4.54, 0.01);
    EXPECT_GT(angleDeg(terrain.normal(), Vec3::UnitZ()), 5.0);
  }
  // One row touched down: only that row's ground planes are refit; the
  // other row keeps what it had (here, since the reset, flat).
  {
    TerrainEstimator terrain = afterAStride(rampTopHeight, -0.4);
    TerrainEstimator fresh;
    fresh.reset(0.0);
    for (int i = 0; i < 4; ++i) EXPECT_FALSE(fresh.groundStandsIn(i)) << i;  // before any refit
    ASSERT_TRUE(terrain.fit(feetOn(rampTopHeight, 0.0), 0xF, 0.4, 0.005, 0x1));
    for (int hind = 2; hind < 4; ++hind) EXPECT_EQ(terrain.groundNormal(hind), Vec3::UnitZ());
    for (int front = 0; front < 2; ++front) EXPECT_NEAR(angleDeg(terrain.groundNormal(front), Vec3::UnitZ()), 4.74, 0.01);
  }
}

// The trot's prior (TrotParams::prior_row_split, prior_row_interior): the
// plane of the feet, or where the two rows stand on two slopes with the
// feet's plane leaning between them, each row's own local plane.
TEST(TerrainEstimator, OnTwoSlopesEachRowTakesItsOwnPlaneInsteadOfTheFeets) {
  const TrotParams trot;
  const auto rows = TerrainEstimator::RowSplit::of(trot.prior_row_split, trot.prior_row_interior);
  const Vec3 slope = Vec3(-std::tan(0.25), 0.0, 1.0).normalized();
  // A ramp's top: the hind row's plane is the slope, the front row's 4.74
  // deg off the top (its footholds on the slope), the feet's plane 9.2 deg
  // off the top, 4.5 and 5.1 deg from the two rows' planes: inside.
  {
    TerrainEstimator terrain = afterAStride(rampTopHeight, -0.4);
    ASSERT_TRUE(terrain.fit(feetOn(rampTopHeight, 0.0), 0xF, 0.4));
    // Off: the feet's plane.
    for (int i = 0; i < 4; ++i) EXPECT_EQ(terrain.feetOrRowNormal(i, TerrainEstimator::RowSplit{}), terrain.normal());
    for (int i = 0; i < 4; ++i) EXPECT_EQ(terrain.feetOrRowNormal(i, rows), terrain.localNormal(i)) << i;
    for (int hind = 2; hind < 4; ++hind) EXPECT_LT(angleDeg(terrain.feetOrRowNormal(hind, rows), slope), 1e-9);
    // A split wider than the rows' (9.6 deg): the feet's plane.
    const auto wide = TerrainEstimator::RowSplit::of(0.2, trot.prior_row_interior);
    for (int i = 0; i < 4; ++i) EXPECT_EQ(terrain.feetOrRowNormal(i, wide), terrain.normal());
  }
  // Flat ground, the hind row's footholds 5 cm low (the odometry's height
  // drifted while they were left): its plane tilts by 7.1 deg alone and the
  // feet's plane is the front row's: at the end of the arc, not inside.
  // Both rows' footholds low: both planes tilt the same way, no split.
  for (const double front_drift : {0.0, -0.05}) {
    TerrainEstimator terrain;
    terrain.reset(0.0);
    for (int i = 0; i < 4; ++i)
      terrain.recordLiftoff(i, Vec3(kFootX[i] - 0.4, kFootY[i], i < 2 ? front_drift : -0.05));
    Mat3x4 feet;
    for (int i = 0; i < 4; ++i) feet.col(i) = Vec3(kFootX[i], kFootY[i], 0.0);
    ASSERT_TRUE(terrain.fit(feet, 0xF, 0.4));
    EXPECT_NEAR(angleDeg(terrain.localNormal(2), Vec3::UnitZ()), 7.13, 0.01);
    for (int i = 0; i < 4; ++i) EXPECT_EQ(terrain.feetOrRowNormal(i, rows), terrain.normal()) << i;
    // With no interior margin the feet's plane at the front row's counts as
    // inside, and the hind feet would take their drifted plane.
    if (front_drift == 0.0) {
      const auto no_margin = TerrainEstimator::RowSplit::of(trot.prior_row_split, 0.0);
      EXPECT_EQ(terrain.feetOrRowNormal(2, no_margin), terrain.localNormal(2));
    }
  }
}

TEST(TerrainEstimator, KeepsOnlyTheLastFootholdsAndForgetsThemOnReset) {
  // Old footholds far below must not count: only kFootholdHistory per leg stay.
  TerrainEstimator terrain;
  terrain.reset(0.0);
  Mat3x4 feet;
  for (int i = 0; i < 4; ++i) feet.col(i) = Vec3(kFootX[i], kFootY[i], 0.0);
  for (int i = 0; i < 4; ++i) {
    terrain.recordLiftoff(i, Vec3(kFootX[i] - 0.1, kFootY[i], -1.0));  // pushed out below
    for (int k = 0; k < TerrainEstimator::kFootholdHistory; ++k)
      terrain.recordLiftoff(i, Vec3(kFootX[i] - 0.2 * (k + 1), kFootY[i], 0.0));
  }
  ASSERT_TRUE(terrain.fit(feet, 0xF, 0.4));
  for (int i = 0; i < 4; ++i) EXPECT_LT(angleDeg(terrain.localNormal(i), Vec3::UnitZ()), 1e-9);
  // Footholds 10 cm below tilt every local plane (0.45 deg or more); a reset
  // forgets them, and the planes are exactly flat again.
  for (int i = 0; i < 4; ++i) terrain.recordLiftoff(i, Vec3(kFootX[i] - 0.3, kFootY[i], -0.1));
  ASSERT_TRUE(terrain.fit(feet, 0xF, 0.4));
  for (int i = 0; i < 4; ++i) EXPECT_GT(angleDeg(terrain.localNormal(i), Vec3::UnitZ()), 0.4);
  terrain.reset(0.0);
  ASSERT_TRUE(terrain.fit(feet, 0xF, 0.4));
  for (int i = 0; i < 4; ++i) EXPECT_LT(angleDeg(terrain.localNormal(i), Vec3::UnitZ()), 1e-9);
  // One foothold recorded anew, 5 cm below and 0.3 m behind LF: the front
  // row's three points (both front feet and it) make its plane, 9.46 deg
  // off (atan(0.05 / 0.3)); the hind row has no foothold, so its legs'
  // planes are the weighted ones, tilted by its weight there (computed
  // independently: 2.60, 1.47 deg).
  terrain.recordLiftoff(0, Vec3(kFootX[0] - 0.3, kFootY[0], -0.05));
  ASSERT_TRUE(terrain.fit(feet, 0xF, 0.4));
  const double expected[4] = {9.4623, 9.4623, 2.6043, 1.4719};
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(angleDeg(terrain.localNormal(i), Vec3::UnitZ()), expected[i], 1e-3) << i;
}

TEST(TerrainEstimator, ARowDoesNotTurnWhereTheOtherRowStandsOnNeitherPlane) {
  // A 6 deg slope going down along W x to flat ground from x = 1.4 m,
  // walked at a heading of 57 deg: the change is crossed 57 deg off square.
  // The feet and footholds where a closed-loop crawl placed them (a drawn
  // validation terrain, hyq plant, LH touching down): LF and LH on the
  // slope, RF and RH on the flat, the hind footholds on the slope. The
  // plane through all feet is level across the walk within the turn's test
  // (sine 0.03), yet the hind row's square-on plane is 10.0 deg off the
  // flat and 14.1 deg off the slope: the feet's height across the walk read
  // as slope along it. The front feet lie 10-14 cm off that plane and
  // 24-29 cm off its old one.
  const double grade = std::tan(6.0 * kPi / 180.0);
  auto ground = [grade](double x, double y) { return Vec3(x, y, x < 1.4 ? grade * (1.4 - x) : 0.0); };
  const Vec3 slope = Vec3(grade, 0.0, 1.0).normalized();
  Mat3x4 feet;
  feet << ground(1.322, 2.674), ground(1.978, 2.487), ground(1.080, 2.298), ground(1.534, 1.783);
  const Vec3 footholds[4] = {ground(1.100, 2.328), ground(1.760, 2.149), ground(0.870, 1.965), ground(1.316, 1.442)};
  TerrainEstimator terrain = afterFootholds(footholds);
  ASSERT_TRUE(fitPreset(terrain, feet));
  const Vec3 walk(std::cos(57.0 * kPi / 180.0), std::sin(57.0 * kPi / 180.0), 0.0);
  EXPECT_LT(std::fabs(terrain.normal().dot(Vec3::UnitZ().cross(walk))), kMaxRowTurnCrossSine);
  // Each hind foot's ground is no further off than the plane through all
  // feet is at that foot (RH: 2.0 deg; its square-on plane was 10.0), and
  // its prior within 4 deg (the square-on plane: 10.0 and 14.1 deg).
  for (int hind = 2; hind < 4; ++hind) {
    const Vec3 under = feet(0, hind) < 1.4 ? slope : Vec3(Vec3::UnitZ());
    EXPECT_LE(angleDeg(terrain.groundNormal(hind), under), angleDeg(terrain.normal(), under) + 1e-6) << hind;
    EXPECT_LT(angleDeg(terrain.localNormal(hind), under), 4.0) << hind;
  }
}

TEST(TerrainEstimator, ARowThatTurnedKeepsItsPlaneWhateverTheOtherRowSays) {
  EXPECT_DOUBLE_EQ(kCosRowTurnKeptAngle, std::cos(2.0 * kPi / 180.0));
  // ARowAcrossASlopeChangeTakesTheNewSlope's front feet on a 0.25 rad ramp
  // rising from x = 1 m, their footholds on the flat. With the hind feet on
  // the flat the front row turns onto the slope. With the hind feet 10 cm
  // off both planes a fresh estimator refuses that turn; one whose front
  // row turned at its last fit takes the same plane again.
  const Vec3 slope = Vec3(-std::tan(0.25), 0.0, 1.0).normalized();
  auto onRampFoot = [](double x, double y) { return Vec3(x, y, x > 1.0 ? std::tan(0.25) * (x - 1.0) : 0.0); };
  Mat3x4 feet;
  feet << onRampFoot(1.35, 0.33), onRampFoot(1.15, -0.33), onRampFoot(0.55, 0.33), onRampFoot(0.75, -0.33);
  Mat3x4 hind_off = feet;
  hind_off(2, 2) += 0.1;
  hind_off(2, 3) += 0.1;
  const Vec3 footholds[4] = {onRampFoot(0.95, 0.33), onRampFoot(0.75, -0.33), onRampFoot(0.15, 0.33),
                             onRampFoot(0.35, -0.33)};
  TerrainEstimator refused = afterFootholds(footholds);
  ASSERT_TRUE(fitPreset(refused, hind_off, 0xF, 0b0011u));
  TerrainEstimator turned = afterFootholds(footholds);
  ASSERT_TRUE(fitPreset(turned, feet, 0xF, 0b0011u));
  ASSERT_TRUE(fitPreset(turned, hind_off, 0xF, 0b0011u));
  for (int front = 0; front < 2; ++front) {
    EXPECT_GT(angleDeg(refused.localNormal(front), slope), 1.0) << front;
    EXPECT_LT(angleDeg(turned.localNormal(front), slope), 1e-9) << front;
    EXPECT_LT(angleDeg(turned.groundNormal(front), slope), 1e-9) << front;
  }
}

}  // namespace
}  // namespace hyq
