// Per-stage timing of Controller::step: the board (or a benchmark) lends the
// controller a clock; after each stage of the tick the controller stores the
// counts the stage took. Without a clock nothing is read or stored.
#pragma once
#include <cstdint>

namespace hyq {

// The stages of one tick, in pipeline order.
enum class Stage : uint8_t {
  kFrameCheck = 0,      // frame check (and the safe hold of a bad frame)
  kLegs,                // IMU, leg kinematics, joint accelerations, forces from torques
  kSlipDetection,       // contact and slip
  kStateEstimate,       // odometry, velocity, terrain plane (and their start on the first good frame)
  kSurfaceAndRecovery,  // friction and normal estimates, recovery and freeze supervisor
  kGait,                // the gait's motion reference
  kWrench,              // trunk wrench
  kQpBuild,             // GRF problem built from this tick's contacts and cones
  kQpSolve,             // the GRF QP solver's call
  kProbe,               // the friction probe (its pair added to the QP's forces)
  kCommands,            // forces checked per foot and their wrench, joint commands, freezing,
                        // output check, telemetry
};
constexpr int kNumStages = 11;

// A free-running counter: read(context) returns its value (wrapping).
struct StageClock {
  uint32_t (*read)(void* context) = nullptr;
  void* context = nullptr;
};

// Counts per stage of the last tick (0 for stages the tick did not reach).
struct StageCounts {
  uint32_t counts[kNumStages] = {};
};

class StageTimer {
 public:
  void setClock(const StageClock& clock) { clock_ = clock; }
  bool enabled() const { return clock_.read != nullptr; }
  // Starts a tick: every stage's count to 0.
  void begin() {
    if (!enabled()) return;
    last_ = clock_.read(clock_.context);
    counts_ = StageCounts{};
  }
  // The stage that just ended.
  void mark(Stage stage) {
    if (!enabled()) return;
    const uint32_t now = clock_.read(clock_.context);
    counts_.counts[static_cast<int>(stage)] += now - last_;
    last_ = now;
  }
  const StageCounts& counts() const { return counts_; }

 private:
  StageClock clock_{};
  uint32_t last_ = 0;
  StageCounts counts_{};
};

}  // namespace hyq
