#include "sim_host/scenario/scenario.hpp"
#include "sim_host/scenario/terrain_generator.hpp"
#include "sim_host/physics/body_model.hpp"

#include "firmware/controller/model/robot_params.hpp"
#include "firmware/controller/params_check.hpp"

#include <yaml-cpp/yaml.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <initializer_list>
#include <set>

namespace hyq::sim {

const KeyRange& scenarioRange(std::string_view key) {
  for (const KeyRange& r : kScenarioRanges)
    if (key == r.key) return r;
  throw std::logic_error("no range for scenario key " + std::string(key));
}

bool inRange(const KeyRange& r, double v) {
  return std::isfinite(v) && (r.min_open ? v > r.min : v >= r.min) &&
         (r.max_open ? v < r.max : v <= r.max);
}

std::string rangeText(const KeyRange& r) {
  char b[96];
  std::snprintf(b, sizeof b, "in %c%.6g, %.6g%c%s%s", r.min_open ? '(' : '[', r.min, r.max,
                r.max_open ? ')' : ']', r.unit[0] ? " " : "", r.unit);
  return b;
}

std::string clipForMessage(std::string_view s, size_t max_chars) {
  std::string out;
  const size_t n = std::min(s.size(), max_chars);
  out.reserve(n + 3);
  for (size_t i = 0; i < n; ++i) {
    const auto c = static_cast<unsigned char>(s[i]);
    out += (c < 0x20 || c == 0x7f) ? '?' : static_cast<char>(c);
  }
  if (s.size() > max_chars) out += "...";
  return out;
}

std::optional<double> parseDecimal(std::string_view text) {
  size_t i = 0;
  auto digits = [&] {
    const size_t from = i;
    while (i < text.size() && text[i] >= '0' && text[i] <= '9') ++i;
    return i - from;
  };
  if (i < text.size() && (text[i] == '+' || text[i] == '-')) ++i;
  size_t mantissa = digits();
  if (i < text.size() && text[i] == '.') {
    ++i;
    mantissa += digits();
  }
  if (mantissa == 0 || text.size() > 64) return std::nullopt;
  if (i < text.size() && (text[i] == 'e' || text[i] == 'E')) {
    ++i;
    if (i < text.size() && (text[i] == '+' || text[i] == '-')) ++i;
    if (digits() == 0) return std::nullopt;
  }
  if (i != text.size()) return std::nullopt;
  const std::string copy(text);
  errno = 0;
  const double v = std::strtod(copy.c_str(), nullptr);
  if (errno == ERANGE || !std::isfinite(v)) return std::nullopt;
  return v;
}

bool isPlainFileName(std::string_view name) {
  if (name.empty() || name.size() > scenarioRange("name").max || name == "." || name == "..")
    return false;
  for (char c : name)
    if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
          c == '-' || c == '.'))
      return false;
  return true;
}

namespace {

// A file name or path in a message: long ones cut.
std::string fileForMessage(const std::string& path) { return clipForMessage(path, 200); }

// Reads one YAML mapping, rejecting keys it was not told about, and every
// value with its dotted path so that errors name the exact key.
class MapReader {
 public:
  MapReader(const YAML::Node& node, std::string path, const std::string& source,
            std::initializer_list<const char*> allowed)
      : node_(node), path_(std::move(path)), origin_(source) {
    if (!node_.IsMap()) fail(path_.empty() ? "(top level)" : path_, "expected a mapping");
    std::set<std::string> seen;
    for (const auto& kv : node_) {
      const std::string key = kv.first.Scalar();
      bool known = false;
      std::string list;
      for (const char* a : allowed) {
        known = known || key == a;
        list += (list.empty() ? "" : ", ") + std::string(a);
      }
      if (!known) fail(join(key), "unknown key (expected one of: " + list + ")");
      // A repeated key would silently override the first one.
      if (!seen.insert(key).second) fail(join(key), "given twice");
    }
  }

  bool has(const char* key) const { return static_cast<bool>(node_[key]); }
  const YAML::Node& node() const { return node_; }
  // The reader of the mapping at `key`, allowing the keys `allowed`.
  MapReader section(const char* key, std::initializer_list<const char*> allowed) const {
    return MapReader(node_[key], join(key), origin_, allowed);
  }
  std::string join(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

  [[noreturn]] void fail(const std::string& key, const std::string& what) const {
    throw ScenarioError(fileForMessage(origin_) + ": " + clipForMessage(key) + ": " + what);
  }

  double number(const YAML::Node& n, const std::string& key) const {
    if (!n.IsScalar()) fail(key, "expected a number");
    double v = 0.0;
    try {
      v = n.as<double>();
    } catch (const YAML::Exception&) {
      fail(key, "expected a number, got '" + clipForMessage(n.Scalar()) + "'");
    }
    if (!std::isfinite(v)) fail(key, "must be finite");
    return v;
  }

  // `v`, read for `key`, checked against the table's range `range_key`.
  double checked(double v, const std::string& key, const char* range_key) const {
    const KeyRange& r = scenarioRange(range_key);
    if (!inRange(r, v)) fail(key, "out of range: must be " + rangeText(r));
    return v;
  }

  // Optional number within the table's range; `out` untouched when absent.
  void optRanged(const char* key, double& out, const char* range_key) const {
    if (!has(key)) return;
    out = checked(number(node_[key], join(key)), join(key), range_key);
  }

  double requiredRanged(const char* key, const char* range_key) const {
    return checked(required(key), join(key), range_key);
  }

  // A fixed-length list of numbers, each within the table's range.
  template <size_t N>
  std::array<double, N> rangedNumbers(const char* key, const char* range_key) const {
    std::array<double, N> out = numbers<N>(key);
    for (size_t i = 0; i < N; ++i) checked(out[i], join(key) + "[" + std::to_string(i) + "]", range_key);
    return out;
  }

  // Any finite number (its range checked elsewhere); `out` untouched when absent.
  void optNumber(const char* key, double& out) const {
    if (has(key)) out = number(node_[key], join(key));
  }

  void optBool(const char* key, bool& out) const {
    if (!has(key)) return;
    const YAML::Node n = node_[key];
    bool v = false;
    if (!n.IsScalar()) fail(join(key), "expected true or false");
    try {
      v = n.as<bool>();
    } catch (const YAML::Exception&) {
      fail(join(key), "expected true or false, got '" + n.Scalar() + "'");
    }
    out = v;
  }

  void optString(const char* key, std::string& out) const {
    if (!has(key)) return;
    const YAML::Node n = node_[key];
    if (!n.IsScalar() || n.Scalar().empty()) fail(join(key), "expected a non-empty string");
    out = n.Scalar();
  }

  void optUnsigned(const char* key, uint64_t& out) const {
    if (!has(key)) return;
    const YAML::Node n = node_[key];
    const std::string s = n.IsScalar() ? n.Scalar() : "";
    if (s.empty() || s.size() > 19 || s.find_first_not_of("0123456789") != std::string::npos)
      fail(join(key), "expected an integer 0..9999999999999999999 (at most 19 digits)");
    out = std::stoull(s);
  }

  // A count for an int parameter: clamped to 1000, above every count the
  // controller accepts, so that its parameter check refuses it by name.
  void optCount(const char* key, int& out) const {
    if (!has(key)) return;
    uint64_t count = 0;
    optUnsigned(key, count);
    out = static_cast<int>(count > 1000 ? 1000 : count);
  }

  // A fixed-length list of numbers, e.g. [x0, x1] or [fx, fy, fz].
  template <size_t N>
  std::array<double, N> numbers(const char* key) const {
    const YAML::Node n = node_[key];
    if (!n) fail(join(key), "missing");
    if (!n.IsSequence() || n.size() != N)
      fail(join(key), "expected a list of " + std::to_string(N) + " numbers");
    std::array<double, N> out{};
    for (size_t i = 0; i < N; ++i) out[i] = number(n[i], join(key) + "[" + std::to_string(i) + "]");
    return out;
  }

  double required(const char* key) const {
    if (!has(key)) fail(join(key), "missing");
    return number(node_[key], join(key));
  }

  // Runs `each(reader_of_item)` on every entry of a list of mappings, of
  // at most the table's count for `key`.
  template <typename F>
  void forEachItem(const char* key, std::initializer_list<const char*> allowed, F each) const {
    if (!has(key)) return;
    const YAML::Node list = node_[key];
    if (list.IsNull()) return;
    if (!list.IsSequence()) fail(join(key), "expected a list");
    const KeyRange& count = scenarioRange(join(key));
    if (static_cast<double>(list.size()) > count.max)
      fail(join(key), "too many entries (" + std::to_string(list.size()) + "): at most " +
                          std::to_string(static_cast<long>(count.max)));
    for (size_t i = 0; i < list.size(); ++i)
      each(MapReader(list[i], join(key) + "[" + std::to_string(i) + "]", origin_, allowed));
  }

  const std::string& path() const { return path_; }

 private:
  YAML::Node node_;
  std::string path_;
  const std::string& origin_;
};

// The document's root mapping: refused when too large, malformed or empty.
YAML::Node loadRoot(const std::string& yaml_text, const std::string& file) {
  if (yaml_text.size() > kMaxScenarioFileBytes)
    throw ScenarioError(file + ": too large: at most " +
                        std::to_string(kMaxScenarioFileBytes) + " bytes");
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::ParserException& e) {
    throw ScenarioError(file + ": malformed YAML at line " + std::to_string(e.mark.line + 1) +
                        ", column " + std::to_string(e.mark.column + 1) + ": " +
                        clipForMessage(e.msg));
  }
  if (!root || root.IsNull()) throw ScenarioError(file + ": (top level): empty file");
  return root;
}

// The top level's own values: name, duration and seed.
void readRunKeys(const MapReader& top, Scenario& s) {
  if (!top.has("name")) top.fail("name", "missing");
  top.optString("name", s.name);
  const KeyRange& name_length = scenarioRange("name");
  if (static_cast<double>(s.name.size()) > name_length.max)
    top.fail("name", "too long (" + std::to_string(s.name.size()) + " characters): at most " +
                         std::to_string(static_cast<int>(name_length.max)));
  for (char c : s.name)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
      top.fail("name", "contains a control character: '" + clipForMessage(s.name) + "'");
  if (!top.has("duration")) top.fail("duration", "missing");
  top.optRanged("duration", s.duration, "duration");
  top.optUnsigned("seed", s.seed);
}

// The sections: each reader reads its own from the top level's reader
// `top`, and leaves the defaults when the file has none.
void readTerrain(const MapReader& top, TerrainSpec& terrain) {
  if (!top.has("terrain")) return;
  const MapReader t = top.section("terrain", {"mu", "patches", "ramps", "generate"});
  if (t.has("generate")) {
    for (const char* key : {"mu", "patches", "ramps"})
      if (t.has(key)) t.fail(t.join(key), "not with terrain.generate (the draw makes the terrain)");
    const MapReader g = t.section("generate", {"seed"});
    double seed = 0.0;
    g.optRanged("seed", seed, "terrain.generate.seed");
    if (seed != std::floor(seed) || seed < 1.0) g.fail("terrain.generate.seed", "expected an integer seed >= 1");
    terrain.generated_seed = static_cast<uint64_t>(seed);
    return;
  }
  t.optRanged("mu", terrain.mu, "terrain.mu");
  t.forEachItem("patches", {"x", "y", "mu", "t"}, [&](const MapReader& p) {
    const auto x = p.rangedNumbers<2>("x", "terrain.patches[].x");
    const auto y = p.rangedNumbers<2>("y", "terrain.patches[].y");
    if (x[0] > x[1]) p.fail(p.join("x"), "x0 > x1 (must be [x0, x1] with x0 <= x1)");
    if (y[0] > y[1]) p.fail(p.join("y"), "y0 > y1 (must be [y0, y1] with y0 <= y1)");
    const double mu = p.requiredRanged("mu", "terrain.patches[].mu");
    FrictionPatch patch{x[0], x[1], y[0], y[1], mu};
    if (p.has("t")) {
      const auto t = p.rangedNumbers<2>("t", "terrain.patches[].t");
      if (t[0] > t[1]) p.fail(p.join("t"), "t0 > t1 (must be [t0, t1] with t0 <= t1)");
      patch.t0 = t[0];
      patch.t1 = t[1];
    }
    terrain.patches.push_back(patch);
  });
  t.forEachItem("ramps", {"x0", "angle", "length"}, [&](const MapReader& r) {
    Ramp ramp{r.requiredRanged("x0", "terrain.ramps[].x0"),
              r.requiredRanged("angle", "terrain.ramps[].angle"),
              r.requiredRanged("length", "terrain.ramps[].length")};
    const KeyRange& end = scenarioRange("terrain.ramps[].end");
    if (!inRange(end, ramp.x0 + ramp.length))
      r.fail(r.join("length"), "out of range: the ramp must end " + rangeText(end) +
                                   " (x0 + length)");
    if (!terrain.ramps.empty()) {
      const Ramp& prev = terrain.ramps.back();
      if (ramp.x0 < prev.x0 + prev.length)
        r.fail(r.join("x0"), "overlaps the previous ramp (ramps go in order along +x)");
    }
    terrain.ramps.push_back(ramp);
  });
}

void readRobot(const MapReader& top, Scenario& s) {
  if (!top.has("robot")) return;
  const MapReader r = top.section("robot", {"payload_kg", "start"});
  r.optRanged("payload_kg", s.payload_kg, "robot.payload_kg");
  if (r.has("start")) {
    const MapReader st = r.section("start", {"x", "y", "yaw"});
    st.optRanged("x", s.start_x, "robot.start.x");
    st.optRanged("y", s.start_y, "robot.start.y");
    st.optRanged("yaw", s.start_yaw, "robot.start.yaw");
  }
}

// gait.trot: the trot's own numbers.
void readTrot(const MapReader& g, TrotParams& trot) {
  if (!g.has("trot")) return;
  const MapReader tr = g.section("trot", {"cycle_time", "duty_factor", "step_height", "landing_fraction",
                                          "touchdown_speed", "load_time",
                                          "unload_time", "foothold_gain", "acceleration", "imu_integration_window",
                                          "walk_time", "guess_delay", "slip_along_ground", "prior_from_feet_now",
                                          "prior_row_split", "prior_row_interior", "peak_of_loaded_samples",
                                          "speed_per_mu", "carry_distance", "carry_agreement",
                                          "carry_agreement_above", "carry_max_samples"});
  tr.optNumber("cycle_time", trot.cycle_time);
  tr.optNumber("duty_factor", trot.duty_factor);
  tr.optNumber("step_height", trot.step_height);
  tr.optNumber("landing_fraction", trot.landing_fraction);
  tr.optNumber("touchdown_speed", trot.touchdown_speed);
  tr.optNumber("load_time", trot.load_time);
  tr.optNumber("unload_time", trot.unload_time);
  tr.optNumber("foothold_gain", trot.foothold_gain);
  tr.optNumber("acceleration", trot.acceleration);
  tr.optNumber("imu_integration_window", trot.imu_integration_window);
  tr.optNumber("walk_time", trot.walk_time);
  tr.optNumber("guess_delay", trot.guess_delay);
  tr.optBool("slip_along_ground", trot.slip_along_ground);
  tr.optBool("prior_from_feet_now", trot.prior_from_feet_now);
  tr.optNumber("prior_row_split", trot.prior_row_split);
  tr.optNumber("prior_row_interior", trot.prior_row_interior);
  tr.optBool("peak_of_loaded_samples", trot.peak_of_loaded_samples);
  tr.optNumber("speed_per_mu", trot.speed_per_mu);
  tr.optNumber("carry_distance", trot.carry_distance);
  tr.optNumber("carry_agreement", trot.carry_agreement);
  tr.optNumber("carry_agreement_above", trot.carry_agreement_above);
  tr.optCount("carry_max_samples", trot.carry_max_samples);
}

// Ranges: checkParams (checkControllerParams), the controller's own.
void readGait(const MapReader& top, GaitParams& gait) {
  if (!top.has("gait")) return;
  const MapReader g = top.section("gait", {"kind", "walk", "speed", "yaw_rate", "cycle_time", "duty_factor",
                                           "step_height", "body_height", "start_delay", "stability_margin",
                                           "liftoff_margin", "liftoff_wait_max", "max_shift_acceleration",
                                           "load_time", "unload_time", "trot", "schedule"});
  if (g.has("kind")) {
    std::string kind;
    g.optString("kind", kind);
    if (kind == "crawl")
      gait.kind = GaitKind::kCrawl;
    else if (kind == "trot")
      gait.kind = GaitKind::kTrot;
    else
      g.fail("gait.kind", "expected crawl or trot, got '" + clipForMessage(kind) + "'");
  }
  g.optBool("walk", gait.walk);
  g.optNumber("yaw_rate", gait.yaw_rate);
  g.optNumber("start_delay", gait.start_delay);
  g.optNumber("speed", gait.speed);
  g.optNumber("cycle_time", gait.cycle_time);
  g.optNumber("duty_factor", gait.duty_factor);
  g.optNumber("step_height", gait.step_height);
  g.optNumber("body_height", gait.body_height);
  g.optNumber("stability_margin", gait.stability_margin);
  g.optNumber("liftoff_margin", gait.liftoff_margin);
  g.optNumber("liftoff_wait_max", gait.liftoff_wait_max);
  g.optNumber("max_shift_acceleration", gait.max_shift_acceleration);
  g.optNumber("load_time", gait.load_time);
  g.optNumber("unload_time", gait.unload_time);
  if (g.has("schedule")) {
    const MapReader sc = g.section("schedule", {"trot_at", "trot_speed"});
    sc.optNumber("trot_at", gait.schedule.trot_at);
    sc.optNumber("trot_speed", gait.schedule.trot_speed);
  }
  readTrot(g, gait.trot);
}

// Ranges: checkParams (checkControllerParams), the controller's own.
void readController(const MapReader& top, Scenario& s) {
  if (!top.has("controller")) return;
  const MapReader c = top.section(
      "controller", {"recovery", "freeze", "mu_default", "guess_holds_for_stance", "cone_force_offset",
                     "force_watch_release", "press_landing_along_normal", "grf_base_rotation", "grf_leg_motion",
                     "max_slide_stiffness", "slide_window", "slide_travel", "min_estimate_force",
                     "prior_switch_angle", "prior_switch_travel", "ending_slip_fraction", "ending_peak_hold",
                     "max_estimate_force_sigma", "min_estimate_samples", "max_slide_acceleration",
                     "prior_turn_margin", "turn_sets_ground", "prior_agreed_ground", "landing_drag_travel",
                     "slip_damping", "k_mu", "friction_map", "friction_probe", "probe", "kind", "qp", "trunk",
                     "joint", "estimator"});
  c.optBool("recovery", s.controller_params.recovery.enabled);
  c.optBool("guess_holds_for_stance", s.controller_params.recovery.guess_holds_for_stance);
  c.optNumber("cone_force_offset", s.controller_params.recovery.cone_force_offset);
  c.optNumber("force_watch_release", s.controller_params.stance.force_watch_release);
  c.optBool("press_landing_along_normal", s.controller_params.stance.press_landing_along_normal);
  c.optBool("freeze", s.controller_params.recovery.freeze);
  c.optBool("friction_map", s.controller_params.recovery.map.enabled);
  c.optBool("friction_probe", s.controller_params.recovery.probe.enabled);
  if (c.has("probe")) {
    const MapReader p = c.section("probe", {"min_load", "rate", "max_force", "max_ratio", "break_release_rate",
                                              "partner_margin", "max_normal_angle"});
    ProbeParams& probe = s.controller_params.recovery.probe;
    p.optNumber("min_load", probe.min_load);
    p.optNumber("rate", probe.rate);
    p.optNumber("max_force", probe.max_force);
    p.optNumber("max_ratio", probe.max_ratio);
    p.optNumber("break_release_rate", probe.break_release_rate);
    p.optNumber("max_normal_angle", probe.max_normal_angle);
    p.optNumber("partner_margin", probe.partner_margin);
  }
  c.optNumber("mu_default", s.controller_params.recovery.mu_default);
  c.optBool("grf_base_rotation", s.controller_params.estimator.grf_base_rotation);
  c.optBool("grf_leg_motion", s.controller_params.estimator.grf_leg_motion);
  c.optNumber("max_slide_stiffness", s.controller_params.slip.max_slide_stiffness);
  c.optNumber("min_estimate_force", s.controller_params.slip.min_estimate_force);
  c.optNumber("prior_switch_angle", s.controller_params.slip.prior_switch_angle);
  c.optNumber("prior_switch_travel", s.controller_params.slip.prior_switch_travel);
  c.optNumber("prior_turn_margin", s.controller_params.slip.prior_turn_margin);
  c.optBool("turn_sets_ground", s.controller_params.slip.turn_sets_ground);
  c.optBool("prior_agreed_ground", s.controller_params.slip.prior_agreed_ground);
  c.optNumber("ending_slip_fraction", s.controller_params.slip.ending_slip_fraction);
  c.optNumber("ending_peak_hold", s.controller_params.slip.ending_peak_hold);
  c.optNumber("max_estimate_force_sigma", s.controller_params.slip.max_estimate_force_sigma);
  c.optNumber("max_slide_acceleration", s.controller_params.slip.max_slide_acceleration);
  c.optCount("min_estimate_samples", s.controller_params.slip.min_estimate_samples);
  c.optNumber("landing_drag_travel", s.controller_params.slip.landing_drag_travel);
  c.optNumber("slip_damping", s.controller_params.recovery.slip_damping);
  c.optNumber("k_mu", s.controller_params.recovery.k_mu);
  c.optCount("slide_window", s.controller_params.slip.slide_window);
  c.optNumber("slide_travel", s.controller_params.slip.slide_travel);
  c.optString("kind", s.controller_kind);
  if (c.has("qp")) {
    const MapReader q = c.section("qp", {"tangential_weight", "force_smoothing", "wrench_weight_lin",
                                         "wrench_weight_ang", "f_normal_min"});
    QpParams& qp = s.controller_params.qp;
    q.optNumber("tangential_weight", qp.tangential_weight);
    q.optNumber("force_smoothing", qp.force_smoothing);
    q.optNumber("wrench_weight_lin", qp.wrench_weight_lin);
    q.optNumber("wrench_weight_ang", qp.wrench_weight_ang);
    q.optNumber("f_normal_min", qp.f_normal_min);
  }
  if (c.has("trunk")) {
    const MapReader t = c.section("trunk", {"kp_lin", "kd_lin"});
    TrunkParams& trunk = s.controller_params.trunk;
    t.optNumber("kp_lin", trunk.kp_lin);
    t.optNumber("kd_lin", trunk.kd_lin);
  }
  if (c.has("joint")) {
    const MapReader j = c.section("joint", {"swing_kp", "swing_kd", "torque_bandwidth", "swing_crossover_fraction"});
    JointParams& joint = s.controller_params.joint;
    j.optNumber("swing_kp", joint.swing_kp);
    j.optNumber("swing_kd", joint.swing_kd);
    j.optNumber("torque_bandwidth", joint.torque_bandwidth);
    j.optNumber("swing_crossover_fraction", joint.swing_crossover_fraction);
  }
  if (c.has("estimator")) {
    const MapReader e = c.section("estimator", {"com_offset_time", "imu_position"});
    e.optNumber("com_offset_time", s.controller_params.estimator.com_offset_time);
    if (e.has("imu_position")) {
      const std::array<double, 3> r = e.numbers<3>("imu_position");
      for (int k = 0; k < 3; ++k) s.controller_params.estimator.imu_position[k] = r[k];
    }
  }
}

void readSensors(const MapReader& top, SensorSpec& sensors) {
  if (!top.has("sensors")) return;
  const MapReader n = top.section("sensors", {"noise", "q", "qd", "tau", "tau_bias", "gyro", "gyro_bias", "acc",
                                              "acc_bias", "orientation", "biases_at_magnitude"});
  SensorNoise& m = sensors.magnitudes;
  n.optBool("noise", sensors.noise);
  n.optBool("biases_at_magnitude", sensors.biases_at_magnitude);
  n.optRanged("q", m.q, "sensors.q");
  n.optRanged("qd", m.qd, "sensors.qd");
  n.optRanged("tau", m.tau, "sensors.tau");
  n.optRanged("tau_bias", m.tau_bias, "sensors.tau_bias");
  n.optRanged("gyro", m.gyro, "sensors.gyro");
  n.optRanged("gyro_bias", m.gyro_bias, "sensors.gyro_bias");
  n.optRanged("acc", m.acc, "sensors.acc");
  n.optRanged("acc_bias", m.acc_bias, "sensors.acc_bias");
  n.optRanged("orientation", m.orientation, "sensors.orientation");
}

void readPhysics(const MapReader& top, PhysicsSpec& physics) {
  if (!top.has("physics")) return;
  const MapReader p = top.section("physics", {"engine", "ode", "mujoco"});
  std::string engine = engineName(physics.engine);
  p.optString("engine", engine);
  if (!parseEngineName(engine, physics.engine))
    p.fail("physics.engine", "expected ode or mujoco, got '" + clipForMessage(engine) + "'");
  if (p.has("ode")) {
    const MapReader o = p.section("ode", {"stiffness_scale"});
    o.optRanged("stiffness_scale", physics.ode_stiffness_scale, "physics.ode.stiffness_scale");
  }
  if (p.has("mujoco")) {
    const MapReader m =
        p.section("mujoco", {"timeconst", "dampratio", "solimp", "impratio", "noslip_iterations"});
    MujocoParams& mj = physics.mujoco;
    m.optRanged("timeconst", mj.timeconst, "physics.mujoco.timeconst");
    m.optRanged("dampratio", mj.dampratio, "physics.mujoco.dampratio");
    if (m.has("solimp")) {
      const std::array<double, 3> si = m.numbers<3>("solimp");
      mj.solimp_d0 = m.checked(si[0], "physics.mujoco.solimp[0]", "physics.mujoco.solimp[0]");
      mj.solimp_dwidth = m.checked(si[1], "physics.mujoco.solimp[1]", "physics.mujoco.solimp[1]");
      mj.solimp_width = m.checked(si[2], "physics.mujoco.solimp[2]", "physics.mujoco.solimp[2]");
    }
    m.optRanged("impratio", mj.impratio, "physics.mujoco.impratio");
    double noslip = mj.noslip_iterations;
    m.optRanged("noslip_iterations", noslip, "physics.mujoco.noslip_iterations");
    if (noslip != std::floor(noslip)) m.fail("physics.mujoco.noslip_iterations", "expected an integer");
    mj.noslip_iterations = static_cast<int>(noslip);
  }
}

// MuJoCo's impedance at penetration `depth` [m]: solimp's d0 at the
// surface to dwidth at `width` deep, along MuJoCo's default curve (midpoint
// 0.5, power 2), clamped to MuJoCo's [0.0001, 0.9999].
double mujocoImpedance(const MujocoParams& mj, double depth) {
  double d = mj.solimp_dwidth;
  if (mj.solimp_width > 1e-15 && depth < mj.solimp_width) {
    const double x = std::max(0.0, depth / mj.solimp_width);
    const double y = x <= 0.5 ? 2.0 * x * x : 1.0 - 2.0 * (1.0 - x) * (1.0 - x);
    d = mj.solimp_d0 + y * (mj.solimp_dwidth - mj.solimp_d0);
  }
  return std::clamp(d, 0.0001, 0.9999);
}

// The depth [m] at which MuJoCo's soft contact holds a foot at rest under a
// load that alone would accelerate it at `a` [m/s^2]. The contact's
// reference acceleration k depth, k = d / (dwidth^2 timeconst^2
// dampratio^2), then balances the share (1 - d) / d of the load that the
// regularised constraint leaves: depth = (1 - d) (dwidth / d)^2
// timeconst^2 dampratio^2 a, with d the impedance at that depth. The
// shallowest such depth; infinity when there is none within 1 m.
double mujocoSink(const MujocoParams& mj, double a) {
  const double scale = std::pow(mj.solimp_dwidth * mj.timeconst * mj.dampratio, 2) * a;
  auto excess = [&](double depth) {
    const double d = mujocoImpedance(mj, depth);
    return depth - (1.0 - d) / (d * d) * scale;
  };
  double lo = 0.0, hi = 1e-7;
  while (excess(hi) < 0.0) {
    lo = hi;
    hi *= 1.25;
    if (hi > 1.0) return std::numeric_limits<double>::infinity();
  }
  for (int k = 0; k < 60; ++k) (excess(0.5 * (lo + hi)) < 0.0 ? lo : hi) = 0.5 * (lo + hi);
  return hi;
}

// MuJoCo's contact settings, each in its range, must together carry HyQ
// (scenario.hpp's table): stable at a 1 ms tick, a sink at rest within the
// foot's radius, and mostly hard where the feet carry the robot.
void checkMujocoContact(const Scenario& s, const std::string& file) {
  const MujocoParams& mj = s.physics.mujoco;
  char settings[160];
  std::snprintf(settings, sizeof settings, "timeconst %g s, dampratio %g, solimp [%g, %g, %g]", mj.timeconst,
                mj.dampratio, mj.solimp_d0, mj.solimp_dwidth, mj.solimp_width);
  char why[400];
  // The contact's time constant is timeconst * dwidth / d: shortest where
  // the impedance is highest.
  const double shortest = mj.timeconst * mj.solimp_dwidth / std::max(mj.solimp_d0, mj.solimp_dwidth);
  if (shortest < kMujocoMinTimeConstant * (1.0 - 1e-9)) {
    std::snprintf(why, sizeof why,
                  "%s: at impedance d0 the contact's time constant, timeconst * dwidth / d0, is %.3g ms: at least "
                  "%g ms (2 ticks), or MuJoCo's contact is unstable",
                  settings, 1e3 * shortest, 1e3 * kMujocoMinTimeConstant);
    throw ScenarioError(file + ": physics.mujoco.solimp: " + why);
  }
  // The simulated body's mass (its trunk scaled by plant.trunk_mass_scale), not the model's.
  const double load =
      kMujocoFootLoadAcceleration * (plantBody(s.plant).total_mass + s.payload_kg) / robot::kTotalMass;
  const double sink = mujocoSink(mj, load);
  if (!(sink <= robot::kFootRadius)) {
    std::snprintf(why, sizeof why,
                  "%s: HyQ's feet (payload %g kg) would sink %s at rest: at most the foot's radius, %.2f mm "
                  "(a shorter timeconst, a lower dampratio or a higher impedance sinks less)",
                  settings, s.payload_kg,
                  std::isfinite(sink) ? (std::to_string(std::lround(1e3 * sink)) + " mm").c_str() : "over 1 m",
                  1e3 * robot::kFootRadius);
    throw ScenarioError(file + ": physics.mujoco: " + why);
  }
  const double d = mujocoImpedance(mj, sink);
  if (d < kMujocoMinImpedance) {
    std::snprintf(why, sizeof why,
                  "%s: the impedance where the feet carry the robot (%.2f mm deep) is %.3g: at least %g, or the "
                  "feet sink and creep under the controller's changing forces",
                  settings, 1e3 * sink, d, kMujocoMinImpedance);
    throw ScenarioError(file + ": physics.mujoco.solimp: " + why);
  }
}

// plant: the preset first (plant.model), then each part's own keys over it.
void readPlantActuator(const MapReader& p, ActuatorParams& a) {
  if (!p.has("actuator")) return;
  const MapReader m =
      p.section("actuator", {"model", "pd_rate", "bandwidth", "damping_ratio", "rate_limit", "torque_sensor_cutoff",
                             "velocity_limit"});
  if (m.has("model")) {
    std::string model;
    m.optString("model", model);
    if (model != "ideal" && model != "hyq")
      m.fail("plant.actuator.model", "expected ideal or hyq, got '" + clipForMessage(model) + "'");
    a.model = model == "hyq";
  }
  m.optRanged("pd_rate", a.pd_rate, "plant.actuator.pd_rate");
  m.optRanged("bandwidth", a.bandwidth, "plant.actuator.bandwidth");
  m.optRanged("damping_ratio", a.damping_ratio, "plant.actuator.damping_ratio");
  m.optRanged("rate_limit", a.rate_limit, "plant.actuator.rate_limit");
  m.optRanged("torque_sensor_cutoff", a.torque_sensor_cutoff, "plant.actuator.torque_sensor_cutoff");
  m.optRanged("velocity_limit", a.velocity_limit, "plant.actuator.velocity_limit");
}

void readPlantEncoder(const MapReader& p, EncoderParams& e) {
  if (!p.has("encoder")) return;
  const MapReader m = p.section("encoder", {"resolution", "velocity", "velocity_cutoff"});
  m.optRanged("resolution", e.resolution, "plant.encoder.resolution");
  if (m.has("velocity")) {
    std::string v;
    m.optString("velocity", v);
    if (v != "truth" && v != "differentiated")
      m.fail("plant.encoder.velocity", "expected truth or differentiated, got '" + clipForMessage(v) + "'");
    e.velocity = v == "truth" ? VelocitySource::truth : VelocitySource::differentiated;
  }
  m.optRanged("velocity_cutoff", e.velocity_cutoff, "plant.encoder.velocity_cutoff");
}

void readPlantDelays(const MapReader& p, DelayParams& d) {
  if (!p.has("delay")) return;
  const MapReader m = p.section("delay", {"sensor_ticks", "command_ticks", "imu_ticks"});
  const auto ticks = [&](const char* key, int& out) {
    double v = out;
    const std::string name = std::string("plant.delay.") + key;
    m.optRanged(key, v, name.c_str());
    if (v != std::floor(v)) m.fail(name, "expected an integer");
    out = static_cast<int>(v);
  };
  ticks("sensor_ticks", d.sensor_ticks);
  ticks("command_ticks", d.command_ticks);
  ticks("imu_ticks", d.imu_ticks);
}

void readPlant(const MapReader& top, PlantSpec& plant) {
  if (!top.has("plant")) return;
  const MapReader p = top.section("plant", {"model", "actuator", "encoder", "delay", "body", "imu",
                                            "trunk_mass_scale", "trunk_inertia_scale"});
  if (p.has("model")) {
    std::string model;
    p.optString("model", model);
    PlantModel kind = PlantModel::ideal;
    if (!parsePlantModelName(model, kind))
      p.fail("plant.model", "expected ideal or hyq, got '" + clipForMessage(model) + "'");
    plant = kind == PlantModel::hyq ? hyqPlant() : idealPlant();
  }
  readPlantActuator(p, plant.actuator);
  readPlantEncoder(p, plant.encoder);
  readPlantDelays(p, plant.delay);
  if (p.has("body")) {
    std::string body;
    p.optString("body", body);
    if (body != "nominal" && body != "published")
      p.fail("plant.body", "expected nominal or published, got '" + clipForMessage(body) + "'");
    plant.body = body == "published" ? BodyModel::published : BodyModel::nominal;
  }
  if (p.has("imu")) {
    std::string imu;
    p.optString("imu", imu);
    if (imu != "origin" && imu != "mounted")
      p.fail("plant.imu", "expected origin or mounted, got '" + clipForMessage(imu) + "'");
    plant.imu = imu == "mounted" ? ImuMount::mounted : ImuMount::origin;
  }
  p.optRanged("trunk_mass_scale", plant.trunk_mass_scale, "plant.trunk_mass_scale");
  p.optRanged("trunk_inertia_scale", plant.trunk_inertia_scale, "plant.trunk_inertia_scale");
}

void readDisturbances(const MapReader& top, std::vector<Disturbance>& disturbances) {
  top.forEachItem("disturbances", {"t", "duration", "force"}, [&](const MapReader& d) {
    disturbances.push_back({d.requiredRanged("t", "disturbances[].t"),
                            d.requiredRanged("duration", "disturbances[].duration"),
                            d.rangedNumbers<3>("force", "disturbances[].force")});
  });
  // The forces add where disturbances overlap; the set of active ones only
  // changes where one starts or ends.
  for (const Disturbance& at : disturbances) {
    for (const double t : {at.t, at.t + at.duration}) {
      double f[3] = {0.0, 0.0, 0.0};
      for (const Disturbance& d : disturbances)
        if (t >= d.t && t < d.t + d.duration)
          for (int k = 0; k < 3; ++k) f[k] += d.force[k];
      const double magnitude = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
      if (magnitude > kMaxForce) {
        char what[160];
        std::snprintf(what, sizeof what,
                      "out of range: the forces active at t = %g s add up to %g N: at most %g N", t,
                      magnitude, kMaxForce);
        top.fail("disturbances", what);
      }
    }
  }
}

// The controller's parameters, checked by the controller's own rules;
// the message names the scenario key that set the offending value.
void checkControllerParams(const Params& params, const std::string& file) {
  ParamIssue issue;
  if (checkParams(params, issue)) return;
  const std::string name = issue.name;
  std::string key = name;
  // Parameters set by a key directly under `controller:`.
  static const char* const kControllerLeaves[] = {"recovery.mu_default",       "recovery.cone_force_offset",
                                                  "stance.force_watch_release", "slip.max_slide_stiffness",
                                                  "slip.slide_window",          "slip.slide_travel",
                                                  "slip.min_estimate_force",
                                                  "slip.prior_switch_angle",    "slip.prior_switch_travel",
                                                  "slip.ending_slip_fraction",  "slip.ending_peak_hold",
                                                  "slip.max_estimate_force_sigma",
                                                  "slip.min_estimate_samples",  "slip.max_slide_acceleration",
                                                  "slip.prior_turn_margin",     "slip.landing_drag_travel",
                                                  "recovery.slip_damping",      "recovery.k_mu"};
  bool leaf = false;
  for (const char* param : kControllerLeaves)
    if (name == param) leaf = true;
  if (leaf)
    key = "controller." + name.substr(name.find('.') + 1);
  else if (name.rfind("qp.", 0) == 0 || name.rfind("trunk.", 0) == 0 || name.rfind("joint.", 0) == 0 ||
           name == "estimator.com_offset_time" || name == "estimator.imu_position")
    key = "controller." + name;
  throw ScenarioError(file + ": " + key + ": out of range: must be " + issue.rule);
}

// What a scenario sets itself of the controller's configuration that the
// plant would otherwise set (configureForPlant).
struct OwnSettings {
  bool torque_bandwidth = false;
  bool shift_acceleration = false;
  bool trot_duty_factor = false;
  bool trot_guess_delay = false;
  bool step_height = false;
  bool imu_position = false;
};

// The controller configured for the plant it runs on, but for what `own`
// says the scenario sets: on HyQ's joints, for their torque loop
// (kHyqControllerTorqueBandwidth), its crawl's body shift bounded for the
// ground's friction (kHyqShiftAcceleration), its crawl's hind feet's swing
// lower (kHyqCrawlStepHeight), its trot standing longer on four feet
// (kHyqTrotDutyFactor) and guessing a flagged landing foot down at once
// (kHyqTrotGuessDelay); and an IMU mounted where HyQ has it is
// where the controller takes its lever arm out (EstimatorParams::imu_position).
void configureForPlant(Scenario& s, const OwnSettings& own) {
  Params& c = s.controller_params;
  if (s.plant.model == PlantModel::hyq) {
    if (!own.torque_bandwidth) c.joint.torque_bandwidth = kHyqControllerTorqueBandwidth;
    if (!own.shift_acceleration) c.gait.max_shift_acceleration = kHyqShiftAcceleration;
    if (!own.trot_duty_factor) c.gait.trot.duty_factor = kHyqTrotDutyFactor;
    if (!own.trot_guess_delay) c.gait.trot.guess_delay = kHyqTrotGuessDelay;
    if (!own.step_height) c.gait.step_height = kHyqCrawlStepHeight;
  }
  if (s.plant.imu == ImuMount::mounted && !own.imu_position) {
    const Vec3 r = imuPlacement(ImuMount::mounted).position;
    for (int k = 0; k < 3; ++k) c.estimator.imu_position[k] = r[k];
  }
}

// Whether the scenario file sets the key at `path` (each step a map's key).
bool fileSets(const MapReader& top, std::initializer_list<const char*> path) {
  YAML::Node node = top.node();
  for (const char* key : path) {
    if (!node.IsMap()) return false;
    const YAML::Node next = static_cast<const YAML::Node&>(node)[key];
    if (!next) return false;
    node.reset(next);
  }
  return true;
}

// The whole reader, section by section; yaml-cpp's exceptions are left to
// parseScenario.
Scenario parseYaml(const std::string& yaml_text, const std::string& origin, PlantModel default_plant) {
  const std::string file = fileForMessage(origin);
  const YAML::Node root = loadRoot(yaml_text, file);

  Scenario s;
  s.source_file = origin;
  const MapReader top(root, "", origin,
                      {"name", "duration", "seed", "terrain", "robot", "gait", "controller",
                       "sensors", "disturbances", "physics", "plant"});
  readRunKeys(top, s);
  readTerrain(top, s.terrain);
  readRobot(top, s);
  readGait(top, s.controller_params.gait);
  readController(top, s);
  readSensors(top, s.sensors);
  readPhysics(top, s.physics);
  s.plant = default_plant == PlantModel::hyq ? hyqPlant() : idealPlant();
  readPlant(top, s.plant);
  readDisturbances(top, s.disturbances);
  // A drawn terrain replaces the file's terrain, start, gait, speed, pushes and duration.
  if (s.terrain.generated_seed != 0) {
    const uint64_t seed = s.terrain.generated_seed;
    generateTerrain(seed, s);
    s.terrain.generated_seed = seed;
  }
  // The controller as the plant has it configured, where the file does not say.
  OwnSettings own;
  own.torque_bandwidth = fileSets(top, {"controller", "joint", "torque_bandwidth"});
  own.shift_acceleration = fileSets(top, {"gait", "max_shift_acceleration"});
  own.trot_duty_factor = fileSets(top, {"gait", "trot", "duty_factor"});
  own.trot_guess_delay = fileSets(top, {"gait", "trot", "guess_delay"});
  own.step_height = fileSets(top, {"gait", "step_height"});
  own.imu_position = fileSets(top, {"controller", "estimator", "imu_position"});
  configureForPlant(s, own);
  checkMujocoContact(s, file);
  checkControllerParams(s.controller_params, file);
  return s;
}

}  // namespace

void putOnHyqPlant(Scenario& s) {
  s.plant = hyqPlant();
  const Params& c = s.controller_params;
  OwnSettings own;
  own.shift_acceleration = c.gait.max_shift_acceleration != 0.0;
  own.trot_duty_factor = c.gait.trot.duty_factor != TrotParams{}.duty_factor;
  own.trot_guess_delay = c.gait.trot.guess_delay != TrotParams{}.guess_delay;
  own.step_height = c.gait.step_height != GaitParams{}.step_height;
  own.imu_position = c.estimator.imu_position[0] != 0.0 || c.estimator.imu_position[1] != 0.0 ||
                     c.estimator.imu_position[2] != 0.0;
  configureForPlant(s, own);
}

Scenario parseScenario(const std::string& yaml_text, const std::string& origin, PlantModel default_plant) {
  try {
    return parseYaml(yaml_text, origin, default_plant);
  } catch (const YAML::Exception& e) {
    // yaml-cpp's own complaints about a document it accepted (e.g. an
    // alias it cannot resolve).
    throw ScenarioError(fileForMessage(origin) + ": malformed YAML: " + clipForMessage(e.what()));
  }
}

namespace {

// What a path that is not a regular file is, for messages.
std::string fileKind(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a plain file";
}

}  // namespace

std::string readRegularFile(const std::string& path, size_t max_bytes) {
  // Opened without blocking (the open of a FIFO with no writer would wait
  // for one for ever), then refused unless it is a regular file: a pipe or
  // a device may never end.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0)
    throw ScenarioError(fileForMessage(path) + ": cannot open file: " + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const int error = errno;
    ::close(fd);
    throw ScenarioError(fileForMessage(path) + ": cannot read file: " + std::strerror(error));
  }
  if (!S_ISREG(st.st_mode)) {
    ::close(fd);
    throw ScenarioError(fileForMessage(path) + ": not a regular file (" + fileKind(st.st_mode) + ")");
  }
  std::string text;
  char buffer[65536];
  for (;;) {
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int error = errno;
      ::close(fd);
      throw ScenarioError(fileForMessage(path) + ": cannot read file: " + std::strerror(error));
    }
    if (n == 0) break;
    text.append(buffer, static_cast<size_t>(n));
    // At most one byte more than allowed: enough to tell it is too long.
    if (text.size() > max_bytes) {
      text.resize(max_bytes + 1);
      break;
    }
  }
  ::close(fd);
  return text;
}

std::string readScenarioFile(const std::string& path) { return readRegularFile(path, kMaxScenarioFileBytes); }

Scenario loadScenario(const std::string& path, PlantModel default_plant) {
  return parseScenario(readScenarioFile(path), path, default_plant);
}

void checkOutputFolderName(const Scenario& scenario) {
  if (isPlainFileName(scenario.name)) return;
  throw ScenarioError(
      fileForMessage(scenario.source_file.empty() ? "scenario" : scenario.source_file) +
      ": name: '" + clipForMessage(scenario.name) +
      "' cannot name the output folder out/<name>: use 1..64 letters, digits, '_', '-' or '.' "
      "(not '.' or '..'), or give --out DIR");
}

}  // namespace hyq::sim
