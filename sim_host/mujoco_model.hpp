// HyQ and its terrain as a MuJoCo model (MJCF text), generated from the one
// set of robot numbers (firmware/controller/robot_params.hpp) and the
// scenario: the same bodies, frames, masses and inertias as the ODE model
// (robot.hpp), the foot spheres and the trunk box as the only robot
// geometry, the ground as static boxes, one per piece of the height profile
// and per region of constant friction.
#pragma once
#include <string>

#include "sim_host/scenario.hpp"
#include "sim_host/terrain.hpp"

namespace hyq::sim {

// Names in the generated model: body "trunk" (its frame is B) with a free
// joint "base"; per leg L in LF, RF, LH, RH bodies "L_hip", "L_upper",
// "L_lower", hinges "L_haa", "L_hfe", "L_kfe" (in that order, legs in
// that order), the foot sphere geom "L_foot"; ground geoms "ground_<k>".
std::string hyqMjcf(const Scenario& scenario, const Terrain& terrain, double timestep);

}  // namespace hyq::sim
