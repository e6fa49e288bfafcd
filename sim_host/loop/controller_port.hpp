// The simulator's side of the controller boundary: anything that turns a
// sensor frame into a command frame, one 1 kHz tick at a time, in lock-step.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "hal/frames.hpp"
#include "sim_host/scenario/scenario.hpp"

namespace hyq::sim {

class ControllerPort {
 public:
  virtual ~ControllerPort();
  virtual void step(const hal::SensorFrame& sensors, hal::CommandFrame& command) = 0;
};

// The controller named `kind` (see controllerKinds()), set up for the
// scenario; nullptr when no controller has that name.
std::unique_ptr<ControllerPort> makeController(const std::string& kind, const Scenario& scenario);
std::vector<std::string> controllerKinds();

}  // namespace hyq::sim
