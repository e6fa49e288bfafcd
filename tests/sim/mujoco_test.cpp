// HyQ in MuJoCo: the generated model against the controller's kinematics
// and mass properties (as robot_test.cpp checks the ODE model), its ground
// against the terrain, and the robot standing on it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "firmware/controller/model/kinematics.hpp"
#include "firmware/controller/model/robot_params.hpp"
#include "sim_host/loop/controller_port.hpp"
#include "sim_host/physics/mujoco_engine.hpp"
#include "sim_host/physics/mujoco_model.hpp"
#include "sim_host/physics/simulator.hpp"
#include "tests/sim/random_posture.hpp"

namespace hyq::sim {
namespace {

Scenario mujocoScenario() {
  Scenario s;
  s.name = "test";
  s.duration = 3.0;
  s.sensors.noise = false;
  s.physics.engine = EngineKind::mujoco;
  return s;
}

int dofOf(const mjModel& m, int leg, int joint) {
  const char* names[3] = {"haa", "hfe", "kfe"};
  const std::string name = std::string(robot::kLegNames[leg]) + "_" + names[joint];
  return m.jnt_dofadr[mj_name2id(&m, mjOBJ_JOINT, name.c_str())];
}

Mat3 rotX(double a) { return Eigen::AngleAxisd(a, Vec3::UnitX()).toRotationMatrix(); }
Mat3 rotY(double a) { return Eigen::AngleAxisd(a, Vec3::UnitY()).toRotationMatrix(); }

// The leg's joint-space inertia with each link a solid cylinder of radius
// kLinkInertiaRadius (the simulator's bodies): the controller's thin-rod
// legMassMatrix plus each link's inertia beyond the rod's, m r^2 / 4
// about its two cross axes and m r^2 / 2 about its own, seen through the
// link's angular-velocity Jacobian.
Mat3 cylinderLegMassMatrix(int leg, const Vec3& q) {
  const double r = robot::kLinkInertiaRadius;
  const double masses[3] = {robot::kHipMass, robot::kUpperMass, robot::kLowerMass};
  const Mat3 r0 = rotX(robot::kHaaAxisSign[leg] * q[0]);
  const Mat3 rot[3] = {r0, r0 * rotY(q[1]), r0 * rotY(q[1] + q[2])};
  const Vec3 axis[3] = {robot::kHaaAxisSign[leg] * Vec3::UnitX(), r0 * Vec3::UnitY(),
                        r0 * Vec3::UnitY()};
  Mat3 mass = legMassMatrix(leg, q);
  for (int link = 0; link < 3; ++link) {
    Mat3 jw = Mat3::Zero();
    for (int j = 0; j <= link; ++j) jw.col(j) = axis[j];
    const Vec3 extra(masses[link] * r * r / 4, masses[link] * r * r / 4, masses[link] * r * r / 2);
    const Mat3 inertia = rot[link] * extra.asDiagonal() * rot[link].transpose();
    mass += jw.transpose() * inertia * jw;
  }
  return mass;
}

// Placed at random postures and base poses: every joint reads back, every
// foot sphere sits where the controller's kinematics puts it, each leg's
// block of MuJoCo's mass matrix is the leg's joint-space inertia and its
// bias force at rest the torque that holds the leg's weight.
TEST(MujocoModel, MatchesTheControllerKinematicsAndMassProperties) {
  const Scenario s = mujocoScenario();
  const Terrain terrain(s.terrain);
  MujocoEngine engine(s, terrain, SimConfig{});
  const mjModel& m = engine.model();
  const mjData& d = engine.data();
  std::vector<mjtNum> full(m.nv * m.nv);
  std::mt19937_64 rng(7);
  double worst_foot = 0.0, worst_mass = 0.0, worst_gravity = 0.0;
  for (int trial = 0; trial < 20; ++trial) {
    const std::array<double, 12> q = randomPosture(rng);
    const Vec3 base(0.3, -0.2, 0.7);
    const Mat3 rot = Quat(Eigen::AngleAxisd(0.3, Vec3(1, 2, 3).normalized())).toRotationMatrix();
    engine.place(base, rot, q);
    for (int j = 0; j < 12; ++j) EXPECT_NEAR(engine.jointAngle(j), q[j], 1e-12) << "joint " << j;
    EXPECT_NEAR((engine.basePosition() - base).norm(), 0.0, 1e-12);
    EXPECT_NEAR((engine.baseRotation() - rot).norm(), 0.0, 1e-12);
    mj_fullM(&m, full.data(), d.qM);
    const Vec3 gravity_base = rot.transpose() * Vec3(0, 0, -robot::kGravity);
    for (int leg = 0; leg < 4; ++leg) {
      const Vec3 q_leg(q[3 * leg], q[3 * leg + 1], q[3 * leg + 2]);
      const Vec3 expected = base + rot * footPositionBase(leg, q_leg);
      worst_foot = std::fmax(worst_foot, (engine.foot(leg).centre - expected).norm());
      const Mat3 mass = cylinderLegMassMatrix(leg, q_leg);
      const Vec3 holding = legGravityTorque(leg, q_leg, gravity_base);
      for (int a = 0; a < 3; ++a) {
        const int da = dofOf(m, leg, a);
        // At rest the bias force is gravity's: the torque that holds the leg.
        worst_gravity = std::fmax(worst_gravity, std::fabs(d.qfrc_bias[da] - holding[a]));
        for (int b = 0; b < 3; ++b)
          worst_mass = std::fmax(worst_mass,
                                 std::fabs(full[da * m.nv + dofOf(m, leg, b)] - mass(a, b)));
      }
    }
  }
  std::printf("MuJoCo model vs controller: feet %.2g m, leg mass matrices %.2g kg m^2, "
              "holding torques %.2g N m\n", worst_foot, worst_mass, worst_gravity);
  EXPECT_LT(worst_foot, 1e-12);
  EXPECT_LT(worst_mass, 1e-12);
  EXPECT_LT(worst_gravity, 1e-11);
}

// Total mass, and the trunk's inertia about its centre of mass, with and
// without a payload spread over the trunk box.
TEST(MujocoModel, MassAndTrunkInertiaAreTheRobots) {
  for (double payload : {0.0, 15.0}) {
    Scenario s = mujocoScenario();
    s.payload_kg = payload;
    const Terrain terrain(s.terrain);
    MujocoEngine engine(s, terrain, SimConfig{});
    const mjModel& m = engine.model();
    EXPECT_NEAR(engine.totalMass(), robot::kTotalMass + payload, 1e-12);
    const int trunk = mj_name2id(&m, mjOBJ_BODY, "trunk");
    EXPECT_NEAR((Vec3(m.body_ipos + 3 * trunk) -
                 Vec3(robot::kTrunkCom[0], robot::kTrunkCom[1], robot::kTrunkCom[2]))
                    .norm(),
                0.0, 1e-12);
    // MuJoCo keeps the inertia as principal moments and axes, found by its
    // iterative eigensolver: equal to ~2e-7 kg m^2 of 9 (2e-8 relative).
    const mjtNum* iq = m.body_iquat + 4 * trunk;
    const Mat3 axes = Quat(iq[0], iq[1], iq[2], iq[3]).toRotationMatrix();
    const Mat3 inertia = axes * Vec3(m.body_inertia + 3 * trunk).asDiagonal() * axes.transpose();
    const double* ti = robot::kTrunkInertia;
    const double sx = robot::kTrunkSize[0], sy = robot::kTrunkSize[1], sz = robot::kTrunkSize[2];
    Mat3 expected;
    expected << ti[0] + payload * (sy * sy + sz * sz) / 12, ti[3], ti[4],
                ti[3], ti[1] + payload * (sx * sx + sz * sz) / 12, ti[5],
                ti[4], ti[5], ti[2] + payload * (sx * sx + sy * sy) / 12;
    EXPECT_LT((inertia - expected).norm(), 1e-6) << "payload " << payload;
  }
}

// The ground boxes: each box's top face lies on the terrain's surface and
// carries the terrain's friction there, and every point of the ground is on
// exactly one of them.
TEST(MujocoModel, GroundCarriesTheTerrainsFrictionAndHeight) {
  Scenario s = mujocoScenario();
  s.terrain.mu = 0.8;
  s.terrain.patches = {{0.4, 1.15, -2.0, 2.0, 0.25}, {1.15, 1.9, -0.5, 0.3, 0.1},
                       {1.0, 1.5, 0.0, 1.0, 0.4}};
  s.terrain.ramps = {{1.0, 0.25, 2.0}};
  const Terrain terrain(s.terrain);
  MujocoEngine engine(s, terrain, SimConfig{});
  const mjModel& m = engine.model();
  const mjData& d = engine.data();
  int boxes = 0;
  for (int g = 0; g < m.ngeom; ++g) {
    const char* name = mj_id2name(&m, mjOBJ_GEOM, g);
    if (!name || std::string(name).rfind("ground_", 0) != 0) continue;
    ++boxes;
    const Vec3 centre(d.geom_xpos + 3 * g);
    Mat3 r;
    for (int i = 0; i < 9; ++i) r(i / 3, i % 3) = d.geom_xmat[9 * g + i];
    const Vec3 half(m.geom_size + 3 * g);
    // Points on the top face, inset from its edges.
    for (double u : {-0.9, 0.0, 0.9})
      for (double v : {-0.9, 0.0, 0.9}) {
        const Vec3 p = centre + r * Vec3(u * std::fmin(half.x(), 5.0), v * std::fmin(half.y(), 5.0), half.z());
        EXPECT_NEAR(p.z(), terrain.height(p.x()), 1e-9) << name;
        EXPECT_EQ(m.geom_friction[3 * g], std::fmax(terrain.mu(p.x(), p.y()), 1e-5)) << name;
      }
  }
  std::printf("%d ground boxes\n", boxes);
  EXPECT_EQ(static_cast<size_t>(boxes), mujocoGroundBoxes(terrain));
  // Every point of the ground lies on the top face of exactly one box,
  // whose friction is the terrain's there.
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> ux(-2.0, 6.0), uy(-3.0, 3.0);
  for (int trial = 0; trial < 2000; ++trial) {
    const double x = ux(rng), y = uy(rng);
    const Vec3 p(x, y, terrain.height(x));
    int under = 0;
    for (int g = 0; g < m.ngeom; ++g) {
      const char* name = mj_id2name(&m, mjOBJ_GEOM, g);
      if (!name || std::string(name).rfind("ground_", 0) != 0) continue;
      Mat3 r;
      for (int i = 0; i < 9; ++i) r(i / 3, i % 3) = d.geom_xmat[9 * g + i];
      const Vec3 local = r.transpose() * (p - Vec3(d.geom_xpos + 3 * g));
      const Vec3 half(m.geom_size + 3 * g);
      if (std::fabs(local.x()) <= half.x() && std::fabs(local.y()) <= half.y() &&
          std::fabs(local.z() - half.z()) < 1e-9) {
        ++under;
        EXPECT_EQ(m.geom_friction[3 * g], std::fmax(terrain.mu(x, y), 1e-5)) << x << " " << y;
      }
    }
    EXPECT_EQ(under, 1) << "at " << x << ", " << y;
  }
}

// A timed patch has boxes of its own (their friction at time 0 is the
// ground's around them), and the engine gives them the terrain's friction
// at each step's time: the oil is there from its t0 up to its t1.
TEST(MujocoModel, ATimedPatchsBoxesTakeTheFrictionOfEachStepsTime) {
  Scenario s = mujocoScenario();
  s.terrain.mu = 0.8;
  FrictionPatch oil{1.0, 1.5, -0.5, 0.5, 0.02};
  oil.t0 = 0.01;
  oil.t1 = 0.02;
  s.terrain.patches = {oil};
  Terrain terrain(s.terrain);
  const std::vector<TimedGroundBox> timed = timedGroundBoxes(terrain);
  ASSERT_EQ(timed.size(), 1u);
  EXPECT_DOUBLE_EQ(timed[0].x, 1.25);
  EXPECT_GT(timed[0].y, -0.5);
  EXPECT_LT(timed[0].y, 0.5);
  EXPECT_EQ(mujocoGroundBoxes(terrain), 5u);  // x: before, under, after; y: either side of it

  const SimConfig config;
  const double h = config.integration.tick / config.integration.substeps;  // [s]
  MujocoEngine engine(s, terrain, config);
  const int g = mj_name2id(&engine.model(), mjOBJ_GEOM, timed[0].name.c_str());
  ASSERT_GE(g, 0);
  auto frictionAfterStepAt = [&](double t) {
    terrain.setTime(t);
    engine.step({}, Vec3::Zero(), h);
    return engine.model().geom_friction[3 * g];
  };
  EXPECT_EQ(engine.model().geom_friction[3 * g], 0.8);
  EXPECT_EQ(frictionAfterStepAt(oil.t0 - 2 * h), 0.8);  // the next step is still before t0
  EXPECT_EQ(frictionAfterStepAt(oil.t0 - h), 0.02);     // the next step starts at t0
  EXPECT_EQ(frictionAfterStepAt(oil.t1 - 2 * h), 0.02);
  EXPECT_EQ(frictionAfterStepAt(oil.t1 - h), 0.8);
}

// Standing under the posture controller: the vertical forces carry the
// weight, the feet stay (they neither creep nor roll off), no fall.
TEST(MujocoStanding, VerticalForcesCarryTheWeightAndFeetStay) {
  const Scenario s = mujocoScenario();
  Simulator sim(s);
  auto controller = makeController("posture", s);
  hal::CommandFrame cmd{};
  TickRecord rec;
  Vec3 force_sum = Vec3::Zero();
  std::array<Vec3, 4> foot0;
  double drift = 0.0;
  int n = 0;
  for (int k = 0; k < 3000; ++k) {
    controller->step(sim.sensorFrame(), cmd);
    sim.step(cmd, rec);
    ASSERT_FALSE(sim.fallen());
    if (k == 1000)
      for (int leg = 0; leg < 4; ++leg) foot0[leg] = Vec3(rec.feet[leg].position.data());
    if (k > 1000) {
      for (int leg = 0; leg < 4; ++leg) {
        EXPECT_TRUE(rec.feet[leg].in_contact);
        force_sum += Vec3(rec.feet[leg].force.data());
        drift = std::fmax(drift, (Vec3(rec.feet[leg].position.data()) - foot0[leg]).norm());
      }
      ++n;
    }
  }
  force_sum /= n;
  const double weight = robot::kTotalMass * robot::kGravity;
  std::printf("MuJoCo standing: sum Fz %.2f N, weight %.2f N, max foot drift %.3g mm\n",
              force_sum.z(), weight, drift * 1e3);
  EXPECT_NEAR(force_sum.z(), weight, 0.01 * weight);
  EXPECT_LT(std::hypot(force_sum.x(), force_sum.y()), 0.01 * weight);
  EXPECT_LT(drift, 1e-3);
}

}  // namespace
}  // namespace hyq::sim
