#include "sim_host/physics/physics_engine.hpp"

#include "sim_host/physics/mujoco_engine.hpp"
#include "sim_host/physics/ode_engine.hpp"

namespace hyq::sim {

const char* engineName(EngineKind e) { return e == EngineKind::mujoco ? "mujoco" : "ode"; }

bool parseEngineName(const std::string& name, EngineKind& out) {
  if (name == "ode")
    out = EngineKind::ode;
  else if (name == "mujoco")
    out = EngineKind::mujoco;
  else
    return false;
  return true;
}

std::unique_ptr<PhysicsEngine> makePhysicsEngine(const Scenario& scenario, const Terrain& terrain,
                                                 const SimConfig& config) {
  if (scenario.physics.engine == EngineKind::mujoco)
    return std::make_unique<MujocoEngine>(scenario, terrain, config);
  return std::make_unique<OdeEngine>(scenario, terrain, config);
}

}  // namespace hyq::sim
