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

// One golden replay: a folder of tests/golden/ holding its scenario
// (scenario.yaml), its recorded sensor frames (trace.bin) and the
// controller's answers to them (reference.csv). Each trace has one corrupt
// frame (a NaN joint torque) at `bad_frame_index` and `dropped_frames`
// frames lost before `gap_index` (the simulator runs on with the last
// command; the tick counter jumps).
struct Case {
  const char* name;        // its folder: crawl, trot, switch
  int ticks;               // [ticks] frames recorded
  int bad_frame_index;     // [-] the corrupt frame
  int gap_index;           // [-] the first frame after the gap
  int dropped_frames;      // [-] frames lost before it
  double freeze_after;     // [s] RecoveryParams::freeze_after for the replay; <= 0: the scenario's
};
// Every golden replay: the crawl's (stance_slip's start, a freeze), the
// trot's and the crawl-to-trot switch's.
const std::vector<Case>& cases();
// The case of that name; nullptr when there is none.
const Case* findCase(const std::string& name);

std::string caseDir(const Case& c);  // tests/golden/<name>/, absolute
std::string scenarioPath(const Case& c);
// The scenario's controller parameters, with the case's freeze_after.
Params goldenParams(const Case& c);

// Closed loop, the simulator and the host controller with goldenParams():
// the case's frames with its corrupt frame and its gap.
std::vector<hal::SensorFrame> recordTrace(const Case& c);

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
