// The terrain generator (terrain.generate.seed): the same seed draws the
// same scenario; every draw keeps inside its distribution and obeys the
// walkability rule; the draws cover what the distribution promises (slopes
// down, up and across, both kinds of slope change, sudden patches, pushes,
// both gaits); the rule refuses a terrain it should; the reader's keys.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "sim_host/scenario/scenario.hpp"
#include "sim_host/scenario/terrain_generator.hpp"

namespace hyq::sim {
namespace {

Scenario drawn(uint64_t seed) {
  Scenario s;
  generateTerrain(seed, s);
  return s;
}

TEST(TerrainGenerator, TheSameSeedDrawsTheSameScenario) {
  for (uint64_t seed : {1ull, 77ull, 123456789ull}) {
    const Scenario a = drawn(seed), b = drawn(seed);
    EXPECT_EQ(a.duration, b.duration);
    EXPECT_EQ(a.start_yaw, b.start_yaw);
    EXPECT_EQ(a.controller_params.gait.speed, b.controller_params.gait.speed);
    EXPECT_EQ(a.terrain.mu, b.terrain.mu);
    ASSERT_EQ(a.terrain.ramps.size(), b.terrain.ramps.size());
    for (size_t i = 0; i < a.terrain.ramps.size(); ++i) EXPECT_EQ(a.terrain.ramps[i].angle, b.terrain.ramps[i].angle);
    ASSERT_EQ(a.terrain.patches.size(), b.terrain.patches.size());
    for (size_t i = 0; i < a.terrain.patches.size(); ++i) EXPECT_EQ(a.terrain.patches[i].mu, b.terrain.patches[i].mu);
    EXPECT_EQ(a.disturbances.size(), b.disturbances.size());
  }
  EXPECT_NE(drawn(1).terrain.mu, drawn(2).terrain.mu);
}

// Draw 17 as this stream and distribution give it, pinned (a change to
// either changes every set's terrains: the sets' figures must be run again).
TEST(TerrainGenerator, Draw17IsPinned) {
  const Scenario s = drawn(17);
  EXPECT_EQ(s.controller_params.gait.kind, GaitKind::kCrawl);
  EXPECT_NEAR(s.controller_params.gait.speed, 0.036, 0.0005);
  EXPECT_EQ(s.start_yaw, 0.0);
  EXPECT_NEAR(s.terrain.mu, 0.75, 0.005);
  ASSERT_EQ(s.terrain.ramps.size(), 2u);
  EXPECT_NEAR(s.terrain.ramps[0].x0, 2.05, 0.005);
  EXPECT_NEAR(s.terrain.ramps[1].angle, 0.210, 0.0005);
  ASSERT_EQ(s.terrain.patches.size(), 2u);
  EXPECT_NEAR(s.terrain.patches[0].mu, 0.214, 0.0005);
  EXPECT_NEAR(s.terrain.patches[1].mu, 0.100, 0.0005);
  ASSERT_EQ(s.disturbances.size(), 1u);
  EXPECT_NEAR(s.disturbances[0].t, 75.6, 0.05);
  EXPECT_NEAR(s.disturbances[0].force[1], -170.0, 0.5);
}

// 2000 draws: each inside the distribution and walkable; together covering it.
TEST(TerrainGenerator, EveryDrawIsInsideItsDistributionAndWalkable) {
  const TerrainDistribution& d = kTerrainDistribution;
  int trots = 0, down = 0, up = 0, across = 0, concave = 0, convex = 0, sudden = 0, pushes = 0, icy = 0;
  for (uint64_t seed = 1; seed <= 2000; ++seed) {
    const Scenario s = drawn(seed);
    const bool trot = s.controller_params.gait.kind == GaitKind::kTrot;
    trots += trot;
    const double v = s.controller_params.gait.speed;
    EXPECT_GE(v, trot ? d.trot_speed[0] : d.crawl_speed[0]) << seed;
    EXPECT_LE(v, trot ? d.trot_speed[1] : d.crawl_speed[1]) << seed;
    EXPECT_NEAR(s.duration, (trot ? d.trot_path : d.crawl_path) / v + d.settle, 1e-9) << seed;
    EXPECT_EQ(walkableTerrain(s), "") << seed;
    const double c = std::cos(s.start_yaw), sn = std::sin(s.start_yaw);
    double last = 0.0, last_end = -1e9;
    for (const Ramp& r : s.terrain.ramps) {
      const double g = std::tan(r.angle);
      const double along = std::atan(g * c), side = std::atan(std::fabs(g * sn));
      EXPECT_GE(along, d.along[0] - 1e-9) << seed;
      EXPECT_LE(along, d.along[1] + 1e-9) << seed;
      EXPECT_LE(side, d.across + 1e-9) << seed;
      down += along < -0.2;
      up += along > 0.25;
      across += side > 0.15;
      // Consecutive pieces: flat between two ramps counts as 0.
      const double before = std::fabs(r.x0 - last_end) < 1e-9 ? last : 0.0;
      concave += g > before + 0.1;
      convex += g < before - 0.1;
      last = g;
      last_end = r.x0 + r.length;
    }
    for (const FrictionPatch& p : s.terrain.patches) {
      EXPECT_GE(p.mu, d.mu[0]) << seed;
      EXPECT_LE(p.mu, d.mu[1]) << seed;
      EXPECT_LE(p.x0, p.x1);
      EXPECT_LE(p.y0, p.y1);
      sudden += std::isfinite(p.t0);
      icy += p.mu < 0.15;
    }
    EXPECT_GE(s.terrain.patches.size(), static_cast<size_t>(d.patches[0]));
    EXPECT_LE(s.terrain.patches.size(), static_cast<size_t>(d.patches[1]));
    for (const Disturbance& f : s.disturbances) {
      const double n = std::hypot(f.force[0], f.force[1]);
      EXPECT_GE(n, d.push_force[0] - 1e-9);
      EXPECT_LE(n, d.push_force[1] + 1e-9);
      EXPECT_NEAR(f.force[0] * c + f.force[1] * sn, 0.0, 1e-9) << "sideways";
      ++pushes;
    }
  }
  std::printf("2000 draws: %d trot, %d pieces down, %d up, %d across, %d concave and %d convex changes, "
              "%d sudden patches, %d icy (mu < 0.15), %d pushes\n",
              trots, down, up, across, concave, convex, sudden, icy, pushes);
  EXPECT_NEAR(trots / 2000.0, d.trot_share, 0.04);
  for (int n : {down, up, across, concave, convex, sudden, icy, pushes}) EXPECT_GT(n, 100);
}

TEST(TerrainGenerator, TheRuleRefusesFrictionUnderTheSlope) {
  Scenario s;
  s.terrain.mu = 0.8;
  s.terrain.ramps.push_back(Ramp{1.0, 0.3, 2.0});  // tan 0.3 = 0.309
  s.terrain.patches.push_back(FrictionPatch{1.5, 2.0, -1.0, 1.0, 0.35});
  EXPECT_NE(walkableTerrain(s).find("patch 0"), std::string::npos);  // 0.35 < 0.309 + 0.1
  s.terrain.patches[0].mu = 0.41;
  EXPECT_EQ(walkableTerrain(s), "");
  s.terrain.patches[0].x0 = 3.5;  // off the slope: flat ground
  s.terrain.patches[0].x1 = 4.0;
  s.terrain.patches[0].mu = 0.1;
  EXPECT_EQ(walkableTerrain(s), "");
  s.controller_params.gait.kind = GaitKind::kTrot;  // the trot's margin, 0.15
  EXPECT_NE(walkableTerrain(s), "");
  s.terrain.mu = 0.4;
  EXPECT_NE(walkableTerrain(s).find("ground"), std::string::npos);
}

TEST(TerrainGenerator, TheReaderDrawsAndRefusesMixedTerrains) {
  const std::string head = "name: g\nduration: 1\n";
  const Scenario s = parseScenario(head + "terrain: {generate: {seed: 17}}\n", "g.yaml");
  const Scenario t = drawn(17);
  EXPECT_EQ(s.terrain.generated_seed, 17u);
  EXPECT_EQ(s.terrain.mu, t.terrain.mu);
  EXPECT_EQ(s.duration, t.duration);
  EXPECT_EQ(s.start_yaw, t.start_yaw);
  EXPECT_EQ(s.terrain.patches.size(), t.terrain.patches.size());
  auto refused = [&](const std::string& body, const std::string& needle) {
    try {
      parseScenario(head + body, "bad.yaml");
    } catch (const ScenarioError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
      return;
    }
    ADD_FAILURE() << "accepted: " << body;
  };
  refused("terrain: {generate: {seed: 3}, mu: 0.5}\n", "not with terrain.generate");
  refused("terrain: {generate: {seed: 0}}\n", "terrain.generate.seed");
  refused("terrain: {generate: {seed: 2.5}}\n", "terrain.generate.seed");
  refused("terrain: {generate: {seed: 3, slope: 1}}\n", "slope");
}

}  // namespace
}  // namespace hyq::sim
