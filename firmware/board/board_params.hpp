// Tuning numbers of the board loop (the controller's own are in
// firmware/controller/params.hpp; the safe state reuses its posture gains).
#pragma once
#include <cstdint>

namespace hyq {

struct BoardParams {
  // [ticks] without an accepted sensor frame before the board holds the safe
  // state: 5 ms, well inside the time the trunk needs to sag noticeably, and
  // long enough that one lost or corrupt frame does not trip it.
  uint32_t link_timeout_ticks = 5;
  // [ms] the watchdog resets the board if the loop stops kicking it this long.
  uint32_t watchdog_timeout_ms = 50;
  // [ticks] Hello repeated at this period until the first sensor frame and
  // while the board holds the safe state.
  uint32_t hello_period_ticks = 20;
};

}  // namespace hyq
