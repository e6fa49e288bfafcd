// Surface normal and friction coefficient under one slipping foot
// (Focchi et al., Section 3). One object per leg.
//
// While a foot slips, its velocity v is tangent to the surface and the ground
// reaction force F lies on the friction cone's boundary, in the plane spanned
// by the normal and v. Hence the normal is the part of F orthogonal to v, and
// mu = tan(angle between F and the normal):
//   n_hat  = (F - (F.v_hat) v_hat) / |...|      (= (pi x v)/|pi x v|, pi = v x F/|v x F|)
//   mu_hat = |F x n_hat| / (F . n_hat)
// Samples are filtered: the slip normal by the geodesic (Karcher) mean of the
// last estimate_samples_n unit vectors on the sphere, mu_hat by a linearly
// weighted average of the last estimate_samples_mu values (newest weighted
// most). Beyond the paper, n_hat is that slip normal fused with the terrain
// plane's normal (SurfaceInput::prior) by inverse variance, and mu_hat is taken against
// n_hat.
//
// A sample is rejected (and the filter state left untouched) when any input
// is not finite, |v| < min_slip_speed, v is steeper than max_slip_elevation
// from W's horizontal (a bouncing or lifting foot, not one sliding along the
// ground), |F| < min_estimate_force, the force's error (its acceleration
// term's, and the torque offsets' not yet learnt) exceeds
// max_estimate_force_sigma |F|, F is within
// min_force_slip_angle of +/-v (no usable normal component), F pushes the foot
// along its slip (F.v > 0: friction must oppose the slip, so the force
// estimate is wrong), the sampled normal is tilted more than max_normal_tilt
// from W z, or mu_hat exceeds max_mu_estimate, or the force ratio changes
// with the foot's travel (the slide test, below), or the slip brakes or
// speeds up too fast (the braking test, below).
// The tilt bound is also the antipodal guard of the spherical mean: all
// samples lie in a cap of radius max_normal_tilt (< pi/2) around z, where the
// Karcher mean is unique and the logarithm map is defined.
//
// The slide test. A sliding foot's friction stays on the cone, mu F_n,
// however far it slides; a foot that moves while its contact sticks (the
// contact's elastic give as the tangential force changes, or the build-up
// before a slide breaks away) carries a force ratio that rises with its
// travel, at the contact's tangential stiffness over its load: k / F_n. So
// over the last slide_window ticks (every tick's aligned force and slip
// velocity, flagged or not), the ratio -F.v_hat / |F - (F.v_hat) v_hat| is
// regressed on the travel along the current v_hat; the slope times the mean
// normal force is the stiffness the foot shows. Above max_slide_stiffness
// the sample is not a slide: rising, a give whose ratio is inside the cone
// and says only that mu is higher; falling as fast, a foot re-sticking
// while it still moves, or the force estimate's own transient (its leg
// dynamics at a slide's onset swing it by 10-15 N within a few ticks).
// The same slope is also fitted over the fewest ticks (at least
// slide_window) whose travel reaches slide_travel, and the smaller of the
// two counts: a give shows over both spans, while over a slow slide's few
// 0.1 mm the force estimate's noise alone is a steep slope.
//
// The braking test. Over the last slide_window ticks, the slope of the slip
// speed along v_hat is the slip's acceleration; above max_slide_acceleration
// (either sign) the sample is dropped: the force estimate's acceleration
// term, a fit over several ticks, lags a leg whose acceleration changes that
// fast, and such samples read mu low.
//
// Slip events: samples do not carry across events unless the caller says
// the foot slips again on the same ground (setGaitMode), because the next
// slip may be on a different patch. update() clears the buffers on the
// rising edge of `slipping` otherwise; until the new event has
// min_estimate_samples accepted samples of its own, hasEstimate() is false.
// normal()/mu() always hold the filter over the samples held (the last
// event's until the new event's first sample).
#pragma once

#include "firmware/controller/params.hpp"
#include "firmware/controller/model/types.hpp"

namespace hyq {

// Ring-buffer capacity: estimate_samples_n and estimate_samples_mu are
// clamped to 1..kMaxEstimateSamples.
constexpr int kMaxEstimateSamples = 32;
// Capacity of the slide test's history: slide_window is clamped to
// 2..kMaxSlideWindow.
constexpr int kMaxSlideWindow = 16;

// Geodesic (Karcher) mean of `count` unit vectors: at most `iterations`
// Gauss-Newton steps from `start`, ending after a step shorter than
// `tolerance` [rad] (each step is shorter than the last by about the
// samples' spread squared: the next would be far smaller). Samples
// (nearly) antipodal to the current mean are skipped
// in that step. Returns `start` (normalised) if count == 0.
Vec3 sphericalMean(const Vec3* samples, int count, const Vec3& start, int iterations, double tolerance = 0.0);

// One tick's input of a foot's surface estimate.
struct SurfaceInput {
  bool slipping = false;                 // the foot is watched and flagged, its slip velocity known
  Vec3 slip_velocity = Vec3::Zero();     // [m/s] W
  Vec3 grf = Vec3::Zero();               // [N] the foot's GRF estimate, W
  // [N] the GRF's error from its acceleration term and from the torque
  // offsets its leg has not learnt yet, in quadrature (0 when it is not
  // computed: the gate passes; not finite: the sample is rejected).
  double force_sigma = 0.0;
  bool history_valid = true;             // the slip velocity is known this tick
  // The surface expected under the foot (the footholds' plane), W; fused
  // into normal() by inverse variance (SlipParams::normal_prior_sigma). A
  // zero or non-finite vector: none, and normal() is the slip-based
  // estimate alone.
  Vec3 prior = Vec3::Zero();
  // A second candidate for the prior (the other row's plane, where the
  // ground may change slope between the rows); zero: none. While the foot
  // slips, the candidate its travel lies in (SlipParams::prior_switch_angle,
  // prior_switch_travel) is the prior.
  Vec3 alternative_prior = Vec3::Zero();
  Vec3 foot = Vec3::Zero();              // [m] the foot now, W (the carry-over's distance)
};

class SurfaceEstimator {
 public:
  // dt [s]: the tick period, the time between two update() calls.
  void reset(const SlipParams& params, double dt);
  // Drop all samples (start of a slip event on new ground); keeps the
  // parameters.
  void clearSamples();
  // Per tick: clears on the rising edge of `slipping` (unless the
  // carry-over keeps the samples held), and while slipping offers one
  // sample. Returns true if a sample was accepted. Every tick's pair also
  // goes into the slide test's history, unless `history_valid` is false
  // (the slip velocity is not known this tick), which clears it.
  bool update(const SurfaceInput& in);
  // One sample: slip velocity of the foot [m/s] and GRF on the foot [N], in W,
  // against the ground of the last update() (or setGround()).
  // The slide test needs update()'s history: without slide_window pairs in
  // it (addSample called alone) the test passes.
  bool addSample(const Vec3& slip_velocity_world, const Vec3& grf_world, double force_sigma = 0.0);
  // The force's part along the ground points against the slip within
  // SlipParams::max_friction_slip_angle, in the prior's plane (always true
  // when that angle is 0 or there is no prior).
  bool slidingFriction(const Vec3& slip_velocity_world, const Vec3& grf_world) const;
  // [N/m] The stiffness the history shows along the current slip direction
  // `direction` (unit): the slope of the force ratio on the travel, times
  // the mean normal force, over the last slide_window ticks and over the
  // last slide_travel of travel, the smaller in magnitude; 0 when the
  // history is shorter than the window or its travel does not spread.
  double slideStiffness(const Vec3& direction) const { return slideFit(direction).stiffness; }
  // [m/s^2] The slip's acceleration along `direction` (unit) over the last
  // slide_window ticks: the least-squares slope of the slip speed along it;
  // 0 when the history is shorter than the window.
  double slideAcceleration(const Vec3& direction) const { return slideFit(direction).acceleration; }

  // At least min_estimate_samples accepted in this slip event: one sample is
  // one tick of one force estimate, too easily an outlier to act on.
  bool hasEstimate() const { return own_ >= min_samples_; }
  // The carry-over of samples across slip events (TrotParams::
  // carry_distance [m], carry_agreement and carry_agreement_above [-],
  // carry_max_samples; distance 0: off). Kept by reset().
  void setCarryParams(double distance, double agreement, double agreement_above, int max_samples) {
    carry_distance_ = distance;
    carry_agreement_ = agreement;
    carry_agreement_above_ = agreement_above;
    carry_max_samples_ = max_samples;
  }
  // How the gait in use takes its samples, set when a gait is picked (kept
  // by reset()):
  // - carry_over (the trot): if a slip event begins with the foot
  //   (SurfaceInput::foot) within carry_distance (horizontal) of where the
  //   last sample was taken, and the last event gave fewer than
  //   carry_max_samples of its own (a longer slide stands on its own), the
  //   samples held stay in the filters with the new event's (the foot slips
  //   again on the same ground). From the new event's
  //   min_estimate_samples-th sample of its own on, the mean mu of its own
  //   samples is compared with the carried samples' mean: below it by more
  //   than carry_agreement times it, or above it by more than
  //   carry_agreement_above times it, the carried samples are dropped
  //   (other ground).
  // - peak_of_loaded_samples: how a slip event's peak speed is taken (the
  //   ending slide's reference, SlipParams::ending_slip_fraction): false,
  //   over every sample offered in the last one to two
  //   SlipParams::ending_peak_hold; true, over those that pass the load and
  //   force-uncertainty gates (TrotParams::peak_of_loaded_samples); with
  //   true, too, a foot whose slip speed fell below min_slip_speed after it
  //   had moved gives no more samples in that event (it stopped; what moves
  //   it again is its contact's rebound inside the cone).
  void setGaitMode(bool carry_over, bool peak_of_loaded_samples) {
    carry_enabled_ = carry_over;
    peak_of_loaded_ = peak_of_loaded_samples;
  }
  // Samples of earlier events in the filters (0 once dropped or none kept).
  int carriedSamples() const { return carried_; }
  // The ground addSample() takes samples against, as update() sets it from
  // its input (SurfaceInput::prior, alternative_prior): for tests and tools
  // that offer samples one at a time.
  void setGround(const Vec3& prior, const Vec3& alternative = Vec3::Zero());
  // The prior in use: the input's, or the alternative the travel chose.
  const Vec3& activePrior() const { return use_alternative_ ? alternative_ : prior_; }
  bool usesAlternativePrior() const { return use_alternative_; }
  // [m] The slip velocity summed since this slip event began, W (between
  // events, the last event's until the next one begins).
  const Vec3& travel() const { return travel_; }
  Vec3 normal() const { return normal_; }  // [-] filtered n_hat, W (fused with the prior)
  Vec3 slipNormal() const { return slip_normal_; }  // [-] the slip-based part alone, W
  double mu() const { return mu_; }        // [-] filtered mu_hat
  int sampleCount() const { return count_; }
  // The last accepted raw sample (before filtering), for logging and tests.
  Vec3 lastNormalSample() const { return last_normal_sample_; }

 private:
  void refilter();
  // The carried samples against this event's own (the carry-over): drops
  // them when the two means of mu disagree (each own sample from the
  // min_estimate_samples-th on).
  void checkCarried();
  // Per-event state (peak speed, moved, stopped) to its start.
  void startEvent();
  Vec3 fuseWithPrior(const Vec3& slip_normal, int n_normals) const;
  // Ring index of the k-th newest sample (k = 0: the last one written).
  int newest(int k) const { return (next_ - 1 - k + 2 * kMaxEstimateSamples) % kMaxEstimateSamples; }
  void pushHistory(const Vec3& slip_velocity_world, const Vec3& grf_world);
  // The event's peak slip speed without peak_of_loaded_, with this sample's.
  void updatePeak(double speed);
  // Both slide-window fits in one pass over the history.
  struct SlideFit {
    double stiffness = 0.0;     // [N/m] slideStiffness()
    double acceleration = 0.0;  // [m/s^2] slideAcceleration()
  };
  SlideFit slideFit(const Vec3& direction) const;
  void choosePrior();
  void setPrior(const Vec3& normal);
  void setAlternativePrior(const Vec3& normal);

  SlipParams params_{};
  // The gates' angles as the sines and cosines they are compared by, taken
  // once in reset (a double sine or cosine costs about a hundred
  // instructions on the board, per sample and gate).
  double max_elevation_sine_ = 0.0;     // sin(max_slip_elevation)
  double min_force_angle_sine_ = 0.0;   // sin(min_force_slip_angle)
  double max_tilt_cosine_ = 0.0;        // cos(max_normal_tilt)
  double friction_angle_cosine_ = 0.0;  // cos(max_friction_slip_angle)
  double switch_angle_sine_ = 0.0;      // sin(prior_switch_angle)
  int window_n_ = 4;
  int window_mu_ = 4;
  int min_samples_ = 1;
  Vec3 normals_[kMaxEstimateSamples];
  double mus_[kMaxEstimateSamples] = {};
  Vec3 forces_[kMaxEstimateSamples];  // [N] the GRF of each sample, W
  double force_norms_[kMaxEstimateSamples] = {};  // [N] |GRF| of each sample
  double speeds_[kMaxEstimateSamples] = {};  // [m/s] |slip velocity| of each sample
  int next_ = 0;      // ring index of the next write
  int count_ = 0;     // samples held (<= kMaxEstimateSamples)
  int own_ = 0;       // of which accepted in this slip event
  int carried_ = 0;   // of which kept from earlier events (the carry-over)
  bool carry_enabled_ = false;
  double carry_distance_ = 0.0;   // [m]
  double carry_agreement_ = 0.0;        // [-] the new event's mean below the carried mean
  double carry_agreement_above_ = 0.0;  // [-] ... above it
  int carry_max_samples_ = 0;           // [-]
  Vec3 foot_ = Vec3::Zero();              // [m] W, the foot at the sample offered (SurfaceInput::foot)
  Vec3 last_sample_foot_ = Vec3::Zero();  // [m] W, the foot at the last accepted sample
  bool was_slipping_ = false;
  double peak_speed_ = 0.0;  // [m/s] fastest slip sample in this event (peak_of_loaded_samples)
  // Without peak_of_loaded_: peak_speed_ is the fastest of the last one to two
  // holds (SlipParams::ending_peak_hold; 0: of the whole event).
  int peak_hold_ticks_ = 0;     // [ticks]
  double bucket_now_ = 0.0;     // [m/s] fastest sample offered in the current hold
  double bucket_before_ = 0.0;  // [m/s] ...in the hold before it
  int bucket_age_ = 0;          // [ticks] samples offered in the current hold
  bool peak_of_loaded_ = false;
  bool moved_ = false;    // this event's slip speed has reached min_slip_speed
  bool stopped_ = false;  // ...and has fallen below it since (peak_of_loaded_samples)
  Vec3 normal_ = Vec3::UnitZ();
  Vec3 slip_normal_ = Vec3::UnitZ();
  Vec3 prior_ = Vec3::UnitZ();
  bool has_prior_ = false;
  Vec3 alternative_ = Vec3::UnitZ();  // the alternative prior, unit
  bool has_alternative_ = false;
  bool use_alternative_ = false;      // activePrior() is the alternative
  Vec3 travel_ = Vec3::Zero();        // [m] the slip velocity summed since this slip event began, W
  double mu_ = 0.0;
  Vec3 last_normal_sample_ = Vec3::UnitZ();
  // The slide test's history: every tick's (slip velocity, force), W.
  double dt_ = 0.0;  // [s]
  int slide_window_ = 2;
  Vec3 history_velocity_[kMaxSlideWindow];
  Vec3 history_force_[kMaxSlideWindow];
  int history_next_ = 0;
  int history_count_ = 0;
};

}  // namespace hyq
