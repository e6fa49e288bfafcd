// libFuzzer target: arbitrary bytes into the streaming decoder. Whatever
// comes out must be a message that re-encodes to bytes the decoder accepts
// again unchanged; the counters must account for what went in.
#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "hal/wire.hpp"

namespace wire = hyq::hal::wire;

namespace {

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

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static wire::Decoder decoder;  // static: keep big objects off the fuzzer's stack
  static wire::Message message;
  static wire::Message again;
  static uint8_t buffer[wire::kMaxMessageBytes];
  decoder = wire::Decoder{};
  uint32_t out = 0;
  for (size_t i = 0; i < size; ++i) {
    if (!decoder.push(data[i], message)) continue;
    ++out;
    const size_t n = reencode(message, buffer, sizeof buffer);
    require(n >= wire::kHeaderBytes + wire::kCrcBytes);
    wire::Decoder fresh;
    uint32_t got = 0;
    for (size_t k = 0; k < n; ++k) got += fresh.push(buffer[k], again) ? 1u : 0u;
    // Without the CRC a body that holds a whole plausible message inside it
    // is cut there by the look-ahead (with the CRC, only if the inner message
    // carries a valid one): then the decoder must say so.
    if (fresh.counters().overrun > 0) {
      require(got >= 1);
      continue;
    }
    require(got == 1 && again.type == message.type && again.sequence == message.sequence);
    require(reencode(again, buffer + 0, sizeof buffer) == n);
  }
  const wire::DecoderCounters& c = decoder.counters();
  require(c.accepted == out);
  // Every accepted message used at least its minimum size of input.
  require(static_cast<size_t>(c.accepted) * (wire::kHeaderBytes + 1 + wire::kCrcBytes) <= size);
  require(c.skipped_bytes <= size);
  return 0;
}
