#include "sim_host/records/replay.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include "firmware/controller/model/kinematics.hpp"
#include "firmware/controller/model/robot_params.hpp"
#include "sim_host/physics/terrain.hpp"
#include "sim_host/records/friction_map_record.hpp"

#ifndef HYQ_REPLAY_TEMPLATE
#define HYQ_REPLAY_TEMPLATE "build/host/web/replay_template.html"
#endif

namespace hyq::sim {
namespace {

// How far the drawn ground reaches beyond the robot's path [m].
constexpr double kGroundMargin = 4.0;

// v rounded to `decimals` places, trailing zeros dropped ("1.5", "-0.02",
// "3"); null when not finite.
void fixed(std::string& out, double v, int decimals) {
  if (!std::isfinite(v)) {
    out += "null";
    return;
  }
  char b[48];
  int n = std::snprintf(b, sizeof b, "%.*f", decimals, v);
  if (n <= 0 || n >= static_cast<int>(sizeof b)) {
    out += "null";
    return;
  }
  if (decimals > 0) {
    while (b[n - 1] == '0') --n;
    if (b[n - 1] == '.') --n;
  }
  if (n == 2 && b[0] == '-' && b[1] == '0') {  // "-0"
    out += '0';
    return;
  }
  out.append(b, n);
}

template <typename T>
void list(std::string& out, const T* v, int n, int decimals) {
  out += '[';
  for (int i = 0; i < n; ++i) {
    if (i) out += ',';
    fixed(out, v[i], decimals);
  }
  out += ']';
}

void key(std::string& out, const char* name) {
  if (out.back() != '{') out += ',';
  out += '"';
  out += name;
  out += "\":";
}

// A JSON string that cannot end the page's <script> element early.
std::string scriptSafe(const std::string& json) {
  std::string out;
  for (char c : json) {
    if (c == '<')
      out += "\\u003c";
    else
      out += c;
  }
  return out;
}

// Appends [t0, t1] or, for a leg, [t0, t1, leg] to a list's items.
void interval(std::string& out, double t0, double t1, int leg) {
  if (out.size() > kReplayMaxIntervalBytes) return;
  if (!out.empty()) out += ',';
  out += '[';
  fixed(out, t0, 3);
  out += ',';
  fixed(out, t1, 3);
  if (leg >= 0) out += ',' + std::to_string(leg);
  out += ']';
}

std::string unableToRead(const std::string& path, const std::string& why) {
  return "--replay: " + clipForMessage(path, 200) + ": " + why +
         " (build the page template with 'make web')";
}

}  // namespace

std::string defaultReplayTemplatePath() { return HYQ_REPLAY_TEMPLATE; }

std::string readReplayTemplate(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ScenarioError(unableToRead(path, "no page template there"));
  std::ostringstream text;
  text << in.rdbuf();
  if (!in.good() && !in.eof()) throw ScenarioError(unableToRead(path, "cannot read it"));
  std::string s = text.str();
  if (s.find(kReplayDataMarker) == std::string::npos)
    throw ScenarioError(unableToRead(path, std::string("not a page template (no ") +
                                               kReplayDataMarker + ")"));
  return s;
}

ReplayLog::ReplayLog(const std::string& path, std::string page_template, const Scenario& scenario)
    : file_(path), template_(std::move(page_template)), scenario_(scenario) {
  const double ticks = scenario.duration * hal::kTicksPerSecond;
  every_ = std::max(kReplayEveryTicks,
                    static_cast<int>(std::ceil(ticks / kReplayMaxPeriodicFrames)));
}

ReplayLog::Masks ReplayLog::masksOf(const TickRecord& r) {
  Masks m;
  for (int leg = 0; leg < 4; ++leg) {
    const FootTruth& f = r.feet[leg];
    const uint32_t bit = 1u << leg;
    if (f.in_contact) m.contact |= bit;
    // The true slip of events.csv.
    if (f.in_contact && f.slip_speed > kTrueSlipSpeed) m.true_slip |= bit;
  }
  m.stance = r.command.telemetry.stance_mask & 0xFu;
  m.slip_flag = r.command.telemetry.slip_mask & 0xFu;
  m.freeze = (r.command.flags & hal::kFlagFreeze) != 0;
  return m;
}

void ReplayLog::intervals(std::string& out, std::array<double, 4>& start, uint32_t before,
                          uint32_t now, double t) {
  for (int leg = 0; leg < 4; ++leg) {
    const uint32_t bit = 1u << leg;
    if ((now & bit) && !(before & bit)) start[leg] = t;
    if (!(now & bit) && (before & bit)) interval(out, start[leg], t, leg);
  }
}

void ReplayLog::onTick(const TickRecord& r) {
  const Masks m = masksOf(r);
  const Masks before = any_ ? last_masks_ : Masks{};
  intervals(slips_json_, slip_start_, before.true_slip, m.true_slip, r.time);
  intervals(flags_json_, flag_start_, before.slip_flag, m.slip_flag, r.time);
  if (m.freeze && !before.freeze) freeze_start_ = r.time;
  if (!m.freeze && before.freeze) interval(freezes_json_, freeze_start_, r.time, -1);

  if (!any_) {
    x_min_ = x_max_ = r.base_pos[0];
    y_min_ = y_max_ = r.base_pos[1];
    map_origin_ = controllerOrigin(r);
  }
  mapWrites(r);
  x_min_ = std::min(x_min_, r.base_pos[0]), x_max_ = std::max(x_max_, r.base_pos[0]);
  y_min_ = std::min(y_min_, r.base_pos[1]), y_max_ = std::max(y_max_, r.base_pos[1]);

  // Periodic frames on the ticks that are multiples of every_ (or the first
  // after one, if ticks were skipped).
  const uint32_t every = static_cast<uint32_t>(every_);
  const bool periodic = !any_ || r.tick / every != last_kept_tick_ / every;
  const bool change = m != last_masks_ && change_frames_ < kReplayMaxChangeFrames;
  last_kept_ = periodic || change;
  if (last_kept_) {
    change_frames_ += !periodic;
    addFrame(r, m);
  }
  last_ = r;
  last_masks_ = m;
  any_ = true;
}

void ReplayLog::mapWrites(const TickRecord& r) {
  const hal::Telemetry& t = r.command.telemetry;
  const double size = scenario_.controller_params.recovery.map.cell_size;
  for (int leg = 0; leg < 4; ++leg) {
    const hal::MapWrite& w = t.map_writes[leg];
    if (w.count == 0 || map_json_.size() > kReplayMaxIntervalBytes) continue;
    const std::array<double, 2> centre = cellCentre(map_origin_, w.cell[0], w.cell[1], size);
    const double v[5] = {r.time, centre[0], centre[1], w.mu, static_cast<double>(w.count)};
    if (!map_json_.empty()) map_json_ += ',';
    list(map_json_, v, 5, 4);
  }
}

std::string ReplayLog::mapJson() const {
  const RecoveryParams& recovery = scenario_.controller_params.recovery;
  if (!recovery.enabled || !recovery.map.enabled) return "null";
  std::string o = "{\"cell\":";
  fixed(o, recovery.map.cell_size, 4);
  o += ",\"max_age\":";
  fixed(o, recovery.map.max_age, 3);
  o += ",\"writes\":[" + map_json_ + "]}";
  return o;
}

void ReplayLog::addFrame(const TickRecord& r, const Masks& m) {
  std::string& o = frames_json_;
  o += frames_ ? ",{" : "{";
  key(o, "t");
  fixed(o, r.time, 3);
  // Base pose (truth), and each leg's HAA, HFE, KFE and foot centre in W:
  // the controller's kinematics on the measured joint angles.
  key(o, "b");
  const double pose[7] = {r.base_pos[0],  r.base_pos[1],  r.base_pos[2], r.base_quat[0],
                          r.base_quat[1], r.base_quat[2], r.base_quat[3]};
  o += '[';
  for (int i = 0; i < 7; ++i) {
    if (i) o += ',';
    fixed(o, pose[i], i < 3 ? 3 : 4);
  }
  o += ']';
  const Quat q_wb(r.base_quat[0], r.base_quat[1], r.base_quat[2], r.base_quat[3]);
  const Mat3 rot = q_wb.normalized().toRotationMatrix();
  const Vec3 base(r.base_pos[0], r.base_pos[1], r.base_pos[2]);
  double points[4][4][3];
  for (int leg = 0; leg < 4; ++leg) {
    const Vec3 q_leg(r.sensors.q[3 * leg], r.sensors.q[3 * leg + 1], r.sensors.q[3 * leg + 2]);
    const Vec3 in_base[4] = {Vec3(robot::kHaaPos[leg][0], robot::kHaaPos[leg][1], robot::kHaaPos[leg][2]),
                             hfePositionBase(leg, q_leg), kfePositionBase(leg, q_leg),
                             footPositionBase(leg, q_leg)};
    for (int p = 0; p < 4; ++p) {
      const Vec3 w = base + rot * in_base[p];
      for (int i = 0; i < 3; ++i) points[leg][p][i] = w[i];
    }
  }
  key(o, "p");
  list(o, &points[0][0][0], 48, 3);
  key(o, "c");
  o += std::to_string(m.contact);
  key(o, "s");
  o += std::to_string(m.stance);
  key(o, "sf");
  o += std::to_string(m.slip_flag);
  key(o, "ts");
  o += std::to_string(m.true_slip);
  key(o, "fz");
  o += m.freeze ? '1' : '0';
  // Per foot: the true contact force, the QP's force and cone (mu_used,
  // normal_used), the true cone (mu and normal under the foot).
  double force[12], true_mu[4], true_normal[12];
  for (int leg = 0; leg < 4; ++leg) {
    true_mu[leg] = r.feet[leg].mu;
    for (int i = 0; i < 3; ++i) {
      force[3 * leg + i] = r.feet[leg].force[i];
      true_normal[3 * leg + i] = r.feet[leg].normal[i];
    }
  }
  const hal::Telemetry& tel = r.command.telemetry;
  key(o, "f");
  list(o, force, 12, 0);
  key(o, "g");
  list(o, &tel.grf_des[0][0], 12, 0);
  key(o, "mu");
  list(o, tel.mu_used, 4, 3);
  key(o, "n");
  list(o, &tel.normal_used[0][0], 12, 3);
  key(o, "tmu");
  list(o, true_mu, 4, 3);
  key(o, "tn");
  list(o, true_normal, 12, 3);
  o += '}';
  last_kept_tick_ = r.tick;
  ++frames_;
}

void ReplayLog::onFinish() {
  if (!file_.isOpen()) return;
  if (any_) {
    if (!last_kept_) addFrame(last_, last_masks_);  // the run's last tick
    // Intervals still open end with the run.
    intervals(slips_json_, slip_start_, last_masks_.true_slip, 0, last_.time);
    intervals(flags_json_, flag_start_, last_masks_.slip_flag, 0, last_.time);
    if (last_masks_.freeze) interval(freezes_json_, freeze_start_, last_.time, -1);
  }

  std::string h = "{";
  key(h, "scenario");
  h += jsonString(scenario_.name);
  key(h, "seed");
  h += std::to_string(scenario_.seed);
  key(h, "recovery");
  h += scenario_.controller_params.recovery.enabled ? "true" : "false";
  key(h, "controller");
  h += jsonString(scenario_.controller_kind);
  key(h, "engine");
  h += jsonString(engineName(scenario_.physics.engine));
  key(h, "duration");
  fixed(h, scenario_.duration, 3);
  key(h, "frame_ticks");
  h += std::to_string(every_);
  key(h, "true_slip_speed");
  fixed(h, kTrueSlipSpeed, 3);
  key(h, "legs");
  h += "[\"LF\",\"RF\",\"LH\",\"RH\"]";
  key(h, "trunk_size");
  list(h, robot::kTrunkSize, 3, 3);
  key(h, "foot_radius");
  fixed(h, robot::kFootRadius, 4);

  // The ground around the robot's path: the profile's straight pieces
  // ([x0, x1, z0, z1]) and the friction patches ([x0, x1, y0, y1, mu]),
  // cut to that box.
  const double bx0 = x_min_ - kGroundMargin, bx1 = x_max_ + kGroundMargin;
  const double by0 = y_min_ - kGroundMargin, by1 = y_max_ + kGroundMargin;
  const Terrain terrain(scenario_.terrain);
  key(h, "ground");
  h += '{';
  key(h, "mu");
  fixed(h, scenario_.terrain.mu, 3);
  key(h, "box");
  const double box[4] = {bx0, bx1, by0, by1};
  list(h, box, 4, 3);
  key(h, "pieces");
  h += '[';
  bool first = true;
  for (const Terrain::Piece& p : terrain.pieces()) {
    const double x0 = std::max(p.x_begin, bx0), x1 = std::min(p.x_end, bx1);
    if (!(x0 < x1)) continue;
    const double v[4] = {x0, x1, terrain.height(x0), terrain.height(x1)};
    if (!first) h += ',';
    list(h, v, 4, 4);
    first = false;
  }
  h += ']';
  key(h, "patches");
  h += '[';
  first = true;
  for (const FrictionPatch& p : scenario_.terrain.patches) {
    const double x0 = std::max(p.x0, bx0), x1 = std::min(p.x1, bx1);
    const double y0 = std::max(p.y0, by0), y1 = std::min(p.y1, by1);
    if (!(x0 < x1) || !(y0 < y1)) continue;
    const double v[5] = {x0, x1, y0, y1, p.mu};
    if (!first) h += ',';
    list(h, v, 5, 3);
    first = false;
  }
  h += "]}";
  key(h, "slips");
  h += '[' + slips_json_ + ']';
  key(h, "slip_flags");
  h += '[' + flags_json_ + ']';
  key(h, "freezes");
  h += '[' + freezes_json_ + ']';
  key(h, "map");
  h += mapJson();
  key(h, "frames");
  h += '[';

  const size_t at = template_.find(kReplayDataMarker);
  file_.write(std::string_view(template_).substr(0, at));
  file_.write(scriptSafe(h));
  file_.write(frames_json_);  // numbers only
  file_.write("]}");
  file_.write(std::string_view(template_).substr(at + std::strlen(kReplayDataMarker)));
  file_.close();
}

}  // namespace hyq::sim
