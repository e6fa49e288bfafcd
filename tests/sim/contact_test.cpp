// The contact model alone: a block on a ramp (stick and slide), the
// isotropy of the friction cone, a foot rolling over the ground and a foot
// in a change of slope, each in a tiny ODE world.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include "sim_host/physics/contact.hpp"
#include "sim_host/physics/ode_engine.hpp"
#include "sim_host/physics/simulator.hpp"

namespace hyq::sim {
namespace {

constexpr double kG = 9.81;
constexpr double kDt = 0.001;  // the simulator's step

// A block (box body) resting on four small spheres at its bottom corners,
// placed on the slope of a long ramp, aligned with it.
class BlockOnRamp {
 public:
  BlockOnRamp(double angle, double mu) : angle_(angle) {
    ensureOdeInitialised();
    TerrainSpec spec;
    spec.mu = mu;
    spec.ramps.push_back({-5.0, angle, 30.0});
    terrain_ = std::make_unique<Terrain>(spec);
    contacts_ = std::make_unique<ContactModel>(*terrain_, ContactParams{});
    world_ = dWorldCreate();
    dWorldSetGravity(world_, 0, 0, -kG);
    body_ = dBodyCreate(world_);
    dMass m;
    dMassSetBoxTotal(&m, kMass, 0.4, 0.3, 0.1);
    dBodySetMass(body_, &m);
    for (int i = 0; i < 4; ++i)
      contacts_->addSphere(body_, Vec3((i & 1) ? 0.15 : -0.15, (i & 2) ? 0.1 : -0.1, -0.05), kRadius);
    // On the slope at x = 5, its bottom spheres just touching.
    const Vec3 downhill(-std::cos(angle), 0.0, -std::sin(angle));
    const Vec3 normal(-std::sin(angle), 0.0, std::cos(angle));
    const double x = 5.0;
    const Vec3 surface(x, 0.0, (x + 5.0) * std::tan(angle));
    const Vec3 centre = surface + normal * (0.05 + kRadius);
    dMatrix3 rot;
    dRFromAxisAndAngle(rot, 0, 1, 0, -angle);
    dBodySetPosition(body_, centre.x(), centre.y(), centre.z());
    dBodySetRotation(body_, rot);
    downhill_ = downhill;
  }
  ~BlockOnRamp() {
    contacts_.reset();
    dWorldDestroy(world_);
  }
  void step() {
    contacts_->applyForces(kDt);
    dWorldStep(world_, kDt);
  }
  double positionDownhill() const { return downhill_.dot(Vec3(dBodyGetPosition(body_))); }
  double velocityDownhill() const { return downhill_.dot(Vec3(dBodyGetLinearVel(body_))); }
  const ContactModel& contacts() const { return *contacts_; }

  static constexpr double kMass = 10.0;      // [kg]
  static constexpr double kRadius = 0.02;    // [m]

 private:
  double angle_;
  Vec3 downhill_;
  std::unique_ptr<Terrain> terrain_;
  std::unique_ptr<ContactModel> contacts_;
  dWorldID world_;
  dBodyID body_;
};

struct RampCase {
  double angle, mu;
};

class Stick : public ::testing::TestWithParam<RampCase> {};

// mu > tan(a): the block stays put, drift below 1 mm over 10 s.
TEST_P(Stick, BlockStaysPut) {
  const RampCase c = GetParam();
  ASSERT_GT(c.mu, std::tan(c.angle));
  BlockOnRamp block(c.angle, c.mu);
  for (int k = 0; k < 500; ++k) block.step();  // settle onto the springs
  const double start = block.positionDownhill();
  double worst = 0.0;
  for (int k = 0; k < 10000; ++k) {
    block.step();
    worst = std::fmax(worst, std::fabs(block.positionDownhill() - start));
  }
  std::printf("stick: angle %.2f rad, mu %.2f (tan a = %.3f): max drift %.3g mm over 10 s\n",
              c.angle, c.mu, std::tan(c.angle), worst * 1e3);
  EXPECT_LT(worst, 1e-3) << "angle " << c.angle << " mu " << c.mu;
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(block.contacts().sphere(i).in_contact);
}

INSTANTIATE_TEST_SUITE_P(Ramp, Stick,
                         ::testing::Values(RampCase{0.2, 0.5}, RampCase{0.25, 0.3},
                                           RampCase{0.4, 0.45}, RampCase{0.2, 0.21}));

class Slide : public ::testing::TestWithParam<RampCase> {};

// mu < tan(a): acceleration g (sin a - mu cos a) within 3 %.
TEST_P(Slide, AccelerationIsCoulomb) {
  const RampCase c = GetParam();
  ASSERT_LT(c.mu, std::tan(c.angle));
  BlockOnRamp block(c.angle, c.mu);
  for (int k = 0; k < 300; ++k) block.step();
  const double v0 = block.velocityDownhill();
  for (int k = 0; k < 1000; ++k) block.step();
  const double measured = (block.velocityDownhill() - v0) / (1000 * kDt);
  const double expected = kG * (std::sin(c.angle) - c.mu * std::cos(c.angle));
  std::printf("slide: angle %.2f rad, mu %.2f: acceleration %.6f m/s^2, expected %.6f\n", c.angle,
              c.mu, measured, expected);
  EXPECT_NEAR(measured, expected, 0.03 * expected) << "angle " << c.angle << " mu " << c.mu;
}

INSTANTIATE_TEST_SUITE_P(Ramp, Slide,
                         ::testing::Values(RampCase{0.3, 0.2}, RampCase{0.25, 0.1},
                                           RampCase{0.4, 0.3}, RampCase{0.5, 0.45}));

constexpr double kFootRadius = 0.02175;  // [m] HyQ's foot sphere

// A world under gravity with one foot sphere's body of `mass` [kg];
// `inertia` [kg m^2] about every axis, 0: a solid sphere's.
dBodyID footWorld(double mass, double inertia, dWorldID& world) {
  ensureOdeInitialised();
  world = dWorldCreate();
  dWorldSetGravity(world, 0, 0, -kG);
  dBodyID foot = dBodyCreate(world);
  dMass m;
  dMassSetSphereTotal(&m, mass, kFootRadius);
  if (inertia > 0.0) m.I[0] = m.I[5] = m.I[10] = inertia;
  dBodySetMass(foot, &m);
  return foot;
}

// A loaded foot (a sphere of HyQ's foot radius carrying ~490 N) pushed by a
// slowly growing horizontal force applied at the contact point (so it does
// not roll): the force at which it starts to slide, per direction.
double breakawayForce(double direction_rad, double mu) {
  TerrainSpec spec;
  spec.mu = mu;
  Terrain terrain(spec);
  ContactModel contacts(terrain, ContactParams{});
  dWorldID world;
  dBodyID foot = footWorld(50.0, 0.0, world);
  dBodySetPosition(foot, 1.0, 2.0, kFootRadius);
  contacts.addSphere(foot, Vec3::Zero(), kFootRadius);
  for (int k = 0; k < 500; ++k) {
    contacts.applyForces(kDt);
    dWorldStep(world, kDt);
  }
  constexpr double kRate = 20.0;  // [N/s]
  double breakaway = NAN;
  for (int k = 0; k < 40000 && std::isnan(breakaway); ++k) {
    const double f = kRate * k * kDt;
    contacts.applyForces(kDt);
    if (contacts.sphere(0).sliding) breakaway = f;
    const Vec3 p = contacts.sphere(0).point;
    dBodyAddForceAtPos(foot, f * std::cos(direction_rad), f * std::sin(direction_rad), 0.0, p.x(),
                       p.y(), p.z());
    dWorldStep(world, kDt);
  }
  dWorldDestroy(world);  // the foot's geom outlives its body harmlessly
  return breakaway;
}

TEST(Isotropy, BreakawayForceIsTheSameInEveryDirection) {
  constexpr double kMu = 0.6;
  const double expected = kMu * 50.0 * kG;
  double lo = HUGE_VAL, hi = 0.0;
  for (double deg : {0.0, 30.0, 45.0, 60.0, 90.0, 135.0, 200.0}) {
    const double f = breakawayForce(deg * M_PI / 180.0, kMu);
    ASSERT_FALSE(std::isnan(f)) << deg << " deg: never slid";
    std::printf("breakaway at %5.1f deg: %.2f N (mu Fn = %.2f N)\n", deg, f, expected);
    EXPECT_NEAR(f, expected, 0.02 * expected) << deg << " deg";
    lo = std::fmin(lo, f);
    hi = std::fmax(hi, f);
  }
  EXPECT_LT(hi / lo - 1.0, 0.02);
}

// HyQ's foot sphere carrying a quarter of the robot's weight, turned about
// the horizontal axis through its centre at a steady rate, as the shank
// turns over a stance foot while the trunk walks on. The material point at
// the contact sticks, so the sphere rolls: its centre moves r per radian,
// and the ground's point under the foot does not slip.
struct RollResult {
  double centre_travel;   // [m] along x
  double turned;          // [rad]
  double depth;           // [m] the sphere's sink at the end
  double max_slip_speed;  // [m/s] of the material point at the contact, after the start
  bool always_in_contact;
};

constexpr int kRampTicks = 200;  // [ticks] the turn's smooth start

RollResult rollFoot(double rate, double seconds) {
  ensureOdeInitialised();
  TerrainSpec spec;
  spec.mu = 0.8;
  Terrain terrain(spec);
  ContactModel contacts(terrain, ContactParams{});
  dWorldID world = dWorldCreate();
  dWorldSetGravity(world, 0, 0, -kG);
  dBodyID foot_body = dBodyCreate(world);
  constexpr double kRadius = 0.02175, kMass = 21.0;
  dMass m;
  dMassSetSphereTotal(&m, kMass, kRadius);
  dBodySetMass(foot_body, &m);
  dBodySetPosition(foot_body, 0.0, 0.0, kRadius);
  const int foot = contacts.addSphere(foot_body, Vec3::Zero(), kRadius);
  RollResult r{0.0, 0.0, 0.0, 0.0, true};
  // Settle, then turn at `rate` about +y: a ball rolling towards +x turns about +y.
  // ODE turns the body by the angular velocity it ends the step with (the
  // contact's torque included): that is the angle to compare with.
  auto step = [&](double w) {
    dBodySetAngularVel(foot_body, 0, w, 0);
    contacts.applyForces(kDt);
    dWorldStep(world, kDt);
    return dBodyGetAngularVel(foot_body)[1] * kDt;
  };
  for (int k = 0; k < 300; ++k) step(0.0);
  const double start = dBodyGetPosition(foot_body)[0];
  const int ticks = static_cast<int>(seconds / kDt);
  for (int k = 0; k < ticks; ++k) {
    // A smooth start over kRampTicks: a step in the rate would ring the
    // 21 kg foot on its bristle spring (69 rad/s, lightly damped).
    const double ramp = k < kRampTicks ? 0.5 - 0.5 * std::cos(M_PI * k / kRampTicks) : 1.0;
    r.turned += step(rate * ramp);
    // The material point at the contact, at the end of the step (before
    // the next step sets the angular velocity again).
    const SphereContact& s = contacts.sphere(foot);
    r.always_in_contact = r.always_in_contact && s.in_contact;
    dVector3 v;
    dBodyGetPointVel(foot_body, s.point.x(), s.point.y(), s.point.z(), v);
    if (k >= kRampTicks) r.max_slip_speed = std::fmax(r.max_slip_speed, std::hypot(v[0], v[1]));
  }
  r.centre_travel = dBodyGetPosition(foot_body)[0] - start;
  r.depth = contacts.sphere(foot).depth;
  dWorldDestroy(world);
  return r;
}

TEST(Rolling, AFootTurnedOverTheGroundMovesItsCentreByRadiusTimesAngle) {
  constexpr double kRadius = 0.02175;
  for (double rate : {0.2, 1.0, -0.5}) {
    const RollResult r = rollFoot(rate, 1.0);
    // The contact point lies r - depth below the centre (1 mm of sink
    // under 206 N): that is the radius the sphere rolls on.
    const double rolling_radius = kRadius - r.depth;
    std::printf("rolled %.3f rad: centre moved %.3f mm, (r - depth) * angle %.3f mm, depth %.3f mm, "
                "slip after the start at most %.2g mm/s\n",
                r.turned, r.centre_travel * 1e3, rolling_radius * r.turned * 1e3, r.depth * 1e3,
                r.max_slip_speed * 1e3);
    EXPECT_TRUE(r.always_in_contact);
    EXPECT_GT(r.depth, 0.0);
    EXPECT_NEAR(r.centre_travel, rolling_radius * r.turned, 0.01 * kRadius * std::fabs(r.turned))
        << "rate " << rate;
    // The material point under the foot stays: far below the 0.05 m/s at
    // which the metrics count a slip.
    EXPECT_LT(r.max_slip_speed, 0.001) << "rate " << rate;
  }
}

// A loaded foot (HyQ's foot radius, 25 kg) set down where a flat piece
// meets a 0.2 rad slope: x0 = 0, the slope rising (a valley, concave) or
// falling (a ridge, convex) from there. The slope is as slippery as the
// slope's pull: mu 0.15 against tan(0.2) = 0.2, so a foot held by the
// slope alone would slide. Returns, over the last second of 2 s, the
// largest reported slip speed, the spread (max - min) of the force's x
// component, the centre's travel, and the most contacts at once.
struct CreaseResult {
  double max_slip_speed = 0.0;  // [m/s]
  double force_x_spread = 0.0;  // [N]
  double travel = 0.0;          // [m]
  int max_contacts = 0;
};
CreaseResult footInCrease(double angle, double x, double mass = 25.0, double push = 0.0) {
  TerrainSpec spec;
  spec.mu = 0.15;
  spec.ramps.push_back({0.0, angle, 2.0});
  Terrain terrain(spec);
  ContactModel contacts(terrain, ContactParams{});
  // A foot at the end of a leg does not roll like a free ball: an inertia
  // of 100 kg m^2 about every axis keeps it from turning.
  dWorldID world;
  dBodyID foot = footWorld(mass, 100.0, world);
  // On the ground under x (the higher of the two planes there), 1 mm up.
  dBodySetPosition(foot, x, 0.0, terrain.height(x) + kFootRadius / std::cos(angle) + 0.001);
  contacts.addSphere(foot, Vec3::Zero(), kFootRadius);
  CreaseResult r;
  double fx_min = 1e9, fx_max = -1e9;
  Vec3 start = Vec3::Zero();
  for (int k = 0; k < 2000; ++k) {
    contacts.applyForces(kDt);
    dBodyAddForce(foot, 0.0, 0.0, -push);
    dWorldStep(world, kDt);
    const SphereContact& s = contacts.sphere(0);
    if (k == 1000) start = Vec3(dBodyGetPosition(foot)[0], dBodyGetPosition(foot)[1], dBodyGetPosition(foot)[2]);
    if (k >= 1000) {
      r.max_slip_speed = std::fmax(r.max_slip_speed, s.slip_velocity.norm());
      fx_min = std::fmin(fx_min, s.force.x());
      fx_max = std::fmax(fx_max, s.force.x());
      r.max_contacts = std::max(r.max_contacts, s.contacts);
    }
  }
  const Vec3 end(dBodyGetPosition(foot)[0], dBodyGetPosition(foot)[1], dBodyGetPosition(foot)[2]);
  r.travel = (end - start).norm();
  r.force_x_spread = fx_max - fx_min;
  dWorldDestroy(world);
  return r;
}

// In a valley the foot touches both planes, each with its own force: it
// rests still, wedged (with one contact at a time it chattered between the
// planes, the force's x component swinging +-45 N every substep and the
// contact point reading 0.08 m/s of slip while the foot stayed put).
TEST(Crease, AFootInAValleyRestsOnBothPlanes) {
  const CreaseResult r = footInCrease(0.2, 0.0);
  std::printf("valley: contacts %d, slip speed max %.2g m/s, force x spread %.3g N, travel %.3g mm\n",
              r.max_contacts, r.max_slip_speed, r.force_x_spread, r.travel * 1e3);
  EXPECT_EQ(r.max_contacts, 2);
  EXPECT_LT(r.max_slip_speed, 0.001);
  EXPECT_LT(r.force_x_spread, 1.0);
  EXPECT_LT(r.travel, 5e-4);
}

// The nominal lower leg puts about 0.3 kg at the foot: pressed into the
// valley by a leg's 240 N it rests as well. Two contacts of full stiffness
// and damping each would break the explicit contact's damping bound
// (c h / m = 3.4 against 2) and ring.
TEST(Crease, ALightFootPressedIntoAValleyDoesNotRing) {
  for (double mass : {0.3}) {
    const CreaseResult r = footInCrease(0.2, 0.0, mass, 240.0 - mass * kG);
    std::printf("valley, %.2f kg foot pressed with 240 N: contacts %d, slip speed max %.2g m/s, "
                "force x spread %.3g N\n",
                mass, r.max_contacts, r.max_slip_speed, r.force_x_spread);
    EXPECT_EQ(r.max_contacts, 2);
    EXPECT_LT(r.max_slip_speed, 0.001);
    EXPECT_LT(r.force_x_spread, 1.0);
  }
}

// Over a ridge the deeper contact alone carries the foot, and on the
// slope's side of it the foot slides down (mu 0.15 under a 0.2 rad pull).
TEST(Crease, AFootOverARidgeTouchesOnePlaneAndSlidesOffIt) {
  const CreaseResult ridge = footInCrease(-0.2, 0.0);
  EXPECT_EQ(ridge.max_contacts, 1);
  const CreaseResult slope = footInCrease(-0.2, 0.05);
  std::printf("ridge: contacts %d; on the slope: slip speed max %.3g m/s, travel %.3g mm\n",
              ridge.max_contacts, slope.max_slip_speed, slope.travel * 1e3);
  EXPECT_EQ(slope.max_contacts, 1);
  EXPECT_GT(slope.max_slip_speed, 0.1);
}

// A foot that leaves a valley feels no step in its force: wedged in the
// valley with 20 N along the crease (mu 0.8, it sticks), then lifted until
// the slope's contact lets go, the contacts' force moves by less than 1 N a
// substep, along the crease and along z. With half of the stiffness to each
// plane whatever their depths, the flat's normal force doubled from 37 to
// 73 N in the substep the slope let go, and the foot bounced off.
TEST(Crease, AFootLeavingAValleyFeelsNoStepInItsForce) {
  TerrainSpec spec;
  spec.mu = 0.8;
  spec.ramps.push_back({0.0, 0.2, 2.0});
  Terrain terrain(spec);
  ContactModel contacts(terrain, ContactParams{});
  dWorldID world;
  const double mass = 25.0;
  dBodyID foot = footWorld(mass, 100.0, world);
  dBodySetPosition(foot, 0.0, 0.0, kFootRadius / std::cos(0.2) + 0.001);
  contacts.addSphere(foot, Vec3::Zero(), kFootRadius);
  Vec3 force_before = Vec3::Zero();
  double max_jump_y = 0.0, max_jump_z = 0.0;
  int left_valley_at = -1;
  for (int k = 0; k < 3000; ++k) {
    // From 1 s on, lifted by a force that outgrows the weight by 50 N/s.
    const double lift = k < 1000 ? 0.0 : std::fmin(1.0, 0.001 * (k - 1000)) * (mass * kG + 50.0);
    contacts.applyForces(kDt);
    dBodyAddForce(foot, 0.0, 20.0, lift);
    dWorldStep(world, kDt);
    const SphereContact& s = contacts.sphere(0);
    if (k > 500 && s.contacts > 0) {
      max_jump_y = std::fmax(max_jump_y, std::fabs(s.force.y() - force_before.y()));
      max_jump_z = std::fmax(max_jump_z, std::fabs(s.force.z() - force_before.z()));
    }
    if (left_valley_at < 0 && k > 1000 && s.contacts == 1) left_valley_at = k;
    force_before = s.force;
  }
  dWorldDestroy(world);
  std::printf("left the valley at %d ms; largest change of the force in a substep: %.3g N along y, "
              "%.3g N along z\n", left_valley_at, max_jump_y, max_jump_z);
  ASSERT_GT(left_valley_at, 1000);
  EXPECT_LT(max_jump_y, 1.0);
  EXPECT_LT(max_jump_z, 1.0);
}

}  // namespace
}  // namespace hyq::sim
