// What survives a reset in no-init RAM (the fault handlers' report for the
// next boot, the link's message numbering), and the stack's high-water mark.
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

// The link's message numbering, kept across resets so that frames sent
// before a reset stay refused after it (a replay cannot restart the count).
struct LinkMemory {
  static constexpr uint32_t kValid = 0x11A4C0DE;
  uint32_t magic;          // kValid once written since power-on
  uint32_t epoch;          // [-] boots since power-on (Hello::link_epoch)
  uint32_t next_sequence;  // [-] the lowest sequence number the board still takes
};

// The no-init objects of the image (section .noinit, survive a reset; after
// power-on their bytes are whatever the RAM holds, hence the magic words).
FaultSnapshot& faultSnapshot();
LinkMemory& linkMemory();

// The stack is painted with this word at reset; stackPeakBytes() is the
// deepest use since then [bytes] (a scan of the unused part: call it
// outside the control step).
constexpr uint32_t kStackPaint = 0x5A5AC3C3u;
uint32_t stackPeakBytes();

}  // namespace hyq::board
