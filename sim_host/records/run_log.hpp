// The run's files: log.csv (one row per tick), events.csv (edges worth
// reading: contacts, slips, controller flags, disturbances, the fall) and
// summary.json.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "sim_host/records/tick_observer.hpp"

namespace hyq::sim {

// An output that could not be written: "<file>: <the OS's error text>".
struct OutputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// One output file, written under a temporary name in its folder
// (".<name>.<pid>.<n>.tmp") and renamed to its name by commit(): a file
// under the final name is always complete, and a symlink there is replaced
// by the file, never written through. Destroyed without commit() (an
// error, an exception), it removes the temporary. Every failure throws
// OutputError naming the final path and removes the temporary.
class OutputFile {
 public:
  explicit OutputFile(std::string path);
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  void write(const char* data, size_t n);
  void write(std::string_view s) { write(s.data(), s.size()); }
  // Writes what is buffered and closes the temporary; later writes are
  // ignored. Idempotent.
  void close();
  // close(), then renames the temporary to the final name.
  void commit();
  bool isOpen() const { return fd_ >= 0; }
  const std::string& path() const { return path_; }

 private:
  [[noreturn]] void fail(int error);
  void flush();

  std::string path_;
  std::string temp_;     // "" once renamed or removed
  int fd_ = -1;
  std::string buffer_;
};

// Closes every file, then commits them in order: all of them appear under
// their names, or (an error) none of them stays and the error is thrown.
void commitAll(const std::vector<OutputFile*>& files);

// Ground-truth slip for events.csv: tangential speed of the contact point
// above this (the same threshold as the slip metrics, docs/metrics.md).
constexpr double kTrueSlipSpeed = 0.05;   // [m/s]

// log.csv and events.csv are written to an OutputFile: onFinish() closes
// it, and the run commits it (file()) once everything is written. Both
// throw OutputError when a write fails.
class CsvLog final : public TickObserver {
 public:
  explicit CsvLog(const std::string& path);
  void onTick(const TickRecord& r) override;
  void onFinish() override;
  OutputFile& file() { return file_; }

 private:
  void num(double v);
  void uint(uint64_t v);
  OutputFile file_;
  std::string line_;
};

class EventLog final : public TickObserver {
 public:
  explicit EventLog(const std::string& path);
  void onTick(const TickRecord& r) override;
  void onFinish() override;
  // leg < 0: not about one leg.
  void add(double time, uint32_t tick, const char* event, int leg, const std::string& detail);
  int count() const { return count_; }
  OutputFile& file() { return file_; }

 private:
  OutputFile file_;
  bool first_ = true;
  TickRecord previous_{};
  std::array<bool, 4> true_slip_{};
  int count_ = 0;
};

// Appends v with 6 significant digits, as printf's %.6g writes it (the last
// digit may differ in rare half-way cases). Several times faster than
// printf: log.csv writes ~260 numbers per tick.
void appendNumber(std::string& out, double v);

// Renders one JSON value.
std::string jsonString(const std::string& s);
std::string jsonNumber(double v);
// {"key": value, ...} in the given order, one field a line.
std::string summaryJson(const SummaryFields& fields);
// Writes summaryJson(fields) as an OutputFile and commits it.
void writeSummaryJson(const std::string& path, const SummaryFields& fields);

}  // namespace hyq::sim
