// The friction probe: finds the friction under a stance foot whose cone is
// a guess, at full load, without moving the trunk.
//
// With four feet on the ground, a pair of equal and opposite forces along
// the line between two feet, f on one and -f on the other, adds nothing to
// the net force, and nothing to the net moment ((p_i - p_j) x f = 0 for f
// along p_i - p_j): the trunk's wrench is the QP's, whatever f is. The
// probe ramps such a pair, at a set rate, on the foot it probes and a
// partner. The probed foot's tangential force grows at constant load until
// it breaks away at |f_t| / f_n = mu; the slip detector flags it, and the
// ratio of the GRF estimate over the ticks before the flag (the samples
// aligned with their joint accelerations, their median) is the foot's
// friction, read while it carries 150-500 N, where the estimate's few N
// are a few percent of its load.
// Whichever of the two feet breaks away first is the one measured. A probed
// foot that holds up to max_ratio has at least that friction.
//
// The probed foot is one whose guess is narrowed (kProbeGuessedPartnerRatio)
// if any, else the most loaded guess.
// Bounded: one probe at a time; only while all four feet stand at full
// load (the controller's `allowed`) for settle_time, no foot flagged for
// quiet_time, the probed foot and its partner each carrying min_load,
// neither with a cone's normal off the feet's plane, and the four feet on
// one plane within kProbeMaxTwist. The pair's magnitude
// ramps at `rate` up to max_force (so for at most max_force / rate), and
// the ramp ends when a flag rises, the probe's own watch sees a foot of the
// pair slide (kProbeWatchSpeed), the robot stops being allowed, a foot's
// load drops below min_load, or the partner's commanded force reaches
// partner_margin of its cone (or kProbeGuessedPartnerRatio: then the
// partner is probed too) (a start asks for kProbeStartLoadShare of
// min_load on both feet). The pair then ramps down: after a break-away it
// steps down to kProbeBreakHoldShare of itself (at kProbeStepRate) and
// comes down from there at break_release_rate; else at `rate` (no faster than it
// rose: the ground's tangential compliance gives way with the force, and
// with the crawl's body shift changing the QP's forces at the same time a
// faster release moved a partner foot faster than a slip), until a foot of
// the pair is flagged: it then takes the break-away's step. Each foot is
// probed once per foothold (a probe that ends aborted before its pair
// reached kProbeRetryForce, or whose guessed partner broke away first, or
// whose watch went unconfirmed, does not count: the second at most once
// per partner, then known, the third once per foothold); after a probe the four feet must be
// allowed for settle_time again.
#pragma once
#include <cstdint>

#include "firmware/controller/model/types.hpp"
#include "firmware/controller/params.hpp"

namespace hyq {

// [ticks] The break-away's ratio is the median of the probe's two feet's
// last this many GRF samples: one sample carries the estimate's noise of
// 1-2 % of the load. The samples are the aligned estimate's, a few ticks
// old (ProbeInput::grf_sample): at a flag, which comes 5-15 ticks after the
// break-away, they are of the foot sliding at its friction limit; at the
// watch (kProbeWatchSpeed), which comes as the foot's speed builds up after
// the break-away, of the ticks around it (probe_standing, hyq plant, seeds
// 1-16: every answer within 4.2 %).
inline constexpr int kProbeRatioWindow = 5;

// [-] A probe starts on a foot (and with a partner) carrying at least this
// share of min_load; it ends, aborted, once either carries less than
// min_load. A front foot's load rises through min_load as the crawl shifts
// its trunk toward it, and its estimate's few N of noise took it back under
// within a tick or two of a start there.
inline constexpr double kProbeStartLoadShare = 1.2;

// [N] A probe aborted before its pair reached this leaves its foot to be
// probed again on the same foothold (after settle_time): it has not pulled
// on the foot. A probe dropped (drop(): a bad frame) is not retried.
inline constexpr double kProbeRetryForce = 5.0;

// [m] Four feet further than this off one plane (stanceTwist) stand across
// a change of slope: a foot's cone normal, the plane's, is then not its
// ground's, and its ratio about it is not its friction. No probe starts,
// and a break-away gives no answer. At the foot and the top of the ramp
// (0.25 rad) the probe read mu 0.32-0.39 for 0.5 about normals 8-14 deg
// off; a foot 4 cm up a 0.25 rad slope from the others' plane is 1 cm off.
inline constexpr double kProbeMaxTwist = 0.01;

// [-] A guess is narrowed when partner_margin of it is below this (mostly
// a floor after the foot's own slip, 0.07-0.15: the ground in question). Such a
// foot is probed before the others, and as a partner it is pulled up to
// this ratio: it is probed too, and its break-away is an answer. At
// partner_margin of a floor cone the ramp held at a ratio of 0.05-0.1 on
// the probed foot (ice_patches, ODE seed 1: 22 of 41 probes held so, the
// front right foot found on 2 of its 4 patches). Above the ice patches'
// mu (0.15-0.3); below good ground's. Every guessed partner pulled to
// max_ratio instead broke away on the ramp's mu 0.5 under a guessed 0.6,
// slid at the release without an answer, and took a floor cone.
inline constexpr double kProbeGuessedPartnerRatio = 0.35;

// [-] At a break-away the pair steps down to this share of its force (at
// kProbeStepRate), then falls at break_release_rate. The step takes the
// push off the sliding foot; the rest, let go slowly, keeps the leg from
// springing back and sliding the other way, as it does when the whole pair
// goes within a few ms. probe_standing (ODE), each probe's slide at the
// flag, without the watch below: on the ideal plant 0.69-1.15 mm and
// 12-16 ms (seeds 1-16), on the hyq plant 3.0-3.9 mm and 27-30 ms (seeds
// 1-8); with the whole pair released at 8 000 N/s, 0.94-1.55 mm and
// 15-19 ms, and 4.4-5.5 mm and 37-40 ms (docs/design-notes.md, "The
// friction probe"). With the watch and the step at kProbeStepRate, the hyq
// plant's 1.27-2.03 mm and 19-23 ms (seeds 1-16).
inline constexpr double kProbeBreakHoldShare = 0.3;

// [N/s] The break-away's step, 30 N a tick: a stance leg's commanded torque
// then moves under 25 N m a tick, the ramp's bound without the probe
// (SlipRecovery.SlipperyRampIsClimbedWithoutTorqueSteps). The torque loop
// (the hyq plant's 40 Hz at damping 0.71: 63 % of a step in 7 ms) cannot
// follow a faster step anyway. On the ramp (ODE, seeds 1-8) the pair's
// step in one tick moved a stance hip by 48-51 N m in a tick; at this rate
// 17.6-20.0 N m. probe_standing's slide (ODE, seeds 1-16): 1.18-1.95 mm and
// 18-23 ms in one tick, 1.27-2.03 mm and 19-23 ms at this rate; at
// 20 000 N/s 1.31-2.15 mm and 19-24 ms (12 N m).
inline constexpr double kProbeStepRate = 30000.0;

// The probe's own watch on its two feet. Each foot slides away from the
// force the pair adds to it; once its slip velocity that way passes
// kProbeWatchSpeed for kProbeWatchTicks, the ramp ends and the pair's
// break-away step begins on that tick, some ticks before the detector's flag
// (its threshold, SlipParams::threshold, and debounce). The break-away is then
// confirmed by the detector's own test: the foot's raw detection (above its
// threshold, before debounce) within kProbeWatchConfirmTicks. Confirmed,
// the foot's ratio median over the ticks up to the watch is its friction;
// unconfirmed, no answer, and the foot may be probed once more on the same
// foothold, without the watch (its break-away then read at the flag). A
// foot whose cone normal is unsure gives no answer, as at a flag. The
// watch starts once the pair has reached kProbeRetryForce: a foot moving
// before the pair pulls on it is not breaking away under it. The
// ground's tangential compliance creeps a pulled foot at
// about 0.01 m/s at the ramp's 1 000 N/s (ODE), the velocity's noise is
// 0.01-0.02 m/s: read at the watch without the detector, an answer on a
// crept foot was mu 0.04 for 0.45 (drawn terrain 55, ODE).
inline constexpr double kProbeWatchSpeed = 0.03;  // [m/s]
inline constexpr int kProbeWatchTicks = 2;        // [ticks] consecutive
inline constexpr int kProbeWatchConfirmTicks = 10;  // [ticks] counted from the watch's own tick

// How a probe ended (its counters in telemetry).
enum class ProbeEnd : uint8_t { kFound, kHeld, kAborted };

struct ProbeInput {
  bool allowed = false;        // four feet in stance at full load, recovery on and not freezing
  LegMask stance;              // the stance set: a foot that leaves it may be probed again on its next foothold
  LegMask slipping;            // this tick's slip flags
  LegMask known;               // feet whose friction on this foothold is known (an estimate, the map's, a probe's)
  // Feet whose cone's normal is not the feet's plane's (a change of slope
  // under or near them): their ratio about it is not their friction. Not
  // probed; a break-away of one as a partner ends the probe without an answer.
  LegMask normal_unsure;
  Mat3x4 feet = Mat3x4::Zero();     // [m] foot centres, W
  Mat3x4 grf = Mat3x4::Zero();      // [N] estimated GRF, W (loads, the ramp's ratio)
  // [N] the GRF estimate aligned with its tick's joint accelerations (a
  // few ticks old, GrfDelayLine), W: the break-away's ratio.
  Mat3x4 grf_sample = Mat3x4::Zero();
  Mat3x4 grf_des = Mat3x4::Zero();  // [N] the QP's forces, W
  // [m/s] the feet's slip velocities, W (the detector's, relative to the
  // feet that hold); zero, and velocity_valid false, when it has none.
  Vec3 slip_velocity[kNumLegs] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
  bool velocity_valid = false;
  LegMask fast;                     // feet above the detector's threshold this tick (before debounce)
  Vec3 normal[kNumLegs] = {Vec3::UnitZ(), Vec3::UnitZ(), Vec3::UnitZ(), Vec3::UnitZ()};  // [-] cones' normals, W
  double mu_in_use[kNumLegs] = {0.0, 0.0, 0.0, 0.0};  // [-] the cones' mu
};

struct ProbeOutput {
  Mat3x4 pair = Mat3x4::Zero();  // [N] added to the QP's forces, W (zero while no probe ramps)
  int leg = kNumLegs;            // [-] the probed foot, kNumLegs: none
  int partner = kNumLegs;        // [-] its partner, kNumLegs: none
  // [-] a foot's friction found this tick (the break-away's ratio), 0: none.
  double mu_found[kNumLegs] = {0.0, 0.0, 0.0, 0.0};
  // [-] unit, W: the cone normal that ratio was read about (with mu_found).
  Vec3 normal_found[kNumLegs] = {Vec3::UnitZ(), Vec3::UnitZ(), Vec3::UnitZ(), Vec3::UnitZ()};
  // [-] the ratio a probed foot held without slipping, this tick, 0: none.
  double mu_held[kNumLegs] = {0.0, 0.0, 0.0, 0.0};
};

// |f - (f . n) n| / (f . n): a force's tangential-to-normal ratio about
// unit normal n; a large number (1e9) when f . n is not positive.
double tangentialRatio(const Vec3& f, const Vec3& n);

// [m] How far four feet are from one plane: of the four distances of a foot
// from the plane through the other three, the smallest (0 for coplanar
// feet; a large number, 1e9, when no three of them span a plane).
double stanceTwist(const Mat3x4& feet);

class FrictionProbe {
 public:
  void reset(const ProbeParams& params);
  void update(const ProbeInput& in, double dt, ProbeOutput& out);
  // Ends a probe at once, without an answer and without a release ramp
  // (after a bad frame or a gap: the safe hold has already dropped the pair).
  void drop();
  bool enabled() const { return params_.enabled; }
  // A pair is on the feet (ramping up, or down after its end).
  bool active() const { return leg_ < kNumLegs; }
  uint32_t started() const { return started_; }
  uint32_t found() const { return found_; }
  uint32_t held() const { return held_; }
  uint32_t aborted() const { return aborted_; }

 private:
  void end(ProbeEnd how);
  // The ramp's end: the pair ramps down from here (after a break-away from
  // its step, kProbeBreakHoldShare).
  void endRamp(bool broken);
  // A watch the detector did not confirm: no answer; the foot may be probed
  // once more on this foothold, without the watch.
  void unconfirmed();
  void ramp(const ProbeInput& in, double dt, ProbeOutput& out);
  void release(const ProbeInput& in, double dt, ProbeOutput& out);
  // The watch (kProbeWatchSpeed): true when it has ended the ramp this tick.
  bool watch(const ProbeInput& in);
  // After the watch: the watched foot's answer once the detector confirms it.
  void confirm(const ProbeInput& in, ProbeOutput& out);
  double medianRatio(int foot) const;  // foot 0: the probed one, 1: the partner
  // A foot's guess is narrowed: partner_margin of its mu in use under
  // kProbeGuessedPartnerRatio.
  bool narrowed(const ProbeInput& in, int foot) const;
  // [-] The partner's commanded ratio at which the ramp ends, held:
  // kProbeGuessedPartnerRatio under a narrowed guess (not known, normal not
  // unsure), else partner_margin of its cone.
  double partnerLimit(const ProbeInput& in, int foot) const;
  // Sets unsure_ for this tick; only where a start or a ramp reads it (the
  // four feet's twist is some hundred instructions).
  void findUnsure(const ProbeInput& in);
  // Starts a probe when one is due; false when none is.
  bool tryStart(const ProbeInput& in);
  // The pair down to kProbeBreakHoldShare of itself, then at break_release_rate.
  void stepDown();

  ProbeParams params_{};
  int leg_ = kNumLegs, partner_ = kNumLegs;
  bool releasing_ = false;         // the pair ramps down (the probe has ended)
  bool stepped_ = false;           // the release has taken its step (kProbeBreakHoldShare)
  double step_to_ = 0.0;           // [N] the step's end, kProbeBreakHoldShare of the pair at the break-away
  double release_rate_ = 0.0;      // [N/s] at this rate
  Vec3 direction_ = Vec3::Zero();  // [-] unit, the force added to the probed foot (its partner's is minus it)
  double force_ = 0.0;             // [N] the pair's magnitude
  double peak_ratio_ = 0.0;        // [-] the probed foot's highest ratio during the ramp
  // [-] the two feet's (probed, partner) last kProbeRatioWindow sample ratios, a ring
  double ratios_[2][kProbeRatioWindow] = {};
  int ratio_count_ = 0;            // [-] samples taken in this ramp
  bool partner_guessed_ = false;   // the partner's friction was a guess at the start
  int watch_ticks_[2] = {0, 0};    // [ticks] each pair foot's consecutive ticks over kProbeWatchSpeed
  int watched_ = -1;               // [-] the foot (0: probed, 1: partner) the watch saw slide, -1: none
  Vec3 watched_normal_ = Vec3::UnitZ();  // [-] its cone normal at the watch (the last ratio's)
  int confirm_ticks_ = 0;          // [ticks] since the watch
  LegMask rewatched_;              // feet whose watch went unconfirmed on this foothold (probed again without it)
  double allowed_time_ = 0.0;      // [s] allowed without a break
  double quiet_ = 0.0;             // [s] since the last flag
  LegMask probed_;                 // probed on this foothold
  LegMask unsure_;                 // feet whose cone normal is unsure (ProbeInput::normal_unsure, kProbeMaxTwist), set by findUnsure
  uint32_t started_ = 0, found_ = 0, held_ = 0, aborted_ = 0;
};

}  // namespace hyq
