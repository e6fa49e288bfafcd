#include "sim_host/physics/contact.hpp"

#include <cmath>

namespace hyq::sim {
namespace {
Vec3 toVec3(const dReal* v) { return Vec3(v[0], v[1], v[2]); }
}  // namespace

ContactModel::ContactModel(const Terrain& terrain, const ContactParams& params)
    : terrain_(terrain), params_(params) {
  for (const Terrain::Piece& piece : terrain_.pieces()) {
    const double dx = piece.x_end - piece.x_begin, dz = piece.z_end - piece.z_begin;
    const double angle = std::atan2(dz, dx);
    const Vec3 n(-std::sin(angle), 0.0, std::cos(angle));
    const Vec3 centre = Vec3(piece.x_begin + 0.5 * dx, 0.0, piece.z_begin + 0.5 * dz) -
                        0.5 * Terrain::kBoxThickness * n;
    dGeomID box = dCreateBox(nullptr, std::hypot(dx, dz), 2.0 * Terrain::kWorldHalfExtent,
                             Terrain::kBoxThickness);
    dMatrix3 rot;
    // Rotating about +y by -angle takes x_B onto the piece's direction.
    dRFromAxisAndAngle(rot, 0.0, 1.0, 0.0, -angle);
    dGeomSetPosition(box, centre.x(), centre.y(), centre.z());
    dGeomSetRotation(box, rot);
    ground_.push_back(box);
  }
}

ContactModel::~ContactModel() {
  for (SphereContact& s : spheres_) dGeomDestroy(s.geom);
  for (dGeomID box : ground_) dGeomDestroy(box);
}

int ContactModel::addSphere(dBodyID body, const Vec3& offset, double radius) {
  SphereContact s;
  s.body = body;
  s.radius = radius;
  s.geom = dCreateSphere(nullptr, radius);
  dGeomSetBody(s.geom, body);
  dGeomSetOffsetPosition(s.geom, offset.x(), offset.y(), offset.z());
  spheres_.push_back(s);
  return size() - 1;
}

void ContactModel::applyForces(double h) {
  for (SphereContact& s : spheres_) {
    update(s, h);
    if (s.in_contact)
      dBodyAddForceAtPos(s.body, s.force.x(), s.force.y(), s.force.z(), s.point.x(), s.point.y(),
                         s.point.z());
  }
}

void ContactModel::update(SphereContact& s, double h) {
  const Vec3 centre = toVec3(dGeomGetPosition(s.geom));
  // Deepest contact over the terrain pieces near the sphere. Near a convex
  // edge two pieces may touch the sphere: the deeper one carries the load.
  dContactGeom best{};
  bool found = false;
  const std::vector<Terrain::Piece>& pieces = terrain_.pieces();
  for (size_t i = 0; i < pieces.size(); ++i) {
    // Pieces are sorted along x; only those under the sphere can touch it.
    if (centre.x() + 2.0 * s.radius < pieces[i].x_begin ||
        centre.x() - 2.0 * s.radius > pieces[i].x_end)
      continue;
    dContactGeom c[4];
    const int n = dCollide(s.geom, ground_[i], 4, c, sizeof(dContactGeom));
    for (int k = 0; k < n; ++k) {
      if (!found || c[k].depth > best.depth) best = c[k];
      found = true;
    }
  }
  if (!found || best.depth <= 0.0) {
    s.in_contact = false;
    s.sliding = false;
    s.force.setZero();
    s.slip_velocity.setZero();
    s.depth = 0.0;
    return;
  }

  // ODE's normal sign depends on the argument order: orient it out of the
  // ground, towards the sphere's centre.
  Vec3 n = toVec3(best.normal);
  if (n.dot(centre - toVec3(best.pos)) < 0.0) n = -n;
  n.normalize();
  const double depth = best.depth;
  const Vec3 p = centre - (s.radius - depth) * n;  // on the ground surface

  dVector3 vel;
  dBodyGetPointVel(s.body, p.x(), p.y(), p.z(), vel);
  const Vec3 v = toVec3(vel);
  const double vn = v.dot(n);
  const Vec3 vt = v - vn * n;

  const double fn = std::fmax(0.0, params_.normal_stiffness * depth - params_.normal_damping * vn);
  const double mu = terrain_.mu(p.x(), p.y());

  // The material point moved by the last step's velocity (ODE moves
  // positions with the velocities it ends a step with, which are this
  // step's starting ones).
  if (!s.in_contact || fn <= 0.0)
    s.deflection.setZero();  // new touch-down, or unloaded: no memory
  else
    s.deflection += h * vt;
  s.deflection -= n * n.dot(s.deflection);  // in the surface plane
  Vec3 ft = -params_.tangent_stiffness * s.deflection - params_.tangent_damping * vt;
  const double limit = mu * fn;
  const double ft_norm = ft.norm();
  s.sliding = ft_norm > limit;
  if (s.sliding) {
    // Radial return: the trial force scaled back onto the cone. Its damping
    // part points against the slip, its spring part along last tick's
    // force, so the sliding force turns with the slip within a few ticks.
    // A force set to minus each tick's slip velocity would let a light
    // foot's leg inertia swing the slip direction tick to tick (tests/
    // sim/robot_test.cpp, SlidingFeet).
    const Vec3 dir = ft_norm > 0.0 ? Vec3(ft / ft_norm) : Vec3::Zero();
    ft = limit * dir;
    // The bristle stretches exactly to the sliding force.
    s.deflection = -ft / params_.tangent_stiffness;
  }

  s.in_contact = true;
  s.point = p;
  s.normal = n;
  s.depth = depth;
  s.mu = mu;
  s.force = fn * n + ft;
  s.slip_velocity = vt;
}

}  // namespace hyq::sim
