#include "firmware/controller/state/terrain_estimator.hpp"

#include <cmath>

namespace hyq {

namespace {

constexpr int kMaxPoints = 4 + 4 * TerrainEstimator::kFootholdHistory;

// A row's candidate plane is defined by a triangle of at least this
// twice-area (0.1 m x 0.1 m); smaller ones tilt with millimetres of noise.
constexpr double kMinTriangleArea2 = 0.01;  // [m^2]
// The square-on plane of a row across a slope change needs its two feet
// this far from side by side: the sine of the angle between their line and
// the row's lateral direction (the crawl's front feet are 0.2 m apart along
// the walk, 0.66 m across: 0.29).
constexpr double kMinRowTurnSine = 0.15;  // [-]
// ... and the feet this far ahead of their footholds (a step).
constexpr double kMinRowTurnWalk = 0.05;  // [m]
// ... and the plane through all feet level across the walk
// (kMaxRowTurnCrossSine, params.hpp).
// A row's points: two feet and the last foothold of each.
constexpr int kRowPoints = 4;
// The ground plane's candidates: the row's points and the other row's two feet.
constexpr int kCandidatePoints = kRowPoints + 2;

// Weighted least-squares plane z = a x + b y + c through `n` points
// (normal equations, centred for conditioning). False when the points are
// (nearly) collinear or the weights vanish.
bool fitPlane(const Vec3* points, const double* weights, int n, double& a, double& b, double& c) {
  double w_sum = 0.0;
  Vec3 mean = Vec3::Zero();
  for (int k = 0; k < n; ++k) {
    w_sum += weights[k];
    mean += weights[k] * points[k];
  }
  if (!(w_sum > 0.0)) return false;
  mean /= w_sum;
  double sxx = 0.0, sxy = 0.0, syy = 0.0, sxz = 0.0, syz = 0.0;
  for (int k = 0; k < n; ++k) {
    const Vec3 d = points[k] - mean;
    const double w = weights[k];
    sxx += w * d.x() * d.x();
    sxy += w * d.x() * d.y();
    syy += w * d.y() * d.y();
    sxz += w * d.x() * d.z();
    syz += w * d.y() * d.z();
  }
  const double det = sxx * syy - sxy * sxy;
  // Collinear points (or all at one point): the plane is not defined.
  const double scale = sxx + syy;
  if (!(scale > 1e-8 * w_sum) || std::fabs(det) < 1e-6 * scale * scale) return false;
  const double a_new = (syy * sxz - sxy * syz) / det;
  const double b_new = (sxx * syz - sxy * sxz) / det;
  if (!std::isfinite(a_new) || !std::isfinite(b_new)) return false;
  a = a_new;
  b = b_new;
  c = mean.z() - a_new * mean.x() - b_new * mean.y();
  return true;
}

// Whether the points flagged in `inlier`, points[0] left out, include a
// triangle of twice-area kMinTriangleArea2 or more.
bool spansATriangle(const Vec3* points, const bool* inlier, int m) {
  for (int a = 1; a < m; ++a)
    for (int b = a + 1; b < m; ++b)
      for (int c = b + 1; c < m; ++c)
        if (inlier[a] && inlier[b] && inlier[c] &&
            (points[b] - points[a]).cross(points[c] - points[a]).norm() >= kMinTriangleArea2)
          return true;
  return false;
}

// The most-inliers search of consensusPlane over the planes through d[0]
// (zero: points[0] itself) and two more of the `m` points, from d[k] =
// points[k] - points[0], M of them (known when compiled: the loops unroll).
// The three points that define a candidate are not tested: they lie on it
// (cross . d[a] and cross . d[b] are rounding, under 1e-15 m^3 against a
// tolerance of at least 1e-2 m^2 times inlier_distance). The answer is the
// one a test of every point gives.
template <int M>
HYQ_INLINE void searchPlanes(const Vec3* d, const int* recency, double inlier_distance, int& best_count,
                             int& best_recency, bool* best_inlier) {
#pragma GCC unroll 6
  for (int a = 1; a < M; ++a)
#pragma GCC unroll 6
    for (int b = a + 1; b < M; ++b) {
      const Vec3 cross = d[a].cross(d[b]);
      const double area2 = cross.norm();
      // A plane needs a triangle of some size, and one far from vertical
      // (and finite points: a NaN fails both).
      if (!(area2 >= kMinTriangleArea2) || !(std::fabs(cross.z()) >= 0.5 * area2)) continue;
      // |n . d| < tol with n = cross / |cross|, without the division.
      const double tolerance = inlier_distance * area2;
      int count = 0, rec = 0;
      bool inlier[kCandidatePoints] = {};
#pragma GCC unroll 6
      for (int k = 0; k < M; ++k) {
        inlier[k] = k == 0 || k == a || k == b || std::fabs(cross.dot(d[k])) < tolerance;
        count += inlier[k] ? 1 : 0;
        rec += inlier[k] ? recency[k] : 0;
      }
      if (count > best_count || (count == best_count && rec > best_recency)) {
        best_count = count;
        best_recency = rec;
        for (int k = 0; k < M; ++k) best_inlier[k] = inlier[k];
      }
    }
}

// The plane through points[0] that holds the most of the points within
// inlier_distance (ties: the most of weight `recency`, then the first
// found), fitted to those it holds. False when it holds fewer than
// min_inliers (and at least 3), or, for four or more, when the points it
// holds besides points[0] lie on one line: a line and a point always share
// a plane. (The crawl's feet and footholds of one side lie along the walk:
// with them, a foot on a new slope found a plane rolled toward that side.)
bool consensusPlane(const Vec3* points, const int* recency, int m, double inlier_distance, int min_inliers,
                    Vec3& normal, int* inlier_count = nullptr) {
  if (m < min_inliers || m < 3) return false;
  Vec3 d[kCandidatePoints];
  for (int k = 0; k < m; ++k) d[k] = points[k] - points[0];
  int best_count = 0, best_recency = -1;
  bool best_inlier[kCandidatePoints] = {};
  static_assert(kCandidatePoints == 6, "one search per point count, 3 to 6");
  switch (m) {
    case 3: searchPlanes<3>(d, recency, inlier_distance, best_count, best_recency, best_inlier); break;
    case 4: searchPlanes<4>(d, recency, inlier_distance, best_count, best_recency, best_inlier); break;
    case 5: searchPlanes<5>(d, recency, inlier_distance, best_count, best_recency, best_inlier); break;
    default: searchPlanes<6>(d, recency, inlier_distance, best_count, best_recency, best_inlier); break;
  }
  if (inlier_count != nullptr) *inlier_count = best_count;
  if (best_count < min_inliers || best_count < 3) return false;
  if (min_inliers >= 4 && !spansATriangle(points, best_inlier, m)) return false;
  Vec3 inliers[kCandidatePoints];
  double ones[kCandidatePoints];
  int q = 0;
  for (int k = 0; k < m; ++k)
    if (best_inlier[k]) {
      inliers[q] = points[k];
      ones[q++] = 1.0;
    }
  double a = 0.0, b = 0.0, c = 0.0;
  if (!fitPlane(inliers, ones, q, a, b, c)) return false;
  normal = Vec3(-a, -b, 1.0).normalized();
  return true;
}

// Ground no steeper than kMaxGroundTilt: a plane steeper than the robot is
// specified to walk is a wrong fit.
bool walkable(const Vec3& normal) { return normal.z() >= kCosMaxGroundTilt; }

// The horizontal square to a row's walk, from its footholds (p, q) to its
// feet (a, b); false where the row has hardly moved.
bool walkAcross(const Vec3& a, const Vec3& b, const Vec3& p, const Vec3& q, Vec3& across) {
  Vec3 walk = 0.5 * (a + b - p - q);
  walk.z() = 0.0;
  if (walk.norm() < kMinRowTurnWalk) return false;
  across = Vec3::UnitZ().cross(walk).normalized();
  return true;
}

// The plane that holds a pair's line and the horizontal `across`, its
// normal up; false where the line is near that horizontal (the pair side
// by side) or the plane steep.
bool pairPlane(const Vec3& line, const Vec3& across, Vec3& n) {
  n = line.cross(across);
  const double size = n.norm();
  if (!(size >= kMinRowTurnSine * line.norm()) || std::fabs(n.z()) < 0.5 * size) return false;
  n = (n.z() > 0.0 ? 1.0 : -1.0) * n / size;
  return true;
}

// The plane of a pair of feet (a, b) that have crossed a slope change
// square to the walk, from their footholds (p, q): both planes hold the
// horizontal square to the walk (the footholds' pair to the feet's); the
// feet's plane is taken when both feet lie off the footholds' plane by more
// than `margin` [m], on the same side. False where that does not
// hold, or a pair's line is near that horizontal (feet side by side), or
// a plane is steep (the feet's: steeper than kMaxGroundTilt), or the plane
// through all feet (`feet_normal`) does not hold that horizontal.
// `witnessed`: every foot of the other row (`others`, `n_others` of them)
// lies on one of the two planes (kMaxRowTurnOtherRowDistance, params.hpp):
// on a change crossed square-on the other row stands on the slope behind
// or the one ahead.
bool squareOnTurn(const Vec3& a, const Vec3& b, const Vec3& p, const Vec3& q, const Vec3& feet_normal,
                  const Vec3* others, int n_others, double margin, Vec3& normal, bool& witnessed) {
  Vec3 across;
  if (!walkAcross(a, b, p, q, across)) return false;
  // Both slopes of a change crossed square-on hold that horizontal, so
  // their blend, the plane through all feet, holds it too. Where it slopes
  // across the walk instead (a change crossed at an angle, or a hillside),
  // the model does not hold: the height between the feet would read as
  // slope along the walk.
  if (!(std::fabs(feet_normal.dot(across)) <= kMaxRowTurnCrossSine)) return false;
  Vec3 old_normal, new_normal;
  if (!pairPlane(q - p, across, old_normal) || !pairPlane(b - a, across, new_normal) || !walkable(new_normal))
    return false;
  const double off_a = (a - p).dot(old_normal), off_b = (b - p).dot(old_normal);
  if (std::fabs(off_a) <= margin || std::fabs(off_b) <= margin || off_a * off_b <= 0.0)
    return false;
  witnessed = true;
  for (int k = 0; k < n_others; ++k)
    if (!(std::fabs((others[k] - a).dot(new_normal)) <= kMaxRowTurnOtherRowDistance ||
          std::fabs((others[k] - p).dot(old_normal)) <= kMaxRowTurnOtherRowDistance))
      witnessed = false;
  normal = new_normal;
  return true;
}

// Whether foot `a` of a row (partner foot `b`, footholds p and q) lies off
// the plane its footholds stand on (the one that holds their line and the
// horizontal square to the walk) by more than `margin` [m]: it has stepped
// past a change of slope. False where that plane is not known (the row
// hardly moved, or its footholds stand side by side). On a hillside that
// plane reads the slope across as slope along, and every foot lies off it
// (docs/design-notes.md, "The prior at a change of slope").
bool footLeftFootholdsPlane(const Vec3& a, const Vec3& b, const Vec3& p, const Vec3& q, double margin) {
  Vec3 across, old_normal;
  if (!walkAcross(a, b, p, q, across) || !pairPlane(q - p, across, old_normal)) return false;
  return std::fabs((a - p).dot(old_normal)) > margin;
}

}  // namespace

void TerrainEstimator::reset(double height) {
  a_ = 0.0;
  b_ = 0.0;
  c_ = height;
  normal_ = Vec3::UnitZ();
  for (int i = 0; i < 4; ++i) {
    local_normal_[i] = normal_;
    ground_normal_[i] = normal_;
    ground_point_[i].setZero();
    ground_own_[i] = false;
    ground_stands_in_[i] = false;
    prior_ground_[i] = false;
    for (int k = 0; k < kFootholdHistory; ++k) history_[i][k].setZero();
    history_count_[i] = 0;
  }
}

void TerrainEstimator::recordLiftoff(int leg, const Vec3& foot_world) {
  if (leg < 0 || leg >= 4 || !foot_world.allFinite()) return;
  for (int k = kFootholdHistory - 1; k > 0; --k) history_[leg][k] = history_[leg][k - 1];
  history_[leg][0] = foot_world;
  if (history_count_[leg] < kFootholdHistory) ++history_count_[leg];
}

bool TerrainEstimator::fit(const Mat3x4& feet_world, uint32_t mask, double local_length,
                           double inlier_distance, uint32_t refit_legs, double turn_margin,
                           bool turn_sets_ground) {
  Vec3 points[kMaxPoints];
  double weights[kMaxPoints];
  int n = 0;
  for (int i = 0; i < 4; ++i) {
    if (!(mask & (1u << i))) continue;
    points[n] = feet_world.col(i);
    weights[n] = 1.0;
    ++n;
  }
  if (n < 3) return false;
  double a = 0.0, b = 0.0, c = 0.0;
  if (!fitPlane(points, weights, n, a, b, c)) return false;
  a_ = a;
  b_ = b;
  c_ = c;
  normal_ = Vec3(-a, -b, 1.0).normalized();
  // Local planes. First choice: the plane of the leg's own row (the two
  // front or the two hind legs) that holds the most of the row's feet and
  // their last footholds, through the leg's own foot. A foothold lies a
  // stride back, so where the slope changes (a ramp's foot, its top) some
  // lie on the plane behind: a least-squares plane through all of them is
  // tilted between the two, the consensus plane is the one the foot is on.
  // Only the last foothold per leg: older ones were placed by an odometry
  // that slips since may have moved, and enough of them can outvote the feet.
  // A row's points change when one of its feet touches down: only those
  // rows are refit (the two searches cost up to 3.5k instructions a leg on
  // the board).
  bool refit[4];
  for (int leg = 0; leg < 4; ++leg) refit[leg] = ((refit_legs >> leg) | (refit_legs >> (leg ^ 1))) & 1u;
  for (int leg = 0; leg < 4; ++leg)
    if (refit[leg]) fitRow(leg, feet_world, mask, local_length, inlier_distance, turn_margin, turn_sets_ground);
  // Otherwise (too few footholds yet): the feet above and every recorded
  // foothold, weighted by their horizontal distance from each foot in turn.
  for (int i = 0; i < 4; ++i)
    for (int k = 0; k < history_count_[i]; ++k) points[n++] = history_[i][k];
  for (int leg = 0; leg < 4; ++leg) {
    if (!refit[leg] || !(local_length > 0.0) || row_fit_[leg]) continue;
    const Vec3& at = feet_world.col(leg);
    for (int k = 0; k < n; ++k) {
      const double dx = points[k].x() - at.x(), dy = points[k].y() - at.y();
      weights[k] = std::exp(-(dx * dx + dy * dy) / (2.0 * local_length * local_length));
    }
    double al = 0.0, bl = 0.0, cl = 0.0;
    if (fitPlane(points, weights, n, al, bl, cl)) local_normal_[leg] = Vec3(-al, -bl, 1.0).normalized();
  }
  return true;
}

// Leg `leg`'s local plane and ground plane from its row's feet and
// footholds (and the other row's feet), at a touch-down in its row.
void TerrainEstimator::fitRow(int leg, const Mat3x4& feet_world, uint32_t mask, double local_length,
                              double inlier_distance, double turn_margin, bool turn_sets_ground) {
  const Vec3 last_ground = ground_normal_[leg], last_ground_point = ground_point_[leg];
  const bool last_ground_own = ground_own_[leg];
  const Vec3 last_local = local_normal_[leg];
  local_normal_[leg] = normal_;
  ground_normal_[leg] = normal_;
  ground_own_[leg] = false;
  ground_stands_in_[leg] = false;
  row_fit_[leg] = false;
  prior_ground_[leg] = false;
  if (!(local_length > 0.0)) return;
  Vec3 row[kCandidatePoints];
  int recency[kCandidatePoints];  // 1: a foot of the row now, 0: a foothold or the other row's foot
  int m = 0;
  for (int i : {leg, leg ^ 1}) {  // LF-RF, LH-RH
    if (mask & (1u << i)) {
      row[m] = feet_world.col(i);
      recency[m++] = 1;
    }
    if (history_count_[i] > 0) {
      row[m] = history_[i][0];
      recency[m++] = 0;
    }
  }
  Vec3 normal;
  int row_inliers = 0;
  bool turned = false;
  row_fit_[leg] = consensusPlane(row, recency, m, inlier_distance, 3, normal, &row_inliers);
  if (row_fit_[leg]) local_normal_[leg] = normal;
  // The other row's feet after the row's points: the turn's witnesses and
  // the ground plane's further candidates.
  const int row_points = m;
  for (int i : {leg ^ 2, leg ^ 3})
    if (mask & (1u << i)) {
      row[m] = feet_world.col(i);
      recency[m++] = 0;
    }
  // Both feet of the row off the plane their footholds lie on, on the same
  // side: the row has crossed a slope change, and the three points the
  // consensus holds are a blend of the two slopes (the front feet's first
  // steps onto a ramp: 12.4 deg for 14.3). Taken as a change crossed
  // square-on (a ramp's foot or top across the walk): each plane holds its
  // pair's line and the horizontal square to the walk, the old one the
  // footholds', the new one the feet's (SlipParams::prior_turn_margin).
  if (turn_margin > 0.0 && row_fit_[leg] && row_inliers == 3 && row_points == 4 && recency[0] == 1 &&
      recency[2] == 1) {
    Vec3 square;
    // A turn onto the row's prior as its last fit left it is taken whatever
    // the other row's feet say: at a ramp's top the front row turns again,
    // onto the same plane, once its footholds are on the slope.
    bool witnessed = false;
    if (squareOnTurn(row[0], row[2], row[1], row[3], normal_, row + row_points, m - row_points, turn_margin, square,
                     witnessed) &&
        (witnessed || square.dot(last_local) >= kCosRowTurnKeptAngle)) {
      local_normal_[leg] = square;
      turned = true;
    }
  }
  // The ground plane: the same search with the other row's feet added
  // (their ties lose to the row's own points), and only a plane that four
  // of the points lie on. Three points always define a plane, and at a
  // slope change a plane through points of both sides is a blend of the
  // two; four agreeing points seldom are. None (turn_sets_ground): the
  // row's turned plane where it turned (the new slope: at a ramp's foot
  // the plane through all feet is a blend of the two), or the row's last
  // own ground where its standing feet all still lie on it (within
  // inlier_distance: the row's next steps up a new slope, before four
  // points agree); else the plane through all feet as it is at this fit
  // (kept until the row's next touch-down; taking the current one instead
  // left fewer loaded slips to estimate from on the ramp,
  // docs/design-notes.md).
  if (consensusPlane(row, recency, m, inlier_distance, 4, normal) && walkable(normal)) {
    ground_normal_[leg] = normal;
    ground_own_[leg] = true;
    // Four row points are the row's two feet, each after its foothold.
    prior_ground_[leg] = row_fit_[leg] && row_points == 4 && row_inliers < 4 && !turned &&
                         footLeftFootholdsPlane(row[0], row[2], row[1], row[3], inlier_distance);
  } else if (turn_sets_ground && turned) {
    ground_normal_[leg] = local_normal_[leg];
    ground_own_[leg] = true;
  } else if (turn_sets_ground && last_ground_own && recency[0] == 1) {
    bool on_last = true;
    for (int k = 0; k < row_points; ++k)
      if (recency[k] == 1 && !(std::fabs((row[k] - last_ground_point).dot(last_ground)) < inlier_distance))
        on_last = false;
    if (on_last) {
      ground_normal_[leg] = last_ground;
      ground_own_[leg] = true;
    }
  }
  ground_point_[leg] = ground_own_[leg] ? row[0] : Vec3(Vec3::Zero());
  ground_stands_in_[leg] = !ground_own_[leg];
}

TerrainEstimator::RowSplit TerrainEstimator::RowSplit::of(double split, double interior) {
  RowSplit rows;
  if (split > 0.0) {
    rows.split_sine = std::sin(split);
    rows.half_split_sine = std::sin(0.5 * split);
  }
  rows.interior = interior;
  return rows;
}

const Vec3& TerrainEstimator::feetOrRowNormal(int leg, const RowSplit& rows) const {
  if (!(rows.split_sine > 0.0)) return normal_;
  const Vec3& own = local_normal_[leg];
  const Vec3& other = local_normal_[leg ^ 2];  // LF <-> LH, RF <-> RH: the other row
  const Vec3 pole = own.cross(other);
  const double apart_sine = pole.norm();
  const double apart_cosine = own.dot(other);
  if (!(apart_sine > rows.split_sine) || !(apart_cosine > 0.0)) return normal_;
  const double least = rows.interior * apart_sine;
  const bool inside = std::fabs(normal_.dot(pole)) < rows.half_split_sine * apart_sine &&
                      normal_.dot(own) >= apart_cosine && normal_.dot(other) >= apart_cosine &&
                      normal_.cross(own).norm() >= least && normal_.cross(other).norm() >= least;
  return inside ? own : normal_;
}

Mat3 terrainAttitude(double yaw, const Vec3& n, double max_tilt) {
  const Eigen::Quaterniond heading(Eigen::AngleAxisd(yaw, Vec3::UnitZ()));
  // The normal in the heading's frame: x ahead, y to the left.
  const Vec3 n_h = heading.conjugate() * n;
  const double pitch = clampAbs(std::atan2(n_h.x(), n_h.z()), max_tilt);
  const double roll = clampAbs(std::atan2(-n_h.y(), n_h.z()), max_tilt);
  return (heading * Eigen::AngleAxisd(pitch, Vec3::UnitY()) * Eigen::AngleAxisd(roll, Vec3::UnitX()))
      .toRotationMatrix();
}

}  // namespace hyq
