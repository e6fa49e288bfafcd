#include "sim_host/loop/wbc_controller.hpp"

#include "firmware/controller/controller.hpp"

namespace hyq::sim {

namespace {

class WbcController final : public ControllerPort {
 public:
  explicit WbcController(const hyq::Params& params) { controller_.init(params); }
  void step(const hal::SensorFrame& s, hal::CommandFrame& c) override { controller_.step(s, c); }

 private:
  hyq::Controller controller_;
};

}  // namespace

std::unique_ptr<ControllerPort> makeWbcController(const Scenario& scenario) {
  return std::make_unique<WbcController>(scenario.controller_params);
}

}  // namespace hyq::sim
