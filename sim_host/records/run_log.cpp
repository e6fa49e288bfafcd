#include "sim_host/records/run_log.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <vector>

#include "firmware/controller/model/robot_params.hpp"
#include "sim_host/scenario/scenario.hpp"

namespace hyq::sim {

namespace {
// ~1.3 kB per tick of log.csv: big buffers, few system calls.
constexpr size_t kOutputBuffer = 1 << 20;
}  // namespace

OutputFile::OutputFile(std::string path) : path_(std::move(path)) {
  const size_t slash = path_.rfind('/');
  const std::string dir = slash == std::string::npos ? "" : path_.substr(0, slash + 1);
  const std::string base = slash == std::string::npos ? path_ : path_.substr(slash + 1);
  // O_EXCL: a fresh file, never an existing one nor a symlink's target.
  for (int n = 0; fd_ < 0; ++n) {
    temp_ = dir + "." + base + "." + std::to_string(::getpid()) + "." + std::to_string(n) + ".tmp";
    fd_ = ::open(temp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
    if (fd_ < 0 && (errno != EEXIST || n >= 100)) {
      temp_.clear();
      fail(errno);
    }
  }
  buffer_.reserve(kOutputBuffer);
}

OutputFile::~OutputFile() {
  if (fd_ >= 0) ::close(fd_);
  if (!temp_.empty()) ::unlink(temp_.c_str());
}

void OutputFile::fail(int error) {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  if (!temp_.empty()) ::unlink(temp_.c_str());
  temp_.clear();
  buffer_.clear();
  throw OutputError(clipForMessage(path_, 200) + ": " + std::strerror(error));
}

void OutputFile::flush() {
  size_t done = 0;
  while (done < buffer_.size()) {
    const ssize_t n = ::write(fd_, buffer_.data() + done, buffer_.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) fail(errno);
    done += static_cast<size_t>(n);
  }
  buffer_.clear();
}

void OutputFile::write(const char* data, size_t n) {
  if (fd_ < 0) return;
  if (buffer_.size() + n > kOutputBuffer) flush();
  buffer_.append(data, n);
}

void OutputFile::close() {
  if (fd_ < 0) return;
  flush();
  const int fd = fd_;
  fd_ = -1;
  // The last chance for a delayed write error (e.g. a full disk on NFS).
  if (::close(fd) != 0 && errno != EINTR) fail(errno);
}

void OutputFile::commit() {
  close();
  if (temp_.empty()) return;  // committed before
  // rename() replaces whatever the final name is (a symlink included) and
  // never follows it.
  if (::rename(temp_.c_str(), path_.c_str()) != 0) fail(errno);
  temp_.clear();
}

void commitAll(const std::vector<OutputFile*>& files) {
  for (OutputFile* f : files) f->close();
  std::vector<OutputFile*> done;
  try {
    for (OutputFile* f : files) {
      f->commit();
      done.push_back(f);
    }
  } catch (...) {
    for (OutputFile* f : done) ::unlink(f->path().c_str());
    throw;
  }
}

namespace {

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
  add("probe_leg"), add("probe_partner"), add("probes_started"), add("probes_found"), add("probes_held");
  for (const char* field : {"map_ix", "map_iy", "map_count", "map_mu", "map_spread"})
    for (const char* leg : kLeg) add(std::string(field) + "_" + leg);
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

CsvLog::CsvLog(const std::string& path) : file_(path) {
  file_.write(header());
  line_.reserve(8192);
}

void CsvLog::onFinish() { file_.close(); }

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
  if (!file_.isOpen()) return;
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
  uint(t.probe_leg);
  uint(t.probe_partner);
  for (uint32_t count : t.probe_counts) uint(count);
  for (const auto& w : t.map_writes) num(w.cell[0]);
  for (const auto& w : t.map_writes) num(w.cell[1]);
  for (const auto& w : t.map_writes) uint(w.count);
  for (const auto& w : t.map_writes) num(w.mu);
  for (const auto& w : t.map_writes) num(w.spread);
  line_ += '\n';
  file_.write(line_);
}

EventLog::EventLog(const std::string& path) : file_(path) {
  file_.write("time,tick,event,leg,detail\n");
}

void EventLog::onFinish() { file_.close(); }

void EventLog::add(double time, uint32_t tick, const char* event, int leg,
                   const std::string& detail) {
  if (!file_.isOpen()) return;
  char head[400];  // %.3f of any double fits
  std::snprintf(head, sizeof head, "%.3f,%u,", time, tick);
  std::string line = head;
  line += event;
  line += ',';
  line += leg >= 0 ? kLeg[leg] : "";
  line += ',';
  line += detail.c_str();
  line += '\n';
  file_.write(line);
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

std::string summaryJson(const SummaryFields& fields) {
  std::string out = "{\n";
  for (size_t i = 0; i < fields.size(); ++i) {
    out += "  " + jsonString(fields[i].first) + ": ";
    out += fields[i].second.c_str();
    out += i + 1 < fields.size() ? ",\n" : "\n";
  }
  return out + "}\n";
}

void writeSummaryJson(const std::string& path, const SummaryFields& fields) {
  OutputFile file(path);
  file.write(summaryJson(fields));
  file.commit();
}

}  // namespace hyq::sim
