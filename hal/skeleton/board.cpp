// Skeleton port: what a new board must provide, and nothing else. Copy this
// directory to hal/<board>/, add linker/<board>.ld (MEMORY regions FLASH,
// FASTRAM, RAM, NOINIT and STACK_SIZE, then INCLUDE sections.ld), a BoardId
// in hal/wire.hpp, and the board to the Makefile's `firmware` list
// (docs/firmware.md, "Adding a board"). `cmake -S firmware/cross
// -DHYQ_BOARD=skeleton` compiles this file so the interface stays complete.
#include "hal/board.hpp"
#include "hal/cortex_m.hpp"
#include "hal/wire.hpp"

namespace hyq::hal {
namespace {

// TODO(port): the core clock after init().
constexpr uint32_t kCoreClockHz = 100000000;

}  // namespace

void Board::init() {
  // TODO(port): read the reset cause (watchdog or power-on) into reset_cause_,
  // start the clocks, the link and log peripherals, and a free-running
  // 32-bit up-counter for clockCounts().
  reset_cause_ = wire::kResetPowerOn;
  cortex_m::startSysTick1kHz(kCoreClockHz);
  last_tick_counts_ = clockCounts();
}

// Usually unchanged: SysTick's COUNTFLAG and the clock give the periods.
uint32_t Board::pollTick() {
  if (!cortex_m::sysTickWrapped()) return 0;
  return periodsSinceLastTick(clockCounts());
}

// TODO(port): read the hardware counter (e.g. the DWT cycle counter).
uint64_t Board::clockCounts() { return extendClock(0); }

uint32_t Board::clockHz() const { return kCoreClockHz; }

// TODO(port): framed transports (Ethernet, CAN-FD, USB) fill link_frame_
// here and return the payload length; byte streams return 0.
size_t Board::linkFetchFrame() { return 0; }

// TODO(port): non-blocking: copy what the link has received, up to capacity.
size_t Board::linkRead(uint8_t*, size_t) { return 0; }

// TODO(port): send one wire message (one frame on framed transports).
void Board::linkWrite(const uint8_t*, size_t) {}

// TODO(port): write the line to a debug UART, ITM or a RAM ring.
void Board::log(const char*) {}

// TODO(port): start the independent watchdog with this timeout.
void Board::watchdogStart(uint32_t) {}

// TODO(port): reload the watchdog.
void Board::watchdogKick() {}

// TODO(port): enable the link's receive interrupt as a wake source in init()
// (cortex_m::enableWakeSource), then sleep here unless data is waiting.
void Board::waitForEvent() {
  cortex_m::waitForInterrupt();
  cortex_m::clearWakeSources(0);
}

uint32_t Board::boardId() const { return wire::kBoardSkeleton; }

bool Board::fpuIsDoublePrecision() const { return cortex_m::fpuHasDoublePrecision(); }

}  // namespace hyq::hal
