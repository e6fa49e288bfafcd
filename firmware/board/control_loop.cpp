#include "firmware/board/control_loop.hpp"

#include "firmware/controller/force/joint_commands.hpp"
#include "firmware/controller/param_table.hpp"
#include "firmware/controller/params_check.hpp"

#include <cstddef>
#include <cstring>

namespace hyq::board {
namespace {

static_assert(hal::wire::kTimedStages == kNumStages, "BoardStatus carries one count per stage");
static_assert(sizeof(Params) <= hal::wire::kMaxConfigBytes, "a configuration message carries the whole Params");

// "<text> <value>" into a fixed buffer: the log channel has no printf.
void formatLine(const char* text, uint32_t value, char (&line)[64]) {
  int n = 0;
  for (; text[n] != '\0' && n < 48; ++n) line[n] = text[n];
  line[n++] = ' ';
  char digits[10];
  int d = 0;
  do {
    digits[d++] = static_cast<char>('0' + value % 10);
    value /= 10;
  } while (value != 0 && d < 10);
  while (d > 0) line[n++] = digits[--d];
  line[n] = '\0';
}

void logValue(hal::Board& board, const char* text, uint32_t value) {
  char line[64];
  formatLine(text, value, line);
  board.log(line);
}

}  // namespace

void ControlLoop::init(const Params& params, const BoardParams& board_params, hal::Board& board,
                       uint32_t reset_cause, LinkMemory& link_memory) {
  reset_cause_ = reset_cause;
  link_memory_ = &link_memory;
  logValue(board, "hyq firmware up, reset cause", reset_cause);
  params_ = params;
  board_params_ = board_params;
  decoder_.reset();
  decoder_.expect(hal::wire::MessageType::kSensor, hal::wire::MessageType::kConfig);
  decoder_.acceptFrom(link_memory.next_sequence);
  status_ = {};
  command_ = {};
  link_up_ = false;
  tx_sequence_ = 0;
}

void ControlLoop::sendHello(hal::Board& board) {
  // volatile: the self test must run on this core, not in the compiler.
  volatile double input = 0.7853981633974483;
  hal::wire::Hello hello{};
  hello.board_id = board.boardId();
  hello.wire_version = hal::wire::kVersion;
  hello.clock_hz = board.clockHz();
  hello.reset_cause = reset_cause_;
  hello.config_crc = config_crc_;
  hello.config_sequence = config_sequence_;
  hello.config_result = config_result_;
  hello.link_epoch = link_memory_->epoch;
  hello.next_sequence = decoder_.nextSequence();
  hello.fpu_double = board.fpuIsDoublePrecision() ? 1u : 0u;
  hello.stack_peak_bytes = stackPeakBytes();
  hello.fpu_input = input;
  hello.fpu_result = hal::wire::fpuSelfTest(hello.fpu_input);
  status_.clock_hz = board.clockHz();
  const size_t n = hal::wire::encodeHello(hello, ++tx_sequence_, tx_buffer_, sizeof tx_buffer_);
  board.linkWrite(tx_buffer_, n);
}

void ControlLoop::runOnce(hal::Board& board, Controller& controller) {
  // Link first: a frame already waiting must count before the timeout does.
  const bool busy = serviceLink(board, controller);
  const uint32_t periods = board.pollTick();
  if (periods > 0) serviceTick(board, periods);
  if (!busy && periods == 0) board.waitForEvent();
}

bool ControlLoop::serviceLink(hal::Board& board, Controller& controller) {
  uint8_t bytes[kMaxBytesPerPass];
  const size_t n = board.linkRead(bytes, sizeof bytes);
  for (size_t i = 0; i < n; ++i) {
    if (!decoder_.push(bytes[i], received_)) continue;
    link_memory_->next_sequence = decoder_.nextSequence();
    if (received_.type == hal::wire::MessageType::kSensor) stepController(board, controller, received_.sensor);
    if (received_.type == hal::wire::MessageType::kConfig) applyConfig(board, controller);
  }
  copyDecoderCounters();
  return n > 0;
}

// New controller parameters from the bridge/simulator: the controller
// restarts with them, and a Hello tells the sender which ones are in use
// (the old set's CRC when they were refused). A new set is taken only
// before the first sensor frame since reset; never while walking. In the
// safe state (link lost) only the set already in use is taken again (a
// sender that restarted confirms it): the link cannot tell who sends, and a
// robot that has walked changes its parameters only through a reset.
void ControlLoop::applyConfig(hal::Board& board, Controller& controller) {
  config_sequence_ = received_.sequence;
  if (status_.frames_accepted != 0 && status_.safe_state == 0) {
    logValue(board, "config refused while controlling, frames accepted", status_.frames_accepted);
    answerConfig(board, hal::wire::kConfigRefusedWhileControlling);
    return;
  }
  if (status_.frames_accepted != 0 &&
      hal::wire::crc32(received_.config, received_.config_bytes) != config_crc_) {
    logValue(board, "config refused in the safe state: not the set in use, frames accepted",
             status_.frames_accepted);
    answerConfig(board, hal::wire::kConfigRefusedOtherSet);
    return;
  }
  if (received_.config_bytes != sizeof(Params)) {
    logValue(board, "config rejected, bytes", received_.config_bytes);
    answerConfig(board, hal::wire::kConfigRefusedSize);
    return;
  }
  // Checked before anything changes: parameters out of range are refused
  // and the controller keeps running the ones it has. A bool's byte must be
  // 0 or 1 before the bytes may be read as a Params (param_table.hpp lists
  // the bools).
  ParamIssue issue;
  if (!checkBoolBytes(received_.config, issue)) {
    logValue(board, "config refused: a bool byte is neither 0 nor 1, bytes", received_.config_bytes);
    answerConfig(board, hal::wire::kConfigRefusedBool);
    return;
  }
  Params candidate;
  std::memcpy(&candidate, received_.config, sizeof(Params));
  if (!checkParams(candidate, issue)) {
    logValue(board, "config refused: a parameter is out of range, bytes", received_.config_bytes);
    answerConfig(board, hal::wire::kConfigRefusedRange);
    return;
  }
  params_ = candidate;
  controller.init(params_);
  config_crc_ = hal::wire::crc32(received_.config, received_.config_bytes);
  logValue(board, "config applied, crc32", config_crc_);
  answerConfig(board, hal::wire::kConfigApplied);
}

void ControlLoop::answerConfig(hal::Board& board, uint32_t result) {
  config_result_ = result;
  sendHello(board);
}

void ControlLoop::stepController(hal::Board& board, Controller& controller,
                                 const hal::SensorFrame& sensors) {
  if (status_.safe_state != 0) {
    status_.safe_state = 0;
    logValue(board, "link recovered at board tick", status_.board_tick);
  }
  link_up_ = true;
  status_.ticks_since_frame = 0;
  last_frame_counts_ = board.clockCounts();
  ++status_.frames_accepted;
  for (int j = 0; j < hal::kNumJoints; ++j) hold_q_[j] = sensors.q[j];
  last_sensor_tick_ = sensors.tick;

  const uint64_t start = board.clockCounts();
  controller.step(sensors, command_);
  const uint64_t duration = board.clockCounts() - start;
  const StageCounts& stages = controller.stageCounts();
  for (int k = 0; k < kNumStages; ++k) status_.stage_counts[k] = stages.counts[k];

  status_.step_counts_last = static_cast<uint32_t>(duration);
  if (status_.step_counts_last > status_.step_counts_max) status_.step_counts_max = status_.step_counts_last;
  if (duration > board.clockHz() / hal::kTicksPerSecond) ++status_.overruns;
  sendCommand(board);
}

void ControlLoop::serviceTick(hal::Board& board, uint32_t periods) {
  board.watchdogKick();
  const uint32_t previous_tick = status_.board_tick;
  status_.board_tick += periods;
  status_.missed_ticks += periods - 1;
  const bool hello_due =
      previous_tick / board_params_.hello_period_ticks != status_.board_tick / board_params_.hello_period_ticks;
  if (!link_up_) {
    // The other end may not be listening yet (a bridge still booting, or
    // an emulator's network backend still connecting): repeat the Hello.
    if (hello_due) sendHello(board);
    return;
  }
  // From the clock, not by counting ticks: a backlog of tick periods (after
  // a long step) must not age a frame that arrived inside it.
  status_.ticks_since_frame =
      static_cast<uint32_t>((board.clockCounts() - last_frame_counts_) / (board.clockHz() / hal::kTicksPerSecond));
  if (status_.ticks_since_frame < board_params_.link_timeout_ticks) return;
  if (status_.safe_state == 0) {
    status_.safe_state = 1;
    ++status_.link_lost_events;
    logValue(board, "link lost, safe state at board tick", status_.board_tick);
  }
  // A sender that restarted learns from the Hello where to continue.
  if (hello_due) sendHello(board);
  // The joint loop keeps receiving a command every tick while the link is
  // down, so that the bridge's own timeout never has to act.
  fillSafeCommand();
  sendCommand(board);
}

// Joints held where they last were, with the posture gains, no feed-forward.
void ControlLoop::fillSafeCommand() {
  command_ = {};
  command_.tick = last_sensor_tick_;
  command_.flags = hal::kFlagLinkLost;
  postureCommand(hold_q_, nullptr, params_.joint, command_);
  command_.telemetry.swing_leg = hal::kNumLegs;
}

void ControlLoop::sendCommand(hal::Board& board) {
  copyDecoderCounters();
  status_.config_crc = config_crc_;
  const size_t n =
      hal::wire::encodeCommand(command_, status_, ++tx_sequence_, tx_buffer_, sizeof tx_buffer_);
  board.linkWrite(tx_buffer_, n);
}

void ControlLoop::copyDecoderCounters() {
  const hal::wire::DecoderCounters& c = decoder_.counters();
  status_.bad_header = c.bad_header;
  status_.bad_crc = c.bad_crc;
  status_.out_of_order = c.out_of_order;
  status_.sequence_gaps = c.sequence_gaps;
  status_.skipped_bytes = c.skipped_bytes;
}

}  // namespace hyq::board
