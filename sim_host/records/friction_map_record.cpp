#include "sim_host/records/friction_map_record.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "sim_host/physics/terrain.hpp"
#include "sim_host/records/run_log.hpp"

namespace hyq::sim {

std::array<double, 2> controllerOrigin(const TickRecord& first) {
  const hal::Telemetry& t = first.command.telemetry;
  return {first.base_pos[0] - t.base_pos_est[0], first.base_pos[1] - t.base_pos_est[1]};
}

std::array<double, 2> cellCentre(const std::array<double, 2>& origin, int ix, int iy, double size) {
  return {origin[0] + (ix + 0.5) * size, origin[1] + (iy + 0.5) * size};
}

FrictionMapRecord::FrictionMapRecord(double cell_size, const Terrain& terrain, std::string json_path)
    : cell_size_(cell_size), terrain_(terrain), json_path_(std::move(json_path)) {}

double FrictionMapRecord::errorPct(const Cell& c) {
  return c.true_mu > 0.0 ? 100.0 * std::fabs(c.mu - c.true_mu) / c.true_mu : 0.0;
}

void FrictionMapRecord::onTick(const TickRecord& r) {
  const hal::Telemetry& t = r.command.telemetry;
  if (!have_origin_) {
    origin_ = controllerOrigin(r);
    low_ = high_ = {r.base_pos[0], r.base_pos[1]};
    have_origin_ = true;
  }
  last_time_ = r.time;
  for (int leg = 0; leg < hal::kNumLegs; ++leg) {
    const FootTruth& foot = r.feet[leg];
    for (int k = 0; k < 2; ++k) {
      low_[k] = std::min(low_[k], foot.position[k]);
      high_[k] = std::max(high_[k], foot.position[k]);
    }
    const hal::MapWrite& w = t.map_writes[leg];
    if (w.count == 0) continue;
    ++writes_;
    const int ix = w.cell[0], iy = w.cell[1];
    Cell& c = cells_[{ix, iy}];
    if (w.count == 1) c.truth_sum = 0.0;  // the cell (re)started
    c.ix = ix;
    c.iy = iy;
    const std::array<double, 2> centre = cellCentre(origin_, ix, iy, cell_size_);
    c.x = centre[0];
    c.y = centre[1];
    c.mu = w.mu;
    c.spread = w.spread;
    c.count = static_cast<int>(w.count);
    c.time = r.time;
    c.truth_sum += foot.mu;
    c.true_mu = c.truth_sum / c.count;
    c.true_mu_centre = terrain_.muAt(c.x, c.y, r.time);
  }
}

void FrictionMapRecord::onFinish() {
  if (json_path_.empty()) return;
  // The true friction on a grid of kTruthStep over the feet's path.
  const double x0 = low_[0] - kTruthMargin, y0 = low_[1] - kTruthMargin;
  const int nx = std::max(1, static_cast<int>(std::ceil((high_[0] + kTruthMargin - x0) / kTruthStep)));
  const int ny = std::max(1, static_cast<int>(std::ceil((high_[1] + kTruthMargin - y0) / kTruthStep)));
  std::string mu = "[";
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      if (i || j) mu += ',';
      mu += jsonNumber(terrain_.muAt(x0 + (i + 0.5) * kTruthStep, y0 + (j + 0.5) * kTruthStep, last_time_));
    }
  mu += ']';
  SummaryFields f = fields();
  f.push_back({"truth", "{\"x0\": " + jsonNumber(x0) + ", \"y0\": " + jsonNumber(y0) +
                            ", \"step\": " + jsonNumber(kTruthStep) + ", \"nx\": " + std::to_string(nx) +
                            ", \"ny\": " + std::to_string(ny) + ", \"mu\": " + mu + "}"});
  writeSummaryJson(json_path_, f);
}

SummaryFields FrictionMapRecord::summaryFields() const { return {{"friction_map", summaryJson(fields())}}; }

SummaryFields FrictionMapRecord::fields() const {
  std::vector<double> errors;
  std::string list = "[";
  for (const auto& [key, c] : cells_) {
    errors.push_back(errorPct(c));
    if (list.size() > 1) list += ", ";
    list += "{\"x\": " + jsonNumber(c.x) + ", \"y\": " + jsonNumber(c.y) + ", \"mu\": " + jsonNumber(c.mu) +
            ", \"spread\": " + jsonNumber(c.spread) + ", \"count\": " + std::to_string(c.count) +
            ", \"time\": " + jsonNumber(c.time) + ", \"true_mu\": " + jsonNumber(c.true_mu) +
            ", \"true_mu_centre\": " + jsonNumber(c.true_mu_centre) + ", \"error_pct\": " + jsonNumber(errorPct(c)) +
            "}";
  }
  list += "]";
  std::sort(errors.begin(), errors.end());
  const auto within = [&](double pct) {
    return std::count_if(errors.begin(), errors.end(), [pct](double e) { return e <= pct; });
  };
  return {{"cell_size", jsonNumber(cell_size_)},
          {"origin", "[" + jsonNumber(origin_[0]) + ", " + jsonNumber(origin_[1]) + "]"},
          {"writes", std::to_string(writes_)},
          {"error_max_pct", errors.empty() ? "null" : jsonNumber(errors.back())},
          {"within_10pct", std::to_string(within(10.0))},
          {"within_15pct", std::to_string(within(15.0))},
          {"cells", list}};
}

}  // namespace hyq::sim
