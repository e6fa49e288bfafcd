#include "sim_host/physics/robot.hpp"

#include "firmware/controller/model/robot_params.hpp"

namespace hyq::sim {
namespace {
using namespace hyq::robot;

Mat3 rotX(double a) { return Eigen::AngleAxisd(a, Vec3::UnitX()).toRotationMatrix(); }
Mat3 rotY(double a) { return Eigen::AngleAxisd(a, Vec3::UnitY()).toRotationMatrix(); }
const Vec3 kDown(0.0, 0.0, -1.0);
const double kLinkLength[3] = {kHipLength, kUpperLength, kLowerLength};

Vec3 haaPos(int leg) { return Vec3(kHaaPos[leg][0], kHaaPos[leg][1], kHaaPos[leg][2]); }

// Frames of one leg's links in B and the joint centres, for angles q.
struct LegPose {
  std::array<Mat3, 3> rot;     // link frames (z along the link, pointing away from the trunk: -z)
  std::array<Vec3, 3> joint;   // HAA, HFE, KFE centres
  Vec3 foot;
};

LegPose legPose(int leg, const Vec3& q, double lower_length) {
  LegPose p;
  p.rot[0] = rotX(kHaaAxisSign[leg] * q[0]);
  p.rot[1] = p.rot[0] * rotY(q[1]);
  p.rot[2] = p.rot[0] * rotY(q[1] + q[2]);
  p.joint[0] = haaPos(leg);
  p.joint[1] = p.joint[0] + p.rot[0] * kDown * kHipLength;
  p.joint[2] = p.joint[1] + p.rot[1] * kDown * kUpperLength;
  p.foot = p.joint[2] + p.rot[2] * kDown * lower_length;
  return p;
}

void setBodyPose(dBodyID b, const Vec3& pos, const Mat3& rot) {
  dMatrix3 r;
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) r[4 * i + k] = rot(i, k);
    r[4 * i + 3] = 0.0;
  }
  dBodySetPosition(b, pos.x(), pos.y(), pos.z());
  dBodySetRotation(b, r);
  dBodySetLinearVel(b, 0.0, 0.0, 0.0);
  dBodySetAngularVel(b, 0.0, 0.0, 0.0);
}
}  // namespace

Vec3 simFootPositionBase(int leg, const Vec3& q_leg) { return legPose(leg, q_leg, kLowerLength).foot; }
Vec3 simFootPositionBase(int leg, const Vec3& q_leg, double lower_length) {
  return legPose(leg, q_leg, lower_length).foot;
}

Vec3 HyqRobot::footOffset() { return Vec3(0.0, 0.0, -0.5 * kLowerLength); }

Vec3 HyqRobot::footOffset(int leg) const {
  if (body_.cylinder_links) return footOffset();
  return kDown * body_.lower_length - body_.links[leg][2].com;
}

HyqRobot::HyqRobot(dWorldID world, double payload_kg, double stop_erp, double stop_cfm,
                   const RobotBody& body)
    : body_(body) {
  trunk_ = dBodyCreate(world);
  dMass m;
  const Mat3& ti = body_.trunk_inertia;
  dMassSetParameters(&m, body_.trunk_mass, 0, 0, 0, ti(0, 0), ti(1, 1), ti(2, 2), ti(0, 1), ti(0, 2), ti(1, 2));
  if (payload_kg > 0.0) {
    dMass payload;
    dMassSetBoxTotal(&payload, payload_kg, kTrunkSize[0], kTrunkSize[1], kTrunkSize[2]);
    dMassAdd(&m, &payload);
  }
  dBodySetMass(trunk_, &m);
  for (int leg = 0; leg < kNumLegs; ++leg)
    for (int link = 0; link < 3; ++link) {
      links_[leg][link] = dBodyCreate(world);
      const LinkInertial& l = body_.links[leg][link];
      dMass ml;
      if (body_.cylinder_links) {
        dMassSetCylinderTotal(&ml, l.mass, 3, kLinkInertiaRadius, kLinkLength[link]);
      } else {
        const Mat3& i = l.inertia;
        dMassSetParameters(&ml, l.mass, 0, 0, 0, i(0, 0), i(1, 1), i(2, 2), i(0, 1), i(0, 2), i(1, 2));
      }
      dBodySetMass(links_[leg][link], &ml);
    }

  // Hinges are created at q = 0, which ODE takes as each joint's zero angle.
  place(Vec3::Zero(), Mat3::Identity(), {});
  for (int leg = 0; leg < kNumLegs; ++leg) {
    const LegPose p = legPose(leg, Vec3::Zero(), body_.lower_length);
    const Vec3 axis[3] = {kHaaAxisSign[leg] * Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitY()};
    const dBodyID parent[3] = {trunk_, links_[leg][0], links_[leg][1]};
    for (int joint = 0; joint < 3; ++joint) {
      dJointID j = dJointCreateHinge(world, nullptr);
      // Child first: ODE's hinge angle and torque then act on the child link.
      dJointAttach(j, links_[leg][joint], parent[joint]);
      dJointSetHingeAnchor(j, p.joint[joint].x(), p.joint[joint].y(), p.joint[joint].z());
      dJointSetHingeAxis(j, axis[joint].x(), axis[joint].y(), axis[joint].z());
      double lo = 0.0, hi = 0.0;
      jointLimits(leg, joint, lo, hi);
      dJointSetHingeParam(j, dParamLoStop, lo);
      dJointSetHingeParam(j, dParamHiStop, hi);
      dJointSetHingeParam(j, dParamStopERP, stop_erp);
      dJointSetHingeParam(j, dParamStopCFM, stop_cfm);
      joints_[3 * leg + joint] = j;
    }
  }
}

HyqRobot::~HyqRobot() {
  for (dJointID j : joints_) dJointDestroy(j);
  for (auto& leg : links_)
    for (dBodyID b : leg) dBodyDestroy(b);
  dBodyDestroy(trunk_);
}

void HyqRobot::place(const Vec3& base_pos, const Mat3& base_rot, const std::array<double, 12>& q) {
  setBodyPose(trunk_, base_pos + base_rot * trunkCom(), base_rot);
  for (int leg = 0; leg < kNumLegs; ++leg) {
    const LegPose p = legPose(leg, Vec3(q[3 * leg], q[3 * leg + 1], q[3 * leg + 2]), body_.lower_length);
    for (int link = 0; link < 3; ++link) {
      // The nominal body's links: CoM at mid-link.
      Vec3 com_b;
      if (body_.cylinder_links)
        com_b = p.joint[link] + p.rot[link] * kDown * (0.5 * kLinkLength[link]);
      else
        com_b = p.joint[link] + p.rot[link] * body_.links[leg][link].com;
      setBodyPose(links_[leg][link], base_pos + base_rot * com_b, base_rot * p.rot[link]);
    }
  }
}

double HyqRobot::jointAngle(int j) const { return dJointGetHingeAngle(joints_[j]); }
double HyqRobot::jointRate(int j) const { return dJointGetHingeAngleRate(joints_[j]); }
void HyqRobot::addJointTorque(int j, double tau) { dJointAddHingeTorque(joints_[j], tau); }

Vec3 HyqRobot::basePosition() const {
  dVector3 p;
  const Vec3 o = -trunkCom();
  dBodyGetRelPointPos(trunk_, o.x(), o.y(), o.z(), p);
  return Vec3(p[0], p[1], p[2]);
}

Mat3 HyqRobot::baseRotation() const {
  const dReal* r = dBodyGetRotation(trunk_);
  Mat3 m;
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) m(i, k) = r[4 * i + k];
  return m;
}

Quat HyqRobot::baseQuaternion() const {
  const dReal* q = dBodyGetQuaternion(trunk_);
  return Quat(q[0], q[1], q[2], q[3]);
}

Vec3 HyqRobot::baseVelocity() const {
  dVector3 v;
  const Vec3 o = -trunkCom();
  dBodyGetRelPointVel(trunk_, o.x(), o.y(), o.z(), v);
  return Vec3(v[0], v[1], v[2]);
}

Vec3 HyqRobot::baseOmega() const {
  const dReal* w = dBodyGetAngularVel(trunk_);
  return Vec3(w[0], w[1], w[2]);
}

double HyqRobot::totalMass() const {
  dMass m;
  double total = 0.0;
  dBodyGetMass(trunk_, &m);
  total += m.mass;
  for (const auto& leg : links_)
    for (dBodyID b : leg) {
      dBodyGetMass(b, &m);
      total += m.mass;
    }
  return total;
}

}  // namespace hyq::sim
