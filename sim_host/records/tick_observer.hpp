// Anything that wants every tick's record (log writers, metrics).
#pragma once
#include <string>
#include <utility>
#include <vector>

#include "sim_host/records/tick_record.hpp"

namespace hyq::sim {

// Extra summary.json fields: key and a pre-rendered JSON value
// (e.g. {"max_slip_speed", "0.12"} or {"legs", "[1, 2]"}).
using SummaryFields = std::vector<std::pair<std::string, std::string>>;

class TickObserver {
 public:
  virtual ~TickObserver() = default;
  virtual void onTick(const TickRecord& record) = 0;
  // Called once after the last tick (flush files, finish statistics).
  virtual void onFinish() {}
  // Fields this observer adds to summary.json (called after onFinish).
  virtual SummaryFields summaryFields() const { return {}; }
};

}  // namespace hyq::sim
