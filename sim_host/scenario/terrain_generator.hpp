// Terrains drawn from a seeded distribution (scenario key
// terrain.generate.seed): slopes along and across the walking direction,
// changes of slope of both kinds, friction patches of random size, place
// and friction (some appearing suddenly), pushes, and the gait's speed. The
// draws come from the code's own stream (splitmix64, one draw per
// statement), not the standard library's distributions: the same seed
// draws the same scenario from the same build. They pass through the maths
// library's tan, atan, sin, cos, exp and log, which another library may
// round differently in the last bit. Only terrains the robot can
// physically walk are drawn: walkableTerrain states the rule.
#pragma once
#include <cstdint>
#include <string>

#include "sim_host/scenario/scenario.hpp"

namespace hyq::sim {

// The distribution, each bound with its unit.
struct TerrainDistribution {
  double trot_share = 0.25;              // [-] of the draws that trot; the others crawl
  double crawl_speed[2] = {0.03, 0.08};  // [m/s]
  double trot_speed[2] = {0.2, 0.5};     // [m/s]
  double along[2] = {-0.3, 0.35};        // [rad] slope along the walking direction, per piece
  double across = 0.2;                   // [rad] largest slope across it
  double straight_share = 0.5;           // [-] of the draws that walk straight up the profile (no slope across)
  int max_ramps = 3;                     // [-] sloped pieces after the start's, 1..3
  double ramp_length[2] = {0.8, 2.0};    // [m] each piece's extent in x
  double mu[2] = {0.08, 0.9};            // [-] a patch's friction, log-uniform
  double ground_mu[2] = {0.5, 0.9};      // [-] the ground's outside the patches
  int patches[2] = {2, 5};               // [-] patches on the path
  double patch_length[2] = {0.3, 1.5};   // [m] along x
  double patch_width[2] = {0.4, 2.5};    // [m] along y
  double patch_offset = 0.3;             // [m] largest offset of a patch's centre from the path
  double sudden_share = 0.2;             // [-] of the draws where one patch appears suddenly, at a drawn time
  double sudden_duration[2] = {2.0, 10.0};  // [s] how long it stays
  double push_share = 0.3;               // [-] of the draws with a sideways push
  double push_force[2] = {100.0, 200.0};  // [N]
  double push_duration = 0.2;            // [s]
  double crawl_path = 3.0;               // [m] walked, crawling
  double trot_path = 5.0;                // [m] walked, trotting
  double settle = 10.0;                  // [s] added to path / speed: the start and the last steps
  // The walkability rule's margin of friction over the steepest gradient
  // under a patch (|tan| of the steepest slope, any direction), where the
  // gait stands still on three feet (crawl) or two (trot).
  double crawl_margin = 0.1;             // [-]
  double trot_margin = 0.15;             // [-]
};
inline constexpr TerrainDistribution kTerrainDistribution{};

// Fills `s`'s terrain, start pose, gait kind and speed, disturbances and
// duration from draw `seed`; everything else in `s` stays.
void generateTerrain(uint64_t seed, Scenario& s, const TerrainDistribution& d = kTerrainDistribution);

// The rule: every place the feet can stand has friction at least the
// steepest ground gradient there plus the gait's margin
// (TerrainDistribution::crawl_margin, trot_margin), the gradient being the
// ground's |tan| of its slope (along and across combined). Checked for the
// ground and for each patch over the pieces it overlaps. Returns "" when it
// holds, else what breaks it.
std::string walkableTerrain(const Scenario& s, const TerrainDistribution& d = kTerrainDistribution);

}  // namespace hyq::sim
