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
  // State carried across substeps
  bool in_contact = false;
  bool sliding = false;               // force capped on the cone this substep
  Vec3 deflection = Vec3::Zero();     // [m] bristle deflection, in the surface plane, W
  // Last substep's result (W)
  Vec3 point = Vec3::Zero();          // [m] contact point on the surface
  Vec3 normal = Vec3::UnitZ();        // [-] surface normal, out of the ground
  Vec3 force = Vec3::Zero();          // [N] on the sphere
  Vec3 slip_velocity = Vec3::Zero();  // [m/s] tangential velocity of the contact point
  double mu = 0.0;                    // [-]
  double depth = 0.0;                 // [m]
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
  void update(SphereContact& s, double h);
  const Terrain& terrain_;
  ContactParams params_;
  std::vector<SphereContact> spheres_;
  std::vector<dGeomID> ground_;   // one box per terrain piece, same order
};

}  // namespace hyq::sim
