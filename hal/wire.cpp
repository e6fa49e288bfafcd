#include "hal/wire.hpp"

#include <cstring>

namespace hyq::hal::wire {

// The fuzzer's build (tests/fuzz/) skips the CRC so that mutated payloads
// reach the body decoder; every other build checks it.
#ifdef FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION
constexpr bool kCheckCrc = false;
#else
constexpr bool kCheckCrc = true;
#endif

namespace {

struct CrcTable {
  uint32_t entry[256];
};

constexpr CrcTable makeCrcTable() {
  CrcTable table{};
  for (uint32_t i = 0; i < 256; ++i) {
    uint32_t c = i;
    for (int bit = 0; bit < 8; ++bit) c = (c & 1u) ? (0xEDB88320u ^ (c >> 1)) : (c >> 1);
    table.entry[i] = c;
  }
  return table;
}

// In flash on the board: computed by the compiler, never written.
constexpr CrcTable kCrcTable = makeCrcTable();

// Byte order is spelled out so the format does not depend on the host's.
class Writer {
 public:
  Writer(uint8_t* out, size_t capacity) : out_(out), capacity_(capacity) {}
  void u8(uint8_t v) {
    if (pos_ < capacity_) out_[pos_] = v;
    ++pos_;
  }
  void u16(uint16_t v) {
    u8(static_cast<uint8_t>(v));
    u8(static_cast<uint8_t>(v >> 8));
  }
  void u32(const uint32_t& v) {
    for (int i = 0; i < 4; ++i) u8(static_cast<uint8_t>(v >> (8 * i)));
  }
  void i32(const int32_t* v, int n) {  // two's complement, as u32
    for (int k = 0; k < n; ++k) u32(static_cast<uint32_t>(v[k]));
  }
  void bytes(const uint8_t* v, size_t n) {
    for (size_t k = 0; k < n; ++k) u8(v[k]);
  }
  void f64(const double* v, int n) {
    for (int k = 0; k < n; ++k) {
      uint64_t bits;
      std::memcpy(&bits, &v[k], sizeof bits);
      for (int i = 0; i < 8; ++i) u8(static_cast<uint8_t>(bits >> (8 * i)));
    }
  }
  size_t position() const { return pos_; }

 private:
  uint8_t* out_;
  size_t capacity_;
  size_t pos_ = 0;
};

class Reader {
 public:
  explicit Reader(const uint8_t* in) : in_(in) {}
  void u32(uint32_t& v) {
    v = 0;
    for (int i = 0; i < 4; ++i) v |= static_cast<uint32_t>(in_[pos_++]) << (8 * i);
  }
  void i32(int32_t* v, int n) {
    for (int k = 0; k < n; ++k) {
      uint32_t bits;
      u32(bits);
      std::memcpy(&v[k], &bits, sizeof bits);
    }
  }
  void f64(double* v, int n) {
    for (int k = 0; k < n; ++k) {
      uint64_t bits = 0;
      for (int i = 0; i < 8; ++i) bits |= static_cast<uint64_t>(in_[pos_++]) << (8 * i);
      std::memcpy(&v[k], &bits, sizeof bits);
    }
  }

 private:
  const uint8_t* in_;
  size_t pos_ = 0;
};

// One field list per struct, walked by the Writer (const frames) and the
// Reader (mutable frames): the two directions cannot drift apart.
template <class Io, class Frame>
void visitSensor(Io& io, Frame& f) {
  io.u32(f.tick);
  io.f64(f.q, kNumJoints);
  io.f64(f.qd, kNumJoints);
  io.f64(f.tau, kNumJoints);
  io.f64(f.imu_quat, 4);
  io.f64(f.imu_gyro, 3);
  io.f64(f.imu_acc, 3);
}

template <class Io, class T>
void visitTelemetry(Io& io, T& t) {
  io.u32(t.stance_mask);
  io.u32(t.slip_mask);
  io.u32(t.swing_leg);
  io.f64(&t.gait_phase, 1);
  io.f64(t.base_pos_est, 3);
  io.f64(t.base_vel_est, 3);
  io.f64(&t.foot_vel_base[0][0], kNumLegs * 3);
  io.f64(&t.grf_est[0][0], kNumLegs * 3);
  io.f64(&t.grf_des[0][0], kNumLegs * 3);
  io.f64(t.mu_used, kNumLegs);
  io.f64(&t.normal_used[0][0], kNumLegs * 3);
  io.f64(t.mu_hat, kNumLegs);
  io.f64(&t.normal_hat[0][0], kNumLegs * 3);
  io.u32(t.probe_leg);
  io.u32(t.probe_partner);
  for (auto& count : t.probe_counts) io.u32(count);
  for (auto& w : t.map_writes) {
    io.i32(w.cell, 2);
    io.u32(w.count);
    io.f64(&w.mu, 1);
    io.f64(&w.spread, 1);
  }
}

template <class Io, class Frame>
void visitCommand(Io& io, Frame& f) {
  io.u32(f.tick);
  io.u32(f.flags);
  io.f64(f.tau_ff, kNumJoints);
  io.f64(f.q_ref, kNumJoints);
  io.f64(f.qd_ref, kNumJoints);
  io.f64(f.kp, kNumJoints);
  io.f64(f.kd, kNumJoints);
  visitTelemetry(io, f.telemetry);
}

template <class Io, class S>
void visitStatus(Io& io, S& s) {
  io.u32(s.board_tick);
  io.u32(s.frames_accepted);
  io.u32(s.bad_header);
  io.u32(s.bad_crc);
  io.u32(s.out_of_order);
  io.u32(s.sequence_gaps);
  io.u32(s.skipped_bytes);
  io.u32(s.link_lost_events);
  io.u32(s.ticks_since_frame);
  io.u32(s.safe_state);
  io.u32(s.overruns);
  io.u32(s.missed_ticks);
  io.u32(s.step_counts_last);
  io.u32(s.step_counts_max);
  io.u32(s.clock_hz);
  io.u32(s.config_crc);
  for (auto& c : s.stage_counts) io.u32(c);
}

template <class Io, class H>
void visitHello(Io& io, H& h) {
  io.u32(h.board_id);
  io.u32(h.wire_version);
  io.u32(h.clock_hz);
  io.u32(h.reset_cause);
  io.u32(h.fpu_double);
  io.u32(h.config_crc);
  io.u32(h.config_sequence);
  io.u32(h.config_result);
  io.u32(h.link_epoch);
  io.u32(h.next_sequence);
  io.u32(h.stack_peak_bytes);
  io.f64(&h.fpu_input, 1);
  io.f64(&h.fpu_result, 1);
}

bool lengthValid(uint8_t type, size_t length) {
  switch (static_cast<MessageType>(type)) {
    case MessageType::kSensor: return length == kSensorPayloadBytes;
    case MessageType::kCommand: return length == kCommandPayloadBytes;
    case MessageType::kHello: return length == kHelloPayloadBytes;
    case MessageType::kConfig: return length >= 1 && length <= kMaxConfigBytes;
  }
  return false;
}

void writeHeader(Writer& w, MessageType type, size_t payload_bytes, uint32_t sequence) {
  w.u8(kSync0);
  w.u8(kSync1);
  w.u8(kVersion);
  w.u8(static_cast<uint8_t>(type));
  w.u16(static_cast<uint16_t>(payload_bytes));
  w.u32(sequence);
}

// Appends the CRC; returns the message length, or 0 if it did not fit.
size_t finish(Writer& w, uint8_t* out, size_t capacity) {
  const size_t body_end = w.position();
  if (body_end + kCrcBytes > capacity) return 0;
  w.u32(crc32(out + 2, body_end - 2));
  return w.position();
}

uint16_t readU16(const uint8_t* p) { return static_cast<uint16_t>(p[0] | (p[1] << 8)); }
uint32_t readU32(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) |
         (static_cast<uint32_t>(p[2]) << 16) | (static_cast<uint32_t>(p[3]) << 24);
}

}  // namespace

uint32_t crc32(const uint8_t* data, size_t n, uint32_t crc) {
  crc = ~crc;
  for (size_t i = 0; i < n; ++i) crc = kCrcTable.entry[(crc ^ data[i]) & 0xFFu] ^ (crc >> 8);
  return ~crc;
}

namespace {

// The top bytes of the CRC table's entries are all different, so the top
// byte of a CRC state names the entry that produced it, and one step of
// crc32 can be undone: entry[t] of this table is the entry whose top byte is
// t, shifted up a byte, with its index in the low byte.
struct CrcBackTable {
  uint32_t entry[256];
};

constexpr CrcBackTable makeCrcBackTable() {
  CrcBackTable table{};
  for (uint32_t i = 0; i < 256; ++i) table.entry[kCrcTable.entry[i] >> 24] = (kCrcTable.entry[i] << 8) ^ i;
  return table;
}

// In flash on the board, as kCrcTable.
constexpr CrcBackTable kCrcBackTable = makeCrcBackTable();

constexpr bool crcTopBytesDistinct() {
  bool seen[256] = {};
  for (uint32_t i = 0; i < 256; ++i) {
    if (seen[kCrcTable.entry[i] >> 24]) return false;
    seen[kCrcTable.entry[i] >> 24] = true;
  }
  return true;
}
static_assert(crcTopBytesDistinct(), "one step of crc32 is undone through its state's top byte");

// The CRC state before `byte` went in, from the state after it.
uint32_t crcUnroll(uint32_t state, uint8_t byte) {
  return (state << 8) ^ kCrcBackTable.entry[state >> 24] ^ byte;
}

}  // namespace

double fpuSelfTest(double input) {
  double x = input;
  double acc = 0.0;
  for (int i = 1; i <= 64; ++i) {
    const double s = __builtin_sqrt(x * x + 1.0 / i);
    acc = acc * 0.5 + s / (1.0 + x * x);
    x = x * 1.000244140625 - acc * 1e-3;
  }
  return acc;
}

size_t encodeSensor(const SensorFrame& frame, uint32_t sequence, uint8_t* out, size_t capacity) {
  Writer w(out, capacity);
  writeHeader(w, MessageType::kSensor, kSensorPayloadBytes, sequence);
  visitSensor(w, frame);
  return finish(w, out, capacity);
}

size_t encodeCommand(const CommandFrame& frame, const BoardStatus& status, uint32_t sequence,
                     uint8_t* out, size_t capacity) {
  Writer w(out, capacity);
  writeHeader(w, MessageType::kCommand, kCommandPayloadBytes, sequence);
  visitCommand(w, frame);
  visitStatus(w, status);
  return finish(w, out, capacity);
}

size_t encodeHello(const Hello& hello, uint32_t sequence, uint8_t* out, size_t capacity) {
  Writer w(out, capacity);
  writeHeader(w, MessageType::kHello, kHelloPayloadBytes, sequence);
  visitHello(w, hello);
  return finish(w, out, capacity);
}

size_t encodeConfig(const uint8_t* config, size_t config_bytes, uint32_t sequence, uint8_t* out,
                    size_t capacity) {
  if (!lengthValid(static_cast<uint8_t>(MessageType::kConfig), config_bytes)) return 0;
  Writer w(out, capacity);
  writeHeader(w, MessageType::kConfig, config_bytes, sequence);
  w.bytes(config, config_bytes);
  return finish(w, out, capacity);
}

void Decoder::reset() {
  forget();
  have_sequence_ = false;
  strict_ = false;
}

void Decoder::acceptFrom(uint32_t first) {
  strict_ = true;
  have_sequence_ = true;
  last_sequence_ = first - 1u;
}

// Lets go of every byte held and every end noted.
void Decoder::forget() {
  length_ = 0;
  head_ = 0;
  head_end_ = 0;
  origin_ = 0;
  std::memset(ends_, 0, sizeof ends_);
}

// Where the message whose header starts at buffer_[p] ends (offset of its
// last byte + 1), if the header is one a message can have; 0 otherwise, and
// while its first kHeaderCheckBytes are not all held.
size_t Decoder::claimedEnd(size_t p) const {
  if (p + kHeaderCheckBytes > length_ || buffer_[p] != kSync0 || buffer_[p + 1] != kSync1 ||
      buffer_[p + 2] != kVersion)
    return 0;
  const size_t payload = readU16(buffer_ + p + 4);
  return lengthValid(buffer_[p + 3], payload) ? p + kHeaderBytes + payload + kCrcBytes : 0;
}

void Decoder::noteEnd(size_t end) {
  const size_t bit = endBit(end);
  ends_[bit / 32] |= 1u << (bit % 32);
}

// Whether a message was noted to end at `end`; the note is cleared.
bool Decoder::takeEnd(size_t end) {
  const size_t bit = endBit(end);
  const uint32_t mask = 1u << (bit % 32);
  const bool noted = (ends_[bit / 32] & mask) != 0u;
  ends_[bit / 32] &= ~mask;
  return noted;
}

// The oldest message held that the last byte completes with a valid CRC:
// its offset, or kNone. One pass backwards from the CRC field unrolls the
// CRC state byte by byte; a header whose message ends here has a valid CRC
// exactly where the state is back at its initial value, behind the header's
// first two bytes. Headers before head_ cannot end here (see advanceHead).
size_t Decoder::messageEndingHere() const {
  size_t found = kNone;
  if (length_ < head_ + kHeaderBytes + 1 + kCrcBytes) return found;
  uint32_t state = ~readU32(buffer_ + length_ - kCrcBytes);
  for (size_t k = length_ - kCrcBytes; k > head_ + 2;) {
    state = crcUnroll(state, buffer_[--k]);  // the state before buffer_[k]
    if ((state == 0xFFFFFFFFu || !kCheckCrc) && claimedEnd(k - 2) == length_) found = k - 2;
  }
  return found;
}

// Hands out (or drops, if its type is not expected or its sequence is not
// newer) the valid message at buffer_[start], then lets go of every byte.
bool Decoder::take(size_t start, Message& out) {
  // A header before it was still awaited: it lied, or its message was cut.
  if (start != head_) ++counters_.overrun;
  const uint8_t* message = buffer_ + start;
  const MessageType type = static_cast<MessageType>(message[3]);
  const uint32_t sequence = readU32(message + 6);
  const bool expected = (expected_types_ & typeBit(type)) != 0u;
  if (!expected) ++counters_.bad_header;
  const bool fresh = expected && sequenceAccepted(type, sequence);
  if (fresh) {
    out.type = type;
    out.sequence = sequence;
    decodePayload(message, out);
    ++counters_.accepted;
  }
  forget();
  return fresh;
}

// Moves head_ over the bytes that cannot start a message still to come, and
// counts them: bytes that start no header (skipped_bytes), headers no
// message can have (bad_header), headers whose message ended without a
// valid CRC (bad_crc). It stops at the oldest header still awaited, or at
// one not complete yet. A header behind it whose end passes is checked then
// (messageEndingHere) and counted once head_ gets to it.
void Decoder::advanceHead() {
  head_end_ = 0;
  while (head_ < length_) {
    const size_t p = head_;
    if (buffer_[p] != kSync0 || (p + 1 < length_ && buffer_[p + 1] != kSync1)) {
      ++counters_.skipped_bytes;
      ++head_;
    } else if (p + kHeaderCheckBytes > length_) {
      return;  // the rest of the header is still to come
    } else {
      const size_t end = claimedEnd(p);
      if (end > length_) {  // awaited
        head_end_ = end;
        return;
      }
      if (end == 0) {
        ++counters_.bad_header;
      } else {
        ++counters_.bad_crc;
      }
      head_ += 2;  // past the sync pair: a message may start inside the rest
    }
  }
}

// Makes room: lets go of the bytes before head_. head_ > 0 whenever the
// buffer is full (a header at 0 has had its whole message's worth of bytes
// and has ended, and a header not complete yet lies in the last bytes).
void Decoder::dropBeforeHead() {
  const size_t n = head_ > 0 ? head_ : 1;  // 1: stays in bounds whatever happens
  std::memmove(buffer_, buffer_ + n, length_ - n);
  length_ -= n;
  head_ = 0;
  if (head_end_ != 0) head_end_ -= n;
  origin_ = (origin_ + n) % kMaxMessageBytes;
}

bool Decoder::sequenceAccepted(MessageType type, uint32_t sequence) {
  if (type == MessageType::kHello && have_sequence_ && !strict_) {
    ++counters_.peer_restarts;
    have_sequence_ = false;
  }
  if (have_sequence_) {
    const uint32_t ahead = sequence - last_sequence_;
    const uint32_t behind = last_sequence_ - sequence;
    if (ahead == 0 || (ahead > 0x80000000u && (strict_ || behind <= kRestartWindow))) {
      ++counters_.out_of_order;
      return false;
    }
    if (ahead <= 0x80000000u) {
      counters_.sequence_gaps += ahead - 1;
    } else {
      ++counters_.peer_restarts;
    }
  }
  have_sequence_ = true;
  last_sequence_ = sequence;
  return true;
}

void Decoder::decodePayload(const uint8_t* message, Message& out) {
  Reader r(message + kHeaderBytes);
  switch (out.type) {
    case MessageType::kSensor: visitSensor(r, out.sensor); break;
    case MessageType::kCommand:
      visitCommand(r, out.command);
      visitStatus(r, out.status);
      break;
    case MessageType::kHello: visitHello(r, out.hello); break;
    case MessageType::kConfig:
      out.config_bytes = readU16(message + 4);
      std::memcpy(out.config, message + kHeaderBytes, out.config_bytes);
      break;
  }
}

bool Decoder::push(uint8_t byte, Message& out) {
  if (length_ == kMaxMessageBytes) dropBeforeHead();
  buffer_[length_++] = byte;
  // The header this byte completes (its length field): note where its message ends.
  if (length_ >= kHeaderCheckBytes && buffer_[length_ - kHeaderCheckBytes] == kSync0) {
    const size_t end = claimedEnd(length_ - kHeaderCheckBytes);
    if (end != 0) noteEnd(end);
  }
  if (takeEnd(length_)) {
    const size_t start = messageEndingHere();
    if (start != kNone) return take(start, out);
  }
  if (length_ >= head_end_) advanceHead();  // else head_ is a header still awaited
  return false;
}

}  // namespace hyq::hal::wire
