// The run's files: log.csv (one row per tick), events.csv (edges worth
// reading: contacts, slips, controller flags, disturbances, the fall) and
// summary.json.
#pragma once
#include <array>
#include <cstdint>
#include <cstdio>
#include <string>

#include "sim_host/tick_observer.hpp"

namespace hyq::sim {

// Ground-truth slip for events.csv: tangential speed of the contact point
// above this (the same threshold as the slip metrics, docs/metrics.md).
constexpr double kTrueSlipSpeed = 0.05;   // [m/s]

class CsvLog final : public TickObserver {
 public:
  explicit CsvLog(const std::string& path);  // throws std::runtime_error if it cannot write
  ~CsvLog() override;
  void onTick(const TickRecord& r) override;
  void onFinish() override;

 private:
  void num(double v);
  void uint(uint64_t v);
  std::FILE* file_ = nullptr;
  std::string line_;
};

class EventLog final : public TickObserver {
 public:
  explicit EventLog(const std::string& path);
  ~EventLog() override;
  void onTick(const TickRecord& r) override;
  void onFinish() override;
  // leg < 0: not about one leg.
  void add(double time, uint32_t tick, const char* event, int leg, const std::string& detail);
  int count() const { return count_; }

 private:
  std::FILE* file_ = nullptr;
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
// Writes {"key": value, ...} in the given order.
void writeSummaryJson(const std::string& path, const SummaryFields& fields);

}  // namespace hyq::sim
