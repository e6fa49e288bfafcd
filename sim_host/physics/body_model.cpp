#include "sim_host/physics/body_model.hpp"

#include "firmware/controller/model/robot_params.hpp"

namespace hyq::sim {
namespace {
using namespace hyq::robot;

// A symmetric inertia tensor from its six entries [kg m^2].
Mat3 tensor(double xx, double yy, double zz, double xy, double xz, double yz) {
  Mat3 i;
  i << xx, xy, xz, xy, yy, yz, xz, yz, zz;
  return i;
}

RobotBody makeNominal() {
  RobotBody b;
  b.model = BodyModel::nominal;
  b.trunk_mass = kTrunkMass;
  b.trunk_com = Vec3(kTrunkCom[0], kTrunkCom[1], kTrunkCom[2]);
  const double* ti = kTrunkInertia;
  b.trunk_inertia = tensor(ti[0], ti[1], ti[2], ti[3], ti[4], ti[5]);
  const double length[3] = {kHipLength, kUpperLength, kLowerLength};
  const double mass[3] = {kHipMass, kUpperMass, kLowerMass};
  const double r = kLinkInertiaRadius;
  for (auto& leg : b.links)
    for (int k = 0; k < 3; ++k) {
      leg[k].mass = mass[k];
      leg[k].com = Vec3(0.0, 0.0, -1.0) * (0.5 * length[k]);  // mid-link
      const double perp = mass[k] * (3.0 * r * r + length[k] * length[k]) / 12.0;
      leg[k].inertia = tensor(perp, perp, 0.5 * mass[k] * r * r, 0.0, 0.0, 0.0);
    }
  b.lower_length = kLowerLength;
  b.total_mass = kTotalMass;
  b.cylinder_links = true;
  return b;
}

// --- The published HyQ description (URDF; a later revision than the
// numbers in robot_params.hpp). Each link's inertial parameters are given in
// that description's own link frame, whose z is the joint axis; its frames
// chain as (origin [m], rpy [rad] in the parent): LF HAA (0.3735, 0.207, 0),
// (0, pi/2, pi); RF HAA (0.3735, -0.207, 0), (0, pi/2, 0); LH and RH as LF
// and RF at x = -0.3735; HFE (0.08, 0, 0), (pi/2, 0, 0) on the left legs,
// (-pi/2, 0, 0) on the right; KFE (0.35, 0, 0); foot (0.346, 0, 0).
// At zero angles those frames' axes in B (the columns below) are: left hip
// x down, y -y_B, z -x_B (the HAA axis); right hip x down, y +y_B, z +x_B;
// every upper and lower leg x down, y -x_B, z +y_B (the HFE and KFE axes).
// The joints' positions, axes and senses are the controller's.
struct PublishedRow {
  double mass;        // [kg]
  double com[3];      // [m] in the description's link frame
  double inertia[6];  // [kg m^2] about the CoM: xx, yy, zz, xy, xz, yz
};
constexpr double kPublishedTrunkMass = 60.96;                         // [kg]
constexpr double kPublishedTrunkCom[3] = {0.056, 0.0215, 0.00358};    // [m] in B
constexpr double kPublishedTrunkInertia[6] = {1.5725937, 8.5015928, 9.1954911,
                                              0.028375, -0.203139, -0.004462};  // [kg m^2] in B
// Hip assembly: LF and RH; RF and LH.
constexpr PublishedRow kHipA = {2.93, {0.04263, 0.0, 0.16931},
                                {0.05071, 0.05486, 0.00571, -4e-05, -0.00159, -5e-05}};
constexpr PublishedRow kHipB = {2.93, {0.04263, 0.0, -0.16931},
                                {0.05071, 0.05486, 0.00571, 4e-05, 0.00159, -5e-05}};
// Upper leg: front; hind.
constexpr PublishedRow kUpperFront = {2.638, {0.15074, -0.02625, 0.0},
                                      {0.00368, 0.02719, 0.02811, -0.00302, 0.0001, 2e-05}};
constexpr PublishedRow kUpperHind = {2.638, {0.15074, 0.02625, 0.0},
                                     {0.00368, 0.02719, 0.02811, 0.00302, -0.0001, 2e-05}};
// Lower leg: front; hind.
constexpr PublishedRow kLowerFront = {0.881, {0.1254, 4e-05, -0.0001},
                                      {0.00047, 0.01256, 0.01233, 6e-05, -1e-05, 0.0}};
constexpr PublishedRow kLowerHind = {0.881, {0.1254, -4e-05, 0.0001},
                                     {0.00047, 0.01256, 0.01233, -6e-05, 1e-05, 0.0}};
constexpr double kPublishedLowerLength = 0.346;  // [m] KFE -> foot centre

Mat3 axes(const Vec3& x, const Vec3& y, const Vec3& z) {
  Mat3 r;
  r.col(0) = x;
  r.col(1) = y;
  r.col(2) = z;
  return r;
}

// A published row in the simulator's link frame, `r` the description's
// link axes in it.
LinkInertial inLinkFrame(const PublishedRow& row, const Mat3& r) {
  LinkInertial l;
  l.mass = row.mass;
  l.com = r * Vec3(row.com[0], row.com[1], row.com[2]);
  const double* i = row.inertia;
  l.inertia = r * tensor(i[0], i[1], i[2], i[3], i[4], i[5]) * r.transpose();
  return l;
}

RobotBody makePublished() {
  RobotBody b;
  b.model = BodyModel::published;
  b.trunk_mass = kPublishedTrunkMass;
  b.trunk_com = Vec3(kPublishedTrunkCom[0], kPublishedTrunkCom[1], kPublishedTrunkCom[2]);
  const double* ti = kPublishedTrunkInertia;
  b.trunk_inertia = tensor(ti[0], ti[1], ti[2], ti[3], ti[4], ti[5]);
  const Vec3 down(0.0, 0.0, -1.0);
  const Mat3 left_hip = axes(down, -Vec3::UnitY(), -Vec3::UnitX());
  const Mat3 right_hip = axes(down, Vec3::UnitY(), Vec3::UnitX());
  const Mat3 thigh_shank = axes(down, -Vec3::UnitX(), Vec3::UnitY());
  b.total_mass = b.trunk_mass;
  for (int leg = 0; leg < kNumLegs; ++leg) {
    const bool front = isFront(leg), left = isLeft(leg);
    const bool hip_a = (leg == LF || leg == RH);
    b.links[leg][0] = inLinkFrame(hip_a ? kHipA : kHipB, left ? left_hip : right_hip);
    b.links[leg][1] = inLinkFrame(front ? kUpperFront : kUpperHind, thigh_shank);
    b.links[leg][2] = inLinkFrame(front ? kLowerFront : kLowerHind, thigh_shank);
    for (const LinkInertial& l : b.links[leg]) b.total_mass += l.mass;
  }
  b.lower_length = kPublishedLowerLength;
  b.cylinder_links = false;
  return b;
}
}  // namespace

const RobotBody& nominalBody() {
  static const RobotBody body = makeNominal();
  return body;
}

const RobotBody& publishedBody() {
  static const RobotBody body = makePublished();
  return body;
}

const RobotBody& robotBody(BodyModel model) {
  return model == BodyModel::published ? publishedBody() : nominalBody();
}

RobotBody plantBody(const PlantSpec& plant) {
  RobotBody b = robotBody(plant.body);
  b.total_mass += (plant.trunk_mass_scale - 1.0) * b.trunk_mass;
  b.trunk_mass *= plant.trunk_mass_scale;
  b.trunk_inertia *= plant.trunk_inertia_scale;
  return b;
}

const char* bodyModelName(BodyModel model) { return model == BodyModel::published ? "published" : "nominal"; }

ImuPlacement imuPlacement(ImuMount mount) {
  ImuPlacement p;
  if (mount == ImuMount::mounted) {
    // The published description's IMU link: (0.290, 0.000, 0.0999) m, rpy
    // (0, -pi, 0): a half turn about y, x and z reversed (written exactly,
    // not through sin(pi)).
    p.position = Vec3(0.290, 0.000, 0.0999);
    p.rotation = Vec3(-1.0, 1.0, -1.0).asDiagonal();
  }
  return p;
}

}  // namespace hyq::sim
