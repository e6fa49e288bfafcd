// The slip-aware locomotion controller: one call per 1 kHz tick.
// Inputs in, outputs out: no I/O, no heap, no globals; all state is a member.
#pragma once
#include "firmware/controller/params.hpp"
#include "firmware/controller/types.hpp"
#include "hal/frames.hpp"

namespace hyq {

class Controller {
 public:
  // Sets parameters and resets all state. The only place that may be slow.
  void init(const Params& params);
  // One control tick: sensor frame in, command frame out. Never allocates.
  void step(const hal::SensorFrame& sensors, hal::CommandFrame& command);

 private:
  Params params_{};
  bool initialised_ = false;
  hal::SensorFrame last_good_{};
  bool have_good_ = false;
};

}  // namespace hyq
