// HyQ and its terrain as a MuJoCo model (MJCF text), generated from the
// robot's joint frames (firmware/controller/model/robot_params.hpp), the
// scenario's body description (body_model.hpp, plant.body) and the
// scenario: the same bodies, frames, masses and inertias as the ODE model
// (robot.hpp), the foot spheres and the trunk box as the only robot
// geometry, the ground as static boxes, one per piece of the height profile
// and per region of constant friction.
#pragma once
#include <cstddef>
#include <string>
#include <vector>

#include "sim_host/scenario/scenario.hpp"
#include "sim_host/physics/terrain.hpp"

namespace hyq::sim {

// Names in the generated model: body "trunk" (its frame is B) with a free
// joint "base"; per leg L in LF, RF, LH, RH bodies "L_hip", "L_upper",
// "L_lower", hinges "L_haa", "L_hfe", "L_kfe" (in that order, legs in
// that order), the foot sphere geom "L_foot"; ground geoms "ground_<k>".
// Throws ScenarioError when the ground would need more than
// kMaxMujocoGroundBoxes boxes (friction patches whose edges cut the ground
// into that many regions).
std::string hyqMjcf(const Scenario& scenario, const Terrain& terrain, double timestep);

// The ground boxes whose friction changes with time (under a timed patch):
// the geom's name and a point of its top face [m] (x, y; off every patch
// edge), where the engine asks the terrain for the friction before each step.
struct TimedGroundBox {
  std::string name;
  double x, y;
};
std::vector<TimedGroundBox> timedGroundBoxes(const Terrain& terrain);
// A ground box's MuJoCo friction for the terrain's mu (at least 1e-5).
double mujocoFriction(double mu);

// The ground's boxes for this terrain; and the bound on them (1000 patches
// with distinct edges could ask for millions).
size_t mujocoGroundBoxes(const Terrain& terrain);
inline constexpr size_t kMaxMujocoGroundBoxes = 4096;
// Throws ScenarioError (naming the scenario's file and terrain.patches) above the bound.
void checkMujocoGround(const Scenario& scenario, const Terrain& terrain);

}  // namespace hyq::sim
