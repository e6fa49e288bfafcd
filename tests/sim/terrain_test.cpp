// Terrain ground truth (height, normal, friction patches) and the collision
// boxes built from it.
#include <gtest/gtest.h>

#include <cmath>

#include "sim_host/contact.hpp"
#include "sim_host/ode_engine.hpp"
#include "sim_host/simulator.hpp"
#include "sim_host/terrain.hpp"

namespace hyq::sim {
namespace {

TerrainSpec rampSpec() {
  TerrainSpec spec;
  spec.mu = 0.8;
  spec.ramps.push_back({1.0, 0.25, 2.0});
  spec.ramps.push_back({4.0, -0.1, 1.0});
  return spec;
}

TEST(Terrain, ProfileAndNormals) {
  ensureOdeInitialised();
  const Terrain t(rampSpec());
  const double top = 2.0 * std::tan(0.25);
  EXPECT_DOUBLE_EQ(t.height(0.0), 0.0);
  EXPECT_DOUBLE_EQ(t.height(1.0), 0.0);
  EXPECT_NEAR(t.height(2.0), std::tan(0.25), 1e-12);
  EXPECT_NEAR(t.height(3.5), top, 1e-12);
  EXPECT_NEAR(t.height(4.5), top - 0.5 * std::tan(0.1), 1e-12);
  EXPECT_NEAR(t.height(10.0), top - std::tan(0.1), 1e-12);
  EXPECT_NEAR((t.normal(2.0) - Vec3(-std::sin(0.25), 0, std::cos(0.25))).norm(), 0.0, 1e-12);
  EXPECT_NEAR((t.normal(0.5) - Vec3::UnitZ()).norm(), 0.0, 1e-12);
  EXPECT_NEAR((t.normal(4.5) - Vec3(std::sin(0.1), 0, std::cos(0.1))).norm(), 0.0, 1e-12);
}

TEST(Terrain, LaterPatchesWin) {
  ensureOdeInitialised();
  TerrainSpec spec;
  spec.mu = 0.8;
  spec.patches.push_back({0.0, 2.0, -1.0, 1.0, 0.3});
  spec.patches.push_back({1.0, 3.0, -1.0, 1.0, 0.1});
  const Terrain t(spec);
  EXPECT_DOUBLE_EQ(t.mu(-0.5, 0.0), 0.8);
  EXPECT_DOUBLE_EQ(t.mu(0.5, 0.0), 0.3);
  EXPECT_DOUBLE_EQ(t.mu(1.5, 0.0), 0.1);
  EXPECT_DOUBLE_EQ(t.mu(2.5, 0.0), 0.1);
  EXPECT_DOUBLE_EQ(t.mu(1.5, 1.5), 0.8);
}

// A heavy, non-rotating sphere settling at a point of the terrain: where it
// rests, and the contact normal it reports.
struct Rest {
  Vec3 centre, normal;
  bool in_contact;
};

Rest settle(const Terrain& terrain, double x) {
  ContactModel contacts(terrain, ContactParams{});
  dWorldID world = dWorldCreate();
  dWorldSetGravity(world, 0, 0, -9.81);
  dBodyID b = dBodyCreate(world);
  dMass m;
  dMassSetSphereTotal(&m, 20.0, 0.02);
  dBodySetMass(b, &m);
  dBodySetPosition(b, x, 0.0, terrain.height(x) + 0.025);
  contacts.addSphere(b, Vec3::Zero(), 0.02);
  for (int k = 0; k < 2000; ++k) {
    contacts.applyForces(0.001);
    dBodySetAngularVel(b, 0, 0, 0);
    dWorldStep(world, 0.001);
  }
  Rest r{Vec3(dBodyGetPosition(b)), contacts.sphere(0).normal, contacts.sphere(0).in_contact};
  dWorldDestroy(world);
  return r;
}

TEST(Terrain, SphereRestsOnTheSlopeWithTheSlopeNormal) {
  ensureOdeInitialised();
  TerrainSpec spec = rampSpec();
  spec.mu = 1.0;  // > tan(0.25): it sticks
  const Terrain t(spec);
  const Rest on_slope = settle(t, 2.0);
  EXPECT_TRUE(on_slope.in_contact);
  EXPECT_NEAR((on_slope.normal - t.normal(2.0)).norm(), 0.0, 1e-6);
  // Centre one radius (minus ~1 mm sink) above the slope, along its normal.
  const double clearance = (on_slope.centre - Vec3(on_slope.centre.x(), 0, t.height(on_slope.centre.x())))
                               .dot(t.normal(2.0));
  EXPECT_NEAR(clearance, 0.02, 1.5e-3);
  const Rest flat = settle(t, 0.3);
  EXPECT_NEAR((flat.normal - Vec3::UnitZ()).norm(), 0.0, 1e-9);
  EXPECT_NEAR(flat.centre.z(), 0.02, 1.5e-3);
  // On the ridge at the top of the slope the normal is between the two.
  const Rest ridge = settle(t, 3.0);
  EXPECT_TRUE(ridge.in_contact);
  EXPECT_GT(ridge.normal.z(), std::cos(0.25) - 1e-9);
}

}  // namespace
}  // namespace hyq::sim
