// The wire format between the controller board and whatever closes the loop
// with it: the robot's motor-driver bridge, or the simulator through QEMU.
// The same code encodes and decodes on the board and on the host.
//
// One message on the wire (all integers little-endian, doubles as IEEE-754
// binary64 little-endian bytes, no padding):
//
//   offset  size  field
//   0       2     sync 0xA5 0x5A
//   2       1     version (kVersion)
//   3       1     type (MessageType)
//   4       2     payload length [bytes]: the type's fixed size (kConfig: 1..kMaxConfigBytes)
//   6       4     sequence number, per direction, +1 per message sent
//   10      n     payload
//   10+n    4     CRC-32 (IEEE 802.3, reflected, poly 0xEDB88320) of bytes 2..10+n
//
// A message with a bad header, a bad CRC, or a sequence number not newer than
// the last accepted one is dropped and counted; it never reaches the caller.
#pragma once
#include <cstddef>
#include <cstdint>

#include "hal/frames.hpp"

namespace hyq::hal::wire {

constexpr uint8_t kSync0 = 0xA5;
constexpr uint8_t kSync1 = 0x5A;
constexpr uint8_t kVersion = 3;
constexpr size_t kHeaderBytes = 10;
constexpr size_t kCrcBytes = 4;

enum class MessageType : uint8_t {
  kSensor = 1,   // bridge/simulator -> board: one SensorFrame per tick
  kCommand = 2,  // board -> bridge/simulator: CommandFrame + BoardStatus
  kHello = 3,    // board -> bridge/simulator: after reset and after a kConfig
  kConfig = 4,   // bridge/simulator -> board: controller parameters (variable length)
};

constexpr int kTimedStages = 11;  // stages of Controller::step timed on the board

// Board health that travels with every command, so the host can log it and
// tests can see what the board counted.
struct BoardStatus {
  uint32_t board_tick;         // [ticks] board's own 1 kHz ticks since reset
  uint32_t frames_accepted;    // [-] sensor frames that reached Controller::step
  uint32_t bad_header;         // [-] dropped: wrong version, type or length
  uint32_t bad_crc;            // [-] dropped: CRC mismatch
  uint32_t out_of_order;       // [-] dropped: sequence not newer than the last accepted
  uint32_t sequence_gaps;      // [-] frames never received (holes in the sequence)
  uint32_t skipped_bytes;      // [bytes] noise between frames
  uint32_t link_lost_events;   // [-] entries into the safe state
  uint32_t ticks_since_frame;  // [ticks] since the last accepted sensor frame
  uint32_t safe_state;         // [-] 1 while the board holds the safe state
  uint32_t overruns;           // [-] steps that did not fit in one tick
  uint32_t missed_ticks;       // [ticks] tick periods that passed unserved
  uint32_t step_counts_last;   // [clock counts] duration of the last Controller::step
  uint32_t step_counts_max;    // [clock counts] longest Controller::step so far
  uint32_t clock_hz;           // [Hz] rate of the clock counts above
  uint32_t config_crc;         // [-] crc32 of the kConfig bytes in use; 0: built-in defaults
  // [clock counts] each stage of the last Controller::step, in pipeline order
  // (hyq::Stage: frame check, legs, slip detection, state estimate, surface
  // and recovery, gait, wrench, QP build, QP solve, probe, commands)
  uint32_t stage_counts[kTimedStages];
};

// Sent by the board after reset until the first frame, after a kConfig, and
// while it holds the safe state: who it is, which parameters it runs, the
// sequence number the sender must continue from, and a floating-point self
// test the host repeats bit for bit.
struct Hello {
  uint32_t board_id;           // [-] BoardId of the image
  uint32_t wire_version;       // [-] kVersion the image was built with
  uint32_t clock_hz;           // [Hz] core clock
  uint32_t reset_cause;        // [-] ResetCause of the last reset
  uint32_t fpu_double;         // [-] 1: the core reports a double-precision FPU (MVFR0)
  uint32_t config_crc;         // [-] crc32 of the kConfig bytes in use; 0: built-in defaults
  uint32_t config_sequence;    // [-] sequence number of the kConfig this Hello answers; 0: none
  uint32_t config_result;      // [-] ConfigResult of that kConfig
  uint32_t link_epoch;         // [-] boots since power-on: a new value means the board restarted
  uint32_t next_sequence;      // [-] the board takes messages numbered from this one on (kept across resets)
  uint32_t stack_peak_bytes;   // [bytes] deepest stack use since reset (painted stack)
  double fpu_input;            // [-] input of fpuSelfTest() as the board read it
  double fpu_result;           // [-] fpuSelfTest(fpu_input) computed on the board
};

enum BoardId : uint32_t { kBoardHost = 0, kBoardMps2An500 = 1, kBoardStm32h743 = 2, kBoardSkeleton = 99 };
enum ResetCause : uint32_t { kResetPowerOn = 0, kResetWatchdog = 1, kResetFault = 2 };
// What the board did with a kConfig (Hello::config_result).
enum ConfigResult : uint32_t {
  kConfigApplied = 0,
  kConfigRefusedWhileControlling = 1,  // taken only before the first frame or in the safe state
  kConfigRefusedSize = 2,              // not sizeof(hyq::Params) bytes
  kConfigRefusedBool = 3,              // a bool's byte neither 0 nor 1
  kConfigRefusedRange = 4,             // a value outside checkParams' ranges
  kConfigRefusedOtherSet = 5,          // in the safe state, after walking: not the set in use
};

// A chain of divisions, square roots, products and sums in double precision:
// single-precision or soft-float arithmetic would not reproduce it bit for bit.
double fpuSelfTest(double input);

constexpr size_t kSensorPayloadBytes = 4 + 8 * (3 * kNumJoints + 4 + 3 + 3);
constexpr size_t kTelemetryBytes =
    8 * 4 + 8 * (1 + 3 + 3 + 4 * 3 * 3 + 4 + 4 * 3 + 4 + 4 * 3) + kNumLegs * (3 * 4 + 2 * 8);  // .., map_writes
constexpr size_t kBoardStatusBytes = (16 + kTimedStages) * 4;
constexpr size_t kCommandPayloadBytes = 2 * 4 + 8 * (5 * kNumJoints) + kTelemetryBytes + kBoardStatusBytes;
constexpr size_t kHelloPayloadBytes = 11 * 4 + 2 * 8;
// The board takes a kConfig of exactly sizeof(hyq::Params) bytes: the struct's
// bytes as laid out by both ABIs (x86-64 SysV and ARM AAPCS agree for a struct
// of doubles, ints and bools), applied with Controller::init.
constexpr size_t kMaxConfigBytes = 1536;
constexpr size_t kMaxPayloadBytes =
    kCommandPayloadBytes > kMaxConfigBytes ? kCommandPayloadBytes : kMaxConfigBytes;
static_assert(kMaxConfigBytes <= kMaxPayloadBytes, "a configuration fits the largest message");
constexpr size_t kMaxMessageBytes = kHeaderBytes + kMaxPayloadBytes + kCrcBytes;

// CRC-32 (IEEE) of n bytes, continuing from `crc` (start with 0).
uint32_t crc32(const uint8_t* data, size_t n, uint32_t crc = 0);

// Each encoder writes one complete message into out[0..capacity) and returns
// its length in bytes, or 0 when capacity is too small.
size_t encodeSensor(const SensorFrame& frame, uint32_t sequence, uint8_t* out, size_t capacity);
size_t encodeCommand(const CommandFrame& frame, const BoardStatus& status, uint32_t sequence,
                     uint8_t* out, size_t capacity);
size_t encodeHello(const Hello& hello, uint32_t sequence, uint8_t* out, size_t capacity);
size_t encodeConfig(const uint8_t* config, size_t config_bytes, uint32_t sequence, uint8_t* out,
                    size_t capacity);

// What the decoder hands out: only the member matching `type` is meaningful.
struct Message {
  MessageType type;
  uint32_t sequence;
  SensorFrame sensor;
  CommandFrame command;
  BoardStatus status;
  Hello hello;
  uint8_t config[kMaxConfigBytes];
  uint32_t config_bytes;
};

struct DecoderCounters {
  uint32_t accepted;        // [-] messages handed out
  uint32_t bad_header;      // [-] wrong version, unknown or unexpected type, or a length the type cannot have
  uint32_t bad_crc;         // [-] CRC mismatch (corrupt or truncated message, or a forged header)
  uint32_t out_of_order;    // [-] sequence not newer than the last accepted: duplicate or late
  uint32_t sequence_gaps;   // [-] sequence numbers skipped between accepted messages
  uint32_t skipped_bytes;   // [bytes] bytes that did not start a message
  uint32_t peer_restarts;   // [-] sequence jumped far back (or a Hello): the sender restarted (not in strict mode)
  uint32_t overrun;         // [-] awaited messages given up for a complete one behind their header
};

// Streaming decoder: bytes in, whole validated messages out. It holds the
// bytes that may still belong to a message (at most kMaxMessageBytes, since
// no message is longer) and, for every header there that a message can have
// (sync, version, a type and a length that type can have), notes the byte
// its message would end with. When such a byte arrives, one backward CRC
// pass over the bytes held checks every header whose message it completes;
// the oldest with a valid CRC is handed out and every byte held is let go.
// No header is given up while its message can still complete, so a valid
// message is handed out when its own last byte arrives, whatever came before
// it: noise, forged headers, messages cut short, in any number. It is lost
// only to bytes that complete a valid CRC of their own before it ends (a
// message inside its body, or a forgery that knew its bytes in advance).
class Decoder {
 public:
  // A sequence this far behind the last accepted one is not a late message
  // but a sender that restarted counting.
  static constexpr uint32_t kRestartWindow = 1024;

  // Feeds one byte. Returns true when `out` holds a new valid message.
  // Worst case work per byte: one move of the bytes held, one backward CRC
  // pass over them (only at a byte that a header held claims as its
  // message's last), then either the decode of the message handed out or
  // one forward scan of them; each covers at most kMaxMessageBytes (1550)
  // bytes. A message after a quiet link costs one CRC pass over itself.
  bool push(uint8_t byte, Message& out);
  const DecoderCounters& counters() const { return counters_; }
  // Forget partial input and the sequence history (counters are kept).
  void reset();
  // Only these two message types are handed out (the ones that travel in
  // this direction); any other is dropped as a bad header before its
  // sequence number is looked at, so that a Hello sent to the board cannot
  // reset its sequence history. Default: every type.
  void expect(MessageType a, MessageType b) { expected_types_ = typeBit(a) | typeBit(b); }
  // Strict numbering (the board's side): only messages numbered from
  // `first` on, each newer than the last accepted; no number behind is ever
  // taken as a sender restart, however far back. A sender that restarts
  // continues from the number the board announces (Hello::next_sequence).
  void acceptFrom(uint32_t first);
  // The number the next message must at least carry (strict mode).
  uint32_t nextSequence() const { return last_sequence_ + 1u; }

 private:
  // [bytes] of a header that tell whether a message can start there: sync, version, type, length.
  static constexpr size_t kHeaderCheckBytes = 6;
  static constexpr size_t kNone = kMaxMessageBytes;  // no offset in buffer_
  static constexpr size_t kEndWords = (kMaxMessageBytes + 31) / 32;

  size_t claimedEnd(size_t p) const;
  size_t messageEndingHere() const;
  bool take(size_t start, Message& out);
  void advanceHead();
  void dropBeforeHead();
  void forget();
  size_t endBit(size_t end) const { return (origin_ + end) % kMaxMessageBytes; }
  void noteEnd(size_t end);
  bool takeEnd(size_t end);
  bool sequenceAccepted(MessageType type, uint32_t sequence);
  static void decodePayload(const uint8_t* message, Message& out);

  static constexpr uint32_t typeBit(MessageType t) { return 1u << static_cast<uint8_t>(t); }

  uint32_t expected_types_ = 0xFFFFFFFFu;
  uint8_t buffer_[kMaxMessageBytes] = {};
  size_t length_ = 0;  // [bytes] held in buffer_
  // buffer_[0..head_) is sorted out (noise, bad headers, messages whose end
  // passed without a valid CRC); head_ is the oldest header whose message is
  // still awaited, the start of a header not complete yet, or length_.
  size_t head_ = 0;
  size_t head_end_ = 0;  // claimedEnd(head_) while that header is awaited, else 0
  // Bit endBit(e) of ends_: a header held claims a message whose last byte
  // is buffer_[e - 1]. The ends noted lie less than kMaxMessageBytes ahead
  // of length_, so no two share a bit; origin_ moves with buffer_[0].
  uint32_t ends_[kEndWords] = {};
  size_t origin_ = 0;
  bool have_sequence_ = false;
  bool strict_ = false;
  uint32_t last_sequence_ = 0;
  DecoderCounters counters_ = {};
};

}  // namespace hyq::hal::wire
