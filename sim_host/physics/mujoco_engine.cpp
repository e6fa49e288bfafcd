#include "sim_host/physics/mujoco_engine.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <stdexcept>

#include "firmware/controller/model/robot_params.hpp"
#include "sim_host/physics/mujoco_model.hpp"

namespace hyq::sim {
namespace {
using namespace hyq::robot;

int id(const mjModel* m, mjtObj type, const std::string& name) {
  const int i = mj_name2id(m, type, name.c_str());
  if (i < 0) throw std::logic_error("MuJoCo model has no " + name);
  return i;
}

Vec3 vec3(const mjtNum* v) { return Vec3(v[0], v[1], v[2]); }

// MuJoCo's warnings go to stderr as one line each: its default prints them
// on stdout, which `hyq_sim run --json` and --quiet keep for the summary or
// for nothing.
void warningToStderr(const char* message) { std::fprintf(stderr, "hyq_sim: MuJoCo warning: %s\n", message); }
}  // namespace

MujocoEngine::MujocoEngine(const Scenario& scenario, const Terrain& terrain,
                           const SimConfig& config)
    : terrain_(terrain) {
  mju_user_warning = warningToStderr;
  const double h = config.integration.tick / config.integration.substeps;
  const std::string xml = hyqMjcf(scenario, terrain, h);
  // The model goes to MuJoCo through its virtual file system, not the disk.
  auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  const char* file = "hyq.xml";
  if (mj_makeEmptyFileVFS(vfs.get(), file, static_cast<int>(xml.size())) != 0)
    throw std::runtime_error("MuJoCo: cannot make the model file in its VFS");
  std::memcpy(vfs->filedata[mj_findFileVFS(vfs.get(), file)], xml.data(), xml.size());
  char error[1000] = "";
  m_ = mj_loadXML(file, vfs.get(), error, sizeof error);
  mj_deleteVFS(vfs.get());
  if (!m_) throw std::runtime_error(std::string("MuJoCo: the generated model: ") + error);
  d_ = mj_makeData(m_);
  // From here the destructor does not run if the constructor throws.
  try {
    if (!d_) throw std::runtime_error("MuJoCo: cannot allocate the model's data");
    setUp();
  } catch (...) {
    if (d_) mj_deleteData(d_);
    mj_deleteModel(m_);
    throw;
  }
}

void MujocoEngine::setUp() {
  trunk_ = id(m_, mjOBJ_BODY, "trunk");
  for (const TimedGroundBox& b : timedGroundBoxes(terrain_))
    timed_ground_.push_back({id(m_, mjOBJ_GEOM, b.name), b.x, b.y});
  const char* joints[3] = {"haa", "hfe", "kfe"};
  for (int leg = 0; leg < kNumLegs; ++leg) {
    for (int k = 0; k < 3; ++k) {
      const int j = id(m_, mjOBJ_JOINT, std::string(kLegNames[leg]) + "_" + joints[k]);
      qpos_[3 * leg + k] = m_->jnt_qposadr[j];
      dof_[3 * leg + k] = m_->jnt_dofadr[j];
    }
    foot_geom_[leg] = id(m_, mjOBJ_GEOM, std::string(kLegNames[leg]) + "_foot");
  }
  mj_forward(m_, d_);
  readFeetMotion();
}

MujocoEngine::~MujocoEngine() {
  mj_deleteData(d_);
  mj_deleteModel(m_);
}

void MujocoEngine::place(const Vec3& base_pos, const Mat3& base_rot,
                         const std::array<double, 12>& q) {
  mj_resetData(m_, d_);
  const Quat r(base_rot);
  const mjtNum pose[7] = {base_pos.x(), base_pos.y(), base_pos.z(), r.w(), r.x(), r.y(), r.z()};
  std::memcpy(d_->qpos, pose, sizeof pose);
  for (int j = 0; j < 12; ++j) d_->qpos[qpos_[j]] = q[j];
  mj_forward(m_, d_);
  for (FootContactState& f : feet_) f = FootContactState{};
  readFeetMotion();
}

// MuJoCo's contacts are soft constraints whose force at rest follows from
// the penetration (solref, solimp). The sink is where, at rest and with no
// acceleration, the contacts hold the whole robot up: inverse dynamics
// (mj_inverse, consistent with the forward dynamics for soft constraints)
// then needs no force on the base's vertical, found by bisection.
double MujocoEngine::staticSink(const Vec3& base_pos, const Mat3& base_rot,
                                const std::array<double, 12>& q, double) {
  // What must push the base up to keep it still at this sink.
  auto push_needed = [&](double sink) {
    place(base_pos - Vec3(0.0, 0.0, sink), base_rot, q);
    mju_zero(d_->qacc, m_->nv);
    mj_inverse(m_, d_);
    return d_->qfrc_inverse[2];  // the free joint's z
  };
  // A bracket first (the softest settings the scenario allows sink
  // decimetres), then bisection.
  double lo = 0.0, hi = 0.01;  // [m]
  for (int k = 0; k < 7 && push_needed(hi) > 0.0; ++k) {
    lo = hi;
    hi *= 2.0;
  }
  for (int k = 0; k < 40; ++k) {
    const double sink = 0.5 * (lo + hi);
    (push_needed(sink) > 0.0 ? lo : hi) = sink;
  }
  return 0.5 * (lo + hi);
}

void MujocoEngine::step(const std::array<double, 12>& joint_torque, const Vec3& trunk_force,
                        double h) {
  m_->opt.timestep = h;
  // The derived quantities (kinematics, contacts) are those of the present
  // state: mj_step1 ended the previous step, or mj_forward placed the robot.
  for (int j = 0; j < 12; ++j) d_->qfrc_applied[dof_[j]] = joint_torque[j];
  mjtNum* f = d_->xfrc_applied + 6 * trunk_;
  f[0] = trunk_force.x();
  f[1] = trunk_force.y();
  f[2] = trunk_force.z();
  mj_step2(m_, d_);
  readContacts();   // the step's contacts and their forces
  // The next step's contacts take their friction from the ground geoms:
  // those under a timed patch get the terrain's friction at that step.
  for (const TimedGeom& g : timed_ground_)
    m_->geom_friction[3 * g.geom] = mujocoFriction(terrain_.muAt(g.x, g.y, terrain_.time() + h));
  mj_step1(m_, d_); // kinematics, contacts of the new state
  readFeetMotion();
}

void MujocoEngine::readContacts() {
  for (int leg = 0; leg < kNumLegs; ++leg) {
    FootContactState& foot = feet_[leg];
    foot.in_contact = false;
    foot.force.setZero();
    foot.slip_velocity.setZero();
    double strongest = 0.0;
    for (int i = 0; i < d_->ncon; ++i) {
      const mjContact& c = d_->contact[i];
      if ((c.geom1 != foot_geom_[leg] && c.geom2 != foot_geom_[leg]) || c.efc_address < 0) continue;
      mjtNum local[6];
      mj_contactForce(m_, d_, i, local);
      if (local[0] <= 0.0) continue;
      // frame rows: normal (from geom1 to geom2), two tangents; the force
      // acts on geom2 along them, on geom1 against them.
      const double sign = c.geom2 == foot_geom_[leg] ? 1.0 : -1.0;
      const Vec3 n = sign * vec3(c.frame);
      const Vec3 force = sign * (local[0] * vec3(c.frame) + local[1] * vec3(c.frame + 3) +
                                 local[2] * vec3(c.frame + 6));
      foot.force += force;
      foot.in_contact = true;
      if (local[0] > strongest) {
        strongest = local[0];
        foot.normal = n;
        foot.point = vec3(c.pos);
        // The velocity of the foot's material point at the contact.
        mjtNum v[6];
        mj_objectVelocity(m_, d_, mjOBJ_GEOM, foot_geom_[leg], v, 0);
        const Vec3 omega = vec3(v), v_centre = vec3(v + 3);
        const Vec3 vp = v_centre + omega.cross(foot.point - vec3(d_->geom_xpos + 3 * foot_geom_[leg]));
        foot.slip_velocity = vp - vp.dot(n) * n;
      }
    }
  }
}

void MujocoEngine::readFeetMotion() {
  for (int leg = 0; leg < kNumLegs; ++leg) {
    mjtNum v[6];
    mj_objectVelocity(m_, d_, mjOBJ_GEOM, foot_geom_[leg], v, 0);
    feet_[leg].centre = vec3(d_->geom_xpos + 3 * foot_geom_[leg]);
    feet_[leg].velocity = vec3(v + 3);
  }
}

double MujocoEngine::jointAngle(int j) const { return d_->qpos[qpos_[j]]; }
double MujocoEngine::jointRate(int j) const { return d_->qvel[dof_[j]]; }
Vec3 MujocoEngine::basePosition() const { return vec3(d_->qpos); }
Quat MujocoEngine::baseQuaternion() const {
  return Quat(d_->qpos[3], d_->qpos[4], d_->qpos[5], d_->qpos[6]).normalized();
}
Mat3 MujocoEngine::baseRotation() const { return baseQuaternion().toRotationMatrix(); }
// The free joint's velocity: linear of the body origin in W, angular in B.
Vec3 MujocoEngine::baseVelocity() const { return vec3(d_->qvel); }
Vec3 MujocoEngine::baseOmega() const { return baseRotation() * vec3(d_->qvel + 3); }
FootContactState MujocoEngine::foot(int leg) const { return feet_[leg]; }

double MujocoEngine::totalMass() const {
  double total = 0.0;
  for (int b = 1; b < m_->nbody; ++b) total += m_->body_mass[b];
  return total;
}

}  // namespace hyq::sim
