// Trot gait, open loop with ideal tracking (feet where their reference is,
// the CoM where the gait asks, at the commanded velocity): its timing (the
// diagonal pairs in turn, the four-foot hand-overs, the clock waiting for a
// foot that has not found the ground), its footholds, its swing reference,
// and starting and stopping from standing.
#include "firmware/controller/gait/trot_gait.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "firmware/controller/model/robot_params.hpp"
#include "tests/unit/gait_world.hpp"

namespace hyq {
namespace {

constexpr double kDt = 0.001;
constexpr double kBodyHeight = 0.6;  // [m]

GaitParams trotParams() {
  GaitParams p;
  p.kind = GaitKind::kTrot;
  p.speed = 0.5;
  return p;
}

class TrotWorld {
 public:
  explicit TrotWorld(const GaitParams& p = trotParams()) : params(p) {
    test::standingStart(kBodyHeight, nominal, in);
    terrain.reset(0.0);
    gait.reset(params, kDt, in, 0.0, nominal);
  }
  // One tick: a swinging foot is where its reference is, down to the ground
  // (below `ground_depth` for the leg `hole_leg`: it finds no ground there);
  // the CoM follows the gait's reference. Returns the lift-off mask.
  uint32_t tick() {
    gait.update(in, terrain, out);
    in.touchdown_mask = LegMask();
    for (int leg = 0; leg < 4; ++leg) {
      const double ground = leg == hole_leg ? -hole_depth : 0.0;
      if (gait.legPhase(leg) != LegPhase::kStance) {
        in.feet_world.col(leg) = out.foot_des[leg];
        if (in.feet_world(2, leg) < ground) in.feet_world(2, leg) = ground;
      }
      if (in.feet_world(2, leg) <= ground + 1e-3) in.touchdown_mask.set(leg);
    }
    in.com_world = Vec3(out.com_des.x(), out.com_des.y(), kBodyHeight);
    in.com_vel_world = out.com_vel_des;
    in.base_world = in.com_world;
    in.foothold_origin = in.base_world + origin_offset;
    ++ticks;
    return out.liftoff_event.bits();
  }
  int airborne() const {
    int n = 0;
    for (int i = 0; i < 4; ++i) n += gait.legPhase(i) != LegPhase::kStance;
    return n;
  }

  GaitParams params;
  Mat3x4 nominal;
  GaitInput in;
  GaitOutput out;
  TerrainEstimator terrain;
  TrotGait gait;
  long ticks = 0;
  int hole_leg = -1;
  double hole_depth = 0.0;  // [m]
  Vec3 origin_offset = Vec3::Zero();  // [m] the footholds' origin from the base (GaitInput::foothold_origin)
};

// Ticks `w` to its first lift-off (at most 4000 ticks), expecting the CoM
// reference to move no faster than kTrotStartShiftSpeed before the commands
// ramp and the CoM within kTrotStartShiftTolerance of `centre` at the
// lift-off. Returns that tick, 0 if none.
long runToFirstLiftoff(TrotWorld& w, const Vec3& centre) {
  Vec3 last = w.in.com_world;
  while (w.ticks < 4000) {
    const uint32_t lifted = w.tick();
    if (w.gait.speedCommand() == 0.0) {  // the shift, before the commands ramp
      EXPECT_LE((w.out.com_des - last).head<2>().norm(), kTrotStartShiftSpeed * kDt + 1e-12) << w.ticks;
    }
    last = w.out.com_des;
    if (lifted) {
      EXPECT_LT((w.in.com_world - centre).head<2>().norm(), kTrotStartShiftTolerance);
      return w.ticks;
    }
  }
  return 0;
}

constexpr uint32_t kPairA = (1u << robot::LF) | (1u << robot::RH);
constexpr uint32_t kPairB = (1u << robot::RF) | (1u << robot::LH);

TEST(TrotGait, DiagonalPairsSwingInTurnHalfAPeriodApart) {
  TrotWorld w;
  const TrotParams& t = w.params.trot;
  std::vector<std::pair<long, uint32_t>> liftoffs;
  long overlap_ticks = 0;  // four feet down between the first lift-off and the end
  for (int k = 0; k < 5000; ++k) {
    const uint32_t lifted = w.tick();
    if (lifted) liftoffs.push_back({w.ticks, lifted});
    ASSERT_LE(w.airborne(), 2) << "tick " << w.ticks;
    // Only one pair is ever in the air.
    uint32_t air = 0;
    for (int i = 0; i < 4; ++i)
      if (w.gait.legPhase(i) != LegPhase::kStance) air |= 1u << i;
    ASSERT_TRUE((air & kPairA) == 0u || (air & kPairB) == 0u) << "tick " << w.ticks;
    if (!liftoffs.empty() && air == 0u) ++overlap_ticks;
  }
  ASSERT_GE(liftoffs.size(), 10u);
  // The first pair lifts once it has unloaded after the start delay.
  EXPECT_EQ(liftoffs[0].second, kPairA);
  EXPECT_NEAR(liftoffs[0].first * kDt, w.params.start_delay + t.unload_time, 2 * kDt);
  const long half = std::lround(0.5 * t.cycle_time / kDt);
  for (size_t k = 1; k < liftoffs.size(); ++k) {
    EXPECT_EQ(liftoffs[k].second, k % 2 == 0 ? kPairA : kPairB) << k;
    EXPECT_NEAR(liftoffs[k].first - liftoffs[k - 1].first, half, 2) << k;
  }
  // Both pairs stand together twice a period, (duty - 0.5) of it each time
  // (the feet land at the end of their swing: ideal tracking).
  const double periods = (5000 - liftoffs[0].first) * kDt / t.cycle_time;
  EXPECT_NEAR(overlap_ticks * kDt / periods, 2.0 * (t.duty_factor - 0.5) * t.cycle_time, 0.015);
}

TEST(TrotGait, TheClockWaitsForAFootThatHasNotFoundTheGround) {
  TrotWorld w;
  w.hole_leg = robot::LF;  // LF's ground is 5 cm lower than planned
  w.hole_depth = 0.05;
  const TrotParams& t = w.params.trot;
  long lf_lift = -1, lf_down = -1, b_lift = -1;
  for (int k = 0; k < 3000 && b_lift < 0; ++k) {
    const uint32_t lifted = w.tick();
    if ((lifted & kPairA) && lf_lift < 0) lf_lift = w.ticks;
    if (lf_lift > 0 && lf_down < 0 && w.out.touchdown_event.has(robot::LF)) lf_down = w.ticks;
    if (lifted & kPairB) b_lift = w.ticks;
    if (w.gait.legPhase(robot::LF) == LegPhase::kSearch) {
      ASSERT_EQ(lifted & kPairB, 0u) << "tick " << w.ticks;
    }
  }
  ASSERT_GT(lf_lift, 0);
  ASSERT_GT(lf_down, 0);
  ASSERT_GT(b_lift, 0);
  // LF searched 5 cm deeper at touchdown_speed; the other pair lifted only
  // after it, the clock having waited.
  const double swing = (1.0 - t.duty_factor) * t.cycle_time;
  EXPECT_NEAR((lf_down - lf_lift) * kDt, swing + 0.05 / t.touchdown_speed, 0.01);
  EXPECT_GT(b_lift, lf_down);
  EXPECT_GT((b_lift - lf_lift) * kDt, 0.5 * t.cycle_time + 0.05);
}

TEST(TrotGait, FootholdIsTheNeutralPointPlusTheVelocityCorrection) {
  TrotWorld w;
  const TrotParams& t = w.params.trot;
  // Past the start and the speed ramp: the commands are at their values.
  while (w.gait.speedCommand() < w.params.speed) w.tick();
  const double swing = (1.0 - t.duty_factor) * t.cycle_time;
  const double stance = t.duty_factor * t.cycle_time;
  const Vec3 base(1.0, 0.2, kBodyHeight);
  const Vec3 v_cmd(w.params.speed, 0.0, 0.0);
  for (int leg = 0; leg < 4; ++leg) {
    for (double s : {0.0, 0.3}) {
      // At the commanded velocity: the hip where it will be at touch-down,
      // half a stance ahead.
      const Vec3 neutral = w.gait.foothold(leg, s, base, v_cmd, w.terrain);
      const Vec3 hip = base + Vec3(w.nominal(0, leg), w.nominal(1, leg), 0.0);
      const Vec3 expected = hip + ((1.0 - s) * swing + 0.5 * stance) * v_cmd;
      EXPECT_NEAR(neutral.x(), expected.x(), 1e-12) << leg;
      EXPECT_NEAR(neutral.y(), expected.y(), 1e-12) << leg;
      EXPECT_NEAR(neutral.z(), 0.0, 1e-12) << leg;  // on the ground plane
      // Faster, and drifting sideways: the foot goes further, by the gain
      // times the error, besides the hip's own travel.
      const Vec3 error(0.2, -0.1, 0.0);
      const Vec3 faster = w.gait.foothold(leg, s, base, v_cmd + error, w.terrain);
      const Vec3 d = faster - neutral - (1.0 - s) * swing * error;
      EXPECT_NEAR(d.x(), t.foothold_gain * error.x(), 1e-12) << leg;
      EXPECT_NEAR(d.y(), t.foothold_gain * error.y(), 1e-12) << leg;
      // A large error's correction is capped.
      const Vec3 big(3.0, 0.0, 0.0);
      const Vec3 far = w.gait.foothold(leg, s, base, v_cmd + big, w.terrain);
      EXPECT_NEAR((far - neutral - (1.0 - s) * swing * big).norm(), t.max_foothold_correction, 1e-12) << leg;
    }
  }
}

// The footholds are centred on GaitInput::foothold_origin (the base moved
// by the CoM offset estimate), not on the base: two walks that differ only
// in that origin land every foot apart by its horizontal offset.
TEST(TrotGait, FootholdsFollowTheirOriginNotTheBase) {
  TrotWorld plain, shifted;
  shifted.origin_offset = Vec3(0.03, 0.015, 0.0);
  int touchdowns = 0;
  for (int k = 0; k < 3000; ++k) {
    plain.tick();
    shifted.tick();
    for (int leg = 0; leg < 4; ++leg) {
      if (!plain.out.touchdown_event.has(leg)) continue;
      ASSERT_TRUE(shifted.out.touchdown_event.has(leg)) << k;
      const Vec3 d = shifted.in.feet_world.col(leg) - plain.in.feet_world.col(leg);
      EXPECT_NEAR(d.x(), 0.03, 1e-9) << leg << " at " << k;
      EXPECT_NEAR(d.y(), 0.015, 1e-9) << leg << " at " << k;
      EXPECT_NEAR(d.z(), 0.0, 1e-9) << leg << " at " << k;
      ++touchdowns;
    }
  }
  EXPECT_GE(touchdowns, 8);
}

TEST(TrotGait, SwingReferenceLandsOnTheFootholdAtTouchdownSpeed) {
  const TrotParams t;
  const double duration = (1.0 - t.duty_factor) * t.cycle_time;
  const Vec3 from(0.3, 0.2, 0.0), to(0.55, 0.18, 0.01);
  Vec3 p, v, a;
  trotSwingReference(from, to, 0.0, duration, t, p, v, a);
  EXPECT_LT((p - from).norm(), 1e-12);
  EXPECT_LT(v.norm(), 1e-12);
  trotSwingReference(from, to, 0.5, duration, t, p, v, a);
  EXPECT_NEAR(p.z(), to.z() + t.step_height, 1e-12);  // the apex, above the higher end
  EXPECT_NEAR(v.z(), 0.0, 1e-12);
  // Above the foothold for the landing part, then down onto it.
  trotSwingReference(from, to, 1.0 - t.landing_fraction, duration, t, p, v, a);
  EXPECT_NEAR(p.x(), to.x(), 1e-12);
  EXPECT_NEAR(p.y(), to.y(), 1e-12);
  EXPECT_GT(p.z(), to.z());
  trotSwingReference(from, to, 1.0, duration, t, p, v, a);
  EXPECT_LT((p - to).norm(), 1e-12);
  EXPECT_NEAR(v.x(), 0.0, 1e-12);
  EXPECT_NEAR(v.y(), 0.0, 1e-12);
  EXPECT_NEAR(v.z(), -t.touchdown_speed, 1e-12);
  // Velocity and acceleration are the derivatives of the path (W, per second).
  const double h = 1e-6;
  for (double s : {0.1, 0.3, 0.45, 0.55, 0.7, 0.85, 0.95}) {
    Vec3 p0, v0, a0, p1, v1, a1;
    trotSwingReference(from, to, s - h, duration, t, p0, v0, a0);
    trotSwingReference(from, to, s + h, duration, t, p1, v1, a1);
    trotSwingReference(from, to, s, duration, t, p, v, a);
    EXPECT_LT(((p1 - p0) / (2.0 * h * duration) - v).norm(), 1e-5) << s;
    EXPECT_LT(((v1 - v0) / (2.0 * h * duration) - a).norm(), 1e-3) << s;
  }
}

TEST(TrotGait, StartsFromStandingAndStopsAfterItsWalkTime) {
  GaitParams p = trotParams();
  p.yaw_rate = 0.2;
  p.trot.walk_time = 3.0;
  TrotWorld w(p);
  // Standing until start_delay: no lift-off, no command.
  for (int k = 0; k < 999; ++k) {
    ASSERT_EQ(w.tick(), 0u);
    ASSERT_EQ(w.gait.speedCommand(), 0.0);
  }
  // The commands ramp up at the acceleration, the turn with the speed.
  for (int k = 0; k < 500; ++k) w.tick();
  EXPECT_NEAR(w.gait.speedCommand(), 0.5 * p.trot.acceleration, 2e-3);
  EXPECT_NEAR(w.gait.yawRateCommand() / w.gait.speedCommand(), p.yaw_rate / p.speed, 1e-9);
  // After walk_time they ramp down; the pair in the air lands, and nothing
  // lifts again: the robot stands, heading turned.
  long last_liftoff = 0;
  for (int k = 0; k < 5000; ++k)
    if (w.tick()) last_liftoff = w.ticks;
  EXPECT_EQ(w.gait.speedCommand(), 0.0);
  EXPECT_EQ(w.airborne(), 0);
  EXPECT_LT(last_liftoff * kDt, p.start_delay + p.trot.walk_time + p.speed / p.trot.acceleration + 0.01);
  EXPECT_GT(w.out.yaw_des, 0.3);  // about 0.2 rad/s for 3 s, less the ramps
  EXPECT_EQ(w.out.com_vel_des.norm(), 0.0);
  for (int leg = 0; leg < 4; ++leg) EXPECT_EQ(w.out.load[leg], 1.0) << leg;  // nothing unloads
}

// Standing on a slope (0.25 rad up x) with the feet 0.225 m uphill of the
// CoM, as under hips along a tilted trunk: before the first lift-off the CoM
// reference moves toward the point where the diagonals cross at
// kTrotStartShiftSpeed, and no foot lifts until the CoM is within
// kTrotStartShiftTolerance of it. On flat ground with the CoM near the
// crossing the trot starts as it stands.
TEST(TrotGait, OnASlopeTheCoMMovesOverTheDiagonalsBeforeTheFirstLiftOff) {
  TrotWorld w;
  const double slope = std::tan(0.25), uphill = 0.225;  // [-], [m]
  for (int leg = 0; leg < 4; ++leg) {
    w.in.feet_world(0, leg) += uphill;
    w.in.feet_world(2, leg) = slope * w.in.feet_world(0, leg);
  }
  ASSERT_TRUE(w.terrain.fit(w.in.feet_world, 0xF));
  w.gait.reset(w.params, kDt, w.in, 0.0, w.nominal);
  const Vec3 start = w.in.com_world;
  // The diagonals of a rectangle cross at its centre.
  const Vec3 centre = 0.25 * w.in.feet_world.rowwise().sum();
  const long first = runToFirstLiftoff(w, centre);
  ASSERT_GT(first, 0);
  // 0.225 m at 0.15 m/s: 1.5 s, past the 1 s start delay; then the trot's
  // own start (unload_time).
  const double shift_time = (centre - start).head<2>().norm() / kTrotStartShiftSpeed;
  EXPECT_NEAR(shift_time, 1.5, 0.01);
  EXPECT_NEAR(first * kDt, shift_time + w.params.trot.unload_time, 0.01);
  EXPECT_GT(first * kDt, w.params.start_delay + w.params.trot.unload_time + 0.4);

  // Flat ground with the CoM 1 cm off the crossing: the reference stays
  // where the CoM stood until the start delay, and the first lift-off comes
  // at start_delay + unload_time.
  TrotWorld flat;
  for (int leg = 0; leg < 4; ++leg) flat.in.feet_world(0, leg) += 0.01;
  flat.gait.reset(flat.params, kDt, flat.in, 0.0, flat.nominal);
  const Vec3 flat_start = flat.in.com_world;
  long flat_first = 0;
  while (flat_first == 0 && flat.ticks < 4000) {
    if (flat.tick()) flat_first = flat.ticks;
    if (flat.gait.speedCommand() == 0.0) {
      EXPECT_EQ((flat.out.com_des - flat_start).head<2>().norm(), 0.0) << flat.ticks;
    }
  }
  EXPECT_NEAR(flat_first * kDt, flat.params.start_delay + flat.params.trot.unload_time, 0.0015);
}

// Flat ground with the feet 0.225 m ahead of the CoM, as where a crawl hands
// over mid-stride: the CoM moves over the diagonals' crossing first, as on
// a slope, and the first pair lifts once it is within the tolerance.
TEST(TrotGait, OnLevelGroundACoMOffTheDiagonalsMovesOverThemFirst) {
  TrotWorld w;
  const double ahead = 0.225;  // [m]
  for (int leg = 0; leg < 4; ++leg) w.in.feet_world(0, leg) += ahead;
  w.gait.reset(w.params, kDt, w.in, 0.0, w.nominal);
  const long first = runToFirstLiftoff(w, 0.25 * w.in.feet_world.rowwise().sum());
  EXPECT_NEAR(first * kDt, ahead / kTrotStartShiftSpeed + w.params.trot.unload_time, 0.01);
}

// Frozen during the start shift (GaitInput::paused), the CoM reference stays
// where it is; the shift goes on once the freeze is over, and the first
// pair lifts later by the freeze's length.
TEST(TrotGait, TheStartShiftHoldsItsReferenceWhileFrozen) {
  const double ahead = 0.225;  // [m]
  TrotWorld plain, frozen;
  for (TrotWorld* w : {&plain, &frozen}) {
    for (int leg = 0; leg < 4; ++leg) w->in.feet_world(0, leg) += ahead;
    w->gait.reset(w->params, kDt, w->in, 0.0, w->nominal);
  }
  const long freeze_from = 300, freeze_ticks = 200;
  long first_plain = 0, first_frozen = 0;
  Vec3 held = Vec3::Zero();
  while ((first_plain == 0 || first_frozen == 0) && frozen.ticks < 6000) {
    if (first_plain == 0 && plain.tick()) first_plain = plain.ticks;
    const bool paused = frozen.ticks >= freeze_from && frozen.ticks < freeze_from + freeze_ticks;
    frozen.in.paused = paused;
    if (first_frozen == 0 && frozen.tick()) first_frozen = frozen.ticks;
    if (frozen.ticks == freeze_from) held = frozen.out.com_des;  // the last tick before the freeze
    if (paused) {
      EXPECT_EQ((frozen.out.com_des - held).head<2>().norm(), 0.0) << frozen.ticks;
    }
  }
  // The shift needs the same number of unfrozen ticks either way.
  EXPECT_GT(first_plain, 0);
  EXPECT_NEAR(first_frozen - first_plain, freeze_ticks, 2) << first_plain << " " << first_frozen;
}

// Cautiousness: with a low mu in use the speed command is held to
// speed_per_mu x mu (the yaw rate with it), approached at the acceleration;
// when the friction comes back it ramps up again; with speed_per_mu 0, or
// without a friction input, the commands are the operator's.
// A swing crosses a stride (speed x period) in (1 - duty_factor) x period;
// above kTrotMaxSwingSpeed on average the swing is lengthened: at 1 m/s and
// duty factor 0.7 (the hyq plant's) it lasts period / 2.7 = 0.222 s, not
// 0.18, and the four-foot hand-overs shrink by as much. At 0.5 m/s the set
// duty factor stands.
TEST(TrotGait, AFastTrotsSwingIsLengthenedToItsSwingSpeedLimit) {
  for (const double speed : {0.5, 1.0}) {
    GaitParams p = trotParams();
    p.speed = speed;
    p.trot.duty_factor = 0.7;
    TrotWorld w(p);
    for (int k = 0; k < 4000; ++k) w.tick();  // standing 1 s, then the ramp: full speed
    ASSERT_NEAR(w.gait.speedCommand(), speed, 1e-9);
    // The next swing of LF, lift-off to touch-down (ideal tracking: at the
    // end of its swing).
    long lifted = -1, landed = -1;
    for (int k = 0; k < 2000 && landed < 0; ++k) {
      const bool before = w.gait.legPhase(0) == LegPhase::kStance;
      w.tick();
      const bool after = w.gait.legPhase(0) == LegPhase::kStance;
      if (before && !after) lifted = w.ticks;
      if (!before && after && lifted >= 0) landed = w.ticks;
    }
    ASSERT_GT(landed, lifted);
    const double swing = (landed - lifted) * kDt;  // [s]
    const double set = (1.0 - p.trot.duty_factor) * p.trot.cycle_time;
    const double limited = speed / kTrotMaxSwingSpeed * p.trot.cycle_time;
    if (speed < 0.6) {
      ASSERT_LT(limited, set);
      EXPECT_NEAR(swing, set, 3 * kDt) << speed;
    } else {
      ASSERT_GT(limited, set);
      EXPECT_NEAR(swing, limited, 3 * kDt) << speed;
      // The stride's average foot speed over the ground at the limit.
      EXPECT_NEAR(speed * p.trot.cycle_time / swing, kTrotMaxSwingSpeed, 0.05);
    }
  }
}

TEST(TrotGait, OnLowFrictionTheSpeedIsHeldToSpeedPerMuTimesMu) {
  GaitParams p = trotParams();
  p.speed = 1.0;
  p.yaw_rate = 0.2;
  ASSERT_GT(p.trot.speed_per_mu, 0.0);
  TrotWorld w(p);
  for (int k = 0; k < 4000; ++k) w.tick();  // standing 1 s, then 2 s of ramp: full speed
  EXPECT_NEAR(w.gait.speedCommand(), 1.0, 1e-9);
  // Ice: the lowest mu in use 0.07 -> at most 7.5 x 0.07 = 0.525 m/s.
  w.in.friction = 0.07;
  const double limit = p.trot.speed_per_mu * 0.07;
  ASSERT_LT(limit, p.speed);
  w.tick();
  const double first = w.gait.speedCommand();
  EXPECT_NEAR(1.0 - first, p.trot.acceleration * kDt, 1e-9);  // down at the acceleration
  for (int k = 0; k < 2000; ++k) w.tick();
  EXPECT_NEAR(w.gait.speedCommand(), limit, 1e-9);
  EXPECT_NEAR(w.gait.yawRateCommand() / w.gait.speedCommand(), p.yaw_rate / p.speed, 1e-9);
  // Back on good ground (mu in use 0.6: 4.5 m/s, above the command).
  w.in.friction = 0.6;
  for (int k = 0; k < 2000; ++k) w.tick();
  EXPECT_NEAR(w.gait.speedCommand(), 1.0, 1e-9);
  // Off: the same ice leaves the command alone.
  GaitParams off = p;
  off.trot.speed_per_mu = 0.0;
  TrotWorld o(off);
  o.in.friction = 0.07;
  for (int k = 0; k < 4000; ++k) o.tick();
  EXPECT_NEAR(o.gait.speedCommand(), 1.0, 1e-9);
  // No friction input (GaitInput's default): no limit.
  TrotWorld d(p);
  for (int k = 0; k < 4000; ++k) d.tick();
  EXPECT_NEAR(d.gait.speedCommand(), 1.0, 1e-9);
}

}  // namespace
}  // namespace hyq
