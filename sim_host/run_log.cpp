#include "sim_host/run_log.hpp"

#include <charconv>
#include <cmath>
#include <stdexcept>

#include "firmware/controller/robot_params.hpp"

namespace hyq::sim {
namespace {

std::FILE* openForWriting(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) throw std::runtime_error(path + ": cannot write");
  return f;
}

const char* const kLeg[4] = {"LF", "RF", "LH", "RH"};
const char* const kJoint[3] = {"haa", "hfe", "kfe"};

struct FlagName {
  uint32_t bit;
  const char* name;
};
const FlagName kFlags[] = {
    {hal::kFlagBadSensorFrame, "bad_sensor_frame"}, {hal::kFlagQpInfeasible, "qp_infeasible"},
    {hal::kFlagQpMaxIter, "qp_max_iter"},           {hal::kFlagFreeze, "freeze"},
    {hal::kFlagNotInitialised, "not_initialised"},  {hal::kFlagLinkLost, "link_lost"},
};

std::string header() {
  std::string h = "time,tick";
  auto add = [&h](const std::string& name) { h += "," + name; };
  auto add3 = [&add](const std::string& name) {
    add(name + "_x"), add(name + "_y"), add(name + "_z");
  };
  add3("base_pos");
  add("base_qw"), add("base_qx"), add("base_qy"), add("base_qz");
  add3("base_vel");
  add3("base_omega");
  for (const char* leg : kLeg) {
    const std::string p = std::string(leg) + "_";
    add(p + "contact");
    add3(p + "force");
    add(p + "mu");
    add3(p + "normal");
    add3(p + "slip_vel");
    add3(p + "foot_pos");
  }
  add3("disturbance");
  for (const char* field : {"q", "qd", "tau"})
    for (const char* leg : kLeg)
      for (const char* joint : kJoint) add(std::string(field) + "_" + leg + "_" + joint);
  add("imu_qw"), add("imu_qx"), add("imu_qy"), add("imu_qz");
  add3("imu_gyro");
  add3("imu_acc");
  for (const char* leg : kLeg)
    for (const char* joint : kJoint) add(std::string("tau_cmd_") + leg + "_" + joint);
  add("flags"), add("stance_mask"), add("slip_mask"), add("swing_leg"), add("gait_phase");
  add3("base_pos_est");
  add3("base_vel_est");
  for (const char* field : {"foot_vel_base", "grf_est", "grf_des"})
    for (const char* leg : kLeg) add3(std::string(field) + "_" + leg);
  for (const char* leg : kLeg) add(std::string("mu_used_") + leg);
  for (const char* leg : kLeg) add3(std::string("normal_used_") + leg);
  for (const char* leg : kLeg) add(std::string("mu_hat_") + leg);
  for (const char* leg : kLeg) add3(std::string("normal_hat_") + leg);
  return h + "\n";
}

// 10^(e+1) for e = -5..5, and 10^(5-e) which scales 10^e to 100000.
constexpr double kUpper[] = {1e-4, 1e-3, 1e-2, 1e-1, 1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6};
constexpr double kScale[] = {1e10, 1e9, 1e8, 1e7, 1e6, 1e5, 1e4, 1e3, 1e2, 1e1, 1e0};

void appendLibrary(std::string& out, double v) {
  char buf[32];
  out.append(buf, std::to_chars(buf, buf + sizeof buf, v, std::chars_format::general, 6).ptr);
}

}  // namespace

void appendNumber(std::string& out, double v) {
  if (v == 0.0) {  // also turns -0 into 0
    out += '0';
    return;
  }
  const double a = std::fabs(v);
  // %.6g uses fixed notation for exponents -4..5; outside it, leave it to the library.
  if (!(a >= 1e-4 && a < 1e6)) return appendLibrary(out, v);
  int e = -5;  // 10^e <= a < 10^(e+1)
  while (a >= kUpper[e + 5]) ++e;
  long long m = std::llround(a * kScale[e + 5]);  // six significant digits
  if (m >= 1000000) {  // rounded up to the next power of ten
    if (e == 5) return appendLibrary(out, v);
    m = 100000;
    ++e;
  }
  char digits[6];
  for (int i = 5; i >= 0; --i, m /= 10) digits[i] = static_cast<char>('0' + m % 10);
  const int int_digits = e >= 0 ? e + 1 : 0;
  int last = 5;  // drop trailing zeros of the fraction
  while (last >= int_digits && digits[last] == '0') --last;
  if (v < 0.0) out += '-';
  if (e >= 0) {
    out.append(digits, int_digits);
    if (last >= int_digits) {
      out += '.';
      out.append(digits + int_digits, last - int_digits + 1);
    }
  } else {
    out += "0.";
    out.append(-e - 1, '0');
    out.append(digits, last + 1);
  }
}

CsvLog::CsvLog(const std::string& path) : file_(openForWriting(path)) {
  // ~1.3 kB per tick: big buffers, few system calls.
  std::setvbuf(file_, nullptr, _IOFBF, 1 << 20);
  const std::string h = header();
  std::fwrite(h.data(), 1, h.size(), file_);
  line_.reserve(8192);
}

CsvLog::~CsvLog() { onFinish(); }

void CsvLog::onFinish() {
  if (file_) std::fclose(file_);
  file_ = nullptr;
}

void CsvLog::num(double v) {
  line_ += ',';
  appendNumber(line_, v);
}

void CsvLog::uint(uint64_t v) {
  char buf[24];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  line_ += ',';
  line_.append(buf, res.ptr);
}

void CsvLog::onTick(const TickRecord& r) {
  if (!file_) return;
  line_.clear();
  char buf[32];
  line_.append(buf, std::to_chars(buf, buf + sizeof buf, r.time, std::chars_format::fixed, 3).ptr);
  uint(r.tick);
  auto nums = [this](const double* v, int n) {
    for (int i = 0; i < n; ++i) num(v[i]);
  };
  nums(r.base_pos.data(), 3);
  nums(r.base_quat.data(), 4);
  nums(r.base_vel.data(), 3);
  nums(r.base_omega.data(), 3);
  for (const FootTruth& f : r.feet) {
    uint(f.in_contact ? 1 : 0);
    nums(f.force.data(), 3);
    num(f.mu);
    nums(f.normal.data(), 3);
    nums(f.slip_velocity.data(), 3);
    nums(f.position.data(), 3);
  }
  nums(r.disturbance.data(), 3);
  const hal::SensorFrame& s = r.sensors;
  nums(s.q, 12);
  nums(s.qd, 12);
  nums(s.tau, 12);
  nums(s.imu_quat, 4);
  nums(s.imu_gyro, 3);
  nums(s.imu_acc, 3);
  nums(r.tau_applied.data(), 12);
  const hal::Telemetry& t = r.command.telemetry;
  uint(r.command.flags);
  uint(t.stance_mask);
  uint(t.slip_mask);
  uint(t.swing_leg);
  num(t.gait_phase);
  nums(t.base_pos_est, 3);
  nums(t.base_vel_est, 3);
  nums(&t.foot_vel_base[0][0], 12);
  nums(&t.grf_est[0][0], 12);
  nums(&t.grf_des[0][0], 12);
  nums(t.mu_used, 4);
  nums(&t.normal_used[0][0], 12);
  nums(t.mu_hat, 4);
  nums(&t.normal_hat[0][0], 12);
  line_ += '\n';
  std::fwrite(line_.data(), 1, line_.size(), file_);
}

EventLog::EventLog(const std::string& path) : file_(openForWriting(path)) {
  std::fputs("time,tick,event,leg,detail\n", file_);
}

EventLog::~EventLog() { onFinish(); }

void EventLog::onFinish() {
  if (file_) std::fclose(file_);
  file_ = nullptr;
}

void EventLog::add(double time, uint32_t tick, const char* event, int leg,
                   const std::string& detail) {
  if (!file_) return;
  std::fprintf(file_, "%.3f,%u,%s,%s,%s\n", time, tick, event, leg >= 0 ? kLeg[leg] : "",
               detail.c_str());
  ++count_;
}

void EventLog::onTick(const TickRecord& r) {
  const TickRecord& p = previous_;
  const bool dist_now = r.disturbance != std::array<double, 3>{};
  const bool dist_before = !first_ && p.disturbance != std::array<double, 3>{};
  if (dist_now && !dist_before) {
    char d[96];
    std::snprintf(d, sizeof d, "force %g %g %g N", r.disturbance[0], r.disturbance[1],
                  r.disturbance[2]);
    add(r.time, r.tick, "disturbance_start", -1, d);
  }
  if (!dist_now && dist_before) add(r.time, r.tick, "disturbance_end", -1, "");

  for (int leg = 0; leg < 4; ++leg) {
    const FootTruth& f = r.feet[leg];
    const bool was_contact = !first_ && p.feet[leg].in_contact;
    if (f.in_contact != was_contact && !(first_ && !f.in_contact))
      add(r.time, r.tick, f.in_contact ? "touchdown" : "liftoff", leg, "");
    const bool slipping = f.in_contact && f.slip_speed > kTrueSlipSpeed;
    if (slipping != true_slip_[leg]) {
      char d[64];
      std::snprintf(d, sizeof d, "speed %.3g m/s, mu %.3g", f.slip_speed, f.mu);
      add(r.time, r.tick, slipping ? "slip_start" : "slip_end", leg, slipping ? d : "");
      true_slip_[leg] = slipping;
    }
    const uint32_t bit = 1u << leg;
    const uint32_t flag_now = r.command.telemetry.slip_mask & bit;
    const uint32_t flag_before = first_ ? 0u : (p.command.telemetry.slip_mask & bit);
    if (flag_now != flag_before)
      add(r.time, r.tick, flag_now ? "slip_flag_on" : "slip_flag_off", leg, "");
  }
  const uint32_t flags_before = first_ ? 0u : p.command.flags;
  for (const FlagName& fl : kFlags) {
    const bool now = r.command.flags & fl.bit, before = flags_before & fl.bit;
    if (now != before) add(r.time, r.tick, now ? "flag_on" : "flag_off", -1, fl.name);
  }
  previous_ = r;
  first_ = false;
}

std::string jsonString(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char b[8];
      std::snprintf(b, sizeof b, "\\u%04x", c);
      out += b;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::string jsonNumber(double v) {
  if (!std::isfinite(v)) return "null";
  char b[32];
  std::snprintf(b, sizeof b, "%.10g", v);
  return b;
}

void writeSummaryJson(const std::string& path, const SummaryFields& fields) {
  std::FILE* f = openForWriting(path);
  std::fputs("{\n", f);
  for (size_t i = 0; i < fields.size(); ++i)
    std::fprintf(f, "  %s: %s%s\n", jsonString(fields[i].first).c_str(), fields[i].second.c_str(),
                 i + 1 < fields.size() ? "," : "");
  std::fputs("}\n", f);
  std::fclose(f);
}

}  // namespace hyq::sim
