// Board entry point: the one place that owns the controller and the loop.
#include <new>

#include "firmware/board/control_loop.hpp"
#include "firmware/board/fault_snapshot.hpp"

namespace {

uint32_t takeResetCause(const hyq::hal::Board& board) {
  hyq::board::FaultSnapshot& snapshot = hyq::board::faultSnapshot();
  if (snapshot.magic != hyq::board::FaultSnapshot::kValid) return board.resetCause();
  snapshot.magic = 0;
  return snapshot.cause;
}

// The controller's per-stage timing reads the board's clock.
uint32_t readBoardClock(void* board) {
  return static_cast<uint32_t>(static_cast<hyq::hal::Board*>(board)->clockCounts());
}

}  // namespace

int main() {
  // Storage for the control state in the board's fastest RAM (linker
  // FASTRAM: DTCM on the STM32H743), owned by main alone: plain bytes (zeroed
  // .bss, no static-initialisation guard), constructed below in order.
  alignas(hyq::Controller) __attribute__((section(".bss.fast_state"))) static unsigned char
      controller_storage[sizeof(hyq::Controller)];
  alignas(hyq::board::ControlLoop) __attribute__((section(".bss.fast_state"))) static unsigned char
      loop_storage[sizeof(hyq::board::ControlLoop)];
  hyq::hal::Board board;
  board.init();
  const hyq::Params params{};
  const hyq::BoardParams board_params{};
  // Placement construction: no allocation, the storage is above.
  auto* controller = ::new (controller_storage) hyq::Controller();
  auto* loop = ::new (loop_storage) hyq::board::ControlLoop();
  controller->init(params);
  controller->setStageClock(hyq::StageClock{readBoardClock, &board});
  hyq::board::LinkMemory& link_memory = hyq::board::linkMemory();
  if (link_memory.magic != hyq::board::LinkMemory::kValid) {
    link_memory.magic = hyq::board::LinkMemory::kValid;
    link_memory.epoch = 0;
    link_memory.next_sequence = 1;
  }
  ++link_memory.epoch;
  loop->init(params, board_params, board, takeResetCause(board), link_memory);
  loop->sendHello(board);
  board.watchdogStart(board_params.watchdog_timeout_ms);
  for (;;) loop->runOnce(board, *controller);
}
