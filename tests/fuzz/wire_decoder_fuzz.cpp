// libFuzzer target: arbitrary bytes into the streaming decoder. Whatever
// comes out must be a message that re-encodes to bytes the decoder accepts
// again unchanged; the counters must account for what went in.
//
// Burst mode: an input that starts with kBurstTag describes a burst instead
// of spelling it out, so that mutations reach long runs of forged headers:
//
//   offset  size  field
//   0       1     kBurstTag
//   1       2     burst length [bytes], little-endian, modulo kMaxBurstBytes + 1
//   3       1     first valid message after the burst: sensor, command, Hello or configuration (modulo 4)
//   4       n     pattern, repeated to fill the burst (none: zeros)
//
// Behind the burst come two valid messages built here, numbered as the
// decoder expects next. Where the CRC is checked (wire_fuzz_replay), each
// must come out when its own last byte goes in and nothing else may: a burst
// never costs a valid message behind it.
#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "hal/wire.hpp"

namespace wire = hyq::hal::wire;

namespace {

constexpr uint8_t kBurstTag = 0xB7;
constexpr size_t kMaxBurstBytes = 4 * wire::kMaxMessageBytes;

void require(bool condition) {
  if (!condition) std::abort();
}

size_t reencode(const wire::Message& m, uint8_t* out, size_t capacity) {
  switch (m.type) {
    case wire::MessageType::kSensor: return wire::encodeSensor(m.sensor, m.sequence, out, capacity);
    case wire::MessageType::kCommand: return wire::encodeCommand(m.command, m.status, m.sequence, out, capacity);
    case wire::MessageType::kHello: return wire::encodeHello(m.hello, m.sequence, out, capacity);
    case wire::MessageType::kConfig: return wire::encodeConfig(m.config, m.config_bytes, m.sequence, out, capacity);
  }
  return 0;
}

// Statics: keep big objects off the fuzzer's stack.
wire::Decoder decoder;
wire::Message message;
wire::Message again;
uint8_t buffer[wire::kMaxMessageBytes];
uint8_t valid[wire::kMaxMessageBytes];
uint8_t config[wire::kMaxConfigBytes];
uint32_t handed_out = 0;
size_t pushed = 0;

// Pushes one byte into `decoder`; a message that comes out must survive a
// round trip through a fresh decoder. Returns whether one came out.
bool push(uint8_t byte) {
  ++pushed;
  if (!decoder.push(byte, message)) return false;
  ++handed_out;
  const size_t n = reencode(message, buffer, sizeof buffer);
  require(n >= wire::kHeaderBytes + wire::kCrcBytes);
  wire::Decoder fresh;
  uint32_t got = 0;
  for (size_t k = 0; k < n; ++k) got += fresh.push(buffer[k], again) ? 1u : 0u;
  // Without the CRC a body that holds a whole plausible message inside it
  // is cut there (with the CRC, only if the inner message carries a valid
  // one): then the decoder must say so.
  if (fresh.counters().overrun > 0) {
    require(got >= 1);
    return true;
  }
  require(got == 1 && again.type == message.type && again.sequence == message.sequence);
  require(reencode(again, buffer + 0, sizeof buffer) == n);
  return true;
}

// Whether this build's decoder checks the CRC (the libFuzzer build does not).
bool crcChecked() {
  uint8_t hello[wire::kMaxMessageBytes];
  const size_t n = wire::encodeHello(wire::Hello{}, 1, hello, sizeof hello);
  hello[n - 1] ^= 0x01u;
  wire::Decoder probe;
  wire::Message out;
  bool taken = false;
  for (size_t k = 0; k < n; ++k) taken = probe.push(hello[k], out) || taken;
  return !taken;
}

// Encodes a valid message of the kind `kind` (modulo 4) into `valid`; returns its length.
size_t validMessage(uint8_t kind, uint8_t fill, size_t config_bytes, uint32_t sequence) {
  switch (kind % 4) {
    case 0: {
      hyq::hal::SensorFrame s{};
      s.tick = fill;
      s.q[0] = 0.25;
      return wire::encodeSensor(s, sequence, valid, sizeof valid);
    }
    case 1: {
      hyq::hal::CommandFrame c{};
      c.tick = fill;
      wire::BoardStatus status{};
      status.board_tick = fill;
      return wire::encodeCommand(c, status, sequence, valid, sizeof valid);
    }
    case 2: {
      wire::Hello h{};
      h.board_id = fill;
      return wire::encodeHello(h, sequence, valid, sizeof valid);
    }
    default: {
      // One repeated byte: a body that cannot hold a sync pair, so no
      // message inside it cuts it short.
      std::memset(config, fill, config_bytes);
      return wire::encodeConfig(config, config_bytes, sequence, valid, sizeof valid);
    }
  }
}

void burst(const uint8_t* data, size_t size) {
  static const bool checked = crcChecked();
  const size_t length = (data[1] | (static_cast<size_t>(data[2]) << 8)) % (kMaxBurstBytes + 1);
  const uint8_t kind = data[3];
  const uint8_t* pattern = data + 4;
  const size_t pattern_bytes = size - 4;
  for (size_t i = 0; i < length; ++i) push(pattern_bytes > 0 ? pattern[i % pattern_bytes] : 0);
  const size_t config_bytes = 1 + length % wire::kMaxConfigBytes;
  for (int m = 0; m < 2; ++m) {
    const uint32_t sequence = decoder.nextSequence();
    const uint8_t this_kind = m == 0 ? kind : 0;
    const size_t n = validMessage(this_kind, kind, config_bytes, sequence);
    require(n > 0);
    for (size_t k = 0; k < n; ++k) {
      const bool out = push(valid[k]);
      if (!checked) continue;
      require(out == (k + 1 == n));
      if (out) require(message.sequence == sequence && static_cast<uint8_t>(message.type) == 1 + this_kind % 4);
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  decoder = wire::Decoder{};
  handed_out = 0;
  pushed = 0;
  if (size >= 4 && data[0] == kBurstTag) {
    burst(data, size);
  } else {
    for (size_t i = 0; i < size; ++i) push(data[i]);
  }
  const wire::DecoderCounters& c = decoder.counters();
  require(c.accepted == handed_out);
  // Every accepted message used at least its minimum size of input.
  require(static_cast<size_t>(c.accepted) * (wire::kHeaderBytes + 1 + wire::kCrcBytes) <= pushed);
  require(c.skipped_bytes <= pushed);
  return 0;
}
