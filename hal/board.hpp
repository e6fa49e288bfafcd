// The board interface: everything the control loop (firmware/board/) needs
// from a board, and nothing above this header knows a register address.
//
// One implementation per board is compiled into each image
// (hal/<board>/board.cpp); hal/skeleton/ lists what a new port must provide.
// The loop is polled (no interrupt handlers carry state): the board turns
// hardware events into return values.
#pragma once
#include <cstddef>
#include <cstdint>

namespace hyq::hal {

class Board {
 public:
  // Clocks, the 1 kHz SysTick, the free-running clock, the link and log
  // UARTs. Called once, after startup code has enabled the FPU.
  void init();

  // Polled 1 kHz tick: 0 while the current period runs; otherwise the number
  // of whole periods since the last non-zero return (more than 1 means the
  // loop missed ticks).
  uint32_t pollTick();

  // Monotonic clock in counts of clockHz(), from init(); never wraps in
  // practice (64 bits). Used for step timing and tick bookkeeping.
  uint64_t clockCounts();
  uint32_t clockHz() const;

  // Link to the robot's motor-driver bridge (or the simulator), seen as a
  // byte stream whatever carries it: a non-blocking read of up to `capacity`
  // bytes; returns the count read.
  size_t linkRead(uint8_t* dst, size_t capacity);
  // Sends one wire message (at most 1500 bytes); returns when the
  // hardware has it. Framed transports (Ethernet) send it as one frame.
  void linkWrite(const uint8_t* src, size_t n);

  // Fault/log channel: one line of text (no newline needed), best effort.
  void log(const char* line);

  // Starts the independent watchdog: the board resets unless watchdogKick()
  // comes at least every `timeout_ms`.
  void watchdogStart(uint32_t timeout_ms);
  void watchdogKick();

  // Sleeps until the next tick or link byte, whichever comes first; saves
  // power on a board and host CPU under emulation.
  void waitForEvent();

  // Why the board last reset (wire::ResetCause), which board this is
  // (wire::BoardId), and whether the core has a double-precision FPU.
  uint32_t resetCause() const { return reset_cause_; }
  uint32_t boardId() const;
  bool fpuIsDoublePrecision() const;

 private:
  // Shared by all backends (hal/board_common.cpp): a 32-bit hardware up-counter extended to 64 bits
  // (called far more often than it wraps), and the tick bookkeeping.
  uint64_t extendClock(uint32_t raw_up_count);
  uint32_t periodsSinceLastTick(uint64_t now);

  // Framed transports: the next link frame, handed out by linkRead().
  static constexpr size_t kLinkFrameBytes = 2048;
  size_t linkFetchFrame();

  uint8_t link_frame_[kLinkFrameBytes] = {};
  size_t link_frame_length_ = 0;
  size_t link_frame_position_ = 0;
  uint32_t clock_last_raw_ = 0;
  uint64_t clock_high_ = 0;
  uint64_t last_tick_counts_ = 0;
  uint32_t reset_cause_ = 0;
};

}  // namespace hyq::hal
