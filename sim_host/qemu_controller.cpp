#include "sim_host/qemu_controller.hpp"

#include <cstdlib>
#include <stdexcept>

#include "hal/host/qemu_link.hpp"

namespace hyq::sim {

namespace {

class QemuController final : public ControllerPort {
 public:
  explicit QemuController(const Scenario& scenario) {
    const std::string elf = defaultFirmwareImage();
    if (!link_.open(elf.c_str()))
      throw std::runtime_error("qemu controller: cannot boot " + elf + ": " + link_.error());
    // The board runs the scenario's parameters, not its built-in defaults.
    const hyq::Params& params = scenario.controller_params;
    if (!link_.configure(&params, sizeof params))
      throw std::runtime_error(std::string("qemu controller: configure failed: ") + link_.error());
  }
  void step(const hal::SensorFrame& s, hal::CommandFrame& c) override {
    if (!link_.exchange(s, c))
      throw std::runtime_error(std::string("qemu controller: link failed: ") + link_.error());
  }

 private:
  hal::QemuLink link_;
};

}  // namespace

std::string defaultFirmwareImage() {
  if (const char* env = std::getenv("HYQ_FW_MPS2_ELF")) return env;
  return HYQ_DEFAULT_FW_ELF;
}

std::unique_ptr<ControllerPort> makeQemuController(const Scenario& scenario) {
  return std::make_unique<QemuController>(scenario);
}

}  // namespace hyq::sim
