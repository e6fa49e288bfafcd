// The table of every Params field (param_table.hpp): it covers Params, and a
// table one field short does not; checkParams refuses a bool whose byte is
// neither 0 nor 1, a time constant below one tick, and every double at the
// smallest positive double unless that value is harmless (listed below, each
// with its reason, and run through the controller).
#include <gtest/gtest.h>

#include <array>
#include <cstring>
#include <limits>
#include <set>
#include <string>
#include <utility>

#include "firmware/controller/controller.hpp"
#include "firmware/controller/force/joint_commands.hpp"
#include "firmware/controller/model/kinematics.hpp"
#include "firmware/controller/model/robot_params.hpp"
#include "firmware/controller/param_table.hpp"
#include "firmware/controller/params_check.hpp"

namespace hyq {
namespace {

constexpr size_t fieldIndex(const char* name) {
  for (size_t k = 0; k < kNumParamFields; ++k) {
    const char* a = kParamFields[k].name;
    size_t i = 0;
    while (a[i] != '\0' && a[i] == name[i]) ++i;
    if (a[i] == name[i]) return k;
  }
  return kNumParamFields;
}

// The table without its entry `skip`.
template <size_t... I>
constexpr std::array<ParamField, kNumParamFields - 1> tableWithout(size_t skip, std::index_sequence<I...>) {
  return {kParamFields[I < skip ? I : I + 1]...};
}
constexpr std::array<ParamField, kNumParamFields - 1> tableWithout(size_t skip) {
  return tableWithout(skip, std::make_index_sequence<kNumParamFields - 1>{});
}

// At compile time: a bool that sits before padding (the tiling alone cannot
// see it missing; the member count does), and a double.
static_assert(!fieldsCoverParams(tableWithout(fieldIndex("slip.prior_agreed_ground")).data(), kNumParamFields - 1));
static_assert(!fieldsCoverParams(tableWithout(fieldIndex("estimator.vel_filter_tau")).data(), kNumParamFields - 1));

TEST(ParamTable, CoversParamsAndATableOneFieldShortDoesNot) {
  EXPECT_TRUE(fieldsCoverParams(kParamFields, kNumParamFields));
  for (size_t skip = 0; skip < kNumParamFields; ++skip) {
    const std::array<ParamField, kNumParamFields - 1> table = tableWithout(skip);
    EXPECT_FALSE(fieldsCoverParams(table.data(), table.size())) << "without " << kParamFields[skip].name;
  }
}

TEST(ParamTable, AFieldTwiceOrAtAWrongOffsetIsCaught) {
  std::array<ParamField, kNumParamFields> table{};
  for (size_t k = 0; k < kNumParamFields; ++k) table[k] = kParamFields[k];
  const size_t bool_field = fieldIndex("gait.trot.prior_from_feet_now");
  table[bool_field] = kParamFields[bool_field - 1];  // slip_along_ground twice
  EXPECT_FALSE(fieldsCoverParams(table.data(), table.size()));
  table[bool_field] = kParamFields[bool_field];
  table[bool_field].type = ParamType::kDouble;  // a bool taken for a double overlaps what follows
  EXPECT_FALSE(fieldsCoverParams(table.data(), table.size()));
}

// The table lists the fields in declaration order (checkParams' order).
TEST(ParamTable, NamesAreUniqueAndEveryFieldHasARule) {
  std::set<std::string> names;
  for (const ParamField& f : kParamFields) {
    if (&f != kParamFields) {
      EXPECT_GT(f.offset, (&f - 1)->offset) << f.name;
    }
    EXPECT_TRUE(names.insert(f.name).second) << f.name;
    EXPECT_NE(std::string(f.rule), "") << f.name;
    EXPECT_LE(f.lo, f.hi) << f.name;
  }
  ParamIssue issue;
  EXPECT_TRUE(checkParams(Params{}, issue)) << issue.name << " " << issue.rule;
}

// Params{} with field f's element 0 set to `value` (through its bytes).
template <class T>
Params withValue(const ParamField& f, T value) {
  Params p;
  std::memcpy(reinterpret_cast<uint8_t*>(&p) + f.offset, &value, sizeof value);
  return p;
}

TEST(ParamTable, EachBoolWhoseByteIsNeitherZeroNorOneIsRefusedByName) {
  int bools = 0;
  for (const ParamField& f : kParamFields) {
    if (f.type != ParamType::kBool) continue;
    ++bools;
    for (const uint8_t byte : {uint8_t{2}, uint8_t{255}}) {
      uint8_t bytes[sizeof(Params)];
      const Params defaults;
      std::memcpy(bytes, &defaults, sizeof bytes);
      bytes[f.offset] = byte;
      ParamIssue issue;
      EXPECT_FALSE(checkBoolBytes(bytes, issue)) << f.name;
      EXPECT_STREQ(issue.name, f.name);
      issue = ParamIssue{};
      EXPECT_FALSE(checkParams(withValue(f, byte), issue)) << f.name;
      EXPECT_STREQ(issue.name, f.name);
      EXPECT_STREQ(issue.rule, "false (0) or true (1)");
    }
  }
  EXPECT_EQ(bools, 18);
  uint8_t bytes[sizeof(Params)];
  const Params defaults;
  std::memcpy(bytes, &defaults, sizeof bytes);
  ParamIssue issue;
  EXPECT_TRUE(checkBoolBytes(bytes, issue)) << issue.name;
}

// Time constants, windows and periods are at least one tick, at any dt in
// range; where 0 means "off" it stays allowed.
TEST(ParamTable, TimesBelowOneTickAreRefused) {
  Params p;
  p.dt = 0.01;
  p.gait.load_time = 0.005;
  ParamIssue issue;
  EXPECT_FALSE(checkParams(p, issue));
  EXPECT_STREQ(issue.name, "gait.load_time");
  EXPECT_STREQ(issue.rule, kTickRule);

  p = Params{};
  p.dt = 0.01;
  p.gait.load_time = p.gait.trot.load_time = 0.01;
  p.gait.trot.walk_time = 0.005;
  EXPECT_FALSE(checkParams(p, issue));
  EXPECT_STREQ(issue.name, "gait.trot.walk_time");
  EXPECT_STREQ(issue.rule, kZeroOrTickRule);
  p.gait.trot.walk_time = 0.0;  // trot for ever
  p.estimator.gyro_bias_time = 0.0;  // off
  EXPECT_TRUE(checkParams(p, issue)) << issue.name << " " << issue.rule;
  p.estimator.gyro_bias_time = 0.001;  // on, below one tick
  EXPECT_FALSE(checkParams(p, issue));
  EXPECT_STREQ(issue.name, "estimator.gyro_bias_time");
}

// Fields that take the smallest positive double, and why it does no harm.
// Each also takes 0, which the value acts as.
struct Harmless {
  const char* name;
  const char* why;
};
constexpr const char* kThreshold = "a threshold or limit compared with a measurement: it acts as 0";
constexpr const char* kGain = "a gain, weight or rate multiplied in: it adds nothing, as 0";
constexpr const char* kTime = "a delay or timeout compared with a time counted in ticks: it acts as 0";
constexpr const char* kGeometry = "a length, height, angle or phase of the gait's geometry: 0 to a double's precision";
const Harmless kHarmless[] = {
    {"qp.regularisation", kGain},
    {"qp.tangential_weight", kGain},
    {"qp.f_normal_min", kThreshold},
    {"qp.force_smoothing", kGain},
    {"gait.phase_offset", kGeometry},
    {"gait.speed", "a command: standing still"},
    {"gait.step_height", kGeometry},
    {"gait.liftoff_margin", kGeometry},
    {"gait.liftoff_wait_max", kTime},
    {"gait.crouch_max", kGeometry},
    {"gait.start_delay", kTime},
    {"gait.initial_phase", kGeometry},
    {"gait.swing_depth", kGeometry},
    {"gait.touchdown_search_max", kGeometry},
    {"gait.touchdown_min_swing", kGeometry},
    {"gait.lane_step", kGeometry},
    {"gait.max_tilt", kThreshold},
    {"gait.trot.step_height", kGeometry},
    {"gait.trot.landing_fraction", kGeometry},
    {"gait.trot.foothold_gain", kGain},
    {"gait.trot.max_foothold_correction", kThreshold},
    {"gait.trot.guess_delay", kTime},
    {"gait.trot.prior_row_split",
     "a split angle: the feet's plane never lies within 1e-324 of the rows' great circle, as with 0 (off)"},
    {"gait.trot.prior_row_interior", kThreshold},
    {"gait.trot.carry_distance", "a distance no foot comes within: as 0 (off)"},
    {"gait.trot.carry_agreement", kThreshold},
    {"gait.trot.carry_agreement_above", kThreshold},
    {"gait.schedule.trot_speed", "a command: standing still"},
    {"trunk.kp_lin", kGain},
    {"trunk.kd_lin", kGain},
    {"trunk.kp_ang", kGain},
    {"trunk.kd_ang", kGain},
    {"joint.posture_kp", kGain},
    {"joint.posture_kd", kGain},
    {"joint.swing_kp", kGain},
    {"joint.swing_kd", kGain},
    {"joint.stance_kd", kGain},
    {"stance.force_on", kThreshold},
    {"stance.joint_stop_margin", kThreshold},
    {"stance.force_watch_release", kThreshold},
    {"estimator.gyro_bias_limit", kThreshold},
    {"estimator.acc_bias_limit", kThreshold},
    {"estimator.torque_bias_settle", kTime},
    {"estimator.torque_bias_limit", kThreshold},
    {"estimator.torque_bias_start_weight", "samples added to a count of at least 1: as 0"},
    {"estimator.torque_offset_sigma", kGain},
    {"estimator.imu_position", "a lever arm: 1e-324 m turns it on and takes out nothing measurable"},
    {"estimator.com_offset_limit", kThreshold},
    {"estimator.com_offset_weight_tolerance", kThreshold},
    {"slip.landing_drag_allowance", kThreshold},
    {"slip.min_slip_speed", kThreshold},
    {"slip.ending_slip_fraction", kThreshold},
    {"slip.min_estimate_force", kThreshold},
    {"slip.min_force_slip_angle", kThreshold},
    {"slip.max_normal_tilt", "a limit whose 0 already refuses every sample, as it does"},
    {"slip.max_slip_elevation", "a limit whose 0 already refuses every sample, as it does"},
    {"slip.slide_travel", kThreshold},
    {"slip.normal_mean_tolerance", kThreshold},
    {"slip.prior_switch_angle", "an angle two planes just apart exceed: the switch still needs the travel in the "
                                "other plane by half their separation"},
    {"slip.prior_switch_travel", kThreshold},
    {"slip.slip_velocity_sigma", kGain},
    {"recovery.k_normal", kGain},
    {"recovery.k_mu", kGain},
    {"recovery.freeze_hold", kTime},
    {"recovery.freeze_min_load", kThreshold},
    {"recovery.freeze_max", kTime},
    {"recovery.slip_damping", kGain},
    {"recovery.cone_force_offset", kThreshold},
    {"recovery.mu_rise_rate", kGain},
    {"recovery.mu_rise_delay", kTime},
    {"recovery.mu_rise_ceiling", kThreshold},
    {"recovery.mu_floor", kThreshold},
    {"recovery.slope_floor_factor", kGain},
    {"recovery.ground_plane_min_angle", kThreshold},
    {"recovery.map.disagreement", kThreshold},
    {"recovery.probe.settle_time", kTime},
    {"recovery.probe.quiet_time", kTime},
    {"recovery.probe.max_force", kThreshold},
    {"recovery.probe.max_ratio", kThreshold},
    {"recovery.probe.partner_margin", kThreshold},
    {"recovery.probe.max_normal_angle", kThreshold},
    {"safety.joint_range_margin", kThreshold},
};
// Fields whose smallest positive value breaks a rule they share with another
// field, which the message names.
const std::pair<const char*, const char*> kRefusedAsPartner[] = {
    {"gait.stability_margin", "gait.liftoff_margin"},     // the lift-off's margin must lie below it
    {"stance.force_watch", "stance.force_watch_release"},  // the release must lie at or below it
};

const Harmless* harmless(const char* name) {
  for (const Harmless& h : kHarmless)
    if (std::string(h.name) == name) return &h;
  return nullptr;
}

const char* partnerOf(const char* name) {
  for (const auto& pair : kRefusedAsPartner)
    if (std::string(pair.first) == name) return pair.second;
  return nullptr;
}

// Standing still in the stand posture, each foot carrying a quarter of the weight.
hal::SensorFrame standingFrame(uint32_t tick) {
  hal::SensorFrame f{};
  f.tick = tick;
  f.imu_quat[0] = 1.0;
  f.imu_acc[2] = robot::kGravity;
  const Vec3 gravity(0.0, 0.0, -robot::kGravity);
  for (int leg = 0; leg < 4; ++leg) {
    const Vec3 q(robot::standAngle(leg, 0), robot::standAngle(leg, 1), robot::standAngle(leg, 2));
    const Vec3 grf(0.0, 0.0, robot::kTotalMass * robot::kGravity / 4.0);
    const Vec3 tau = legGravityTorque(leg, q, gravity) - footJacobianBase(leg, q).transpose() * grf;
    for (int k = 0; k < 3; ++k) {
      f.q[3 * leg + k] = q[k];
      f.tau[3 * leg + k] = tau[k];
    }
  }
  return f;
}

// Every double field at the smallest positive double: refused by its own
// name, refused by a rule it shares with another field, or harmless: then 0
// is in range too, and the controller stands 0.3 s on it without a safe hold.
TEST(ParamTable, TheSmallestPositiveDoubleIsRefusedOrHarmless) {
  constexpr double kTiny = std::numeric_limits<double>::denorm_min();
  constexpr uint32_t kBadFlags = hal::kFlagBadSensorFrame | hal::kFlagBadCommand | hal::kFlagBadParams |
                                 hal::kFlagQpInfeasible | hal::kFlagQpMaxIter;
  std::set<std::string> accepted;
  for (const ParamField& f : kParamFields) {
    if (f.type != ParamType::kDouble) continue;
    ParamIssue issue;
    if (!checkParams(withValue(f, kTiny), issue)) {
      const char* partner = partnerOf(f.name);
      EXPECT_STREQ(issue.name, partner != nullptr ? partner : f.name) << "rule " << issue.rule;
      EXPECT_EQ(harmless(f.name), nullptr) << f.name << " is refused";
      continue;
    }
    accepted.insert(f.name);
    const Harmless* h = harmless(f.name);
    ASSERT_NE(h, nullptr) << f.name << " takes 1e-324: refuse it or say why it is harmless";
    EXPECT_TRUE(checkParams(withValue(f, 0.0), issue)) << f.name << " (" << h->why << "): " << issue.rule;
    Controller controller;
    ASSERT_TRUE(controller.init(withValue(f, kTiny))) << f.name;
    hal::CommandFrame command{};
    uint32_t flags = 0;
    for (uint32_t t = 0; t < 300; ++t) {
      controller.step(standingFrame(t), command);
      flags |= command.flags;
      EXPECT_TRUE(commandFinite(command)) << f.name << " tick " << t;
    }
    EXPECT_EQ(flags & kBadFlags, 0u) << f.name;
  }
  for (const Harmless& h : kHarmless) EXPECT_EQ(accepted.count(h.name), 1u) << h.name << " is refused";
}

// A velocity filter with a time constant of 1e-324 s: refused, not run.
TEST(ParamTable, ATinyFilterTimeConstantIsRefused) {
  Params p;
  p.estimator.vel_filter_tau = std::numeric_limits<double>::denorm_min();
  ParamIssue issue;
  EXPECT_FALSE(checkParams(p, issue));
  EXPECT_STREQ(issue.name, "estimator.vel_filter_tau");
  EXPECT_STREQ(issue.rule, "in [0.001, 10.0]");
}

}  // namespace
}  // namespace hyq
