// What the fault handlers leave in no-init RAM for the next boot to report.
#pragma once
#include <cstdint>

namespace hyq::board {

struct FaultSnapshot {
  static constexpr uint32_t kValid = 0xFA017ED5;
  uint32_t magic;   // kValid when the rest was written by a fault handler
  uint32_t cause;   // wire::ResetCause
  uint32_t pc;      // stacked program counter of the faulting code
  uint32_t lr;      // stacked link register
  uint32_t psr;     // stacked xPSR
  uint32_t cfsr;    // configurable fault status (SCB)
  uint32_t hfsr;    // hard fault status (SCB)
  uint32_t bfar;    // bus fault address (SCB)
};

// The single no-init object of the image (section .noinit, survives reset).
FaultSnapshot& faultSnapshot();

}  // namespace hyq::board
