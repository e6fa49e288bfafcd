// The firmware's controller (firmware/controller/) run on the host: the
// "wbc" controller kind of hyq_sim.
#pragma once
#include <memory>

#include "sim_host/loop/controller_port.hpp"

namespace hyq::sim {

std::unique_ptr<ControllerPort> makeWbcController(const Scenario& scenario);

}  // namespace hyq::sim
