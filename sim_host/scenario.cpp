#include "sim_host/scenario.hpp"

#include "firmware/controller/params_check.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <initializer_list>
#include <set>
#include <sstream>

namespace hyq::sim {
namespace {

// Reads one YAML mapping, rejecting keys it was not told about, and every
// value with its dotted path so that errors name the exact key.
class MapReader {
 public:
  MapReader(const YAML::Node& node, std::string path, const std::string& origin,
            std::initializer_list<const char*> allowed)
      : node_(node), path_(std::move(path)), origin_(origin) {
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
  YAML::Node child(const char* key) const { return node_[key]; }
  std::string join(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

  [[noreturn]] void fail(const std::string& key, const std::string& what) const {
    throw ScenarioError(origin_ + ": " + key + ": " + what);
  }

  double number(const YAML::Node& n, const std::string& key) const {
    if (!n.IsScalar()) fail(key, "expected a number");
    double v = 0.0;
    try {
      v = n.as<double>();
    } catch (const YAML::Exception&) {
      fail(key, "expected a number, got '" + n.Scalar() + "'");
    }
    if (!std::isfinite(v)) fail(key, "must be finite");
    return v;
  }

  // Optional number with a range check; leaves `out` untouched when absent.
  void optNumber(const char* key, double& out, double lo, double hi, const char* range) const {
    if (!has(key)) return;
    const double v = number(node_[key], join(key));
    if (!(v >= lo && v <= hi)) fail(join(key), std::string("out of range: must be ") + range);
    out = v;
  }

  // Any finite number (a range checked elsewhere).
  void optNumber(const char* key, double& out) const {
    optNumber(key, out, -HUGE_VAL, HUGE_VAL, "finite");
  }

  void optPositive(const char* key, double& out) const {
    if (!has(key)) return;
    const double v = number(node_[key], join(key));
    if (!(v > 0.0)) fail(join(key), "out of range: must be > 0");
    out = v;
  }

  void optNonNegative(const char* key, double& out) const {
    optNumber(key, out, 0.0, HUGE_VAL, ">= 0");
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
      fail(join(key), "expected a non-negative integer");
    out = std::stoull(s);
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

  // Runs `each(reader_of_item)` on every entry of a list of mappings.
  template <typename F>
  void forEachItem(const char* key, std::initializer_list<const char*> allowed, F each) const {
    if (!has(key)) return;
    const YAML::Node list = node_[key];
    if (list.IsNull()) return;
    if (!list.IsSequence()) fail(join(key), "expected a list");
    for (size_t i = 0; i < list.size(); ++i)
      each(MapReader(list[i], join(key) + "[" + std::to_string(i) + "]", origin_, allowed));
  }

  const std::string& path() const { return path_; }

 private:
  YAML::Node node_;
  std::string path_;
  const std::string& origin_;
};

}  // namespace

Scenario parseScenario(const std::string& yaml_text, const std::string& origin) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::ParserException& e) {
    throw ScenarioError(origin + ": malformed YAML at line " + std::to_string(e.mark.line + 1) +
                        ", column " + std::to_string(e.mark.column + 1) + ": " + e.msg);
  }
  if (!root || root.IsNull()) throw ScenarioError(origin + ": (top level): empty file");

  Scenario s;
  s.source_file = origin;
  const MapReader top(root, "", origin,
                      {"name", "duration", "seed", "terrain", "robot", "gait", "controller",
                       "sensors", "disturbances"});
  if (!top.has("name")) top.fail("name", "missing");
  top.optString("name", s.name);
  if (!top.has("duration")) top.fail("duration", "missing");
  top.optPositive("duration", s.duration);
  top.optUnsigned("seed", s.seed);

  if (top.has("terrain")) {
    const MapReader t(top.child("terrain"), "terrain", origin, {"mu", "patches", "ramps"});
    t.optNonNegative("mu", s.terrain.mu);
    t.forEachItem("patches", {"x", "y", "mu"}, [&](const MapReader& p) {
      const auto x = p.numbers<2>("x");
      const auto y = p.numbers<2>("y");
      if (x[0] > x[1]) p.fail(p.join("x"), "x0 > x1 (must be [x0, x1] with x0 <= x1)");
      if (y[0] > y[1]) p.fail(p.join("y"), "y0 > y1 (must be [y0, y1] with y0 <= y1)");
      const double mu = p.required("mu");
      if (mu < 0.0) p.fail(p.join("mu"), "out of range: must be >= 0");
      s.terrain.patches.push_back({x[0], x[1], y[0], y[1], mu});
    });
    t.forEachItem("ramps", {"x0", "angle", "length"}, [&](const MapReader& r) {
      Ramp ramp{r.required("x0"), r.required("angle"), r.required("length")};
      if (!(std::fabs(ramp.angle) < 1.2))
        r.fail(r.join("angle"), "out of range: must be in (-1.2, 1.2) rad");
      if (!(ramp.length > 0.0)) r.fail(r.join("length"), "out of range: must be > 0");
      if (!s.terrain.ramps.empty()) {
        const Ramp& prev = s.terrain.ramps.back();
        if (ramp.x0 < prev.x0 + prev.length)
          r.fail(r.join("x0"), "overlaps the previous ramp (ramps go in order along +x)");
      }
      s.terrain.ramps.push_back(ramp);
    });
  }

  if (top.has("robot")) {
    const MapReader r(top.child("robot"), "robot", origin, {"payload_kg", "start"});
    r.optNonNegative("payload_kg", s.payload_kg);
    if (r.has("start")) {
      const MapReader st(r.child("start"), "robot.start", origin, {"x", "y", "yaw"});
      st.optNumber("x", s.start_x, -HUGE_VAL, HUGE_VAL, "finite");
      st.optNumber("y", s.start_y, -HUGE_VAL, HUGE_VAL, "finite");
      st.optNumber("yaw", s.start_yaw, -M_PI, M_PI, "in [-pi, pi]");
    }
  }

  GaitParams& gait = s.controller_params.gait;
  if (top.has("gait")) {
    const MapReader g(top.child("gait"), "gait", origin,
                      {"walk", "speed", "cycle_time", "duty_factor", "step_height", "body_height",
                       "start_delay", "liftoff_margin", "load_time", "unload_time"});
    // Ranges: checkParams below, the controller's own.
    g.optBool("walk", gait.walk);
    g.optNumber("start_delay", gait.start_delay);
    g.optNumber("speed", gait.speed);
    g.optNumber("cycle_time", gait.cycle_time);
    g.optNumber("duty_factor", gait.duty_factor);
    g.optNumber("step_height", gait.step_height);
    g.optNumber("body_height", gait.body_height);
    g.optNumber("liftoff_margin", gait.liftoff_margin);
    g.optNumber("load_time", gait.load_time);
    g.optNumber("unload_time", gait.unload_time);
  }

  if (top.has("controller")) {
    const MapReader c(top.child("controller"), "controller", origin,
                      {"recovery", "mu_default", "kind", "qp", "trunk"});
    c.optBool("recovery", s.controller_params.recovery.enabled);
    c.optNumber("mu_default", s.controller_params.recovery.mu_default);
    c.optString("kind", s.controller_kind);
    if (c.has("qp")) {
      const MapReader q(c.child("qp"), "controller.qp", origin,
                        {"tangential_weight", "force_smoothing"});
      QpParams& qp = s.controller_params.qp;
      q.optNumber("tangential_weight", qp.tangential_weight);
      q.optNumber("force_smoothing", qp.force_smoothing);
    }
    if (c.has("trunk")) {
      const MapReader t(c.child("trunk"), "controller.trunk", origin, {"kp_lin", "kd_lin"});
      TrunkParams& trunk = s.controller_params.trunk;
      t.optNumber("kp_lin", trunk.kp_lin);
      t.optNumber("kd_lin", trunk.kd_lin);
    }
  }

  if (top.has("sensors")) {
    const MapReader n(top.child("sensors"), "sensors", origin,
                      {"noise", "q", "qd", "tau", "tau_bias", "gyro", "gyro_bias", "acc",
                       "acc_bias", "orientation"});
    SensorNoise& m = s.sensors.magnitudes;
    n.optBool("noise", s.sensors.noise);
    n.optNonNegative("q", m.q);
    n.optNonNegative("qd", m.qd);
    n.optNonNegative("tau", m.tau);
    n.optNonNegative("tau_bias", m.tau_bias);
    n.optNonNegative("gyro", m.gyro);
    n.optNonNegative("gyro_bias", m.gyro_bias);
    n.optNonNegative("acc", m.acc);
    n.optNonNegative("acc_bias", m.acc_bias);
    n.optNonNegative("orientation", m.orientation);
  }

  top.forEachItem("disturbances", {"t", "duration", "force"}, [&](const MapReader& d) {
    Disturbance dist{d.required("t"), d.required("duration"), d.numbers<3>("force")};
    if (dist.t < 0.0) d.fail(d.join("t"), "out of range: must be >= 0");
    if (!(dist.duration > 0.0)) d.fail(d.join("duration"), "out of range: must be > 0");
    s.disturbances.push_back(dist);
  });

  // The controller's parameters, checked by the controller's own rules;
  // the message names the scenario key that set the offending value.
  ParamIssue issue;
  if (!checkParams(s.controller_params, issue)) {
    const std::string name = issue.name;
    std::string key = name;
    if (name == "recovery.mu_default")
      key = "controller.mu_default";
    else if (name.rfind("qp.", 0) == 0 || name.rfind("trunk.", 0) == 0)
      key = "controller." + name;
    throw ScenarioError(origin + ": " + key + ": out of range: must be " + issue.rule);
  }
  return s;
}

Scenario loadScenario(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ScenarioError(path + ": cannot open file");
  std::stringstream text;
  text << in.rdbuf();
  return parseScenario(text.str(), path);
}

}  // namespace hyq::sim
