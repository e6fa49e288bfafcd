// Terrain estimation from the feet alone: a least-squares plane through the
// stance feet, refit at every touch-down (paper Fig. 1 "terrain estimation").
// Its normal is the n0 the controller uses for every stance foot until slip
// recovery corrects a foot's own normal.
// Each foot also gets a local plane, the prior of the foot's surface
// estimate: the plane of its row's feet and their last footholds (the front
// pair's or the hind pair's) that most of them lie on. Where the slope changes
// between the front and the hind feet (a ramp's foot or top), the plane
// through the four feet is wrong for both rows, and a row's footholds reach
// a stride back onto the plane behind.
// A third plane per foot, its ground plane (groundNormal), is what the
// foot's friction cone is taken about where it differs from the global one.
#pragma once
#include <cstdint>

#include "firmware/controller/params.hpp"
#include "firmware/controller/model/types.hpp"

namespace hyq {

class TerrainEstimator {
 public:
  // Flat ground through `height` [m].
  void reset(double height);
  // Fit z = a x + b y + c through the feet in `mask` (W positions, columns).
  // Needs >= 3 feet that are not collinear; otherwise keeps the last plane
  // and returns false.
  // Also refits each leg's local plane: the plane of its row's feet and
  // their last footholds (LF-RF or LH-RH) that holds the most of them within
  // inlier_distance [m], through the leg's own foot (ties: the one that
  // holds the most feet), fitted to those it holds; with fewer than 3 row
  // points, a fit through all feet and footholds weighted
  // exp(-d^2 / 2 length^2), d the horizontal distance from that leg's foot.
  // local_length <= 0: the local planes are the global one. Only the rows
  // (LF-RF, LH-RH) with a leg in refit_legs get new local planes; the
  // others keep theirs. turn_margin > 0 [m]: a row whose two feet both lie
  // further than this off the plane of their footholds, on the same side,
  // and that no four of its points agree on, has crossed a slope change:
  // its plane is the one through its two feet that holds the horizontal
  // square to the walk (the walk: from the footholds to the feet); not
  // where the feet stand nearly side by side across the walk, nor where the
  // plane through all feet slopes across the walk (a change crossed at an
  // angle, or a hillside). No ground or turned plane steeper than
  // kMaxGroundTilt is taken.
  // turn_sets_ground: that turned plane is also the row's ground plane
  // (groundNormal) where no four points agree on one, and a row whose
  // standing feet all still lie on its last own ground plane keeps it.
  bool fit(const Mat3x4& feet_world, uint32_t mask, double local_length = 0.0,
           double inlier_distance = SlipParams{}.prior_inlier_distance, uint32_t refit_legs = 0xF,
           double turn_margin = 0.0, bool turn_sets_ground = false);
  const Vec3& normal() const { return normal_; }
  const Vec3& localNormal(int leg) const { return local_normal_[leg]; }
  // The plane through the leg's foot that at least four of its row's feet and
  // last footholds and the other row's feet lie on (within inlier_distance;
  // ties: the row's own points); where none does, the global plane as it
  // was at that fit, or the row's turned plane or last ground (fit's
  // turn_sets_ground). Refit with the local planes, at a touch-down of the
  // leg's row. Where the front and hind feet stand on different slopes it
  // is the one under the foot; where the foot has just crossed onto a new
  // slope no four points agree yet, and only a turned row knows the new
  // slope.
  const Vec3& groundNormal(int leg) const { return ground_normal_[leg]; }
  // The foot's surface prior: its local plane, or its ground plane where
  // the row's own points did not all lie on the local plane (three held it:
  // across a slope change, a blend of the two slopes) while four points of
  // both rows agree on the ground plane, the row did not turn, and the foot
  // lies off the plane of its row's footholds (their line and the
  // horizontal square to the walk) by more than inlier_distance. As of the
  // row's last refit (SlipParams::prior_agreed_ground).
  const Vec3& priorNormal(int leg) const { return prior_ground_[leg] ? ground_normal_[leg] : local_normal_[leg]; }
  // The leg's last row refit found no ground plane of its own (no four
  // points agreed, its row did not turn, its feet left its last own one):
  // the plane through all feet stands in for it, and at a slope change
  // that plane is a blend of the two slopes. False before any refit, and
  // without local planes (fit's local_length <= 0: every ground is the
  // feet's plane by choice).
  bool groundStandsIn(int leg) const { return ground_stands_in_[leg]; }
  // When a foot's prior is the plane of the feet (the trot's), where the
  // front and the hind feet stand on two slopes each takes its row's local
  // plane instead: where the two rows' local planes stand further apart
  // than `split` [rad] and the feet's plane lies inside the arc between
  // them, off their great circle by less than half the split and at least
  // `interior` of the way from each (as a ratio of sines). At a slope change
  // the feet's plane leans between the rows' slopes; a row whose footholds'
  // heights drifted tilts alone, with the feet's plane at the other row's.
  // The sines are taken once (RowSplit::of); split <= 0: never.
  struct RowSplit {
    double split_sine = 0.0, half_split_sine = 0.0, interior = 0.0;
    static RowSplit of(double split, double interior);
  };
  const Vec3& feetOrRowNormal(int leg, const RowSplit& rows) const;
  // A foot lifts off from where it stood: a point of the ground for the
  // local planes (the last kFootholdHistory per leg are kept).
  void recordLiftoff(int leg, const Vec3& foot_world);
  static constexpr int kFootholdHistory = 2;
  // Plane height [m] under (x, y).
  double heightAt(double x, double y) const { return a_ * x + b_ * y + c_; }

 private:
  // One leg's row refit (fit's local and ground planes).
  void fitRow(int leg, const Mat3x4& feet_world, uint32_t mask, double local_length, double inlier_distance,
              double turn_margin, bool turn_sets_ground);
  double a_ = 0.0, b_ = 0.0, c_ = 0.0;
  Vec3 normal_ = Vec3::UnitZ();
  Vec3 local_normal_[4] = {Vec3::UnitZ(), Vec3::UnitZ(), Vec3::UnitZ(), Vec3::UnitZ()};
  Vec3 ground_normal_[4] = {Vec3::UnitZ(), Vec3::UnitZ(), Vec3::UnitZ(), Vec3::UnitZ()};
  // A point of each leg's ground plane, and whether that plane is its own
  // (four points agreed, or its row turned) rather than the feet's.
  Vec3 ground_point_[4] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
  bool ground_own_[4] = {false, false, false, false};
  bool prior_ground_[4] = {false, false, false, false};  // priorNormal is the ground plane
  bool ground_stands_in_[4] = {false, false, false, false};  // groundStandsIn
  Vec3 history_[4][kFootholdHistory];  // valid up to history_count_
  int history_count_[4] = {0, 0, 0, 0};
  bool row_fit_[4] = {false, false, false, false};  // the local plane is its row's
};

// The trunk's attitude that lays it on ground of normal n (W), as the
// controller's terrain following holds it: the heading yaw [rad], then the
// pitch and roll that tilt it onto the ground, taken in the heading's frame
// (a slope across the walk rolls the trunk, one along it pitches it,
// whatever the heading), each at most max_tilt [rad].
Mat3 terrainAttitude(double yaw, const Vec3& n, double max_tilt);

}  // namespace hyq
