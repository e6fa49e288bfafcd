// The firmware image running in QEMU (-M mps2-an500) as hyq_sim's "qemu"
// controller kind: processor in the loop, frames exchanged in lock-step over
// the board's emulated Ethernet (hal/host/qemu_link.hpp).
#pragma once
#include <memory>
#include <string>

#include "sim_host/loop/controller_port.hpp"

namespace hyq::sim {

// The image: $HYQ_FW_MPS2_ELF, else the one `make firmware` builds.
std::string defaultFirmwareImage();
std::unique_ptr<ControllerPort> makeQemuController(const Scenario& scenario);

}  // namespace hyq::sim
