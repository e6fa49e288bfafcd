// Terrain ground truth (height, normal, friction patches) and the collision
// boxes built from it.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "firmware/controller/model/robot_params.hpp"
#include "sim_host/physics/contact.hpp"
#include "sim_host/physics/ode_engine.hpp"
#include "sim_host/physics/simulator.hpp"
#include "sim_host/physics/terrain.hpp"

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

// A timed patch (a sudden oil spill) is there from t0 up to t1, and only
// then; the terrain's clock says which friction its mu() gives.
TEST(Terrain, ATimedPatchIsThereOnlyInItsWindow) {
  TerrainSpec spec;
  spec.mu = 0.8;
  FrictionPatch oil{0.0, 1.0, -1.0, 1.0, 0.02};
  oil.t0 = 2.0;
  oil.t1 = 5.0;
  spec.patches.push_back({0.5, 2.0, -1.0, 1.0, 0.3});
  spec.patches.push_back(oil);
  Terrain t(spec);
  EXPECT_DOUBLE_EQ(t.muAt(0.2, 0.0, 1.999), 0.8);
  EXPECT_DOUBLE_EQ(t.muAt(0.2, 0.0, 2.0), 0.02);
  EXPECT_DOUBLE_EQ(t.muAt(0.2, 0.0, 4.999), 0.02);
  EXPECT_DOUBLE_EQ(t.muAt(0.2, 0.0, 5.0), 0.8);
  EXPECT_DOUBLE_EQ(t.muAt(0.7, 0.0, 1.0), 0.3);   // the untimed patch under it
  EXPECT_DOUBLE_EQ(t.muAt(0.7, 0.0, 3.0), 0.02);  // the later entry wins while there
  EXPECT_DOUBLE_EQ(t.muAt(1.5, 0.0, 3.0), 0.3);
  EXPECT_EQ(t.frictionChanges(), (std::vector<double>{2.0, 5.0}));
  EXPECT_DOUBLE_EQ(t.mu(0.2, 0.0), 0.8);  // the clock starts at 0
  t.setTime(3.0);
  EXPECT_DOUBLE_EQ(t.mu(0.2, 0.0), 0.02);
}

// A heavy sphere (20 kg, 2 cm) dropped 5 mm above the terrain at x, its
// spin held at zero, stepped at 1 ms by ODE with the project's contact.
class HeavySphere {
 public:
  HeavySphere(const Terrain& terrain, double x) : contacts_(terrain, ContactParams{}) {
    world_ = dWorldCreate();
    dWorldSetGravity(world_, 0, 0, -9.81);
    body_ = dBodyCreate(world_);
    dMass m;
    dMassSetSphereTotal(&m, 20.0, 0.02);
    dBodySetMass(body_, &m);
    dBodySetPosition(body_, x, 0.0, terrain.height(x) + 0.025);
    contacts_.addSphere(body_, Vec3::Zero(), 0.02);
  }
  ~HeavySphere() { dWorldDestroy(world_); }
  HeavySphere(const HeavySphere&) = delete;
  HeavySphere& operator=(const HeavySphere&) = delete;
  void step() {
    contacts_.applyForces(0.001);
    dBodySetAngularVel(body_, 0, 0, 0);
    dWorldStep(world_, 0.001);
  }
  Vec3 centre() const { return Vec3(dBodyGetPosition(body_)); }
  const SphereContact& contact() const { return contacts_.sphere(0); }

 private:
  ContactModel contacts_;
  dWorldID world_;
  dBodyID body_;
};

// Where the sphere rests after 2 s at a point of the terrain, and the
// contact normal it reports.
struct Rest {
  Vec3 centre, normal;
  bool in_contact;
};

Rest settle(const Terrain& terrain, double x) {
  HeavySphere sphere(terrain, x);
  for (int k = 0; k < 2000; ++k) sphere.step();
  return Rest{sphere.centre(), sphere.contact().normal, sphere.contact().in_contact};
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

// The ODE contact reads the friction at the terrain's clock: a sphere resting
// on the slope (mu 1 > tan 0.25) holds until an oil patch (mu 0.02)
// appears under it, then slides down.
TEST(Terrain, ASphereOnTheSlopeSlidesOnceTheOilComes) {
  ensureOdeInitialised();
  TerrainSpec spec = rampSpec();
  spec.mu = 1.0;
  FrictionPatch oil{1.5, 2.5, -1.0, 1.0, 0.02};
  oil.t0 = 1.0;
  spec.patches.push_back(oil);
  Terrain t(spec);
  HeavySphere sphere(t, 2.0);
  Vec3 before = Vec3::Zero();
  for (int k = 0; k < 1500; ++k) {
    t.setTime(0.001 * k);
    if (k == 800) before = sphere.centre();  // settled on the dry slope
    sphere.step();
    if (k == 999) {
      // On the dry slope the sphere only creeps (about 5 mm/s here: a
      // point contact with the sphere's spin held at zero).
      const double dry_travel = (sphere.centre() - before).norm();  // [m] over 0.2 s
      EXPECT_LT(dry_travel, 2e-3);
    }
  }
  const Vec3 moved = sphere.centre() - before;
  // Half a second on mu 0.02: a = g (sin 0.25 - 0.02 cos 0.25) = 2.24 m/s^2,
  // 0.28 m along the slope.
  EXPECT_LT(moved.x(), -0.2);
  EXPECT_GT(moved.x(), -0.35);
}

// The robot starts on a slope the way the controller holds it there: the
// trunk laid on the ground (its z along the slope's normal, to the 1 mrad by
// which pitch-then-roll in the heading's frame misses a slope partly across
// it) and the four feet on it, each foot's centre one radius off the plane
// less its static sink (to the 0.2 mm that miss leaves).
// With the trunk level instead, two feet hung up to 0.2 m above a 0.29 rad
// start, and trots drawn there fell within a second. Both engines, walking up
// the slope and along it.
TEST(Terrain, TheRobotStartsWithFourFeetOnASlope) {
  ensureOdeInitialised();
  for (const EngineKind engine : {EngineKind::ode, EngineKind::mujoco}) {
    for (const double yaw : {0.0, 1.2}) {
      Scenario s;
      s.terrain.mu = 0.8;
      s.terrain.ramps.push_back({-3.0, 0.25, 6.0});
      s.start_yaw = yaw;
      s.physics.engine = engine;
      const Simulator sim(s);
      const Terrain& t = sim.terrain();
      const Vec3 n = t.normal(0.0);
      EXPECT_NEAR((sim.engine().baseRotation().col(2) - n).norm(), 0.0, yaw == 0.0 ? 1e-12 : 1.5e-3) << "yaw " << yaw;
      for (int leg = 0; leg < 4; ++leg) {
        const FootContactState f = sim.engine().foot(leg);
        const double clearance = (f.centre - Vec3(f.centre.x(), 0.0, t.height(f.centre.x()))).dot(n);
        EXPECT_LT(clearance, robot::kFootRadius + 3e-4) << "yaw " << yaw << " leg " << leg;
        EXPECT_GT(clearance, robot::kFootRadius - 3e-3) << "yaw " << yaw << " leg " << leg;
      }
    }
  }
  // Level ground: the heading alone, exactly.
  Scenario flat;
  flat.start_yaw = 0.7;
  const Simulator sim(flat);
  const Mat3 heading = Eigen::AngleAxisd(0.7, Vec3::UnitZ()).toRotationMatrix();
  EXPECT_NEAR((sim.engine().baseRotation() - heading).norm(), 0.0, 1e-12);
}

}  // namespace
}  // namespace hyq::sim
