// The friction map against the truth (summary.json's "friction_map" and
// friction_map.json), from synthetic ticks whose telemetry writes cells.
#include "sim_host/records/friction_map_record.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>

#include "sim_host/physics/terrain.hpp"
#include "sim_host/scenario/scenario.hpp"
#include "tests/sim/test_files.hpp"

namespace hyq::sim {
namespace {

TerrainSpec iceStrip() {
  TerrainSpec t;
  t.mu = 0.8;
  t.patches.push_back({1.0, 2.0, -2.0, 2.0, 0.2});
  return t;
}

// A tick at `time` with the base truly at (bx, by); the controller's world
// origin is at x = 1 in the simulator's.
TickRecord tickAt(double time, double bx, double by) {
  TickRecord r;
  r.time = time;
  r.base_pos = {bx, by, 0.6};
  r.command.telemetry.base_pos_est[0] = bx - 1.0;
  r.command.telemetry.base_pos_est[1] = by;
  for (int leg = 0; leg < 4; ++leg) {
    r.feet[leg].position = {bx + (leg < 2 ? 0.37 : -0.37), by + (leg % 2 ? -0.33 : 0.33), 0.0};
    r.feet[leg].mu = 0.8;
  }
  return r;
}

void write(TickRecord& r, int leg, int ix, int iy, uint32_t count, double mu, double spread, double true_mu) {
  r.command.telemetry.map_writes[leg] = {{ix, iy}, count, mu, spread};
  r.feet[leg].mu = true_mu;
}

TEST(FrictionMapRecord, EachCellsLastStateSitsBesideTheTruthUnderItsFeetAndAtItsCentre) {
  const Terrain terrain(iceStrip());
  FrictionMapRecord record(0.25, terrain, "");
  TickRecord r = tickAt(0.0, 0.0, 0.0);
  record.onTick(r);                              // no write
  r = tickAt(1.0, 0.5, 0.0);
  write(r, 0, 1, 1, 1, 0.21, 0.0, 0.2);          // cell (1, 1): centre (1 + 0.375, 0.375): on the ice
  write(r, 2, -3, 0, 1, 0.9, 0.0, 0.8);          // cell (-3, 0): centre (0.375, 0.125): off it
  record.onTick(r);
  r = tickAt(2.0, 0.6, 0.0);
  write(r, 1, 1, 1, 2, 0.23, 0.028, 0.25);       // the same cell, a second estimate
  record.onTick(r);
  record.onFinish();

  EXPECT_EQ(record.writes(), 3);
  ASSERT_EQ(record.cells().size(), 2u);
  const FrictionMapRecord::Cell& ice = record.cells().at({1, 1});
  EXPECT_DOUBLE_EQ(ice.x, 1.375);
  EXPECT_DOUBLE_EQ(ice.y, 0.375);
  EXPECT_EQ(ice.count, 2);
  EXPECT_DOUBLE_EQ(ice.mu, 0.23);
  EXPECT_DOUBLE_EQ(ice.spread, 0.028);
  EXPECT_DOUBLE_EQ(ice.time, 2.0);
  EXPECT_DOUBLE_EQ(ice.true_mu, 0.225);          // the mean of 0.2 and 0.25 under the writing feet
  EXPECT_DOUBLE_EQ(ice.true_mu_centre, 0.2);
  EXPECT_NEAR(FrictionMapRecord::errorPct(ice), 100.0 * 0.005 / 0.225, 1e-9);
  const FrictionMapRecord::Cell& grip = record.cells().at({-3, 0});
  EXPECT_DOUBLE_EQ(grip.x, 0.375);
  EXPECT_DOUBLE_EQ(grip.true_mu_centre, 0.8);
  EXPECT_NEAR(FrictionMapRecord::errorPct(grip), 12.5, 1e-9);

  const SummaryFields f = record.summaryFields();
  ASSERT_EQ(f.size(), 1u);
  EXPECT_EQ(f[0].first, "friction_map");
  const YAML::Node map = YAML::Load(f[0].second);
  EXPECT_EQ(map["writes"].as<int>(), 3);
  EXPECT_NEAR(map["error_max_pct"].as<double>(), 12.5, 1e-6);
  EXPECT_EQ(map["within_10pct"].as<int>(), 1);
  EXPECT_EQ(map["within_15pct"].as<int>(), 2);
  EXPECT_EQ(map["cells"].size(), 2u);
  EXPECT_DOUBLE_EQ(map["origin"][0].as<double>(), 1.0);
}

TEST(FrictionMapRecord, ARestartedCellForgetsItsEarlierTruth) {
  const Terrain terrain(iceStrip());
  FrictionMapRecord record(0.25, terrain, "");
  TickRecord r = tickAt(0.0, 0.0, 0.0);
  write(r, 0, 4, 0, 1, 0.2, 0.0, 0.2);
  record.onTick(r);
  r = tickAt(1.0, 0.0, 0.0);
  write(r, 0, 4, 0, 1, 0.6, 0.0, 0.7);  // the cell restarted on a disagreeing estimate
  record.onTick(r);
  EXPECT_DOUBLE_EQ(record.cells().at({4, 0}).true_mu, 0.7);
}

TEST(FrictionMapRecord, FrictionMapJsonHoldsTheTruthOnAGridOverThePath) {
  const Terrain terrain(iceStrip());
  const std::filesystem::path dir = testTempDir("hyq_friction_map_record_");
  const std::string path = (dir / "friction_map.json").string();
  {
    FrictionMapRecord record(0.25, terrain, path);
    for (int k = 0; k <= 20; ++k) record.onTick(tickAt(0.1 * k, 0.1 * k, 0.0));
    record.onFinish();
  }
  const YAML::Node json = YAML::LoadFile(path);
  const YAML::Node truth = json["truth"];
  const double x0 = truth["x0"].as<double>(), y0 = truth["y0"].as<double>(), step = truth["step"].as<double>();
  const int nx = truth["nx"].as<int>(), ny = truth["ny"].as<int>();
  EXPECT_DOUBLE_EQ(step, FrictionMapRecord::kTruthStep);
  EXPECT_NEAR(x0, -0.37 - FrictionMapRecord::kTruthMargin, 1e-12);  // the hind feet's start
  EXPECT_GE(x0 + nx * step, 2.0 + 0.37 + FrictionMapRecord::kTruthMargin - 1e-9);  // the front feet's end
  EXPECT_GE(y0 + ny * step, 0.33 + FrictionMapRecord::kTruthMargin - 1e-9);
  ASSERT_EQ(truth["mu"].size(), static_cast<size_t>(nx * ny));
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const double x = x0 + (i + 0.5) * step;
      EXPECT_DOUBLE_EQ(truth["mu"][j * nx + i].as<double>(), x >= 1.0 && x < 2.0 ? 0.2 : 0.8) << x;
    }
  EXPECT_EQ(json["cells"].size(), 0u);
}

}  // namespace
}  // namespace hyq::sim
