#include "tests/golden/golden.hpp"

#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <memory>
#include <sstream>

#include "firmware/controller/controller.hpp"
#include "sim_host/loop/run.hpp"
#include "sim_host/scenario/scenario.hpp"

namespace hyq::golden {
namespace {

constexpr char kMagic[8] = {'H', 'Y', 'Q', 'T', 'R', 'A', 'C', 'E'};
constexpr uint32_t kVersion = 1;
constexpr int kDoublesPerFrame = 3 * hal::kNumJoints + 4 + 3 + 3;  // q, qd, tau, quat, gyro, acc

// The doubles of a sensor frame in declaration order.
void forEachDouble(hal::SensorFrame& f, const std::function<void(double&)>& fn) {
  for (double& v : f.q) fn(v);
  for (double& v : f.qd) fn(v);
  for (double& v : f.tau) fn(v);
  for (double& v : f.imu_quat) fn(v);
  for (double& v : f.imu_gyro) fn(v);
  for (double& v : f.imu_acc) fn(v);
}

void putU32(std::string& out, uint32_t v) {
  for (int b = 0; b < 4; ++b) out.push_back(static_cast<char>((v >> (8 * b)) & 0xFF));
}
void putF64(std::string& out, double d) {
  uint64_t v;
  std::memcpy(&v, &d, sizeof v);
  for (int b = 0; b < 8; ++b) out.push_back(static_cast<char>((v >> (8 * b)) & 0xFF));
}
uint32_t getU32(const unsigned char* p) {
  return p[0] | (p[1] << 8) | (p[2] << 16) | (static_cast<uint32_t>(p[3]) << 24);
}
double getF64(const unsigned char* p) {
  uint64_t v = 0;
  for (int b = 7; b >= 0; --b) v = (v << 8) | p[b];
  double d;
  std::memcpy(&d, &v, sizeof d);
  return d;
}

uint64_t fnv1a(const double* v, int n) {
  uint64_t h = 14695981039346656037ull;
  for (int i = 0; i < n; ++i) {
    uint64_t bits;
    std::memcpy(&bits, &v[i], sizeof bits);
    for (int b = 0; b < 8; ++b) {
      h ^= (bits >> (8 * b)) & 0xFF;
      h *= 1099511628211ull;
    }
  }
  return h;
}

uint32_t fold(uint64_t h) { return static_cast<uint32_t>(h ^ (h >> 32)); }

// Each field of a command frame: its name, and where its doubles are (or its integer).
struct FieldView {
  const char* name;
  const double* values = nullptr;
  int count = 0;
  uint64_t integer = 0;
  bool hex = false;
};

std::vector<FieldView> views(const hal::CommandFrame& c) {
  const hal::Telemetry& t = c.telemetry;
  std::vector<FieldView> fields = {
      {"tick", nullptr, 0, c.tick},
      {"flags", nullptr, 0, c.flags, true},
      {"stance_mask", nullptr, 0, t.stance_mask, true},
      {"slip_mask", nullptr, 0, t.slip_mask, true},
      {"swing_leg", nullptr, 0, t.swing_leg},
      {"tau_ff", c.tau_ff, hal::kNumJoints},
      {"q_ref", c.q_ref, hal::kNumJoints},
      {"qd_ref", c.qd_ref, hal::kNumJoints},
      {"kp", c.kp, hal::kNumJoints},
      {"kd", c.kd, hal::kNumJoints},
      {"gait_phase", &t.gait_phase, 1},
      {"base_pos_est", t.base_pos_est, 3},
      {"base_vel_est", t.base_vel_est, 3},
      {"foot_vel_base", &t.foot_vel_base[0][0], 3 * hal::kNumLegs},
      {"grf_est", &t.grf_est[0][0], 3 * hal::kNumLegs},
      {"grf_des", &t.grf_des[0][0], 3 * hal::kNumLegs},
      {"mu_used", t.mu_used, hal::kNumLegs},
      {"normal_used", &t.normal_used[0][0], 3 * hal::kNumLegs},
      {"mu_hat", t.mu_hat, hal::kNumLegs},
      {"normal_hat", &t.normal_hat[0][0], 3 * hal::kNumLegs},
      {"probe_leg", nullptr, 0, t.probe_leg},
      {"probe_partner", nullptr, 0, t.probe_partner},
      {"probes_started", nullptr, 0, t.probe_counts[0]},
      {"probes_found", nullptr, 0, t.probe_counts[1]},
      {"probes_held", nullptr, 0, t.probe_counts[2]},
  };
  // Each foot's write into the friction map: its cell (as unsigned), count, mean and spread.
  static const char* const kNames[hal::kNumLegs][5] = {
      {"map_ix_LF", "map_iy_LF", "map_count_LF", "map_mu_LF", "map_spread_LF"},
      {"map_ix_RF", "map_iy_RF", "map_count_RF", "map_mu_RF", "map_spread_RF"},
      {"map_ix_LH", "map_iy_LH", "map_count_LH", "map_mu_LH", "map_spread_LH"},
      {"map_ix_RH", "map_iy_RH", "map_count_RH", "map_mu_RH", "map_spread_RH"}};
  for (int leg = 0; leg < hal::kNumLegs; ++leg) {
    const hal::MapWrite& w = t.map_writes[leg];
    fields.push_back({kNames[leg][0], nullptr, 0, static_cast<uint32_t>(w.cell[0])});
    fields.push_back({kNames[leg][1], nullptr, 0, static_cast<uint32_t>(w.cell[1])});
    fields.push_back({kNames[leg][2], nullptr, 0, w.count});
    fields.push_back({kNames[leg][3], &w.mu, 1});
    fields.push_back({kNames[leg][4], &w.spread, 1});
  }
  return fields;
}

std::vector<std::string> splitCsv(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  std::string cell;
  while (std::getline(in, cell, ',')) out.push_back(cell);
  return out;
}

}  // namespace

const std::vector<Case>& cases() {
  // The crawl's stance slip is stopped by the correction about 30 ms after
  // it is flagged; a freeze_after of 20 ms makes the same slip freeze the
  // robot, so that the trace has a freeze, its exit and the hand-back blend.
  static const std::vector<Case> all = {
      {"crawl", 5200, 3300, 3700, 3, 0.02},
      {"trot", 4500, 2600, 3100, 3, 0.0},
      {"switch", 6000, 1200, 4200, 3, 0.0},
  };
  return all;
}

const Case* findCase(const std::string& name) {
  for (const Case& c : cases())
    if (name == c.name) return &c;
  return nullptr;
}

std::string caseDir(const Case& c) { return std::string(HYQ_SOURCE_DIR) + "/tests/golden/" + c.name + "/"; }

std::string scenarioPath(const Case& c) { return caseDir(c) + "scenario.yaml"; }

Params goldenParams(const Case& c) {
  Params p = sim::loadScenario(scenarioPath(c)).controller_params;
  if (c.freeze_after > 0.0) p.recovery.freeze_after = c.freeze_after;
  return p;
}

std::vector<hal::SensorFrame> recordTrace(const Case& c) {
  sim::Scenario scenario = sim::loadScenario(scenarioPath(c));
  scenario.controller_params = goldenParams(c);
  sim::FrameFaults faults;
  const int gap = c.gap_index, dropped = c.dropped_frames, bad = c.bad_frame_index;
  faults.dropped_before = [gap, dropped](int k) { return k == gap ? dropped : 0; };
  faults.corrupt = [bad](int k, hal::SensorFrame& frame) {
    if (k == bad) frame.tau[4] = std::nan("");
  };
  return sim::recordSensorFrames(scenario, c.ticks, faults);
}

bool writeTrace(const std::string& path, const std::vector<hal::SensorFrame>& frames, std::string& error) {
  std::string bytes(kMagic, sizeof kMagic);
  putU32(bytes, kVersion);
  putU32(bytes, static_cast<uint32_t>(frames.size()));
  for (hal::SensorFrame f : frames) {
    putU32(bytes, f.tick);
    forEachDouble(f, [&](double& v) { putF64(bytes, v); });
  }
  const std::string tmp = path + ".tmp";
  std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out || std::rename(tmp.c_str(), path.c_str()) != 0) {
    error = path + ": cannot write";
    return false;
  }
  return true;
}

std::vector<hal::SensorFrame> readTrace(const std::string& path, std::string& error) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    error = path + ": cannot open";
    return {};
  }
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto* p = reinterpret_cast<const unsigned char*>(bytes.data());
  const size_t frame_bytes = 4 + 8 * kDoublesPerFrame;
  if (bytes.size() < 16 || std::memcmp(p, kMagic, 8) != 0 || getU32(p + 8) != kVersion) {
    error = path + ": not a version-1 HYQTRACE file";
    return {};
  }
  const uint32_t count = getU32(p + 12);
  if (bytes.size() != 16 + count * frame_bytes) {
    error = path + ": size does not match its frame count";
    return {};
  }
  std::vector<hal::SensorFrame> frames(count);
  const unsigned char* at = p + 16;
  for (hal::SensorFrame& f : frames) {
    f.tick = getU32(at);
    at += 4;
    forEachDouble(f, [&](double& v) {
      v = getF64(at);
      at += 8;
    });
  }
  return frames;
}

std::vector<hal::CommandFrame> replay(const std::vector<hal::SensorFrame>& trace, const Params& params) {
  auto controller = std::make_unique<Controller>();
  controller->init(params);
  std::vector<hal::CommandFrame> commands(trace.size());
  for (size_t k = 0; k < trace.size(); ++k) controller->step(trace[k], commands[k]);
  return commands;
}

std::vector<Field> digest(const hal::CommandFrame& command) {
  std::vector<Field> out;
  char text[32];
  for (const FieldView& v : views(command)) {
    if (v.values)
      std::snprintf(text, sizeof text, "%08" PRIx32, fold(fnv1a(v.values, v.count)));
    else
      std::snprintf(text, sizeof text, v.hex ? "0x%" PRIx64 : "%" PRIu64, v.integer);
    out.push_back({v.name, text});
  }
  return out;
}

std::string header() {
  std::string h;
  for (const Field& f : digest(hal::CommandFrame{})) h += (h.empty() ? "" : ",") + std::string(f.name);
  return h;
}

std::string line(const hal::CommandFrame& command) {
  std::string s;
  for (const Field& f : digest(command)) s += (s.empty() ? "" : ",") + f.text;
  return s;
}

std::string describe(const hal::CommandFrame& command, const std::string& field) {
  for (const FieldView& v : views(command)) {
    if (field != v.name) continue;
    if (!v.values) return field + " = " + std::to_string(v.integer);
    std::string s = field + " =";
    char text[64];
    for (int i = 0; i < v.count; ++i) {
      std::snprintf(text, sizeof text, " %a (%.17g)", v.values[i], v.values[i]);
      s += text;
    }
    return s;
  }
  return field + ": no such field";
}

bool writeReference(const std::string& path, const std::vector<hal::CommandFrame>& commands, std::string& error) {
  const std::string tmp = path + ".tmp";
  std::ofstream out(tmp, std::ios::trunc);
  out << header() << '\n';
  for (const hal::CommandFrame& c : commands) out << line(c) << '\n';
  out.close();
  if (!out || std::rename(tmp.c_str(), path.c_str()) != 0) {
    error = path + ": cannot write";
    return false;
  }
  return true;
}

std::string compare(const std::string& reference_path, const std::vector<hal::CommandFrame>& commands) {
  std::ifstream in(reference_path);
  if (!in) return reference_path + ": cannot open";
  std::string row;
  std::getline(in, row);
  if (row != header())
    return reference_path + ": its fields are\n  " + row + "\nthe controller's are\n  " + header() +
           "\n(a command or telemetry field was added or removed: regenerate with `make golden`)";
  const std::vector<std::string> names = splitCsv(row);
  size_t k = 0;
  for (; k < commands.size() && std::getline(in, row); ++k) {
    const std::vector<std::string> expected = splitCsv(row);
    const std::vector<Field> actual = digest(commands[k]);
    for (size_t f = 0; f < actual.size(); ++f) {
      if (f < expected.size() && expected[f] == actual[f].text) continue;
      std::ostringstream msg;
      msg << "replay differs from " << reference_path << " first at frame " << k << " (tick "
          << commands[k].tick << "), field " << actual[f].name << ": reference "
          << (f < expected.size() ? expected[f] : "<missing>") << ", now " << actual[f].text << "\n  "
          << describe(commands[k], actual[f].name);
      return msg.str();
    }
  }
  if (k < commands.size())
    return reference_path + ": has " + std::to_string(k) + " rows, the replay " + std::to_string(commands.size());
  if (std::getline(in, row) && !row.empty())
    return reference_path + ": has more rows than the replay's " + std::to_string(commands.size());
  return "";
}

}  // namespace hyq::golden
