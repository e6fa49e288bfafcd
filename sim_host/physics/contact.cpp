#include "sim_host/physics/contact.hpp"

#include <cmath>
#include <utility>

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
    for (const PieceContact& c : s.contacts)
      if (c.piece >= 0)
        dBodyAddForceAtPos(s.body, c.force.x(), c.force.y(), c.force.z(), c.point.x(), c.point.y(),
                           c.point.z());
  }
}

bool ContactModel::concave(int a, int b) const {
  const std::vector<Terrain::Piece>& pieces = terrain_.pieces();
  if (b != a + 1) return false;
  const auto slope = [&](const Terrain::Piece& p) { return (p.z_end - p.z_begin) / (p.x_end - p.x_begin); };
  return slope(pieces[b]) > slope(pieces[a]);
}

void ContactModel::update(SphereContact& s, double h) {
  const Vec3 centre = toVec3(dGeomGetPosition(s.geom));
  // The deepest contact with each terrain piece near the sphere (pieces are
  // sorted along x; only those under the sphere can touch it).
  const std::vector<Terrain::Piece>& pieces = terrain_.pieces();
  dContactGeom deepest[2]{};
  int piece[2] = {-1, -1};
  int found = 0;
  for (size_t i = 0; i < pieces.size(); ++i) {
    if (centre.x() + 2.0 * s.radius < pieces[i].x_begin || centre.x() - 2.0 * s.radius > pieces[i].x_end)
      continue;
    dContactGeom c[4];
    const int n = dCollide(s.geom, ground_[i], 4, c, sizeof(dContactGeom));
    dContactGeom best{};
    bool touched = false;
    for (int k = 0; k < n; ++k)
      if (c[k].depth > 0.0 && (!touched || c[k].depth > best.depth)) {
        best = c[k];
        touched = true;
      }
    if (!touched) continue;
    // Keep the two deepest pieces.
    if (found < 2) {
      deepest[found] = best;
      piece[found++] = static_cast<int>(i);
    } else {
      const int weaker = deepest[0].depth < deepest[1].depth ? 0 : 1;
      if (best.depth > deepest[weaker].depth) {
        deepest[weaker] = best;
        piece[weaker] = static_cast<int>(i);
      }
    }
  }
  // Two pieces: both contacts in a concave change of slope, else the deeper.
  if (found == 2) {
    const int a = piece[0] < piece[1] ? 0 : 1;
    if (!concave(piece[a], piece[1 - a])) {
      if (deepest[0].depth < deepest[1].depth) {
        deepest[0] = deepest[1];
        piece[0] = piece[1];
      }
      found = 1;
    }
  }
  // Each contact continues the bristle its piece had last substep; a single
  // contact whose piece changed (over a convex edge) continues the main one.
  PieceContact next[2];
  for (int k = 0; k < found; ++k) {
    next[k].piece = piece[k];
    bool continued = false;
    for (const PieceContact& last : s.contacts)
      if (last.piece == piece[k]) {
        next[k].deflection = last.deflection;
        continued = true;
      }
    if (!continued && found == 1 && s.in_contact) {
      next[k].deflection = s.contacts[0].deflection;
      continued = true;
    }
    contactForce(s, deepest[k], continued, found, h, next[k]);
  }
  // The main contact (the larger normal force) in the first slot.
  if (found == 2 && next[1].normal_force > next[0].normal_force) std::swap(next[0], next[1]);
  s.contacts[0] = next[0];
  s.contacts[1] = next[1];

  s.in_contact = found > 0;
  s.force.setZero();
  for (int k = 0; k < found; ++k) s.force += next[k].force;
  if (!s.in_contact) {
    s.sliding = false;
    s.slip_velocity.setZero();
    s.depth = 0.0;
    return;
  }
  const PieceContact& main = next[0];
  s.sliding = main.sliding;
  s.point = main.point;
  s.normal = main.normal;
  s.depth = main.depth;
  s.mu = main.mu;
  s.slip_velocity = main.slip_velocity;
}

void ContactModel::contactForce(const SphereContact& s, const dContactGeom& geom, bool continued, int shared,
                                double h, PieceContact& c) const {
  const Vec3 centre = toVec3(dGeomGetPosition(s.geom));
  // ODE's normal sign depends on the argument order: orient it out of the
  // ground, towards the sphere's centre.
  Vec3 n = toVec3(geom.normal);
  if (n.dot(centre - toVec3(geom.pos)) < 0.0) n = -n;
  n.normalize();
  const double depth = geom.depth;
  const Vec3 p = centre - (s.radius - depth) * n;  // on the ground surface

  dVector3 vel;
  dBodyGetPointVel(s.body, p.x(), p.y(), p.z(), vel);
  const Vec3 v = toVec3(vel);
  const double vn = v.dot(n);
  const Vec3 vt = v - vn * n;

  // Both contacts of a crease push nearly along one direction: their
  // stiffnesses and dampings add, and twice one contact's is beyond the
  // explicit step's bound on a light foot (it shakes in place). Each then
  // takes its share, so the pair is as stiff and as damped as one contact.
  const double stiffness = params_.normal_stiffness / shared;
  const double damping = params_.normal_damping / shared;
  const double fn = std::fmax(0.0, stiffness * depth - damping * vn);
  const double mu = terrain_.mu(p.x(), p.y());

  // The material point moved by the last step's velocity (ODE moves
  // positions with the velocities it ends a step with, which are this
  // step's starting ones).
  if (!continued || fn <= 0.0)
    c.deflection.setZero();  // new touch-down, or unloaded: no memory
  else
    c.deflection += h * vt;
  c.deflection -= n * n.dot(c.deflection);  // in the surface plane
  Vec3 ft = -params_.tangent_stiffness * c.deflection - params_.tangent_damping * vt;
  const double limit = mu * fn;
  const double ft_norm = ft.norm();
  c.sliding = ft_norm > limit;
  if (c.sliding) {
    // Radial return: the trial force scaled back onto the cone. Its damping
    // part points against the slip, its spring part along last tick's
    // force, so the sliding force turns with the slip within a few ticks.
    // A force set to minus each tick's slip velocity would let a light
    // foot's leg inertia swing the slip direction tick to tick (tests/
    // sim/robot_test.cpp, SlidingFeet).
    const Vec3 dir = ft_norm > 0.0 ? Vec3(ft / ft_norm) : Vec3::Zero();
    ft = limit * dir;
    // The bristle stretches exactly to the sliding force.
    c.deflection = -ft / params_.tangent_stiffness;
  }
  c.point = p;
  c.normal = n;
  c.depth = depth;
  c.mu = mu;
  c.normal_force = fn;
  c.force = fn * n + ft;
  c.slip_velocity = vt;
}

}  // namespace hyq::sim
