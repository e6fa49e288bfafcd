// Traction recovery (Focchi et al., Section 4) plus friction "rise again":
// the surface normal and friction coefficient each stance foot's cone uses
// in the GRF QP, and the freezing-mode decision.
//
// Per leg, per tick:
//  - The foot's ground: the terrain-plane estimate (the plane through all
//    feet), or the foot's own ground plane where that differs from it by more
//    than ground_plane_min_angle (a slope change between the front and hind
//    feet; RecoveryInput::ground_normal). With recovery disabled, always the
//    terrain plane.
//  - Swing: the normal in use is the foot's ground (the QP ignores a swing
//    foot, so a jump here costs no torque step); the correction ends.
//  - Stance, slipping (debounced flag) with an estimate: first-order
//    correction toward the estimate, as in the paper,
//      dtheta = atan2(|n x n_hat|, n . n_hat), e = (n x n_hat)/|n x n_hat|,
//      n <- Rodrigues(e * K_n * dtheta * dt) n,
//      mu <- K_mu dt * mu_hat + (1 - K_mu dt) * mu
//    but mu only downwards (mu_hat < mu): a slip is evidence that the cone in
//    use is too wide, never too narrow; an estimate above the mu in use
//    (a bad sample, or a slip caused by the normal alone) leaves mu alone.
//    And never below mu_floor (mu_hat is clamped to it), nor, on ground
//    tilted by theta (the foot's ground normal vs W z), below
//    slope_floor_factor * tan(theta) / pyramid_scale: a narrower pyramid
//    cannot carry the foot's share of the weight there, so an estimate that
//    low is wrong or the robot cannot stand anyway. When the plane tilts
//    under a foot whose mu is lower, mu rises to the new floor by the same
//    K_mu law.
//    Where that slope floor holds mu in use above the foot's own estimate
//    on this foothold (a slope steeper than its friction allows a margin
//    for: 0.35 rad at mu 0.55), the square pyramid's corners would lie
//    outside the estimated cone. The pyramid then becomes a rectangle about
//    the ground's fall line: the floor's width along it, and across it only
//    what puts the corners on the estimated cone (muAcross; at least
//    mu_floor), reached by the same K_mu law. The floor holds the slope; the
//    foot is no longer loaded sideways beyond its friction.
//    A corrected normal is kept for the rest of that stance (the estimate is
//    better than the plane fit under this foot), until the foot is flagged
//    again and guessed down before a new estimate: any new flag whose event
//    has no estimate yet takes the cone back about the foot's ground (a foot
//    that rolled over a crest onto the other slope slides under its old
//    estimate's cone; a new estimate turns the cone again).
//  - Stance otherwise: an uncorrected normal follows the foot's ground
//    with the same first-order law, so a new plane fit at another leg's
//    touch-down never steps a stance foot's torques. In the crawl, a guess
//    toward the floor goes on while the foot is light (setGuessHolds); behind
//    a torque loop, a loaded stance foot's guess starts at its force ratio
//    (setGuessFromStanceRatio).
//    A stance foot that slides without an estimate, and whose travel
//    (RecoveryInput::slip_travel) has left its ground's plane, stands on
//    other ground: its cone is taken about its ground turned the least to
//    hold the travel, for the rest of that stance (kTravelPlaneLength).
//  Per-tick changes are therefore bounded by K_n*dt*dtheta and K_mu*dt*|mu_hat-mu|,
//  but for the downward start of a loaded stance foot's guess at its force ratio.
//
// Friction rising again (beyond the paper, whose mu can only fall): the
// friction under a foot that stands still cannot change, so mu may only rise
// after the foot has been placed somewhere new. A leg's mu in use rises at
// mu_rise_rate, up to mu_rise_ceiling, once the leg has touched down after its
// last slip and stood slip-free on that foothold for mu_rise_delay. Any slip
// flag stops the rise at once (and the paper's correction pulls mu back down
// to the new estimate); the next rise then needs a new foothold again. With
// the defaults, mu climbs from 0.15 to 0.5 in 1.0 + 0.35/0.15 = 3.33 s of
// slip-free stance on the new foothold, within the 6.8 s stance of a crawl.
//
// Freezing mode (only with RecoveryParams::freeze, off by default): entered
// on the tick at which any stance leg has been flagged
// slipping for freeze_after (the correction did not stop it) while carrying
// at least freeze_min_load (RecoveryInput::normal_force): a nearly unloaded
// foot dragged before lift-off is flagged, correctly, but is no reason to
// stiffen the robot; its slip clock holds while it is unloaded. Left when no
// stance leg has been flagged for freeze_hold seconds in a row (counted from
// entry), i.e. freezing lasts at least freeze_hold; or, at the latest, after
// freeze_max: a frozen robot whose foot keeps creeping on ice would never be
// calm, and stiff joints do not stop a creeping foot, the corrected cones
// might. On exit the slip timers restart, so only a fresh slip that lasts
// freeze_after can re-enter. Estimation and correction keep
// running while frozen; mu does not rise while frozen.
//
// recovery.enabled == false: nothing is corrected and nothing freezes: mu in
// use stays mu_default, the normal in use is the terrain estimate (smoothed as
// above), freezing() is always false. Detection and estimation run elsewhere
// unchanged.
//
// NaN safety: a non-finite or non-unit terrain normal keeps the previous one;
// a non-finite estimate is ignored for that tick; a non-finite or
// non-positive dt skips the tick.
#pragma once
#include <cstdint>

#include "firmware/controller/params.hpp"
#include "firmware/controller/model/types.hpp"

namespace hyq {

constexpr int kRecoveryLegs = kNumLegs;
constexpr double kAssumeLoaded = 1e300;  // [N] RecoveryInput::normal_force when not wired

struct RecoveryInput {
  uint32_t stance_mask = 0;   // bit i: leg i in stance (controller's view)
  uint32_t slip_mask = 0;     // bit i: leg i flagged slipping (debounced)
  bool estimate_valid[kRecoveryLegs] = {false, false, false, false};
  Vec3 normal_estimate[kRecoveryLegs] = {Vec3::UnitZ(), Vec3::UnitZ(), Vec3::UnitZ(),
                                         Vec3::UnitZ()};  // [-] n_hat, W
  double mu_estimate[kRecoveryLegs] = {0.0, 0.0, 0.0, 0.0};  // [-] mu_hat
  Vec3 terrain_normal = Vec3::UnitZ();  // [-] latest terrain-plane fit, W
  // [-] each foot's ground plane (TerrainEstimator::groundNormal), W. Where
  // it differs from terrain_normal by more than
  // RecoveryParams::ground_plane_min_angle, the foot's cone is taken about
  // it (until a slip estimate corrects the foot's normal) and its mu floor
  // is for its slope. Not a unit vector: terrain_normal for that foot.
  Vec3 ground_normal[kRecoveryLegs] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
  // [N] estimated normal GRF of each foot; the default (infinite) counts every
  // foot as loaded. NaN counts as loaded (may freeze: the safe side).
  double normal_force[kRecoveryLegs] = {kAssumeLoaded, kAssumeLoaded, kAssumeLoaded,
                                        kAssumeLoaded};
  // [-] the friction map's mu in the cell under each foot, 0 where it knows
  // none (RecoveryParams::map).
  double map_mu[kRecoveryLegs] = {0.0, 0.0, 0.0, 0.0};
  // [-] a friction probe's answer for a stance foot, 0 where none came this
  // tick (friction_probe.hpp): probe_mu, the friction it found (the foot's
  // friction on this foothold from now on: mu in use goes to
  // estimate_margin x it, at most mu_default and at least the floor, at
  // K_mu, and a later slip brakes toward brake_margin x it); probe_held, a
  // ratio the foot held without slipping (its friction is at least that:
  // mu in use below estimate_margin x it, up to mu_default, rises to it at
  // K_mu, and a guess toward the floor is over). A flag ends the approach.
  double probe_mu[kRecoveryLegs] = {0.0, 0.0, 0.0, 0.0};
  double probe_held[kRecoveryLegs] = {0.0, 0.0, 0.0, 0.0};
  // [-] each foot's estimated |f_t| / f_n about its normal in use (0 where
  // f_n <= 0): where a loaded stance foot's guess starts
  // (TractionRecovery::setGuessFromStanceRatio).
  double force_ratio[kRecoveryLegs] = {0.0, 0.0, 0.0, 0.0};
  // [m] each foot's travel in its slip event so far (the slip velocity
  // summed since its flag rose, SurfaceEstimator::travel), W; zero: none.
  // A stance slide's travel lies in the ground it slides on
  // (kTravelPlaneLength).
  Vec3 slip_travel[kRecoveryLegs] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
};

// Rotates unit vector `from` toward unit vector `to` by the first-order law:
// angle step = min(gain*dt, 1) * angle(from, to), about from x to. Returns
// `from` unchanged if the two are antipodal (no defined axis).
Vec3 rotateToward(const Vec3& from, const Vec3& to, double gain, double dt);

// The slip velocity the slip damping acts on (RecoveryParams::slip_damping),
// W [m/s]: the mean of this tick's v and last tick's v_last (v alone when
// last tick's was not valid), and of that mean its part along the ground of
// unit normal n. A landing foot keeps the part that lifts it off the ground
// (along +n), so a flagged foot that bounces is pressed back down.
// The damping closes a loop through the leg one tick late; on the raw
// velocity it rang at 500 Hz, where the two-tick mean has no gain
// (docs/design-notes.md, "Slip damping rang at 500 Hz").
Vec3 slipDampingVelocity(const Vec3& v, const Vec3& v_last, bool last_valid, const Vec3& n, bool landing);

class TractionRecovery {
 public:
  void reset(const RecoveryParams& params, const Vec3& terrain_normal = Vec3::UnitZ());
  void update(const RecoveryInput& in, double dt);
  // [s] A flag that rises within this long of a foot's touch-down (a
  // landing slide) moves its mu in use toward the floor
  // (RecoveryParams::guess_floor_before_estimate) only once it has lasted
  // this long without an estimate; later flags at once. 0 (the crawl's):
  // every flag at once. Kept by reset().
  void setGuessDelay(double delay) { guess_delay_ = delay; }
  // holds: a guess goes on between flags while the foot carries less than
  // below_load [N] (too little to sample an estimate from); it is over once
  // an estimate comes, the foot carries at least below_load, or it lifts
  // off (RecoveryParams::guess_holds_for_stance, the crawl's). false (the
  // trot's): only while flagged. Kept by reset().
  void setGuessHolds(bool holds, double below_load) {
    guess_holds_ = holds;
    guess_hold_load_ = below_load;
  }
  // [N] A flagged foot that carries more than this, with no estimate, is
  // not guessed down: loaded that much, a slide on the friction cone gives
  // an estimate (SlipParams::min_estimate_force), so a flag without one is
  // a landing's skid or bounce, not ground worse than the cone; unless its
  // flag has lasted kLoadedSlideGuessAge, longer than such a skid. The trot
  // behind a torque loop sets min_estimate_force; kAssumeLoaded (the
  // default): no limit.
  // Kept by reset().
  void setGuessLoadLimit(double load) { guess_load_limit_ = load; }
  // A guess that begins on a foot that has stood kStanceSlideAge and carries
  // kStanceSlideLoad starts at its force ratio where that is below mu in use
  // (params.hpp). false (the default): from mu in use. Kept by reset().
  void setGuessFromStanceRatio(bool on) { guess_from_ratio_ = on; }

  Vec3 normalInUse(int leg) const { return normal_[leg]; }   // [-] W
  double muInUse(int leg) const { return mu_[leg]; }          // [-] cone mu
  // [-] The cone's mu across its ground's fall line, <= muInUse: below it
  // the QP's pyramid is a rectangle (GrfInput::mu_across).
  double muAcross(int leg) const { return mu_across_[leg]; }
  // The mu to put in an inscribed friction pyramid: muInUse * pyramid_scale.
  double muPyramid(int leg) const { return mu_[leg] * params_.pyramid_scale; }
  bool freezing() const { return freezing_; }
  uint32_t freezeCount() const { return freeze_count_; }
  // This stance's normal came from a slip estimate (not the terrain fit), and
  // no flag guessed the foot down since without a new estimate.
  bool corrected(int leg) const { return corrected_[leg]; }
  // The foot's friction on this foothold is known: a slip's estimate, the
  // map's cell or a probe's answer.
  bool knowsFriction(int leg) const { return stance_estimate_[leg] > 0.0 || known_mu_[leg] > 0.0 || held_[leg]; }
  double slipTime(int leg) const { return slip_time_[leg]; }          // [s]
  // [-] The foot's ground turned to hold its stance slide's travel, W
  // (kTravelPlaneLength); zero where none this stance.
  const Vec3& travelGround(int leg) const { return travel_ground_[leg]; }
  bool enabled() const { return params_.enabled; }

 private:
  // k_mu: K_mu's share of one tick (mu <- k_mu * target + (1 - k_mu) * mu).
  // Returns the leg's mu floor on its ground (muFloorFor).
  double updateLeg(int leg, const RecoveryInput& in, double dt, double k_mu);
  // A flagged foot without an estimate is guessed down this tick: light
  // (setGuessLoadLimit) or flagged for kLoadedSlideGuessAge, and past the
  // guess delay (setGuessDelay).
  bool guessDue(int leg, const RecoveryInput& in) const;
  // A guess toward the floor begins: mu in use before it, and a loaded
  // stance foot's start at its force ratio (setGuessFromStanceRatio).
  void beginGuess(int leg, const RecoveryInput& in, double guess_target);
  // A probe's answer for a stance leg (RecoveryInput::probe_mu, probe_held).
  void takeProbe(int leg, const RecoveryInput& in, double floor);
  // mu in use toward a probe's answer at K_mu (no lower than leg_floor):
  // a cone that narrows in one tick steps the QP's forces (48-51 N m at a
  // stance hip on the ramp, ODE). A flag, or a held ratio's target reached
  // from above, ends it. True while it moves mu in use this tick.
  bool approachProbeTarget(int leg, bool slipping, double leg_floor, double k_mu);
  // A leg's touch-down: a new foothold, at once at the map's friction
  // (map_mu > 0: estimate_margin of it, within [floor, mu_default]).
  void touchDown(int leg, double map_mu, double floor);
  // A leg out of stance: its cone about `ground` again, its slip state cleared.
  void leaveStance(int leg, const Vec3& ground);
  // The stance leg's slip clocks, and the brake's release once its slip is over.
  void advanceSlipClocks(int leg, bool slipping, double normal_force, double dt, double k_mu);
  void updateAcross(int leg, double floor, double k_mu);
  // A stance slide without an estimate whose travel leaves `ground`'s plane
  // turns the plane its cone is taken about (travel_ground_; kTravelPlaneLength).
  void turnGroundToTravel(int leg, const RecoveryInput& in, const Vec3& ground);
  Vec3 groundUnder(const Vec3& ground_normal) const;  // [-] the plane a foot's cone is taken about, W
  static double muFloorFor(const RecoveryParams& params, const Vec3& ground);  // [-] lowest mu in use on that ground
  // The floor of a stance whose own estimate's braking target
  // (brake_margin x estimate) lies below the constant floor
  // (RecoveryParams::mu_floor): that target, kEstimatedMuFloor at least.
  // `floor` on a slope whose floor is above the constant one, without an
  // estimate (0), or with a braking target at the floor or above. Guesses
  // (a slip without an estimate) and probe answers keep the floor.
  double floorUnderEstimate(double floor, double estimate) const;
  // The floor a stance's weight asks for: the slope floor, or mu_floor for a light flagged foot.
  double weightFloor(int leg, const RecoveryInput& in, bool stance, double slope_floor);
  void updateFreezing(uint32_t flagged, double dt);

  RecoveryParams params_{};
  double cos_ground_min_ = 1.0;  // [-] cos(params_.ground_plane_min_angle)
  Vec3 terrain_normal_ = Vec3::UnitZ();
  Vec3 normal_[kRecoveryLegs];
  double mu_[kRecoveryLegs] = {};
  double mu_across_[kRecoveryLegs] = {};  // [-] muAcross
  // [-] the last friction estimate that corrected this stance (0: none yet)
  double stance_estimate_[kRecoveryLegs] = {};
  bool corrected_[kRecoveryLegs] = {};
  bool in_stance_[kRecoveryLegs] = {};
  bool new_foothold_[kRecoveryLegs] = {};
  double known_mu_[kRecoveryLegs] = {};  // [-] the map's mu at this stance's touch-down, or a probe's, 0: none
  bool held_[kRecoveryLegs] = {};        // a probe held on this foothold (RecoveryInput::probe_held)
  // Slipping before any estimate: mu in use was sent toward the floor; once
  // the estimate comes, mu in use follows it either way until the slip ends.
  bool guessing_[kRecoveryLegs] = {};
  double mu_before_guess_[kRecoveryLegs] = {};  // mu in use when the guess began
  // A guess began this stance and no estimate has come since (the guess goes
  // on between flags: setGuessHolds).
  bool guess_pending_[kRecoveryLegs] = {};
  // [-] where mu in use returns after a braked slip (estimate_margin *
  // mu_hat at the end of the slip); 0 = nothing to return to
  double mu_settle_[kRecoveryLegs] = {};
  // [-] where a probe's answer takes mu in use at K_mu (approachProbeTarget);
  // 0 = nothing to reach
  double probe_target_[kRecoveryLegs] = {};
  bool probe_target_held_[kRecoveryLegs] = {};  // the target is a held ratio's: only up
  double mu_before_slip_[kRecoveryLegs] = {};  // mu in use when the flag rose
  bool was_slipping_[kRecoveryLegs] = {};      // flagged on the previous tick
  double slip_time_[kRecoveryLegs] = {};
  double slip_free_time_[kRecoveryLegs] = {};
  double flagged_time_[kRecoveryLegs] = {};  // [s] flagged without a break, this stance
  double stance_time_[kRecoveryLegs] = {};   // [s] since this stance began
  double guess_delay_ = 0.0;                 // [s] setGuessDelay
  bool guess_holds_ = false;                 // setGuessHolds
  double guess_hold_load_ = 0.0;             // [N] setGuessHolds
  double guess_load_limit_ = kAssumeLoaded;  // [N] setGuessLoadLimit (kAssumeLoaded: none)
  bool light_slide_[kRecoveryLegs] = {false, false, false, false};  // flagged while light this stance, still light
  // [-] the foot's ground turned to hold its slide's travel, W; zero: none
  // this stance (turnGroundToTravel)
  Vec3 travel_ground_[kRecoveryLegs] = {Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
  bool guess_from_ratio_ = false;             // setGuessFromStanceRatio
  bool freezing_ = false;
  double calm_time_ = 0.0;
  double frozen_time_ = 0.0;
  uint32_t freeze_count_ = 0;
};

}  // namespace hyq
