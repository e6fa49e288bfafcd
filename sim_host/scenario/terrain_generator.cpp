#include "sim_host/scenario/terrain_generator.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace hyq::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;

// splitmix64: the same stream on every machine and compiler.
class Draw {
 public:
  // The seed mixed first: consecutive seeds start far apart in the stream
  // (seed k + 1 would otherwise be seed k one draw on).
  explicit Draw(uint64_t seed) : state_(mix(seed ^ 0x632BE59BD9B4E5ULL)) {}
  uint64_t next() { return mix(state_ += 0x9E3779B97F4A7C15ULL); }
  double uniform() { return static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0); }  // [0, 1)
  double in(const double (&range)[2]) { return range[0] + (range[1] - range[0]) * uniform(); }
  double in(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  int count(const int (&range)[2]) { return range[0] + static_cast<int>(next() % (range[1] - range[0] + 1)); }
  bool chance(double p) { return uniform() < p; }

 private:
  static uint64_t mix(uint64_t z) {
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  uint64_t state_;
};

// The ground's steepest |gradient| over x in [x0, x1]: the pieces the
// range overlaps, flat ground 0.
double steepestGradient(const TerrainSpec& t, double x0, double x1) {
  double g = 0.0;
  for (const Ramp& r : t.ramps)
    if (r.x0 < x1 && r.x0 + r.length > x0) g = std::max(g, std::fabs(std::tan(r.angle)));
  return g;
}

// World gradient (tan of the slope along +x) of a piece whose slope along
// the heading psi is drawn from d.along, its slope across the heading at
// most d.across.
double pieceGradient(Draw& draw, double psi, const TerrainDistribution& d) {
  const double c = std::cos(psi), s = std::sin(psi), across = std::tan(d.across);
  if (std::fabs(c) < 0.2) return draw.in(-across, across) / std::max(std::fabs(s), 1e-9);
  double g = std::tan(draw.in(d.along)) / c;
  if (std::fabs(g * s) > across) g = std::copysign(across / std::fabs(s), g);
  return g;
}

void drawProfile(Draw& draw, double psi, const TerrainDistribution& d, TerrainSpec& t) {
  // The start's piece reaches 4 m behind the robot; flat in 40 % of the
  // draws, else sloped like the rest (a start on a slope or a hillside).
  double x = -4.0;
  const double start_length = 4.0 + draw.in(0.5, 1.5);
  const double g0 = draw.chance(0.4) ? 0.0 : pieceGradient(draw, psi, d);
  if (g0 != 0.0) t.ramps.push_back(Ramp{x, std::atan(g0), start_length});
  x += start_length;
  const int n = 1 + static_cast<int>(draw.next() % static_cast<uint64_t>(d.max_ramps));
  for (int i = 0; i < n; ++i) {
    const double length = draw.in(d.ramp_length);
    const double g = draw.chance(0.2) ? 0.0 : pieceGradient(draw, psi, d);
    if (g != 0.0) t.ramps.push_back(Ramp{x, std::atan(g), length});
    x += length;
  }
}

void drawPatches(Draw& draw, double psi, double path, double margin, double duration,
                 const TerrainDistribution& d, TerrainSpec& t) {
  const double hx = std::cos(psi), hy = std::sin(psi);
  const int n = draw.count(d.patches);
  for (int i = 0; i < n; ++i) {
    const double s = draw.in(0.6, path), off = draw.in(-d.patch_offset, d.patch_offset);
    const double cx = s * hx - off * hy, cy = s * hy + off * hx;
    const double lx = draw.in(d.patch_length), ly = draw.in(d.patch_width);
    // Log-uniform: as many patches between 0.08 and 0.27 as between 0.27 and 0.9.
    const double mu = std::exp(draw.in(std::log(d.mu[0]), std::log(d.mu[1])));
    FrictionPatch p{cx - 0.5 * lx, cx + 0.5 * lx, cy - 0.5 * ly, cy + 0.5 * ly, std::min(mu, d.mu[1])};
    p.mu = std::max(p.mu, steepestGradient(t, p.x0, p.x1) + margin);
    t.patches.push_back(p);
  }
  if (!t.patches.empty() && draw.chance(d.sudden_share)) {
    FrictionPatch& p = t.patches[draw.next() % t.patches.size()];
    p.t0 = draw.in(5.0, std::max(5.0, 0.5 * duration));
    p.t1 = p.t0 + draw.in(d.sudden_duration);
  }
}

double marginOf(const Scenario& s, const TerrainDistribution& d) {
  return s.controller_params.gait.kind == GaitKind::kTrot ? d.trot_margin : d.crawl_margin;
}

}  // namespace

void generateTerrain(uint64_t seed, Scenario& s, const TerrainDistribution& d) {
  Draw draw(seed);
  GaitParams& gait = s.controller_params.gait;
  const bool trot = draw.chance(d.trot_share);
  gait.kind = trot ? GaitKind::kTrot : GaitKind::kCrawl;
  gait.speed = draw.in(trot ? d.trot_speed : d.crawl_speed);
  const double path = trot ? d.trot_path : d.crawl_path;
  s.duration = path / gait.speed + d.settle;
  const double psi = draw.chance(d.straight_share) ? 0.0 : draw.in(-0.5 * kPi, 0.5 * kPi);
  s.start_x = 0.0;
  s.start_y = 0.0;
  s.start_yaw = psi;

  TerrainSpec t;
  drawProfile(draw, psi, d, t);
  const double margin = marginOf(s, d);
  double steepest = 0.0;
  for (const Ramp& r : t.ramps) steepest = std::max(steepest, std::fabs(std::tan(r.angle)));
  t.mu = std::max(draw.in(d.ground_mu), steepest + margin);
  drawPatches(draw, psi, path, margin, s.duration, d, t);
  s.terrain = t;

  s.disturbances.clear();
  if (draw.chance(d.push_share)) {
    // One draw per statement: the stream's order is the code's, whatever the compiler.
    const double size = draw.in(d.push_force);
    const double f = draw.chance(0.5) ? size : -size;
    const double t = draw.in(5.0, std::max(5.0, s.duration - 5.0));
    s.disturbances.push_back(Disturbance{t, d.push_duration, {-f * std::sin(psi), f * std::cos(psi), 0.0}});
  }
}

std::string walkableTerrain(const Scenario& s, const TerrainDistribution& d) {
  const double margin = marginOf(s, d);
  char why[160];
  const double ground = steepestGradient(s.terrain, -1e9, 1e9);
  if (s.terrain.mu < ground + margin) {
    std::snprintf(why, sizeof why, "ground mu %.3f under gradient %.3f + margin %.2f", s.terrain.mu, ground, margin);
    return why;
  }
  for (size_t i = 0; i < s.terrain.patches.size(); ++i) {
    const FrictionPatch& p = s.terrain.patches[i];
    const double g = steepestGradient(s.terrain, p.x0, p.x1);
    if (p.mu < g + margin) {
      std::snprintf(why, sizeof why, "patch %zu mu %.3f under gradient %.3f + margin %.2f", i, p.mu, g, margin);
      return why;
    }
  }
  return "";
}

}  // namespace hyq::sim
