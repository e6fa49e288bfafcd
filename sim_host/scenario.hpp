// A simulation scenario, read from a YAML file (documented in
// docs/scenarios.md). Parsing is strict: an unknown key, a wrong type or an
// out-of-range value is a ScenarioError naming the file and the key.
#pragma once
#include <array>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "firmware/controller/params.hpp"
#include "sim_host/sim_params.hpp"

namespace hyq::sim {

struct ScenarioError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct FrictionPatch {
  double x0, x1;    // [m] extent along x, W
  double y0, y1;    // [m] extent along y, W
  double mu;        // [-]
};

// Flat ground at z = 0 up to x0, a slope rising at `angle` for `length`
// (measured along x), then flat again. Ramps follow each other along +x.
struct Ramp {
  double x0;        // [m] foot of the slope
  double angle;     // [rad] slope angle, positive uphill towards +x
  double length;    // [m] horizontal extent of the slope
};

struct TerrainSpec {
  double mu = 0.8;                       // [-] everywhere not covered by a patch
  std::vector<FrictionPatch> patches;    // later entries win where they overlap
  std::vector<Ramp> ramps;               // sorted by x0, not overlapping
};

struct Disturbance {
  double t;                              // [s] start
  double duration;                       // [s]
  std::array<double, 3> force;           // [N] at the trunk CoM, W
};

struct SensorSpec {
  bool noise = true;
  SensorNoise magnitudes;
};

struct Scenario {
  std::string name;
  std::string source_file;               // where it came from ("" if built in code)
  double duration = 10.0;                // [s] simulated
  uint64_t seed = 1;
  TerrainSpec terrain;
  double payload_kg = 0.0;               // [kg] extra trunk mass unknown to the controller
  double start_x = 0.0, start_y = 0.0, start_yaw = 0.0;  // [m], [m], [rad]
  std::string controller_kind = "wbc";
  hyq::Params controller_params;         // params.hpp defaults + scenario overrides
  SensorSpec sensors;
  std::vector<Disturbance> disturbances;
};

// Reads and checks a scenario file. Throws ScenarioError.
Scenario loadScenario(const std::string& path);
// Same, from YAML text; `origin` names the source in messages.
Scenario parseScenario(const std::string& yaml_text, const std::string& origin);

}  // namespace hyq::sim
