// The board's superloop: link bytes in -> sensor frame -> Controller::step ->
// command frame out, with the 1 kHz tick, watchdog, overrun accounting and
// the safe state on a lost or corrupt link. Board-independent: it talks to
// the hardware only through hal::Board.
#pragma once
#include <cstdint>

#include "firmware/board/board_params.hpp"
#include "firmware/board/fault_snapshot.hpp"
#include "firmware/controller/controller.hpp"
#include "firmware/controller/params.hpp"
#include "hal/board.hpp"
#include "hal/frames.hpp"
#include "hal/wire.hpp"

namespace hyq::board {

class ControlLoop {
 public:
  // link_memory: the numbering kept across resets; the board takes messages
  // numbered from its next_sequence on, and advances it with every one.
  void init(const Params& params, const BoardParams& board_params, hal::Board& board, uint32_t reset_cause,
            LinkMemory& link_memory);
  // After reset until the first sensor frame, after a kConfig and in the
  // safe state: identifies the image, its parameters, the sequence number
  // to continue from, and reports the FPU self test.
  void sendHello(hal::Board& board);
  // One pass of the superloop. Sleeps until the next tick or link byte when
  // there is nothing to do.
  void runOnce(hal::Board& board, Controller& controller);
  const hal::wire::BoardStatus& status() const { return status_; }

 private:
  // Upper bound on link bytes handled per pass (one whole message), so
  // that a flood of bytes cannot starve the tick.
  static constexpr size_t kMaxBytesPerPass = hal::wire::kMaxMessageBytes;

  bool serviceLink(hal::Board& board, Controller& controller);
  void applyConfig(hal::Board& board, Controller& controller);
  void stepController(hal::Board& board, Controller& controller, const hal::SensorFrame& sensors);
  void serviceTick(hal::Board& board, uint32_t periods);
  void fillSafeCommand();
  void answerConfig(hal::Board& board, uint32_t result);  // Hello with the result
  void sendCommand(hal::Board& board);
  void copyDecoderCounters();

  Params params_{};
  BoardParams board_params_{};
  hal::wire::Decoder decoder_;
  hal::wire::Message received_{};
  hal::CommandFrame command_{};
  hal::wire::BoardStatus status_{};
  uint8_t tx_buffer_[hal::wire::kMaxMessageBytes] = {};
  uint32_t tx_sequence_ = 0;
  uint32_t reset_cause_ = 0;                      // wire::ResetCause
  LinkMemory* link_memory_ = nullptr;             // survives resets (main owns it)
  uint32_t config_crc_ = 0;                       // crc32 of the applied kConfig, 0: defaults
  uint32_t config_sequence_ = 0;                  // sequence of the last kConfig answered, 0: none
  uint32_t config_result_ = 0;                    // wire::ConfigResult of it
  bool link_up_ = false;                          // a frame was accepted since reset
  double hold_q_[hal::kNumJoints] = {};           // [rad] joint positions of the last accepted frame
  uint32_t last_sensor_tick_ = 0;
  uint64_t last_frame_counts_ = 0;                // [clock counts] when the last frame was accepted
};

}  // namespace hyq::board
