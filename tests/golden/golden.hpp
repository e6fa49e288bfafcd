// Golden replay: a stored sensor-frame trace, replayed open loop through the
// controller, and a stored reference of what the controller answered, one
// line per tick. Any change in any command or telemetry field shows as the
// first tick and field whose value differs from the reference.
//
// The reference holds the integer fields as they are and a 32-bit hash
// (FNV-1a, folded) of each floating-point field's bit patterns, so that a one-bit change
// of any value is seen while the file stays small.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "firmware/controller/params.hpp"
#include "hal/frames.hpp"

namespace hyq::golden {

// The scenario the trace was recorded from (tests/golden/scenario.yaml) and
// the controller parameters it is replayed with.
std::string scenarioPath();
Params goldenParams();

// Closed loop, the simulator and the host controller with goldenParams():
// `ticks` frames, with one corrupt frame (a NaN joint torque) at
// kBadFrameIndex and kDroppedFrames frames lost before kGapIndex (the
// simulator runs on with the last command; the tick counter jumps).
constexpr int kTraceTicks = 5200;
constexpr int kBadFrameIndex = 3300;
constexpr int kGapIndex = 3700;
constexpr int kDroppedFrames = 3;
std::vector<hal::SensorFrame> recordTrace();

// The trace file: "HYQTRACE", a version, the frame count, then per frame the
// tick (u32) and the 46 doubles of SensorFrame in declaration order, little
// endian. Empty vector and a message in `error` on failure.
bool writeTrace(const std::string& path, const std::vector<hal::SensorFrame>& frames, std::string& error);
std::vector<hal::SensorFrame> readTrace(const std::string& path, std::string& error);

// Replays `trace` through a controller initialised with `params`.
std::vector<hal::CommandFrame> replay(const std::vector<hal::SensorFrame>& trace, const Params& params);

// One digest per command frame: a named field and its text.
struct Field {
  const char* name;
  std::string text;
};
std::vector<Field> digest(const hal::CommandFrame& command);
std::string header();                       // the CSV header: the field names
std::string line(const hal::CommandFrame& command);  // one CSV row
// Every value of one field of `command`, exactly (%a) and readably (%.17g).
std::string describe(const hal::CommandFrame& command, const std::string& field);

bool writeReference(const std::string& path, const std::vector<hal::CommandFrame>& commands, std::string& error);

// Compares `commands` with the reference file's rows. Returns "" when equal,
// else one message naming the first differing tick and field (or what is
// missing), with the field's current values.
std::string compare(const std::string& reference_path, const std::vector<hal::CommandFrame>& commands);

}  // namespace hyq::golden
