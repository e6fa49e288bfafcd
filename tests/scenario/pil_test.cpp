// Processor in the loop: the first 15 s of ice_patches (the crawl onto
// the first patch, with slips) and the whole of trot_ice_patches (20 s,
// the trot across the slab with its touch-down slips) run once with the
// controller on the host and once with the firmware image in QEMU
// (mps2-an500), on the hyq plant, whose transport delays, torque loop and
// mounted IMU sit between the simulator and either controller, so that the
// board meets them through its link; ice_patches also on the ideal plant.
// Same outcome:
// fall or not, distance within 1 cm, the same slip detections. The two are
// not bit-identical: newlib's and glibc's sin/cos/atan2 differ in the last
// bits (docs/firmware.md), and the stick/slip contact amplifies that. On
// the hyq plant the encoders' quantisation amplifies it further: a
// last-bit difference in a joint angle that lies on a count's edge reads
// as a whole count (7.9e-5 rad), and the runs part after 2.8 s (measured
// at commit 9825fa8, 15 s: 0.464 m and 2 flags on the board against 0.493 m
// and 4 on the host); with the counts off they agree for the whole 15 s
// (the same distance and flags), so the cases run the hyq plant with
// encoder.resolution 0.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <vector>

#include "sim_host/loop/qemu_controller.hpp"
#include "sim_host/physics/plant_params.hpp"
#include "tests/scenario/scenario_runner.hpp"

namespace hyq::test {
namespace {

// Rising edges of the controller's slip flag, per leg [s].
class FlagEdges final : public sim::TickObserver {
 public:
  void onTick(const sim::TickRecord& r) override {
    const uint32_t mask = r.command.telemetry.slip_mask;
    for (int leg = 0; leg < 4; ++leg)
      if (((mask >> leg) & 1u) && !((previous_ >> leg) & 1u)) edges[leg].push_back(r.time);
    previous_ = mask;
    freeze = freeze || (r.command.flags & hal::kFlagFreeze);
  }
  std::vector<double> edges[4];
  bool freeze = false;

 private:
  uint32_t previous_ = 0;
};

struct Outcome {
  sim::RunResult result;
  FlagEdges flags;
};

struct PilCase {
  const char* name;
  const char* scenario;  // relative to the source tree
  double duration;       // [s]
  sim::PlantModel plant;  // hyq: but unquantised encoders (above)
};

void PrintTo(const PilCase& c, std::ostream* out) { *out << c.name; }

const PilCase kCases[] = {
    {"ice_patches", "sim_host/scenarios/ice_patches.yaml", 15.0, sim::PlantModel::hyq},
    {"trot_ice_patches", "sim_host/scenarios/trot_ice_patches.yaml", 20.0, sim::PlantModel::hyq},
    {"ice_patches_ideal_plant", "sim_host/scenarios/ice_patches.yaml", 15.0, sim::PlantModel::ideal},
};

void run(const PilCase& c, const std::string& kind, Outcome& out) {
  sim::Scenario scenario = sim::loadScenario(std::string(HYQ_SOURCE_DIR) + "/" + c.scenario, c.plant);
  scenario.duration = c.duration;
  if (c.plant == sim::PlantModel::hyq) scenario.plant.encoder.resolution = 0.0;
  auto controller = sim::makeController(kind, scenario);
  ASSERT_NE(controller, nullptr);
  sim::RunOptions options;
  options.out_dir = std::string(HYQ_BINARY_DIR) + "/scenario_out/pil_" + c.name + "_" + kind;
  options.write_log = false;
  options.progress = false;
  out.result = sim::runScenario(scenario, *controller, options, {&out.flags});
}

class ProcessorInTheLoop : public ::testing::TestWithParam<PilCase> {};

TEST_P(ProcessorInTheLoop, FirmwareInQemuMatchesTheHostController) {
  if (!std::ifstream(sim::defaultFirmwareImage()).good())
    GTEST_FAIL() << "no firmware image at " << sim::defaultFirmwareImage() << " (make firmware)";
  const PilCase& c = GetParam();
  Outcome host, board;
  run(c, "wbc", host);
  run(c, "qemu", board);
  EXPECT_NEAR(board.result.sim_time, c.duration, 1e-6);
  EXPECT_EQ(board.result.fell, host.result.fell);
  EXPECT_NEAR(board.result.distance, host.result.distance, 0.01);
  EXPECT_EQ(board.flags.freeze, host.flags.freeze);
  int detections = 0;
  for (int leg = 0; leg < 4; ++leg) {
    ASSERT_EQ(board.flags.edges[leg].size(), host.flags.edges[leg].size()) << "leg " << leg;
    for (size_t k = 0; k < host.flags.edges[leg].size(); ++k) {
      // The runs can drift apart as the contact amplifies libm's last-bit
      // differences; how far depends on the controller (measured: identical
      // edges; up to 13 ms apart with freeze_after at 80 ms).
      EXPECT_NEAR(board.flags.edges[leg][k], host.flags.edges[leg][k], 0.005) << "leg " << leg << " #" << k;
      ++detections;
    }
  }
  EXPECT_GT(detections, 0) << "the cut must contain slips to compare";
}

INSTANTIATE_TEST_SUITE_P(Scenarios, ProcessorInTheLoop, ::testing::ValuesIn(kCases),
                         [](const ::testing::TestParamInfo<PilCase>& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace hyq::test
