// The published HyQ body (plant.body: published) against the controller's
// nominal model, on both engines: the same joint frames (joint centres and
// axes to 1e-9 m), the lower leg 5 mm longer (each foot exactly 5 mm
// further along its lower leg: 0.346 against 0.341 m), 2 kg more trunk
// with its centre of mass 46 mm forward and 21.5 mm left, each link's
// centre of mass where the description puts it; 86.756 kg in all.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "firmware/controller/model/kinematics.hpp"
#include "firmware/controller/model/robot_params.hpp"
#include "sim_host/physics/body_model.hpp"
#include "sim_host/physics/mujoco_engine.hpp"
#include "sim_host/physics/ode_engine.hpp"
#include "sim_host/physics/simulator.hpp"
#include "sim_host/records/tick_record.hpp"
#include "tests/sim/random_posture.hpp"

namespace hyq::sim {
namespace {

Vec3 anchor(dJointID j) {
  dVector3 a;
  dJointGetHingeAnchor(j, a);
  return Vec3(a[0], a[1], a[2]);
}

Vec3 axis(dJointID j) {
  dVector3 a;
  dJointGetHingeAxis(j, a);
  return Vec3(a[0], a[1], a[2]);
}

Vec3 position(dBodyID b) {
  const dReal* p = dBodyGetPosition(b);
  return Vec3(p[0], p[1], p[2]);
}

Vec3 footCentre(const HyqRobot& robot, int leg) {
  const Vec3 off = robot.footOffset(leg);
  dVector3 f;
  dBodyGetRelPointPos(robot.lowerLeg(leg), off.x(), off.y(), off.z(), f);
  return Vec3(f[0], f[1], f[2]);
}

std::array<double, 12> standPosture() {
  std::array<double, 12> q{};
  for (int j = 0; j < 12; ++j) q[j] = robot::standAngle(j / 3, j % 3);
  return q;
}

TEST(PublishedBody, WeighsThePublished86_76Kg) {
  const RobotBody& b = publishedBody();
  EXPECT_NEAR(b.total_mass, 86.756, 1e-12);
  EXPECT_NEAR(b.total_mass, 86.76, 0.005);
  EXPECT_NEAR(b.total_mass - nominalBody().total_mass, 2.0, 1e-12);  // the trunk's 60.96 against 58.96 kg
  for (int leg = 0; leg < 4; ++leg)
    for (int link = 0; link < 3; ++link)
      EXPECT_EQ(b.links[leg][link].mass, nominalBody().links[leg][link].mass);
  EXPECT_LT((b.trunk_com - nominalBody().trunk_com - Vec3(0.046, 0.0215, 0.0)).norm(), 1e-15);
}

// plant.trunk_mass_scale and trunk_inertia_scale scale the trunk alone.
TEST(PublishedBody, TrunkScalesMoveOnlyTheTrunk) {
  PlantSpec plant = hyqPlant();
  plant.trunk_mass_scale = 1.2;
  plant.trunk_inertia_scale = 0.9;
  const RobotBody b = plantBody(plant);
  const RobotBody& p = publishedBody();
  EXPECT_NEAR(b.trunk_mass, 1.2 * 60.96, 1e-12);
  EXPECT_NEAR(b.total_mass, p.total_mass + 0.2 * 60.96, 1e-12);
  EXPECT_LT((b.trunk_inertia - 0.9 * p.trunk_inertia).norm(), 1e-12);
  EXPECT_EQ(b.trunk_com, p.trunk_com);
  for (int leg = 0; leg < 4; ++leg)
    for (int link = 0; link < 3; ++link) EXPECT_EQ(b.links[leg][link].mass, p.links[leg][link].mass);
  Scenario s;
  s.plant = plant;
  s.physics.engine = EngineKind::mujoco;
  const Terrain terrain(s.terrain);
  MujocoEngine engine(s, terrain, SimConfig{});
  EXPECT_NEAR(engine.totalMass(), b.total_mass, 1e-9);
}

// The published body on ODE's explicit foot contact: its lower leg puts
// 0.219 kg at the foot, and the feet's forces stay at the weight only with
// the contact damping that mass allows (ContactParams::
// published_normal_damping). The robot stands on a joint PD for 2 s, then
// takes a 150 N forward push for 0.2 s; the four feet's vertical forces
// over its last second: their sum's spread about the weight.
double standingForceSpread(double published_damping) {
  Scenario s;
  s.name = "stand";
  s.plant.body = BodyModel::published;
  s.sensors.noise = false;
  s.disturbances.push_back(Disturbance{2.0, 0.2, {150.0, 0.0, 0.0}});
  SimConfig config;
  config.contact.published_normal_damping = published_damping;
  Simulator sim(s, config);
  TickRecord rec;
  double lo = 1e9, hi = -1e9;
  for (uint32_t k = 0; k < 3000; ++k) {
    hal::CommandFrame c{};
    c.tick = k;
    for (int j = 0; j < 12; ++j) {
      c.q_ref[j] = robot::standAngle(j / 3, j % 3);
      c.kp[j] = 400.0;
      c.kd[j] = 6.0;
    }
    sim.step(c, rec);
    if (k < 2000) continue;
    double fz = 0.0;
    for (const FootTruth& f : rec.feet) fz += f.force[2];
    lo = std::min(lo, fz);
    hi = std::max(hi, fz);
  }
  return hi - lo;
}

TEST(PublishedBody, OdeFeetForcesDoNotRingWithItsContactDamping) {
  const double spread = standingForceSpread(SimConfig{}.contact.published_normal_damping);
  const double ringing = standingForceSpread(SimConfig{}.contact.normal_damping);
  std::printf("published body's standing force spread: %.1f N at 250 N s/m, %.1f N at 500 N s/m\n", spread, ringing);
  EXPECT_LT(spread, 200.0);
  EXPECT_GT(ringing, 2.0 * spread);
}

// ODE: a published and a nominal robot placed at the same random postures.
TEST(PublishedBody, OdeHasTheControllersJointFramesAndTheDescriptionsMasses) {
  ensureOdeInitialised();
  dWorldID world = dWorldCreate();
  {
    HyqRobot published(world, 0.0, 0.2, 1e-9, publishedBody());
    HyqRobot nominal(world, 0.0, 0.2, 1e-9, nominalBody());
    EXPECT_NEAR(published.totalMass(), 86.756, 1e-9);
    std::mt19937_64 rng(11);
    double worst_joint = 0.0, worst_foot = 0.0, worst_com = 0.0;
    for (int trial = 0; trial < 20; ++trial) {
      const std::array<double, 12> q = trial == 0 ? standPosture() : randomPosture(rng);
      const Vec3 base(0.3, -0.2, 0.7);
      const Mat3 rot = Quat(Eigen::AngleAxisd(0.3, Vec3(1, 2, 3).normalized())).toRotationMatrix();
      published.place(base, rot, q);
      nominal.place(base, rot, q);
      EXPECT_NEAR((published.basePosition() - base).norm(), 0.0, 1e-12);
      for (int leg = 0; leg < 4; ++leg) {
        const Vec3 q_leg(q[3 * leg], q[3 * leg + 1], q[3 * leg + 2]);
        const Vec3 haa(robot::kHaaPos[leg][0], robot::kHaaPos[leg][1], robot::kHaaPos[leg][2]);
        const Vec3 centres[3] = {haa, hfePositionBase(leg, q_leg), kfePositionBase(leg, q_leg)};
        for (int joint = 0; joint < 3; ++joint) {
          const int j = 3 * leg + joint;
          EXPECT_NEAR(published.jointAngle(j), q[j], 1e-9);
          worst_joint = std::fmax(worst_joint, (anchor(published.joint(j)) - (base + rot * centres[joint])).norm());
          worst_joint = std::fmax(worst_joint, (axis(published.joint(j)) - axis(nominal.joint(j))).norm());
        }
        // The foot: 5 mm further along the lower leg than the controller's.
        const Vec3 ctrl_foot = base + rot * footPositionBase(leg, q_leg);
        const Vec3 knee = base + rot * centres[2];
        const Vec3 expected = ctrl_foot + (0.005 / robot::kLowerLength) * (ctrl_foot - knee);
        worst_foot = std::fmax(worst_foot, (footCentre(published, leg) - expected).norm());
        EXPECT_NEAR((footCentre(published, leg) - ctrl_foot).norm(), 0.005, 1e-9);
        EXPECT_LT((footCentre(nominal, leg) - ctrl_foot).norm(), 1e-9);
        // Each link's CoM: the nominal body's at the controller's mid-link,
        // the published one's offset from it by the description's CoM in
        // the same link frame.
        for (int link = 0; link < 3; ++link) {
          // Each hinge's first body is its child link.
          const dBodyID nb = dJointGetBody(nominal.joint(3 * leg + link), 0);
          const dBodyID pb = dJointGetBody(published.joint(3 * leg + link), 0);
          EXPECT_LT((position(nb) - (base + rot * linkComPositionBase(leg, link, q_leg))).norm(), 1e-9);
          const dReal* r = dBodyGetRotation(nb);
          Mat3 link_rot;
          for (int a = 0; a < 3; ++a)
            for (int c = 0; c < 3; ++c) link_rot(a, c) = r[4 * a + c];
          const Vec3 shift = publishedBody().links[leg][link].com - nominalBody().links[leg][link].com;
          worst_com = std::fmax(worst_com, (position(pb) - position(nb) - link_rot * shift).norm());
        }
      }
    }
    std::printf("published body vs the controller: joint centres and axes %.2g m, feet 5 mm along the lower leg "
                "to %.2g m, link CoMs to %.2g m\n", worst_joint, worst_foot, worst_com);
    EXPECT_LT(worst_joint, 1e-9);
    EXPECT_LT(worst_foot, 1e-9);
    EXPECT_LT(worst_com, 1e-9);
  }
  dWorldDestroy(world);
}

// The whole robot's centre of mass at the stance posture: where the
// published body puts it against the controller's model.
TEST(PublishedBody, CentreOfMassAtTheStance) {
  auto com = [](const RobotBody& b) {
    const std::array<double, 12> q = standPosture();
    Vec3 sum = b.trunk_mass * b.trunk_com;
    ensureOdeInitialised();
    dWorldID world = dWorldCreate();
    {
      HyqRobot robot(world, 0.0, 0.2, 1e-9, b);
      robot.place(Vec3::Zero(), Mat3::Identity(), q);
      for (int j = 0; j < 12; ++j) {
        dMass m;
        const dBodyID link = dJointGetBody(robot.joint(j), 0);
        dBodyGetMass(link, &m);
        sum += m.mass * position(link);
      }
    }
    dWorldDestroy(world);
    return Vec3(sum / b.total_mass);
  };
  const Vec3 pub = com(publishedBody()), nom = com(nominalBody());
  std::printf("CoM at the stance, in B: published (%.1f, %.1f, %.1f) mm, nominal (%.1f, %.1f, %.1f) mm\n",
              1e3 * pub.x(), 1e3 * pub.y(), 1e3 * pub.z(), 1e3 * nom.x(), 1e3 * nom.y(), 1e3 * nom.z());
  // The trunk's 46 mm forward and 21.5 mm left, 2 kg heavier, dominate:
  // the whole CoM moves about 32 mm forward and 15 mm left.
  EXPECT_NEAR(pub.x() - nom.x(), 0.032, 0.004);
  EXPECT_NEAR(pub.y() - nom.y(), 0.015, 0.002);
}

// MuJoCo builds the same published body: its link CoMs where ODE's are,
// its feet 5 mm along the lower legs, 86.756 kg.
TEST(PublishedBody, MujocoBuildsTheSameBody) {
  Scenario s;
  s.name = "published";
  s.plant.body = BodyModel::published;
  s.physics.engine = EngineKind::mujoco;
  const Terrain terrain(s.terrain);
  MujocoEngine engine(s, terrain, SimConfig{});
  EXPECT_NEAR(engine.totalMass(), 86.756, 1e-9);
  ensureOdeInitialised();
  dWorldID world = dWorldCreate();
  {
    HyqRobot ode(world, 0.0, 0.2, 1e-9, publishedBody());
    std::mt19937_64 rng(5);
    double worst_com = 0.0, worst_foot = 0.0;
    const mjModel& m = engine.model();
    const mjData& d = engine.data();
    for (int trial = 0; trial < 10; ++trial) {
      const std::array<double, 12> q = randomPosture(rng);
      const Vec3 base(0.1, 0.2, 0.8);
      const Mat3 rot = Quat(Eigen::AngleAxisd(-0.2, Vec3(2, -1, 1).normalized())).toRotationMatrix();
      engine.place(base, rot, q);
      ode.place(base, rot, q);
      const char* links[3] = {"hip", "upper", "lower"};
      for (int leg = 0; leg < 4; ++leg) {
        worst_foot = std::fmax(worst_foot, (engine.foot(leg).centre - footCentre(ode, leg)).norm());
        for (int link = 0; link < 3; ++link) {
          const std::string name = std::string(robot::kLegNames[leg]) + "_" + links[link];
          const int b = mj_name2id(&m, mjOBJ_BODY, name.c_str());
          const Vec3 xipos(d.xipos[3 * b], d.xipos[3 * b + 1], d.xipos[3 * b + 2]);
          worst_com = std::fmax(worst_com, (xipos - position(dJointGetBody(ode.joint(3 * leg + link), 0))).norm());
        }
      }
    }
    EXPECT_LT(worst_com, 1e-9);
    EXPECT_LT(worst_foot, 1e-9);
  }
  dWorldDestroy(world);
}

}  // namespace
}  // namespace hyq::sim
