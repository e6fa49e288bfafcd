// replay.html: a run as one self-contained page that replays it in 3D (the
// page itself: web/replay/). The page template is built from web/replay/
// (`make web`); this writer inserts the run's data into it as one JSON
// block: the terrain, the slip events, and frames decimated from the 1 kHz
// ticks (docs/replay.md lists the fields).
#pragma once
#include <array>
#include <cstdint>
#include <string>

#include "sim_host/records/run_log.hpp"
#include "sim_host/scenario/scenario.hpp"
#include "sim_host/records/tick_observer.hpp"

namespace hyq::sim {

// The text of the template that stands for the run's data.
constexpr const char* kReplayDataMarker = "/*HYQ_REPLAY_DATA*/";
// A frame on every tick that is a multiple of this (25 Hz), on every tick
// where a foot's contact, stance, slip flag or true slip changes or the
// freeze flag does, and on the last tick.
constexpr int kReplayEveryTicks = 40;
// Longer runs keep fewer periodic frames, at most about this many.
constexpr int kReplayMaxPeriodicFrames = 6000;
// Frames kept for a change of the masks, at most; beyond, only periodic
// frames (a contact or a flag chattering for a long run cannot grow the page
// past about 16 MB).
constexpr int kReplayMaxChangeFrames = 20000;
// [bytes] each list of intervals (true slips, slip flags, freezes), and the
// friction map's writes, at most; later ones are left out.
constexpr size_t kReplayMaxIntervalBytes = 1 << 20;

// Where `make web` puts the page template (this build's web/ folder).
std::string defaultReplayTemplatePath();

// The page template's text. Throws ScenarioError, one line saying how to
// build it, when the file cannot be read or lacks kReplayDataMarker.
std::string readReplayTemplate(const std::string& path);

// Collects the frames during the run; onFinish() writes the page to an
// OutputFile that the run commits (file()) with its other outputs.
class ReplayLog final : public TickObserver {
 public:
  // page_template: readReplayTemplate's text.
  ReplayLog(const std::string& path, std::string page_template, const Scenario& scenario);
  void onTick(const TickRecord& r) override;
  void onFinish() override;
  OutputFile& file() { return file_; }
  int frames() const { return frames_; }
  int periodicTicks() const { return every_; }

 private:
  // What decides which ticks are kept: bit i of each mask is leg i.
  struct Masks {
    uint32_t contact = 0, stance = 0, slip_flag = 0, true_slip = 0;
    bool freeze = false;
    bool operator!=(const Masks& o) const {
      return contact != o.contact || stance != o.stance || slip_flag != o.slip_flag ||
             true_slip != o.true_slip || freeze != o.freeze;
    }
  };
  static Masks masksOf(const TickRecord& r);
  void addFrame(const TickRecord& r, const Masks& m);
  // Opens or closes the [start, end, leg] intervals of one mask's bits.
  void intervals(std::string& out, std::array<double, 4>& start, uint32_t before, uint32_t now,
                 double t);

  OutputFile file_;
  std::string template_;
  Scenario scenario_;
  int every_ = kReplayEveryTicks;
  // Writes into the controller's friction map: [t, x, y, mu, count], the
  // cell's centre [m] in the simulator's world (the controller's world
  // starts at the base's first position).
  void mapWrites(const TickRecord& r);
  // The page's "map": null when the controller keeps none, else the cell's
  // side [m], the age [s] at which a cell is forgotten, and every write.
  std::string mapJson() const;

  std::string frames_json_, slips_json_, flags_json_, freezes_json_, map_json_;
  std::array<double, 2> map_origin_{};  // [m] the controller's world origin in the simulator's
  std::array<double, 4> slip_start_{}, flag_start_{};
  double freeze_start_ = 0.0;
  TickRecord last_{};
  Masks last_masks_{};
  bool any_ = false, last_kept_ = false;
  uint32_t last_kept_tick_ = 0;
  int frames_ = 0;
  int change_frames_ = 0;
  double x_min_ = 0.0, x_max_ = 0.0, y_min_ = 0.0, y_max_ = 0.0;
};

}  // namespace hyq::sim
