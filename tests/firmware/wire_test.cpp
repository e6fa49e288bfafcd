// The wire format: round trips, CRC, and every way a message must be dropped.
#include "hal/wire.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "firmware/controller/params.hpp"

namespace wire = hyq::hal::wire;
using hyq::hal::CommandFrame;
using hyq::hal::SensorFrame;

namespace {

SensorFrame makeSensor(uint32_t tick) {
  SensorFrame s{};
  s.tick = tick;
  for (int j = 0; j < hyq::hal::kNumJoints; ++j) {
    s.q[j] = 0.1 * j - 0.7 + 1e-3 * tick;
    s.qd[j] = -0.01 * j;
    s.tau[j] = 12.5 * j - 40.0;
  }
  s.imu_quat[0] = 1.0;
  s.imu_gyro[2] = 0.03;
  s.imu_acc[2] = 9.81;
  return s;
}

CommandFrame makeCommand(uint32_t tick) {
  CommandFrame c{};
  c.tick = tick;
  c.flags = hyq::hal::kFlagQpMaxIter;
  for (int j = 0; j < hyq::hal::kNumJoints; ++j) {
    c.tau_ff[j] = -3.25 * j;
    c.q_ref[j] = 0.5 - 0.1 * j;
    c.kp[j] = 400.0;
    c.kd[j] = 6.0;
  }
  c.telemetry.stance_mask = 0xB;
  c.telemetry.swing_leg = 2;
  c.telemetry.normal_hat[3][2] = 0.999;
  c.telemetry.mu_hat[1] = 0.31;
  return c;
}

std::vector<uint8_t> encode(const SensorFrame& s, uint32_t sequence) {
  std::vector<uint8_t> out(wire::kMaxMessageBytes);
  out.resize(wire::encodeSensor(s, sequence, out.data(), out.size()));
  return out;
}

// A header with nothing behind it: what a forged or corrupted length looks like.
void appendForgedHeader(std::vector<uint8_t>& bytes, uint8_t type, size_t length) {
  const uint8_t h[wire::kHeaderBytes] = {wire::kSync0, wire::kSync1, wire::kVersion, type,
                                         static_cast<uint8_t>(length & 0xFF),
                                         static_cast<uint8_t>(length >> 8), 0, 0, 0, 0};
  bytes.insert(bytes.end(), h, h + wire::kHeaderBytes);
}

// A seed of tests/fuzz/corpus (written by tests/fuzz/make_seeds.py); empty if missing.
std::vector<uint8_t> readSeed(const std::string& name) {
  std::vector<uint8_t> bytes;
  std::FILE* f = std::fopen((std::string(HYQ_FUZZ_CORPUS "/") + name).c_str(), "rb");
  if (f == nullptr) return bytes;
  uint8_t chunk[4096];
  for (size_t n; (n = std::fread(chunk, 1, sizeof chunk, f)) > 0;) bytes.insert(bytes.end(), chunk, chunk + n);
  std::fclose(f);
  return bytes;
}

// Feeds bytes; returns the messages that came out.
std::vector<wire::Message> feed(wire::Decoder& d, const std::vector<uint8_t>& bytes) {
  std::vector<wire::Message> out;
  wire::Message m{};
  for (uint8_t b : bytes)
    if (d.push(b, m)) out.push_back(m);
  return out;
}

}  // namespace

TEST(Wire, Crc32MatchesTheStandardCheckValue) {
  const char* text = "123456789";
  EXPECT_EQ(wire::crc32(reinterpret_cast<const uint8_t*>(text), 9), 0xCBF43926u);
}

TEST(Wire, SizesFollowTheFieldLists) {
  EXPECT_EQ(encode(makeSensor(1), 1).size(), wire::kHeaderBytes + wire::kSensorPayloadBytes + wire::kCrcBytes);
  EXPECT_EQ(wire::kSensorPayloadBytes, 372u);
  std::vector<uint8_t> out(wire::kMaxMessageBytes);
  EXPECT_EQ(wire::encodeCommand(makeCommand(1), wire::BoardStatus{}, 1, out.data(), out.size()),
            wire::kHeaderBytes + wire::kCommandPayloadBytes + wire::kCrcBytes);
  EXPECT_EQ(wire::kCommandPayloadBytes, 1340u);
  // The largest message: a command, or a configuration of the largest size.
  EXPECT_EQ(wire::kMaxMessageBytes,
            wire::kHeaderBytes + std::max(wire::kCommandPayloadBytes, wire::kMaxConfigBytes) + wire::kCrcBytes);
  EXPECT_GE(wire::kMaxConfigBytes, sizeof(hyq::Params));
  EXPECT_EQ(wire::encodeSensor(makeSensor(1), 1, out.data(), 100), 0u) << "too small a buffer must fail";
}

TEST(Wire, LayoutIsLittleEndianWithIeeeDoubles) {
  SensorFrame s{};
  s.tick = 0x01020304;
  s.q[0] = 1.0;  // 0x3FF0000000000000
  const auto bytes = encode(s, 0xA0B0C0D0);
  EXPECT_EQ(bytes[0], 0xA5);
  EXPECT_EQ(bytes[1], 0x5A);
  EXPECT_EQ(bytes[2], wire::kVersion);
  EXPECT_EQ(bytes[3], 1);
  EXPECT_EQ(bytes[4] | (bytes[5] << 8), 372);
  EXPECT_EQ(bytes[6], 0xD0);
  EXPECT_EQ(bytes[9], 0xA0);
  EXPECT_EQ(bytes[10], 0x04);
  EXPECT_EQ(bytes[13], 0x01);
  EXPECT_EQ(bytes[14 + 6], 0xF0);
  EXPECT_EQ(bytes[14 + 7], 0x3F);
}

TEST(Wire, SensorAndCommandRoundTripBitForBit) {
  wire::Decoder d;
  const SensorFrame s = makeSensor(42);
  auto got = feed(d, encode(s, 7));
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].type, wire::MessageType::kSensor);
  EXPECT_EQ(got[0].sequence, 7u);
  EXPECT_EQ(std::memcmp(&got[0].sensor, &s, sizeof s), 0);

  CommandFrame c = makeCommand(42);
  wire::BoardStatus st{};
  st.bad_crc = 3;
  st.clock_hz = 25000000;
  std::vector<uint8_t> out(wire::kMaxMessageBytes);
  out.resize(wire::encodeCommand(c, st, 8, out.data(), out.size()));
  got = feed(d, out);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].type, wire::MessageType::kCommand);
  EXPECT_EQ(got[0].command.tick, 42u);
  EXPECT_EQ(got[0].command.flags, hyq::hal::kFlagQpMaxIter);
  EXPECT_EQ(std::memcmp(got[0].command.tau_ff, c.tau_ff, sizeof c.tau_ff), 0);
  EXPECT_EQ(std::memcmp(got[0].command.kd, c.kd, sizeof c.kd), 0);
  EXPECT_EQ(got[0].command.telemetry.normal_hat[3][2], 0.999);
  EXPECT_EQ(got[0].command.telemetry.mu_hat[1], 0.31);
  EXPECT_EQ(got[0].command.telemetry.stance_mask, 0xBu);
  EXPECT_EQ(got[0].status.bad_crc, 3u);
  EXPECT_EQ(got[0].status.clock_hz, 25000000u);
}

TEST(Wire, EveryCorruptedByteIsDetected) {
  const auto good = encode(makeSensor(5), 1);
  for (size_t i = 0; i < good.size(); ++i) {
    wire::Decoder d;
    auto bad = good;
    bad[i] ^= 0x10;
    EXPECT_TRUE(feed(d, bad).empty()) << "flipped byte " << i;
    const auto& c = d.counters();
    EXPECT_EQ(c.accepted, 0u);
    EXPECT_GE(c.bad_crc + c.bad_header + c.skipped_bytes, 1u) << "byte " << i << " not counted";
  }
}

TEST(Wire, TruncatedMessageCostsOnlyItself) {
  wire::Decoder d;
  auto first = encode(makeSensor(1), 1);
  first.resize(120);
  auto bytes = first;
  const auto second = encode(makeSensor(2), 2);
  bytes.insert(bytes.end(), second.begin(), second.end());
  const auto got = feed(d, bytes);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].sensor.tick, 2u);
  EXPECT_EQ(d.counters().bad_crc, 1u);
}

// A header that claims a long message (a forged or corrupted length) must
// not hold up the valid frames behind it: each is handed out at its own last
// byte, with a forged header before every third frame.
TEST(Wire, ForgedLengthsLoseNoValidFrame) {
  for (size_t claimed : {size_t{1}, size_t{200}, wire::kMaxConfigBytes}) {
    wire::Decoder d;
    std::vector<uint8_t> bytes;
    std::vector<size_t> frame_ends;
    uint32_t sequence = 1;
    for (uint32_t tick = 1; tick <= 30; ++tick) {
      if (tick % 3 == 0) {
        appendForgedHeader(bytes, static_cast<uint8_t>(wire::MessageType::kConfig), claimed);
      }
      const auto msg = encode(makeSensor(tick), sequence++);
      bytes.insert(bytes.end(), msg.begin(), msg.end());
      frame_ends.push_back(bytes.size());
    }
    wire::Message m{};
    std::vector<uint32_t> ticks;
    for (size_t i = 0; i < bytes.size(); ++i) {
      if (d.push(bytes[i], m)) {
        ticks.push_back(m.sensor.tick);
        EXPECT_EQ(i + 1, frame_ends[ticks.size() - 1]) << "claimed " << claimed << ", frame " << m.sensor.tick
                                                       << " not handed out at its last byte";
      }
    }
    ASSERT_EQ(ticks.size(), 30u) << "claimed " << claimed;
    for (uint32_t k = 0; k < 30; ++k) EXPECT_EQ(ticks[k], k + 1);
    EXPECT_EQ(d.counters().accepted, 30u);
  }
}

// Valid frames with up to three pieces of junk before each, in random order
// and amounts: forged headers of any type and length, the start of another
// message cut short, runs of sync pairs, random bytes. Every valid frame must
// come out, in order, at its own last byte.
TEST(Wire, EveryValidFrameSurvivesRandomJunkBeforeIt) {
  std::mt19937 rng(7);
  auto pick = [&rng](uint32_t n) { return static_cast<uint32_t>(rng() % n); };
  auto addJunk = [&](std::vector<uint8_t>& bytes, uint32_t tick) {
    const uint32_t kind = pick(4);
    if (kind == 0) {  // a forged header of a valid type and length
      const uint8_t type = static_cast<uint8_t>(1 + pick(4));
      const size_t length = type == 1   ? wire::kSensorPayloadBytes
                            : type == 2 ? wire::kCommandPayloadBytes
                            : type == 3 ? wire::kHelloPayloadBytes
                                        : 1 + pick(wire::kMaxConfigBytes);
      appendForgedHeader(bytes, type, length);
    } else if (kind == 1) {  // another message cut short
      const auto cut = encode(makeSensor(1000 + tick), 50000 + tick);
      bytes.insert(bytes.end(), cut.begin(), cut.begin() + 1 + pick(static_cast<uint32_t>(cut.size() - 1)));
    } else if (kind == 2) {  // a run of sync pairs
      for (uint32_t k = 0, n = 1 + pick(24); k < n; ++k) {
        bytes.push_back(wire::kSync0);
        bytes.push_back(wire::kSync1);
      }
    } else {  // noise
      for (uint32_t k = 0, n = 1 + pick(40); k < n; ++k) bytes.push_back(static_cast<uint8_t>(rng()));
    }
  };
  std::vector<uint32_t> all(12);
  for (uint32_t k = 0; k < 12; ++k) all[k] = k + 1;
  for (int stream = 0; stream < 400; ++stream) {
    std::vector<uint8_t> bytes;
    std::vector<size_t> ends;
    for (uint32_t tick = 1; tick <= 12; ++tick) {
      for (uint32_t piece = 0, pieces = pick(4); piece < pieces; ++piece) addJunk(bytes, tick);
      const auto msg = encode(makeSensor(tick), tick);
      bytes.insert(bytes.end(), msg.begin(), msg.end());
      ends.push_back(bytes.size());
    }
    wire::Decoder d;
    wire::Message m{};
    std::vector<uint32_t> ticks;
    bool on_time = true;
    for (size_t i = 0; i < bytes.size(); ++i)
      if (d.push(bytes[i], m) && m.type == wire::MessageType::kSensor && m.sensor.tick < 1000) {
        ticks.push_back(m.sensor.tick);
        on_time = on_time && ticks.size() <= ends.size() && i + 1 == ends[ticks.size() - 1];
      }
    EXPECT_EQ(ticks, all) << "stream " << stream;
    EXPECT_TRUE(on_time) << "stream " << stream;
  }
}

// The decoder's promise after any burst up to its buffer size: the first
// valid message behind the burst comes out when its own last byte arrives,
// the next one too, and nothing from the burst ever comes out. Bursts of
// every length from 0 to kMaxMessageBytes [bytes], of noise, of forged
// headers (the same one repeated, or mixed types and lengths), and of a
// forged header before a message cut short. The first valid message is in
// turn a sensor frame, a command, the largest configuration, and the largest
// configuration whose body is a flood of forged headers.
TEST(Wire, ResynchronisesAtTheFirstValidMessageAfterAnyBurst) {
  std::mt19937 rng(11);
  auto pick = [&rng](uint32_t n) { return static_cast<uint32_t>(rng() % n); };
  const auto config = [](uint32_t sequence, bool forged_body) {
    std::vector<uint8_t> body;
    if (forged_body) {
      while (body.size() < wire::kMaxConfigBytes)
        appendForgedHeader(body, static_cast<uint8_t>(wire::MessageType::kConfig), wire::kMaxConfigBytes);
      body.resize(wire::kMaxConfigBytes);
    } else {
      for (size_t k = 0; k < wire::kMaxConfigBytes; ++k) body.push_back(static_cast<uint8_t>(7 * k + 3));
    }
    std::vector<uint8_t> out(wire::kMaxMessageBytes);
    out.resize(wire::encodeConfig(body.data(), body.size(), sequence, out.data(), out.size()));
    return out;
  };
  const auto cut = config(900, false);  // never sent whole
  const auto forgedHeaders = [&](std::vector<uint8_t>& bytes, size_t n, bool mixed) {
    while (bytes.size() < n) {
      if (!mixed) {
        appendForgedHeader(bytes, static_cast<uint8_t>(wire::MessageType::kConfig), wire::kMaxConfigBytes);
        continue;
      }
      const uint8_t type = static_cast<uint8_t>(1 + pick(4));
      const size_t length = type == 1   ? wire::kSensorPayloadBytes
                            : type == 2 ? wire::kCommandPayloadBytes
                            : type == 3 ? wire::kHelloPayloadBytes
                                        : 1 + pick(wire::kMaxConfigBytes);
      appendForgedHeader(bytes, type, length);
    }
  };
  const char* const kinds[] = {"noise", "header-like noise", "forged headers", "mixed forged headers",
                               "a forged header before a message cut short"};
  for (int kind = 0; kind < 5; ++kind) {
    std::vector<size_t> failed;
    for (size_t burst = 0; burst <= wire::kMaxMessageBytes; ++burst) {
      std::vector<uint8_t> bytes;
      if (kind == 0) {
        while (bytes.size() < burst) bytes.push_back(static_cast<uint8_t>(rng()));
      } else if (kind == 1) {  // sync pairs, header bytes and the start of headers among random bytes
        const uint8_t alphabet[] = {wire::kSync0, wire::kSync1, wire::kVersion, 1, 2, 3, 4, 0x74, 0x01, 0x00};
        while (bytes.size() < burst)
          bytes.push_back(pick(3) == 0 ? static_cast<uint8_t>(rng()) : alphabet[pick(10)]);
      } else if (kind == 2 || kind == 3) {
        forgedHeaders(bytes, burst, kind == 3);
      } else {
        appendForgedHeader(bytes, static_cast<uint8_t>(wire::MessageType::kConfig), wire::kMaxConfigBytes);
        if (burst > wire::kHeaderBytes)
          bytes.insert(bytes.end(), cut.begin(), cut.begin() + (burst - wire::kHeaderBytes));
      }
      bytes.resize(burst);
      std::vector<uint8_t> first;
      switch (burst % 4) {
        case 0: first = encode(makeSensor(1), 1); break;
        case 1:
          first.resize(wire::kMaxMessageBytes);
          first.resize(wire::encodeCommand(makeCommand(1), wire::BoardStatus{}, 1, first.data(), first.size()));
          break;
        case 2: first = config(1, false); break;
        default: first = config(1, true); break;
      }
      bytes.insert(bytes.end(), first.begin(), first.end());
      const size_t first_end = bytes.size();
      const auto second = encode(makeSensor(2), 2);
      bytes.insert(bytes.end(), second.begin(), second.end());
      wire::Decoder d;
      wire::Message m{};
      std::vector<size_t> out_ends;
      std::vector<uint32_t> out_sequences;
      for (size_t i = 0; i < bytes.size(); ++i)
        if (d.push(bytes[i], m)) {
          out_ends.push_back(i + 1);
          out_sequences.push_back(m.sequence);
        }
      const bool on_time = out_ends == std::vector<size_t>{first_end, bytes.size()} &&
                           out_sequences == std::vector<uint32_t>{1u, 2u};
      if (!on_time) failed.push_back(burst);
    }
    std::string lengths;
    for (size_t k = 0; k < failed.size() && k < 12; ++k) lengths += " " + std::to_string(failed[k]);
    EXPECT_TRUE(failed.empty()) << "bursts of " << kinds[kind] << ": " << failed.size() << " of "
                                << wire::kMaxMessageBytes + 1 << " lengths lose a valid message, e.g. [bytes]"
                                << lengths;
  }
}

// A message cut short and overrun by its successor: the successor comes out
// when it is complete, even when the cut one claimed more bytes than both.
TEST(Wire, ATruncatedLongMessageCostsOnlyItself) {
  wire::Decoder d;
  std::vector<uint8_t> config(wire::kMaxConfigBytes, 0x11);
  std::vector<uint8_t> bytes(wire::kMaxMessageBytes);
  bytes.resize(wire::encodeConfig(config.data(), config.size(), 1, bytes.data(), bytes.size()));
  bytes.resize(300);  // the rest never comes
  const auto next = encode(makeSensor(7), 2);
  bytes.insert(bytes.end(), next.begin(), next.end());
  const auto got = feed(d, bytes);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].sensor.tick, 7u);
  EXPECT_EQ(d.counters().overrun, 1u);
}

// A decoder that expects only the messages of its direction drops the others
// before their sequence number counts: a Hello cannot reopen old sequences.
TEST(Wire, UnexpectedTypesAreDroppedBeforeTheSequenceCheck) {
  wire::Decoder d;
  d.expect(wire::MessageType::kSensor, wire::MessageType::kConfig);
  auto bytes = encode(makeSensor(1), 50);
  std::vector<uint8_t> hello(wire::kMaxMessageBytes);
  hello.resize(wire::encodeHello(wire::Hello{}, 51, hello.data(), hello.size()));
  bytes.insert(bytes.end(), hello.begin(), hello.end());
  const auto replay = encode(makeSensor(2), 10);
  bytes.insert(bytes.end(), replay.begin(), replay.end());
  const auto got = feed(d, bytes);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].sensor.tick, 1u);
  EXPECT_EQ(d.counters().bad_header, 1u);
  EXPECT_EQ(d.counters().out_of_order, 1u);
  EXPECT_EQ(d.counters().peer_restarts, 0u);
}

TEST(Wire, NoiseBetweenMessagesIsSkippedAndCounted) {
  wire::Decoder d;
  std::vector<uint8_t> bytes = {0x00, 0xA5, 0x13, 0xFF, 0x5A};
  const auto msg = encode(makeSensor(3), 1);
  bytes.insert(bytes.end(), msg.begin(), msg.end());
  const auto got = feed(d, bytes);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(d.counters().skipped_bytes, 5u);
}

TEST(Wire, WrongVersionTypeOrLengthIsABadHeader) {
  for (int field : {2, 3, 4}) {
    wire::Decoder d;
    auto bytes = encode(makeSensor(3), 1);
    bytes[field] ^= 0x40;
    EXPECT_TRUE(feed(d, bytes).empty());
    EXPECT_EQ(d.counters().bad_header, 1u) << "header byte " << field;
  }
}

TEST(Wire, DuplicateAndLateMessagesAreDroppedGapsCounted) {
  wire::Decoder d;
  std::vector<uint8_t> bytes;
  for (uint32_t seq : {10u, 11u, 11u, 9u, 15u, 14u, 16u}) {
    const auto m = encode(makeSensor(seq), seq);
    bytes.insert(bytes.end(), m.begin(), m.end());
  }
  const auto got = feed(d, bytes);
  ASSERT_EQ(got.size(), 4u);
  EXPECT_EQ(got[0].sequence, 10u);
  EXPECT_EQ(got[1].sequence, 11u);
  EXPECT_EQ(got[2].sequence, 15u);
  EXPECT_EQ(got[3].sequence, 16u);
  EXPECT_EQ(d.counters().out_of_order, 3u);
  EXPECT_EQ(d.counters().sequence_gaps, 3u);
}

TEST(Wire, SequenceWrapsAndPeerRestartsAreAccepted) {
  wire::Decoder d;
  std::vector<uint8_t> bytes;
  for (uint32_t seq : {0xFFFFFFFEu, 0xFFFFFFFFu, 0u, 1u}) {
    const auto m = encode(makeSensor(seq), seq);
    bytes.insert(bytes.end(), m.begin(), m.end());
  }
  EXPECT_EQ(feed(d, bytes).size(), 4u);
  // Far behind: the sender restarted counting.
  EXPECT_EQ(feed(d, encode(makeSensor(1), 1)).size(), 0u) << "1 again is a duplicate";
  wire::Decoder e;
  feed(e, encode(makeSensor(1), 50000));
  EXPECT_EQ(feed(e, encode(makeSensor(1), 1)).size(), 1u);
  EXPECT_EQ(e.counters().peer_restarts, 1u);
}

TEST(Wire, HelloResetsTheSequenceHistory) {
  wire::Decoder d;
  std::vector<uint8_t> out(wire::kMaxMessageBytes);
  wire::Hello h{};
  h.fpu_result = 1.5;
  feed(d, encode(makeSensor(1), 500));
  out.resize(wire::encodeHello(h, 1, out.data(), out.size()));
  const auto got = feed(d, out);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].hello.fpu_result, 1.5);
  EXPECT_EQ(feed(d, encode(makeSensor(2), 2)).size(), 1u);
}

// The board's side: numbers from the announced one on, strictly newer each
// time; nothing behind is a restart, however far back, and a Hello does
// not reopen the count.
TEST(Wire, StrictNumberingRefusesEveryReplayHoweverOld) {
  wire::Decoder d;
  d.acceptFrom(100);
  EXPECT_EQ(d.nextSequence(), 100u);
  EXPECT_EQ(feed(d, encode(makeSensor(1), 99)).size(), 0u) << "below the announced number";
  EXPECT_EQ(feed(d, encode(makeSensor(1), 100)).size(), 1u);
  EXPECT_EQ(feed(d, encode(makeSensor(2), 5000)).size(), 1u) << "a gap is taken";
  EXPECT_EQ(d.nextSequence(), 5001u);
  for (uint32_t old : {4999u, 3000u, 101u, 100u, 1u, 0u, 5000u - 0x7FFFFFFFu})
    EXPECT_EQ(feed(d, encode(makeSensor(3), old)).size(), 0u) << "replay of " << old;
  std::vector<uint8_t> hello(wire::kMaxMessageBytes);
  hello.resize(wire::encodeHello(wire::Hello{}, 5001, hello.data(), hello.size()));
  feed(d, hello);
  EXPECT_EQ(feed(d, encode(makeSensor(4), 200)).size(), 0u) << "a Hello reopened the count";
  EXPECT_EQ(d.counters().out_of_order, 9u);
  EXPECT_EQ(d.counters().peer_restarts, 0u);
  EXPECT_EQ(feed(d, encode(makeSensor(5), 5002)).size(), 1u);
  // The same far replay in the default (host) mode is a sender restart.
  wire::Decoder host;
  feed(host, encode(makeSensor(1), 5000));
  EXPECT_EQ(feed(host, encode(makeSensor(3), 1)).size(), 1u);
}

TEST(Wire, FpuSelfTestIsDeterministicAndNotTrivial) {
  const double a = wire::fpuSelfTest(0.7853981633974483);
  EXPECT_EQ(a, wire::fpuSelfTest(0.7853981633974483));
  EXPECT_NE(a, wire::fpuSelfTest(0.7853981633974484)) << "one ulp of input must show";
  EXPECT_GT(a, 0.5);
  EXPECT_LT(a, 3.0);
}

// tests/fuzz/make_seeds.py writes messages with Python's struct and zlib:
// an encoder independent of hal/wire.cpp.
TEST(Wire, AgreesWithTheIndependentPythonEncoder) {
  const auto bytes = readSeed("stream");
  ASSERT_FALSE(bytes.empty());
  wire::Decoder d;
  const auto got = feed(d, bytes);
  ASSERT_EQ(got.size(), 4u);
  EXPECT_EQ(got[0].type, wire::MessageType::kHello);
  EXPECT_EQ(got[0].hello.clock_hz, 25000000u);
  EXPECT_EQ(got[1].sensor.imu_acc[2], 9.81);
  EXPECT_EQ(got[2].sensor.tick, 2u);
  EXPECT_EQ(got[3].type, wire::MessageType::kCommand);
  // The friction map's writes: two of them, a negative cell coordinate each.
  const hyq::hal::MapWrite* w = got[3].command.telemetry.map_writes;
  EXPECT_EQ(w[0].cell[0], -2);
  EXPECT_EQ(w[0].cell[1], 0);
  EXPECT_EQ(w[0].count, 3u);
  EXPECT_EQ(w[0].mu, 0.2);
  EXPECT_EQ(w[0].spread, 0.01);
  EXPECT_EQ(w[1].cell[0], 5);
  EXPECT_EQ(w[1].cell[1], -1);
  EXPECT_EQ(w[1].count, 1u);
  EXPECT_EQ(w[1].mu, 0.25);
  EXPECT_EQ(w[2].count, 0u);
  EXPECT_EQ(got[3].status.clock_hz, 14u);
  EXPECT_EQ(got[3].status.config_crc, 15u);
  EXPECT_EQ(d.counters().bad_crc + d.counters().bad_header, 0u);
}

// The burst seeds of the same encoder: forged headers (117, a buffer's
// worth, mixed types and lengths, or in the body of a valid configuration)
// and a message cut short, before valid messages. Only the valid messages
// come out, the last at the last byte.
TEST(Wire, PythonBurstSeedsLoseNoValidMessage) {
  struct Seed {
    const char* name;
    std::vector<uint32_t> sequences;
  };
  for (const Seed& seed : {Seed{"forged_burst", {1, 2}}, Seed{"forged_burst_full", {1, 2}},
                           Seed{"mixed_forged_burst", {1, 2}}, Seed{"forged_then_cut", {1}},
                           Seed{"forged_body", {1, 2}}}) {
    const auto bytes = readSeed(seed.name);
    ASSERT_FALSE(bytes.empty()) << seed.name;
    wire::Decoder d;
    wire::Message m{};
    std::vector<uint32_t> sequences;
    size_t last_end = 0;
    for (size_t i = 0; i < bytes.size(); ++i)
      if (d.push(bytes[i], m)) {
        sequences.push_back(m.sequence);
        last_end = i + 1;
      }
    EXPECT_EQ(sequences, seed.sequences) << seed.name;
    EXPECT_EQ(last_end, bytes.size()) << seed.name;
  }
}
