// The controller's friction map against the ground's true friction, from
// the telemetry's map writes (each foot's write into a cell, as the write
// left the cell). summary.json's "friction_map" holds every cell written
// (its last state) beside the truth; friction_map.json adds the true
// friction on a fine grid under the robot's path, for the figure
// (docs/plots.py) and people.
//
// The controller's world frame starts at the base's first position (x-y),
// with the same axes as the simulator's: a cell (ix, iy) of side s covers
// [ix s, (ix + 1) s) x [iy s, (iy + 1) s) there, which is
// origin + that square in the simulator's world.
#pragma once
#include <array>
#include <map>
#include <string>
#include <utility>

#include "sim_host/records/tick_observer.hpp"

namespace hyq::sim {

class Terrain;

// [m] The controller's world origin in the simulator's (x-y), from the
// run's first tick: the true base position less the estimated one.
std::array<double, 2> controllerOrigin(const TickRecord& first);
// [m] The centre of the controller's cell (ix, iy) of side `size` [m], in
// the simulator's world.
std::array<double, 2> cellCentre(const std::array<double, 2>& origin, int ix, int iy, double size);

class FrictionMapRecord final : public TickObserver {
 public:
  static constexpr double kTruthStep = 0.05;    // [m] friction_map.json's grid of true friction
  static constexpr double kTruthMargin = 0.25;  // [m] the grid's reach beyond the feet's path

  struct Cell {
    int ix = 0, iy = 0;            // [-] the controller's cell coordinates
    double x = 0.0, y = 0.0;       // [m] its centre, the simulator's world
    double mu = 0.0;               // [-] the cell's mean as its last write left it
    double spread = 0.0;           // [-] its estimates' standard deviation
    int count = 0;                 // [-] its estimates
    double time = 0.0;             // [s] of the last write
    double true_mu = 0.0;          // [-] mean of the true mu under the writing feet since the cell (re)started
    double true_mu_centre = 0.0;   // [-] the true mu at the cell's centre (at the last write's time)
    double truth_sum = 0.0;        // [-] sum behind true_mu
  };

  // cell_size [m]: the controller's; json_path empty: no friction_map.json.
  FrictionMapRecord(double cell_size, const Terrain& terrain, std::string json_path);
  void onTick(const TickRecord& record) override;
  void onFinish() override;
  SummaryFields summaryFields() const override;

  const std::map<std::pair<int, int>, Cell>& cells() const { return cells_; }
  int writes() const { return writes_; }
  // [%] |mu - true_mu| / true_mu of a cell.
  static double errorPct(const Cell& c);

 private:
  SummaryFields fields() const;  // friction_map's fields, without the truth's grid

  double cell_size_;
  const Terrain& terrain_;
  std::string json_path_;
  bool have_origin_ = false;
  std::array<double, 2> origin_{};   // [m] the controller's world origin in the simulator's
  std::array<double, 2> low_{}, high_{};  // [m] the feet's path's box, simulator's world
  double last_time_ = 0.0;
  int writes_ = 0;
  std::map<std::pair<int, int>, Cell> cells_;
};

}  // namespace hyq::sim
