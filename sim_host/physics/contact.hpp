// Ground contact of spheres fixed to ODE bodies, applied as forces.
// ODE finds the geometry (sphere vs. terrain boxes); the forces are ours:
//   normal:     Fn = max(0, k * depth - c * v_n)            (never pulls)
//   tangential: a bristle spring-damper on the sphere's material point at
//               the contact, Ft = -kt d - ct v_t, where v_t is that point's
//               tangential velocity and d the bristle's deflection, the
//               integral of v_t since touch-down (d += v_t h each step);
//               capped at |Ft| = mu Fn; when capped the foot slides: the
//               force is the trial force scaled onto the cone (a radial
//               return) and the deflection follows, so the bristle is
//               always the spring that carries the force.
// A sphere in a concave change of slope (a valley between two terrain
// pieces) touches both planes: each contact has its own normal force and
// bristle, each with half the stiffness and damping, and the two add. Over a convex edge the deeper contact alone
// carries the load (the sphere rests on the edge, one point).
// The cap is on the force's norm, so the friction cone is isotropic, and
// while under it the material point stays, so a loaded foot does not creep.
// What sticks is the material point at the contact, not the sphere's
// centre: a sphere turning over the ground rolls, its centre moving r per
// radian. Rolling meets no resistance (a rigid sphere on a rigid plane
// touches in one point); a rubber foot's rolling resistance, a torque of
// about Fn times the contact patch's offset, is left out.
#pragma once
#include <ode/ode.h>

#include <vector>

#include "firmware/controller/model/types.hpp"
#include "sim_host/physics/sim_params.hpp"
#include "sim_host/physics/terrain.hpp"

namespace hyq::sim {

struct SphereContact {
  // Set up once
  dBodyID body = nullptr;
  dGeomID geom = nullptr;
  double radius = 0.0;                // [m]
  // One contact with one terrain piece: its bristle is carried across
  // substeps while the sphere stays on that piece.
  struct Touch {
    int piece = -1;                   // [-] the terrain piece, -1: none
    Vec3 deflection = Vec3::Zero();   // [m] bristle deflection, in the surface plane, W
    Vec3 point = Vec3::Zero();        // [m] contact point on the surface, W
    Vec3 force = Vec3::Zero();        // [N] on the sphere, W
    double share = 1.0;               // [-] of the contact's stiffness and damping (ContactModel::update)
  };
  // State carried across substeps: at most two contacts (a concave crease).
  Touch touch[2];
  bool in_contact = false;
  bool sliding = false;               // the main contact's force capped on the cone this substep
  // Last substep's result (W): the contacts' total force; the rest of the
  // main contact (the one with the larger normal force).
  Vec3 point = Vec3::Zero();          // [m] contact point on the surface
  Vec3 normal = Vec3::UnitZ();        // [-] surface normal, out of the ground
  Vec3 force = Vec3::Zero();          // [N] on the sphere, every contact's
  Vec3 slip_velocity = Vec3::Zero();  // [m/s] tangential velocity of the contact point
  double mu = 0.0;                    // [-]
  double depth = 0.0;                 // [m]
  int contacts = 0;                   // [-] 0, 1, or 2 in a concave crease
};

class ContactModel {
 public:
  ContactModel(const Terrain& terrain, const ContactParams& params);
  ~ContactModel();
  ContactModel(const ContactModel&) = delete;
  ContactModel& operator=(const ContactModel&) = delete;

  // A sphere of `radius` whose centre is at `offset` in the body's frame.
  int addSphere(dBodyID body, const Vec3& offset, double radius);
  // Computes and applies (dBodyAddForceAtPos) every contact force for the
  // coming ODE step of `h` seconds. Call once per step, before dWorldStep.
  void applyForces(double h);

  const SphereContact& sphere(int i) const { return spheres_[i]; }
  int size() const { return static_cast<int>(spheres_.size()); }

 private:
  // The deepest contact of a sphere with one terrain piece.
  struct PieceContact {
    int piece = -1;
    dContactGeom geom{};
  };
  void update(SphereContact& s, double h);
  // The sphere's contacts: the deepest, and a second piece's in a concave
  // crease. Returns how many (0-2), deepest first.
  int findContacts(const SphereContact& s, const Vec3& centre, PieceContact found[2]) const;
  // What one contact reports besides its force (W).
  struct TouchResult {
    double normal_force;  // [N]
    double mu;            // [-] the ground's at the contact point
    Vec3 normal;          // [-] out of the ground
    Vec3 slip_velocity;   // [m/s] the contact point's tangential velocity
    bool sliding;         // force capped on the cone
  };
  // One contact's force (and its bristle, `t`), with `share` of the
  // contact's stiffness and damping.
  TouchResult touchForce(const SphereContact& s, const Vec3& centre, const dContactGeom& c, double share,
                         bool was_touching, double h, SphereContact::Touch& t) const;
  // Pieces a and b meet in a valley (b's slope rises above a's, adjacent).
  bool concaveCrease(int a, int b) const;
  const Terrain& terrain_;
  ContactParams params_;
  std::vector<SphereContact> spheres_;
  std::vector<dGeomID> ground_;   // one box per terrain piece, same order
};

}  // namespace hyq::sim
