// Crawl gait, open loop with ideal CoM tracking (the CoM is wherever the gait
// asks): the crawl walks; a foot that slides after the body shift was planned
// does not stall it (the shift is re-planned into the new triangle), nor does
// a CoM held short of the lift-off margin (the trunk crouches); a freeze
// called mid-swing puts the swinging foot straight down where it is; a
// lift-off waits while the CoM moves toward the lifting foot, a trunk
// tipping toward the swinging foot puts it down, and one tipping toward the
// unloading foot loads it again; on a slope a body shift
// brakes within the friction the slope leaves.
#include "firmware/controller/gait/crawl_gait.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <vector>

#include "firmware/controller/model/robot_params.hpp"
#include "tests/unit/gait_world.hpp"

namespace hyq {
namespace {

constexpr double kDt = 0.001;
constexpr double kBodyHeight = 0.6;  // [m]

// Signed distance of p inside triangle abc (xy plane), > 0 inside.
double marginInside(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& p) {
  const Vec3 v[3] = {a, b, c};
  const double orientation = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
  double m = 1e9;
  for (int k = 0; k < 3; ++k) {
    const Vec3& s = v[k];
    const Vec3& e = v[(k + 1) % 3];
    const double ex = e.x() - s.x(), ey = e.y() - s.y();
    const double cross = ex * (p.y() - s.y()) - ey * (p.x() - s.x());
    const double d = (orientation > 0.0 ? cross : -cross) / std::hypot(ex, ey);
    m = d < m ? d : m;
  }
  return m;
}

class CrawlWorld {
 public:
  CrawlWorld() {
    test::standingStart(kBodyHeight, nominal, in);
    terrain.reset(0.0);
    gait.reset(params, kDt, in, 0.0, nominal);
  }
  // One tick: swing feet follow their reference down to the ground, the CoM
  // follows the gait's reference exactly. Returns the lift-off mask.
  uint32_t tick() {
    gait.update(in, terrain, out);
    for (int leg = 0; leg < 4; ++leg) {
      if (gait.legPhase(leg) != LegPhase::kStance) {
        in.feet_world.col(leg) = out.foot_des[leg];
        if (in.feet_world(2, leg) < 0.0) in.feet_world(2, leg) = 0.0;
      }
    }
    in.touchdown_mask = LegMask();
    for (int leg = 0; leg < 4; ++leg)
      if (in.feet_world(2, leg) <= 1e-3) in.touchdown_mask.set(leg);
    in.com_world = pin_com ? pinned_com : Vec3(out.com_des.x(), out.com_des.y(), kBodyHeight);
    in.base_world = in.com_world;
    return out.liftoff_event.bits();
  }
  // Ticks until some leg lifts off (at most `limit`); which leg in `leg`.
  int runToLiftoff(int limit, int& leg) {
    for (int k = 1; k <= limit; ++k) {
      const uint32_t lifted = tick();
      for (int i = 0; i < 4; ++i)
        if ((lifted >> i) & 1u) {
          leg = i;
          return k;
        }
    }
    leg = -1;
    return -1;
  }

  // A CoM held where it is, whatever the gait asks (a leg at its reach).
  bool pin_com = false;
  Vec3 pinned_com = Vec3::Zero();

  GaitParams params;
  Mat3x4 nominal;
  GaitInput in;
  GaitOutput out;
  TerrainEstimator terrain;
  CrawlGait gait;
};

TEST(CrawlGait, WalksForwardOneLegAtATimeWithTheCoMInsideTheTriangle) {
  CrawlWorld w;
  const int cycle_ticks = static_cast<int>(w.params.cycle_time / kDt);
  int lifts = 0;
  for (int k = 0; k < 2 * cycle_ticks + 2000; ++k) {
    const uint32_t lifted = w.tick();
    int swinging = 0;
    for (int i = 0; i < 4; ++i) swinging += w.gait.legPhase(i) != LegPhase::kStance;
    ASSERT_LE(swinging, 1) << "tick " << k;
    for (int i = 0; i < 4; ++i) {
      if (!((lifted >> i) & 1u)) continue;
      ++lifts;
      Vec3 tri[3];
      int n = 0;
      for (int j = 0; j < 4; ++j)
        if (j != i) tri[n++] = w.in.feet_world.col(j);
      EXPECT_GE(marginInside(tri[0], tri[1], tri[2], w.in.com_world), w.params.liftoff_margin - 1e-9);
    }
  }
  EXPECT_GE(lifts, 8);  // two cycles: every leg twice
  // Forward at about the commanded speed (one stride per cycle).
  EXPECT_GT(w.in.com_world.x(), 0.5 * w.params.speed * 2.0 * w.params.cycle_time);
}

// How far each lift-off's foot trails its stand place under the trunk
// (along x, the CoM where the gait put it) [m], in lift-off order, over
// `cycles` cycles of a crawl at `speed` [m/s] on flat ground.
std::vector<double> liftoffTrails(double speed, int cycles) {
  CrawlWorld w;
  w.params.speed = speed;
  w.gait.reset(w.params, kDt, w.in, 0.0, w.nominal);
  std::vector<double> trails;
  const int cycle_ticks = static_cast<int>(w.params.cycle_time / kDt);
  for (int k = 0; k < cycles * cycle_ticks; ++k) {
    const Vec3 com = w.in.com_world;
    const Mat3x4 feet = w.in.feet_world;
    const uint32_t lifted = w.tick();
    for (int i = 0; i < 4; ++i)
      if ((lifted >> i) & 1u) trails.push_back(com.x() + w.nominal(0, i) - feet(0, i));
  }
  return trails;
}

// From the stand each foothold is the other feet's centre plus half a
// stride, so the first cycle's fourth foot trails further than any foot of
// the steady crawl: at 0.08 m/s 0.39 m behind its stand place, the body
// shift included, against 0.28 m (a knee on its stop on the hyq plant).
// The stride starts at kCrawlStartStride and grows by at most
// kCrawlStrideGrowth, so no foot on the way trails more than 2 mm further
// than the steady crawl's (measured: 0.279 m against 0.278 m; the open-loop
// crawl is deterministic), and at the default speed nothing changes.
TEST(CrawlGait, FromTheStandNoFootTrailsFurtherThanInTheSteadyCrawl) {
  ASSERT_LE(GaitParams{}.speed * GaitParams{}.cycle_time, kCrawlStartStride);
  const std::vector<double> fast = liftoffTrails(0.08, 5);
  ASSERT_GE(fast.size(), 18u);
  const auto last_cycle = fast.end() - 4;
  const double on_the_way = *std::max_element(fast.begin(), last_cycle);
  const double steady = *std::max_element(last_cycle, fast.end());
  std::printf("lift-off trails [m]:");
  for (double t : fast) std::printf(" %.3f", t);
  std::printf("\nmost on the way %.3f m, steady %.3f m\n", on_the_way, steady);
  EXPECT_LE(on_the_way, steady + 2e-3);
  EXPECT_GT(steady, 0.25);  // the steady crawl at 0.08 m/s: 0.38 of its 0.64 m stride, and the shift
}

// Each leg's highest swing reference above its lift-off height [m], over
// two cycles of a crawl on flat ground with the given apex.
std::array<double, 4> swingApexes(double step_height) {
  CrawlWorld w;
  w.params.step_height = step_height;
  w.gait.reset(w.params, kDt, w.in, 0.0, w.nominal);
  std::array<double, 4> apex = {-1.0, -1.0, -1.0, -1.0};
  const int cycle_ticks = static_cast<int>(w.params.cycle_time / kDt);
  for (int k = 0; k < 2 * cycle_ticks + 2000; ++k) {
    w.tick();
    for (int i = 0; i < 4; ++i)
      if (w.gait.legPhase(i) == LegPhase::kSwing) apex[i] = std::max(apex[i], w.out.foot_des[i].z());
  }
  return apex;
}

// The front feet meet ground no foot has stood on, so they swing at least
// kFrontStepHeight high; the hind feet step where the front feet stood,
// at the gait's own apex (lower on the hyq plant: its landings bounce
// less from there).
TEST(CrawlGait, TheFrontFeetSwingAtLeastTheFrontApex) {
  const std::array<double, 4> low = swingApexes(0.06);
  EXPECT_NEAR(low[robot::LF], kFrontStepHeight, 1e-3);
  EXPECT_NEAR(low[robot::RF], kFrontStepHeight, 1e-3);
  EXPECT_NEAR(low[robot::LH], 0.06, 1e-3);
  EXPECT_NEAR(low[robot::RH], 0.06, 1e-3);
  // An apex above it is every foot's.
  const std::array<double, 4> high = swingApexes(0.12);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(high[i], 0.12, 1e-3) << "leg " << i;
}

TEST(CrawlGait, AFootSlidingAfterTheShiftIsPlannedDoesNotStallTheCrawl) {
  CrawlWorld w;
  int leg = -1;
  // The first lift-off, then that leg's touch-down: the four-foot phase in
  // which the shift toward the next triangle is planned.
  ASSERT_GT(w.runToLiftoff(20000, leg), 0);
  for (int k = 0; k < 20000 && w.gait.legPhase(leg) != LegPhase::kStance; ++k) w.tick();
  ASSERT_EQ(w.gait.legPhase(leg), LegPhase::kStance);
  for (int k = 0; k < 100; ++k) w.tick();

  // Which leg lifts next (a copy of the world, run ahead).
  CrawlWorld ahead = w;
  int next = -1;
  ASSERT_GT(ahead.runToLiftoff(20000, next), 0);

  // Its lateral neighbour slides 25 cm forward (as a foot can on
  // ice_patches' ice): the planned target is no longer inside
  // the triangle the lift-off check uses.
  const int lateral = next ^ 1;  // LF<->RF, LH<->RH
  w.in.feet_world(0, lateral) += 0.25;
  Vec3 tri[3];
  int n = 0;
  for (int j = 0; j < 4; ++j)
    if (j != next) tri[n++] = w.in.feet_world.col(j);

  // The crawl goes on: `next` lifts off within a bounded time, with the CoM
  // inside the new triangle by the lift-off margin.
  const int limit = static_cast<int>((w.params.cycle_time + 0.25 / w.params.reshift_speed) / kDt);
  int lifted = -1;
  ASSERT_GT(w.runToLiftoff(limit, lifted), 0) << "the crawl stalled";
  EXPECT_EQ(lifted, next);
  EXPECT_GE(marginInside(tri[0], tri[1], tri[2], w.in.com_world), w.params.liftoff_margin - 1e-9);
}

// A CoM held 1.5 cm inside the coming triangle: a hind foot dragged back by
// a slide, its knee straight, holds the body back short of the 3 cm
// lift-off margin. Waiting for the margin, the crawl would stall for good.
// It waits liftoff_wait_max after the shift, then crouches. reach_gain
// [m/m]: how far the held CoM can then move toward its target per metre of
// crouch (0: not at all). Returns the lift-off's delay [s] against a free
// CoM's (-1: none in 20 s), the leg, the CoM's margin at the lift-off and
// the deepest crouch; `w` is left 3 s after the lift-off.
struct HeldLiftoff {
  int leg = -1, expected_leg = -2;
  double delay = -1.0, margin = 0.0, deepest = 0.0;
};
// The first lift-off and touch-down, and 100 ticks on: the four-foot
// phase of the next shift. False if no leg lifted.
bool toTheSecondShift(CrawlWorld& w) {
  int leg = -1;
  if (w.runToLiftoff(20000, leg) <= 0) return false;
  for (int k = 0; k < 20000 && w.gait.legPhase(leg) != LegPhase::kStance; ++k) w.tick();
  for (int k = 0; k < 100; ++k) w.tick();
  return true;
}

HeldLiftoff liftoffWithTheCoMHeld(CrawlWorld& w, double reach_gain) {
  HeldLiftoff h;
  EXPECT_TRUE(toTheSecondShift(w));
  // The next lift-off with the CoM free: which leg, when, the CoM then.
  CrawlWorld ahead = w;
  const int free_ticks = ahead.runToLiftoff(20000, h.expected_leg);
  EXPECT_GT(free_ticks, 0);
  Vec3 tri[3];
  int n = 0;
  for (int j = 0; j < 4; ++j)
    if (j != h.expected_leg) tri[n++] = w.in.feet_world.col(j);
  // The point 1.5 cm inside the triangle on the way from the CoM now to the
  // CoM at that lift-off (the margin is concave along the way).
  const Vec3 from = w.in.com_world, to = ahead.in.com_world;
  double lo = 0.0, hi = 1.0;
  for (int k = 0; k < 60; ++k) {
    const double mid = 0.5 * (lo + hi);
    (marginInside(tri[0], tri[1], tri[2], from + mid * (to - from)) < 0.015 ? lo : hi) = mid;
  }
  const Vec3 held = from + hi * (to - from);
  const Vec3 toward = (to - held).normalized();
  w.pin_com = true;
  int k = 0;
  for (; k < 20000 && h.leg < 0; ++k) {
    w.pinned_com = held + reach_gain * w.out.crouch * toward;
    const uint32_t lifted = w.tick();
    h.deepest = std::fmax(h.deepest, w.out.crouch);
    for (int i = 0; i < 4; ++i)
      if ((lifted >> i) & 1u) h.leg = i;
  }
  if (h.leg < 0) return h;
  h.delay = (k - free_ticks) * kDt;
  h.margin = marginInside(tri[0], tri[1], tri[2], w.in.com_world);
  for (int j = 0; j < 3000; ++j) w.tick();
  return h;
}

TEST(CrawlGait, ACoMHeldShortOfTheMarginMakesTheTrunkCrouchAndTheCrawlGoesOn) {
  const GaitParams defaults;
  const double crouch_time = defaults.crouch_max / defaults.crouch_speed;  // [s]
  {
    // Waiting for the margin for ever: no lift-off, no crouch.
    CrawlWorld w;
    w.params.liftoff_wait_max = 1e6;
    w.gait.reset(w.params, kDt, w.in, 0.0, w.nominal);
    const HeldLiftoff h = liftoffWithTheCoMHeld(w, 0.0);
    EXPECT_EQ(h.leg, -1) << "waiting for the margin, no lift-off in 20 s";
    EXPECT_EQ(h.deepest, 0.0);
  }
  {
    // Crouching lets the leg reach: the CoM gets the margin part way down.
    CrawlWorld w;
    const HeldLiftoff h = liftoffWithTheCoMHeld(w, 1.0);
    std::printf("reach with the crouch: lift-off %.3f s late, margin %.1f mm, crouched %.1f mm\n", h.delay,
                1e3 * h.margin, 1e3 * h.deepest);
    EXPECT_EQ(h.leg, h.expected_leg);
    EXPECT_GE(h.margin, defaults.liftoff_margin);
    EXPECT_GT(h.deepest, 0.0);
    EXPECT_LT(h.deepest, defaults.crouch_max);
    EXPECT_GE(h.delay, defaults.liftoff_wait_max);
    EXPECT_EQ(w.out.crouch, 0.0) << "risen again 3 s after the lift-off";
  }
  {
    // No reach gained: crouched to crouch_max, it lifts with the CoM inside.
    CrawlWorld w;
    const HeldLiftoff h = liftoffWithTheCoMHeld(w, 0.0);
    std::printf("no reach: lift-off %.3f s late, margin %.1f mm\n", h.delay, 1e3 * h.margin);
    ASSERT_EQ(h.leg, h.expected_leg) << "the crawl stalled";
    EXPECT_GE(h.margin, 0.0);
    EXPECT_DOUBLE_EQ(h.deepest, defaults.crouch_max);
    EXPECT_GE(h.delay, defaults.liftoff_wait_max + crouch_time);
    EXPECT_LE(h.delay, defaults.liftoff_wait_max + crouch_time + defaults.unload_time + 0.01);
  }
}

// The lift-off looks at where the CoM is going as well as where it is: a
// trunk moving toward the foot about to lift (a push) holds the lift-off
// for as long as it moves; moving the other way, into the triangle, it
// does not. 0.3 m/s carries the CoM about 7 cm over the pendulum's time
// constant (sqrt(0.6 m / g), 0.25 s), more than the shift's 5 cm margin.
TEST(CrawlGait, ALiftOffWaitsWhileTheCoMMovesTowardTheLiftingFoot) {
  CrawlWorld w;
  ASSERT_TRUE(toTheSecondShift(w));
  CrawlWorld still = w;
  int next = -1;
  const int free_ticks = still.runToLiftoff(20000, next);
  ASSERT_GT(free_ticks, 0);
  ASSERT_LT(free_ticks * kDt, 1.0);
  Vec3 toward = w.in.feet_world.col(next) - still.in.com_world;
  toward.z() = 0.0;
  toward.normalize();

  CrawlWorld inward = w;
  inward.in.com_vel_world = -0.3 * toward;
  int inward_leg = -1;
  EXPECT_EQ(inward.runToLiftoff(20000, inward_leg), free_ticks) << "moving into the triangle: on time";
  EXPECT_EQ(inward_leg, next);

  CrawlWorld pushed = w;
  pushed.in.com_vel_world = 0.3 * toward;
  const int hold_ticks = free_ticks + 1000;
  int pushed_leg = -1;
  for (int k = 0; k < hold_ticks && pushed_leg < 0; ++k) {
    const uint32_t lifted = pushed.tick();
    for (int i = 0; i < 4; ++i)
      if ((lifted >> i) & 1u) pushed_leg = i;
  }
  EXPECT_EQ(pushed_leg, -1) << "no lift-off while the CoM moves toward the lifting foot";
  pushed.in.com_vel_world.setZero();
  const int after_ticks = pushed.runToLiftoff(20000, pushed_leg);
  EXPECT_GT(after_ticks, 0);
  EXPECT_LE(after_ticks * kDt, w.params.unload_time + 0.01) << "the CoM at rest again: it lifts";
  EXPECT_EQ(pushed_leg, next);
}

// The body shift's peak horizontal acceleration over two and a half
// cycles: with max_shift_acceleration the shifts are lengthened to keep
// within it, and the crawl still walks (every leg lifts at least twice).
TEST(CrawlGait, AnAccelerationBoundLengthensTheBodyShifts) {
  auto peak = [](double bound, int& lifts) {
    CrawlWorld w;
    w.params.max_shift_acceleration = bound;
    w.gait.reset(w.params, kDt, w.in, 0.0, w.nominal);
    double a_max = 0.0;  // [m/s^2]
    lifts = 0;
    for (int k = 0; k < static_cast<int>(2.5 * w.params.cycle_time / kDt); ++k) {
      lifts += __builtin_popcount(w.tick());
      a_max = std::fmax(a_max, w.out.com_acc_des.head<2>().norm());
    }
    return a_max;
  };
  int lifts_free = 0, lifts_bound = 0;
  const double free_peak = peak(0.0, lifts_free);
  const double bound_peak = peak(0.5, lifts_bound);
  std::printf("peak shift acceleration: %.2f m/s^2 free, %.2f m/s^2 bound to 0.5\n", free_peak, bound_peak);
  EXPECT_GT(free_peak, 1.0);  // the four-foot phase's shifts
  EXPECT_LE(bound_peak, 0.5 + 1e-9);
  EXPECT_GE(lifts_free, 8);
  EXPECT_GE(lifts_bound, 8);
}

TEST(CrawlGait, AFreezeCalledMidSwingPutsTheFootStraightDown) {
  CrawlWorld w;
  int leg = -1;
  ASSERT_GT(w.runToLiftoff(20000, leg), 0);
  // Half-way through the swing: the foot is high and moving forward.
  const int half_swing =
      static_cast<int>(0.5 * (1.0 - w.params.duty_factor) * w.params.cycle_time / kDt);
  for (int k = 0; k < half_swing; ++k) w.tick();
  ASSERT_EQ(w.gait.legPhase(leg), LegPhase::kSwing);
  const Vec3 foot = w.in.feet_world.col(leg);
  ASSERT_GT(foot.z(), 0.05);

  // Freeze called (the gait is paused): the foot goes down where it is.
  w.in.paused = true;
  w.gait.update(w.in, w.terrain, w.out);
  EXPECT_EQ(w.gait.legPhase(leg), LegPhase::kSearch);
  EXPECT_NEAR(w.out.foot_des[leg].x(), foot.x(), 1e-9);
  EXPECT_NEAR(w.out.foot_des[leg].y(), foot.y(), 1e-9);
  EXPECT_NEAR(w.out.foot_des[leg].z(), foot.z() - w.params.freeze_drop_speed * kDt, 1e-9);
  EXPECT_NEAR(w.out.foot_vel_des[leg].z(), -w.params.freeze_drop_speed, 1e-12);
  EXPECT_FALSE(w.out.stance_mask.has(leg));

  // It reaches the ground at the drop speed and joins the stance there.
  const int expected = static_cast<int>(std::ceil(foot.z() / (w.params.freeze_drop_speed * kDt)));
  int k = 1;
  for (; k < 2 * expected && w.gait.legPhase(leg) != LegPhase::kStance; ++k) w.tick();
  EXPECT_EQ(w.gait.legPhase(leg), LegPhase::kStance);
  EXPECT_NEAR(k, expected, 3);
  EXPECT_EQ(w.out.stance_mask, LegMask::all());
  EXPECT_NEAR(w.in.feet_world(0, leg), foot.x(), 1e-9);  // where it was, not at the foothold
}

// [rad/s] A trunk turn toward `leg` at three times kCrawlTipRate: about the
// line through the two feet beside it, the side of the foot across from it
// (3 - leg: LF-RH, RF-LH) rising.
Vec3 tipTowards(const Mat3x4& feet, int leg) {
  const int light = 3 - leg;
  int a = -1, b = -1;
  for (int j = 0; j < 4; ++j)
    if (j != leg && j != light) (a < 0 ? a : b) = j;
  const Vec3 edge = (feet.col(b) - feet.col(a)).normalized();
  const double side = edge.cross(Vec3(feet.col(light) - feet.col(a))).z();
  return (side > 0.0 ? 1.0 : -1.0) * 3.0 * kCrawlTipRate * edge;
}

// A trunk that tips toward the swinging foot: the standing foot across from
// it carries next to nothing (under kCrawlTipForce) and the trunk turns
// about the line through the other two, that foot's side rising, faster
// than kCrawlTipRate. The swinging foot then goes straight down at
// kCrawlTipDropSpeed and the clock holds. Either sign alone, or a turn the
// other way, leaves the swing as it is.
TEST(CrawlGait, ATrunkTippingTowardTheSwingingFootPutsItDown) {
  CrawlWorld start;
  for (int i = 0; i < 4; ++i) start.in.normal_force[i] = 200.0;
  int leg = -1;
  ASSERT_GT(start.runToLiftoff(20000, leg), 0);
  const int half_swing =
      static_cast<int>(0.5 * (1.0 - start.params.duty_factor) * start.params.cycle_time / kDt);
  for (int k = 0; k < half_swing; ++k) start.tick();
  ASSERT_EQ(start.gait.legPhase(leg), LegPhase::kSwing);
  // The standing foot across from the swinging one, and the line through the other two.
  const int light = 3 - leg;  // LF-RH, RF-LH
  const Vec3 tip = tipTowards(start.in.feet_world, leg);

  struct Case {
    const char* what;
    double force;  // [N] the light foot's
    Vec3 omega;    // [rad/s]
    bool drops;
  };
  const Case cases[] = {
      {"light and turning: tipping", 0.5 * kCrawlTipForce, tip, true},
      {"light, the trunk still", 0.5 * kCrawlTipForce, Vec3::Zero(), false},
      {"turning, the foot loaded", 2.0 * kCrawlTipForce, tip, false},
      {"light, turning the other way", 0.5 * kCrawlTipForce, -tip, false},
      {"light, turning under the rate", 0.5 * kCrawlTipForce, 0.5 / 3.0 * tip, false},
  };
  for (const Case& c : cases) {
    CrawlWorld w = start;
    w.in.normal_force[light] = c.force;
    w.in.omega_world = c.omega;
    const Vec3 foot = w.in.feet_world.col(leg);
    const double gait_phase = w.out.phase;
    w.tick();
    EXPECT_EQ(w.gait.legPhase(leg) == LegPhase::kSearch, c.drops) << c.what;
    if (!c.drops) continue;
    EXPECT_NEAR(w.out.foot_des[leg].x(), foot.x(), 1e-9) << c.what;
    EXPECT_NEAR(w.out.foot_des[leg].z(), foot.z() - kCrawlTipDropSpeed * kDt, 1e-9) << c.what;
    EXPECT_DOUBLE_EQ(w.out.phase, gait_phase) << "the clock holds while the trunk tips";
    // The trunk still again: the foot keeps going down at the drop speed and stands.
    w.in.omega_world.setZero();
    w.in.normal_force[light] = 200.0;
    const int expected = static_cast<int>(std::ceil(foot.z() / (kCrawlTipDropSpeed * kDt)));
    int k = 1;
    for (; k < 2 * expected && w.gait.legPhase(leg) != LegPhase::kStance; ++k) w.tick();
    EXPECT_EQ(w.gait.legPhase(leg), LegPhase::kStance);
    EXPECT_NEAR(k, expected, 3);
  }
}

// A trunk that tips toward a foot that unloads for its lift-off (a push
// toward it; the clock holds): the foot takes its load back at the load
// ramp's rate, and once the trunk stops tipping it unloads again at the
// unload's rate before it lifts.
TEST(CrawlGait, AnUnloadingFootTakesItsLoadBackWhileTheTrunkTipsTowardIt) {
  CrawlWorld w;
  for (int i = 0; i < 4; ++i) w.in.normal_force[i] = 200.0;
  // To a foot halfway through its unloading.
  int leg = -1;
  for (int k = 0; k < 20000 && leg < 0; ++k) {
    w.tick();
    for (int i = 0; i < 4; ++i)
      if (w.out.unloading[i] && w.out.load[i] < 0.5 && w.out.load[i] > 0.0) leg = i;
  }
  ASSERT_GE(leg, 0);
  const double unloaded = w.out.load[leg];
  const int light = 3 - leg;  // LF-RH, RF-LH: across from it
  const double up = kDt / w.params.load_time, down = kDt / w.params.unload_time;  // [-] a tick
  w.in.normal_force[light] = 0.5 * kCrawlTipForce;
  w.in.omega_world = tipTowards(w.in.feet_world, leg);
  const double gait_phase = w.out.phase;
  const int ticks = static_cast<int>(std::ceil(1.0 / up)) + 5;
  for (int k = 1; k <= ticks; ++k) {
    EXPECT_EQ(w.tick(), 0u) << "no lift-off";
    ASSERT_NEAR(w.out.load[leg], std::fmax(unloaded, std::fmin(1.0, k * up)), 1e-9) << "tick " << k;
  }
  EXPECT_DOUBLE_EQ(w.out.load[leg], 1.0);
  EXPECT_DOUBLE_EQ(w.out.phase, gait_phase) << "the clock holds while the trunk tips";
  // The trunk still again: it unloads at the unload's rate, and lifts only after.
  w.in.normal_force[light] = 200.0;
  w.in.omega_world.setZero();
  for (int k = 1; k <= 10; ++k) {
    EXPECT_EQ(w.tick(), 0u);
    EXPECT_NEAR(w.out.load[leg], 1.0 - k * down, 1e-9) << "tick " << k;
  }
  int lifted = -1;
  const int k_lift = w.runToLiftoff(20000, lifted);
  EXPECT_EQ(lifted, leg);
  EXPECT_GE(k_lift, static_cast<int>(std::floor(1.0 / down)) - 11);
  EXPECT_LE(k_lift * kDt, 2.0 * w.params.unload_time + 0.05);
}

// The slope's bound on a shift's deceleration, against its closed form:
// 0.2 rad falling along +x, usable friction 0.3.
TEST(SlopeShift, TheDecelerationBoundIsWhatTheSlopeLeavesOfTheFriction) {
  constexpr double kTilt = 0.2, kTraction = 0.3;
  const Vec3 n(std::sin(kTilt), 0.0, std::cos(kTilt));  // its horizontal part points down the slope
  const double g = robot::kGravity, s = std::sin(kTilt), c = std::cos(kTilt);
  EXPECT_NEAR(slopeShiftDeceleration(Vec3(0.1, 0, 0), n, kTraction), g * (kTraction * c - s), 1e-12);
  EXPECT_NEAR(slopeShiftDeceleration(Vec3(-0.1, 0, 0), n, kTraction), g * (kTraction * c + s), 1e-12);
  EXPECT_NEAR(slopeShiftDeceleration(Vec3(0, 0.05, 0), n, kTraction),
              g * std::sqrt(kTraction * kTraction * c * c - s * s), 1e-12);
  // Diagonally down: the braking force's two parts, |a d + g s f| = traction g c.
  const Vec3 d = Vec3(1, 1, 0).normalized();
  const double a = slopeShiftDeceleration(0.1 * d, n, kTraction);
  EXPECT_NEAR((a * d + g * s * Vec3(1, 0, 0)).norm(), kTraction * g * c, 1e-9);
  // Too little friction to hold the slope at all: the floor.
  EXPECT_EQ(slopeShiftDeceleration(Vec3(0.1, 0, 0), n, 0.1), kSlopeShiftMinAcceleration);
  // 0.04 rad, the slope of a drawn terrain whose unbounded shift ran the
  // trunk over its feet with every cone at the floor: bounded.
  const double gentle_tilt = 0.04;
  const Vec3 gentle(std::sin(gentle_tilt), 0.0, std::cos(gentle_tilt));
  EXPECT_NEAR(slopeShiftDeceleration(Vec3(0.1, 0, 0), gentle, kTraction),
              g * (kTraction * std::cos(gentle_tilt) - std::sin(gentle_tilt)), 1e-12);
  // Nearly flat ground, no shift, no friction known: no bound.
  const Vec3 flat(std::sin(0.5 * kShiftBoundMinTilt), 0.0, std::cos(0.5 * kShiftBoundMinTilt));
  EXPECT_EQ(slopeShiftDeceleration(Vec3(0.1, 0, 0), flat, kTraction), 0.0);
  EXPECT_EQ(slopeShiftDeceleration(Vec3::Zero(), n, kTraction), 0.0);
  EXPECT_EQ(slopeShiftDeceleration(Vec3(0.1, 0, 0), n, kNoFrictionLimit), 0.0);
}

// The crawl on ground estimated 0.2 rad falling along +x (its walking
// direction), usable friction 0.3: no shift brakes harder than the slope
// allows along it; with no friction known, some do.
TEST(SlopeShift, TheCrawlsShiftsDownASlopeBrakeWithinTheBound) {
  constexpr double kTilt = 0.2, kTraction = 0.3;
  // The largest excess [m/s^2] of a braking shift's deceleration over the
  // bound for kTraction, the gait told `traction`.
  auto worstExcess = [](double traction) {
    CrawlWorld w;
    // Feet on the tilted plane, the estimator fitted to them.
    Mat3x4 feet = w.in.feet_world;
    for (int leg = 0; leg < 4; ++leg) feet(2, leg) = -std::tan(kTilt) * feet(0, leg);
    w.terrain.fit(feet, 0xF);
    w.in.traction = traction;
    double worst = -1e9;
    for (int k = 0; k < static_cast<int>(2.5 * w.params.cycle_time / kDt); ++k) {
      w.tick();
      const Vec3 v = w.out.com_vel_des, acc = w.out.com_acc_des;
      // Braking: the acceleration against the shift's velocity.
      if (v.head<2>().norm() > 1e-6 && acc.head<2>().dot(v.head<2>()) < 0.0)
        worst = std::fmax(worst, acc.head<2>().norm() - slopeShiftDeceleration(v, w.terrain.normal(), kTraction));
    }
    return worst;
  };
  const double free_excess = worstExcess(kNoFrictionLimit);
  const double bound_excess = worstExcess(kTraction);
  std::printf("braking shifts on the slope, largest excess over the bound: %.2f m/s^2 with no friction "
              "known, %.2g m/s^2 with traction %.1f\n",
              free_excess, bound_excess, kTraction);
  EXPECT_GT(free_excess, 0.2);
  EXPECT_LE(bound_excess, 1e-9);
}

}  // namespace
}  // namespace hyq
