// Board entry point: the one place that owns the controller and the loop.
#include <new>

#include "firmware/board/control_loop.hpp"
#include "firmware/board/fault_snapshot.hpp"

namespace {

// Storage for the control state in the board's fastest RAM (linker
// FASTRAM: DTCM on the STM32H743). Constructed in main, not by static
// initialisation, so that nothing depends on constructor order.
alignas(hyq::Controller) __attribute__((section(".bss.fast_state")))
unsigned char g_controller_storage[sizeof(hyq::Controller)];
alignas(hyq::board::ControlLoop) __attribute__((section(".bss.fast_state")))
unsigned char g_loop_storage[sizeof(hyq::board::ControlLoop)];

uint32_t takeResetCause(const hyq::hal::Board& board) {
  hyq::board::FaultSnapshot& snapshot = hyq::board::faultSnapshot();
  if (snapshot.magic != hyq::board::FaultSnapshot::kValid) return board.resetCause();
  snapshot.magic = 0;
  return snapshot.cause;
}

}  // namespace

int main() {
  hyq::hal::Board board;
  board.init();
  const hyq::Params params{};
  const hyq::BoardParams board_params{};
  // Placement construction: no allocation, the storage is above.
  auto* controller = new (g_controller_storage) hyq::Controller();
  auto* loop = new (g_loop_storage) hyq::board::ControlLoop();
  controller->init(params);
  loop->init(params, board_params, board, takeResetCause(board));
  loop->sendHello(board);
  board.watchdogStart(board_params.watchdog_timeout_ms);
  for (;;) loop->runOnce(board, *controller);
}
