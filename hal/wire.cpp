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

// The CRC at the end of the `total` bytes of a message starting at m
// (always true in the fuzzer's build).
bool crcValid(const uint8_t* m, size_t total) {
  return !kCheckCrc || crc32(m + 2, total - kCrcBytes - 2) == readU32(m + total - kCrcBytes);
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
  length_ = 0;
  candidate_count_ = 0;
  have_sequence_ = false;
  strict_ = false;
}

void Decoder::acceptFrom(uint32_t first) {
  strict_ = true;
  have_sequence_ = true;
  last_sequence_ = first - 1u;
}

Decoder::Check Decoder::checkBuffer() {
  if (buffer_[0] != kSync0) return Check::kInvalid;
  if (length_ < 2) return Check::kIncomplete;
  if (buffer_[1] != kSync1) return Check::kInvalid;
  if (length_ < kHeaderBytes) return Check::kIncomplete;
  const size_t expected = readU16(buffer_ + 4);
  if (buffer_[2] != kVersion || !lengthValid(buffer_[3], expected)) {
    ++counters_.bad_header;
    return Check::kInvalid;
  }
  const size_t total = kHeaderBytes + expected + kCrcBytes;
  if (length_ < total) return Check::kIncomplete;
  if (!crcValid(buffer_, total)) {
    ++counters_.bad_crc;
    return Check::kInvalid;
  }
  return Check::kValid;
}

// Drops the first byte, then everything up to the next possible sync byte.
void Decoder::dropLeadingBytes() {
  size_t start = 1;
  while (start < length_ && buffer_[start] != kSync0) ++start;
  // A frame that got as far as a valid sync pair was counted by checkBuffer;
  // anything else is noise.
  if (!(length_ >= 2 && buffer_[0] == kSync0 && buffer_[1] == kSync1))
    counters_.skipped_bytes += static_cast<uint32_t>(start);
  std::memmove(buffer_, buffer_ + start, length_ - start);
  length_ -= start;
  findCandidates();
}

// A sync pair at p that may start a message: its header, as far as it is
// in the buffer, is one a message can have.
bool Decoder::plausibleStart(size_t p) const {
  if (p + 1 >= length_ || buffer_[p] != kSync0 || buffer_[p + 1] != kSync1) return false;
  if (length_ - p < kHeaderBytes) return true;
  return buffer_[p + 2] == kVersion && lengthValid(buffer_[p + 3], readU16(buffer_ + p + 4));
}

void Decoder::findCandidates() {
  candidate_count_ = 0;
  for (size_t p = 1; p + 1 < length_ && candidate_count_ < kMaxCandidates; ++p)
    if (plausibleStart(p)) candidates_[candidate_count_++] = p;
}

size_t Decoder::completedCandidate() {
  const bool new_pair = length_ >= 3 && buffer_[length_ - 2] == kSync0 && buffer_[length_ - 1] == kSync1 &&
                        !(candidate_count_ > 0 && candidates_[candidate_count_ - 1] == length_ - 2);
  if (new_pair) {
    if (candidate_count_ == kMaxCandidates) {  // let the oldest go
      for (int i = 1; i < kMaxCandidates; ++i) candidates_[i - 1] = candidates_[i];
      --candidate_count_;
    }
    candidates_[candidate_count_++] = length_ - 2;
  }
  size_t found = 0;
  int kept = 0;
  for (int i = 0; i < candidate_count_; ++i) {
    const size_t p = candidates_[i];
    const size_t have = length_ - p;
    bool keep = true;
    if (!plausibleStart(p)) {
      keep = false;
    } else if (have >= kHeaderBytes && have == kHeaderBytes + readU16(buffer_ + p + 4) + kCrcBytes) {
      keep = false;
      if (found == 0 && crcValid(buffer_ + p, have)) found = p;
    }
    if (keep) candidates_[kept++] = p;
  }
  candidate_count_ = kept;
  return found;
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

void Decoder::decodePayload(Message& out) const {
  Reader r(buffer_ + kHeaderBytes);
  switch (out.type) {
    case MessageType::kSensor: visitSensor(r, out.sensor); break;
    case MessageType::kCommand:
      visitCommand(r, out.command);
      visitStatus(r, out.status);
      break;
    case MessageType::kHello: visitHello(r, out.hello); break;
    case MessageType::kConfig:
      out.config_bytes = readU16(buffer_ + 4);
      std::memcpy(out.config, buffer_ + kHeaderBytes, out.config_bytes);
      break;
  }
}

bool Decoder::push(uint8_t byte, Message& out) {
  // checkBuffer never lets length_ reach the capacity without deciding.
  buffer_[length_++] = byte;
  // Each pass either returns or removes at least one byte: bounded by length_.
  while (length_ > 0) {
    switch (checkBuffer()) {
      case Check::kIncomplete: {
        const size_t behind = completedCandidate();
        if (behind == 0) return false;
        // A whole message behind an awaited header: that header lied.
        ++counters_.overrun;
        std::memmove(buffer_, buffer_ + behind, length_ - behind);
        length_ -= behind;
        candidate_count_ = 0;
        break;
      }
      case Check::kInvalid: dropLeadingBytes(); break;
      case Check::kValid: {
        const MessageType type = static_cast<MessageType>(buffer_[3]);
        const uint32_t sequence = readU32(buffer_ + 6);
        const bool expected = (expected_types_ & typeBit(type)) != 0u;
        if (!expected) ++counters_.bad_header;
        const bool fresh = expected && sequenceAccepted(type, sequence);
        if (fresh) {
          out.type = type;
          out.sequence = sequence;
          decodePayload(out);
          ++counters_.accepted;
        }
        length_ = 0;
        candidate_count_ = 0;
        return fresh;
      }
    }
  }
  return false;
}

}  // namespace hyq::hal::wire
