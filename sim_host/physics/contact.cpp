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
    for (int k = 0; k < s.contacts; ++k) {
      const SphereContact::Touch& t = s.touch[k];
      dBodyAddForceAtPos(s.body, t.force.x(), t.force.y(), t.force.z(), t.point.x(), t.point.y(), t.point.z());
    }
  }
}

bool ContactModel::concaveCrease(int a, int b) const {
  const std::vector<Terrain::Piece>& pieces = terrain_.pieces();
  if (a > b) std::swap(a, b);
  if (b != a + 1) return false;
  const Terrain::Piece& pa = pieces[a];
  const Terrain::Piece& pb = pieces[b];
  const double slope_a = std::atan2(pa.z_end - pa.z_begin, pa.x_end - pa.x_begin);
  const double slope_b = std::atan2(pb.z_end - pb.z_begin, pb.x_end - pb.x_begin);
  return slope_b > slope_a + 1e-9;
}

int ContactModel::findContacts(const SphereContact& s, const Vec3& centre, PieceContact found[2]) const {
  int count = 0;
  const std::vector<Terrain::Piece>& pieces = terrain_.pieces();
  for (size_t i = 0; i < pieces.size(); ++i) {
    // Pieces are sorted along x; only those under the sphere can touch it.
    if (centre.x() + 2.0 * s.radius < pieces[i].x_begin ||
        centre.x() - 2.0 * s.radius > pieces[i].x_end)
      continue;
    dContactGeom c[4];
    const int n = dCollide(s.geom, ground_[i], 4, c, sizeof(dContactGeom));
    PieceContact f;
    for (int k = 0; k < n; ++k)
      if (f.piece < 0 || c[k].depth > f.geom.depth) {
        f.piece = static_cast<int>(i);
        f.geom = c[k];
      }
    if (f.piece < 0 || f.geom.depth <= 0.0) continue;
    // Keep the two deepest, deepest first.
    if (count < 2)
      found[count++] = f;
    else if (f.geom.depth > found[1].geom.depth)
      found[1] = f;
    if (count == 2 && found[1].geom.depth > found[0].geom.depth) std::swap(found[0], found[1]);
  }
  // Two pieces count only in a concave crease; over a convex edge the
  // deeper one carries the load.
  if (count == 2 && !concaveCrease(found[0].piece, found[1].piece)) count = 1;
  return count;
}

ContactModel::TouchResult ContactModel::touchForce(const SphereContact& s, const Vec3& centre,
                                                   const dContactGeom& c, double share, bool was_touching,
                                                   double h, SphereContact::Touch& t) const {
  // ODE's normal sign depends on the argument order: orient it out of the
  // ground, towards the sphere's centre.
  Vec3 n = toVec3(c.normal);
  if (n.dot(centre - toVec3(c.pos)) < 0.0) n = -n;
  n.normalize();
  const Vec3 p = centre - (s.radius - c.depth) * n;  // on the ground surface

  dVector3 vel;
  dBodyGetPointVel(s.body, p.x(), p.y(), p.z(), vel);
  const Vec3 v = toVec3(vel);
  const double vn = v.dot(n);
  const Vec3 vt = v - vn * n;

  const double fn =
      std::fmax(0.0, share * (params_.normal_stiffness * c.depth - params_.normal_damping * vn));
  const double mu = terrain_.mu(p.x(), p.y());

  // The material point moved by the last step's velocity (ODE moves
  // positions with the velocities it ends a step with, which are this
  // step's starting ones). A new contact, or an unloaded one, has no memory.
  if (!was_touching || fn <= 0.0)
    t.deflection.setZero();
  else
    t.deflection += h * vt;
  t.deflection -= n * n.dot(t.deflection);  // in the surface plane
  Vec3 ft = -share * (params_.tangent_stiffness * t.deflection + params_.tangent_damping * vt);
  const double limit = mu * fn;
  const double ft_norm = ft.norm();
  const bool sliding = ft_norm > limit;
  if (sliding) {
    // Radial return: the trial force scaled back onto the cone. Its damping
    // part points against the slip, its spring part along last tick's
    // force, so the sliding force turns with the slip within a few ticks.
    // A force set to minus each tick's slip velocity would let a light
    // foot's leg inertia swing the slip direction tick to tick (tests/
    // sim/robot_test.cpp, SlidingFeet).
    const Vec3 dir = ft_norm > 0.0 ? Vec3(ft / ft_norm) : Vec3::Zero();
    ft = limit * dir;
    // The bristle stretches exactly to the sliding force.
    t.deflection = -ft / (share * params_.tangent_stiffness);
  }
  t.point = p;
  t.force = fn * n + ft;
  return TouchResult{fn, mu, n, vt, sliding};
}

void ContactModel::update(SphereContact& s, double h) {
  const Vec3 centre = toVec3(dGeomGetPosition(s.geom));
  PieceContact found[2];
  const int count = findContacts(s, centre, found);

  // In a crease the two contacts share one contact's stiffness and damping,
  // each in proportion to its depth: the foot meets the same ground wherever
  // it stands, the explicit contact stays within its damping bound (c h / m
  // < 2: 1.7 on the nominal lower leg, twice that with two full contacts,
  // which rang), and a contact's share goes to zero with its depth, so a foot
  // that leaves a valley feels no step in its force (with half shares the
  // remaining plane's normal force doubled in a substep, and the foot bounced).
  double share[2] = {1.0, 1.0};
  if (count == 2) {
    const double depth = found[0].geom.depth + found[1].geom.depth;
    share[0] = found[0].geom.depth / depth;
    share[1] = found[1].geom.depth / depth;
  }
  // Each contact keeps the bristle it had on its piece; a single contact
  // keeps the single contact's before, whichever piece it was on (a foot
  // that rolls across an edge in one substep stays stuck). A bristle whose
  // share changes keeps its force: its deflection scales by the old share
  // over the new.
  SphereContact::Touch next[2];
  bool was_touching[2] = {false, false};
  for (int k = 0; k < count; ++k) {
    next[k].piece = found[k].piece;
    next[k].share = share[k];
    for (const SphereContact::Touch& t : s.touch)
      if (t.piece == found[k].piece) {
        next[k].deflection = t.deflection * (t.share / share[k]);
        was_touching[k] = true;
      }
  }
  if (count == 1 && s.contacts == 1 && !was_touching[0]) {
    next[0].deflection = s.touch[0].deflection * (s.touch[0].share / share[0]);
    was_touching[0] = true;
  }

  s.contacts = count;
  s.force.setZero();
  s.slip_velocity.setZero();
  s.sliding = false;
  s.depth = 0.0;
  double main_fn = -1.0;
  for (int k = 0; k < count; ++k) {
    const TouchResult r = touchForce(s, centre, found[k].geom, share[k], was_touching[k], h, next[k]);
    s.force += next[k].force;
    s.depth = std::fmax(s.depth, found[k].geom.depth);
    // The main contact (the larger normal force) stands for the foot's.
    if (r.normal_force > main_fn) {
      main_fn = r.normal_force;
      s.point = next[k].point;
      s.normal = r.normal;
      s.mu = r.mu;
      s.slip_velocity = r.slip_velocity;
      s.sliding = r.sliding;
    }
  }
  s.touch[0] = next[0];
  s.touch[1] = next[1];
  s.in_contact = count > 0;
}

}  // namespace hyq::sim
