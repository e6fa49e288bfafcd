// Every field of Params (params.hpp) with its key, its place in Params' bytes,
// its type and its documented range: one table that the range checks
// (checkParams) and the board's check of a received configuration both walk.
// A compile-time check below refuses a Params with a member the table lacks.
#pragma once
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <utility>

#include "firmware/controller/params.hpp"
#include "firmware/controller/params_check.hpp"

namespace hyq {

enum class ParamType : uint8_t { kDouble, kInt, kBool, kGaitKind };

// ParamField::flags
constexpr uint8_t kParamOpenLow = 1u << 0;    // lo < value (else lo <= value)
constexpr uint8_t kParamAtLeastTick = 1u << 1;  // besides the range: 0 or at least Params::dt (one tick)

// One field of Params. A value is in range when it is finite, lo <= value
// (lo < value with kParamOpenLow), value <= hi, and not in (0, on_min): a
// field whose 0 (or negative values) means "off" takes positive values only
// from on_min on. Bools and the gait kind are read as their byte: 0 or 1.
struct ParamField {
  const char* name;    // the key, e.g. "gait.duty_factor"
  const char* rule;    // what the range check asks, for messages, e.g. "in [0.5, 0.99]"
  uint16_t offset;     // [bytes] offsetof(Params, ...)
  ParamType type;
  uint8_t count;       // [-] elements: 1, or an array's length
  uint8_t flags;       // kParamOpenLow, kParamAtLeastTick
  double lo, hi;       // the range
  double on_min;       // smallest positive value accepted (0: any)
};

// The rule a kParamAtLeastTick field breaks below one tick, where its range
// holds 0 and where it does not.
constexpr const char* kZeroOrTickRule = "0 or at least dt (one tick)";
constexpr const char* kTickRule = "at least dt (one tick)";

constexpr size_t paramElementSize(ParamType type) {
  return type == ParamType::kDouble ? sizeof(double)
         : type == ParamType::kInt  ? sizeof(int)
         : type == ParamType::kBool ? sizeof(bool)
                                    : sizeof(GaitKind);
}

constexpr size_t paramElementAlign(ParamType type) {
  return type == ParamType::kDouble ? alignof(double)
         : type == ParamType::kInt  ? alignof(int)
         : type == ParamType::kBool ? alignof(bool)
                                    : alignof(GaitKind);
}

namespace param_detail {

// The table's type of a member's declared type (a type without one does not compile).
template <class T>
struct TypeOf;
template <>
struct TypeOf<double> {
  static constexpr ParamType value = ParamType::kDouble;
};
template <>
struct TypeOf<int> {
  static constexpr ParamType value = ParamType::kInt;
};
template <>
struct TypeOf<bool> {
  static constexpr ParamType value = ParamType::kBool;
};
template <>
struct TypeOf<GaitKind> {
  static constexpr ParamType value = ParamType::kGaitKind;
};
template <class T, size_t N>
struct TypeOf<T[N]> {
  static constexpr ParamType value = TypeOf<T>::value;
};

template <class T>
constexpr uint8_t countOf() {
  return std::extent_v<T> == 0 ? 1 : static_cast<uint8_t>(std::extent_v<T>);
}

// How many initializers the aggregate T takes: one per member, an array's
// elements each (brace elision), a nested struct one.
struct AnyValue {
  template <class T>
  operator T() const;
};
template <class T, class Seq, class = void>
struct TakesInitializers : std::false_type {};
template <class T, size_t... I>
struct TakesInitializers<T, std::index_sequence<I...>, std::void_t<decltype(T{(void(I), AnyValue{})...})>>
    : std::true_type {};
template <class T, size_t N = 0>
constexpr size_t initializerCount() {
  if constexpr (TakesInitializers<T, std::make_index_sequence<N + 1>>::value)
    return initializerCount<T, N + 1>();
  else
    return N;
}

}  // namespace param_detail

// The member `path` of Params ("gait.trot.cycle_time" from gait.trot.cycle_time),
// its type and element count taken from its declaration.
#define HYQ_PARAM(path, flags, lo, hi, on_min, rule)                                                          \
  ParamField {                                                                                                 \
    #path, rule, static_cast<uint16_t>(offsetof(Params, path)),                                                \
        param_detail::TypeOf<decltype(std::declval<Params&>().path)>::value,                                   \
        param_detail::countOf<decltype(std::declval<Params&>().path)>(), flags, lo, hi, on_min                  \
  }
// lo <= value <= hi
#define HYQ_IN(path, lo, hi) HYQ_PARAM(path, 0, lo, hi, 0.0, "in [" #lo ", " #hi "]")
// lo < value <= hi
#define HYQ_ABOVE(path, lo, hi) HYQ_PARAM(path, kParamOpenLow, lo, hi, 0.0, "in (" #lo ", " #hi "]")
// 0 (off), or on_min <= value <= hi
#define HYQ_OFF_OR_IN(path, on_min, hi) HYQ_PARAM(path, 0, 0.0, hi, on_min, "0 or in [" #on_min ", " #hi "]")
// lo <= value <= 0 (off), or on_min <= value <= hi
#define HYQ_OFF_BELOW_OR_IN(path, lo, on_min, hi) \
  HYQ_PARAM(path, 0, lo, hi, on_min, "in [" #lo ", 0.0] or [" #on_min ", " #hi "]")
// A time constant, window or period: in [lo, hi], and 0 or at least one tick.
#define HYQ_TICKS_IN(path, lo, hi) HYQ_PARAM(path, kParamAtLeastTick, lo, hi, 0.0, "in [" #lo ", " #hi "]")
// ... whose 0 means "off": 0, or on_min <= value <= hi and at least one tick.
#define HYQ_TICKS_OFF_OR_IN(path, on_min, hi) \
  HYQ_PARAM(path, kParamAtLeastTick, 0.0, hi, on_min, "0 or in [" #on_min ", " #hi "]")
#define HYQ_BOOL(path) HYQ_PARAM(path, 0, 0.0, 1.0, 0.0, "false (0) or true (1)")

// Every field of Params, in declaration order (the order checkParams tests them in).
inline constexpr ParamField kParamFields[] = {
    HYQ_PARAM(dt, 0, 0.0005, 0.01, 0.0, "in [0.0005, 0.01] s"),

    HYQ_IN(qp.regularisation, 0.0, 1.0),
    HYQ_IN(qp.tangential_weight, 0.0, 1.0),
    // Squared in the QP's Hessian, where 1e-162 is 0 and leaves the wrench
    // out: at least 1 % of the default's weight.
    HYQ_IN(qp.wrench_weight_lin, 0.1, 1000.0),
    HYQ_IN(qp.wrench_weight_ang, 0.1, 1000.0),
    HYQ_IN(qp.f_normal_min, 0.0, 1000.0),
    HYQ_ABOVE(qp.f_normal_max, 0.0, 10000.0),  // and above qp.f_normal_min
    HYQ_IN(qp.max_iterations, 1, 256),
    HYQ_IN(qp.force_smoothing, 0.0, 100.0),
    // Forces of 1 kN carry rounding errors of 1e-13 N.
    HYQ_IN(qp.feasibility_tolerance, 1e-12, 1e-3),

    HYQ_PARAM(gait.kind, 0, 0.0, 1.0, 0.0, "crawl (0) or trot (1)"),
    HYQ_BOOL(gait.walk),
    HYQ_IN(gait.cycle_time, 0.5, 100.0),
    HYQ_IN(gait.duty_factor, 0.5, 0.99),
    HYQ_PARAM(gait.phase_offset, 0, 0.0, 1.0, 0.0, "each in [0, 1]"),
    HYQ_IN(gait.speed, -1.0, 1.0),
    HYQ_IN(gait.yaw_rate, -1.0, 1.0),  // and 0 with the crawl
    HYQ_IN(gait.step_height, 0.0, 0.3),
    HYQ_IN(gait.body_height, 0.3, 0.75),
    HYQ_IN(gait.stability_margin, 0.0, 0.2),
    // The shift puts the CoM stability_margin inside the coming triangle: a
    // lift-off that waits for more would wait for ever (a cross-field rule).
    HYQ_IN(gait.liftoff_margin, -1.0, 0.2),
    HYQ_IN(gait.liftoff_wait_max, 0.0, 1e6),
    HYQ_IN(gait.crouch_speed, 0.001, 1.0),  // [m/s] crouch_max (at most 0.3 m) within 300 s
    HYQ_IN(gait.crouch_max, 0.0, 0.3),
    HYQ_IN(gait.start_delay, 0.0, 1e6),
    HYQ_IN(gait.reshift_speed, 0.001, 1.0),  // a divisor: a re-planned shift's distance over it
    HYQ_IN(gait.min_shift_time, 0.05, 5.0),
    HYQ_OFF_OR_IN(gait.max_shift_acceleration, 0.01, 10.0),  // a divisor when on
    HYQ_IN(gait.initial_phase, 0.0, 1.0),
    HYQ_IN(gait.swing_lift_fraction, 0.05, 0.5),  // a divisor of the swing's lift and its rate
    HYQ_IN(gait.swing_depth, 0.0, 0.1),
    HYQ_IN(gait.touchdown_search_speed, 0.01, 1.0),  // [m/s] touchdown_search_max within 30 s
    HYQ_IN(gait.touchdown_search_max, 0.0, 0.3),
    HYQ_IN(gait.freeze_drop_speed, 0.01, 1.0),
    HYQ_IN(gait.touchdown_min_swing, 0.0, 1.0),
    HYQ_TICKS_IN(gait.load_time, 0.001, 1.0),
    HYQ_TICKS_IN(gait.unload_time, 0.001, 1.0),
    HYQ_IN(gait.ramp_force, 1.0, 2000.0),
    HYQ_IN(gait.lane_step, 0.0, 0.2),
    HYQ_IN(gait.max_tilt, 0.0, 1.2),

    HYQ_IN(gait.trot.cycle_time, 0.3, 2.0),
    HYQ_IN(gait.trot.duty_factor, 0.5, 0.8),
    HYQ_IN(gait.trot.step_height, 0.0, 0.3),
    HYQ_IN(gait.trot.landing_fraction, 0.0, 0.5),
    HYQ_IN(gait.trot.touchdown_speed, 0.01, 2.0),
    HYQ_TICKS_IN(gait.trot.load_time, 0.001, 1.0),
    HYQ_TICKS_IN(gait.trot.unload_time, 0.001, 1.0),  // and below the stance time
    HYQ_IN(gait.trot.foothold_gain, 0.0, 1.0),
    HYQ_IN(gait.trot.max_foothold_correction, 0.0, 0.5),
    HYQ_IN(gait.trot.acceleration, 0.01, 10.0),  // [m/s^2] 1 m/s within 100 s
    HYQ_IN(gait.trot.max_com_error, 0.001, 1.0),
    HYQ_TICKS_IN(gait.trot.imu_integration_window, 0.001, 10.0),
    HYQ_IN(gait.trot.guess_delay, 0.0, 1.0),
    HYQ_BOOL(gait.trot.slip_along_ground),
    HYQ_BOOL(gait.trot.prior_from_feet_now),
    HYQ_IN(gait.trot.prior_row_split, 0.0, 0.5),
    HYQ_IN(gait.trot.prior_row_interior, 0.0, 0.5),
    HYQ_BOOL(gait.trot.peak_of_loaded_samples),
    HYQ_IN(gait.trot.carry_distance, 0.0, 2.0),
    HYQ_IN(gait.trot.carry_agreement, 0.0, 10.0),
    HYQ_IN(gait.trot.carry_agreement_above, 0.0, 10.0),
    HYQ_IN(gait.trot.carry_max_samples, 0, 32),
    // Below 0.1 the trot on ice (mu in use 0.07) is held under 7 mm/s.
    HYQ_OFF_OR_IN(gait.trot.speed_per_mu, 0.1, 100.0),
    HYQ_TICKS_IN(gait.trot.walk_time, 0.0, 1e6),

    HYQ_TICKS_IN(gait.schedule.trot_at, 0.0, 1e6),  // and 0 unless the run starts with the crawl
    HYQ_IN(gait.schedule.trot_speed, -1.0, 1.0),
    HYQ_IN(gait.schedule.max_com_speed, 0.01, 1.0),  // a CoM never stiller than its estimate's noise

    HYQ_IN(trunk.kp_lin, 0.0, 1e5),
    HYQ_IN(trunk.kd_lin, 0.0, 1e4),
    HYQ_IN(trunk.kp_ang, 0.0, 1e5),
    HYQ_IN(trunk.kd_ang, 0.0, 1e4),

    HYQ_IN(joint.posture_kp, 0.0, 2000.0),
    HYQ_IN(joint.posture_kd, 0.0, 100.0),
    HYQ_IN(joint.swing_kp, 0.0, 2000.0),
    HYQ_IN(joint.swing_kd, 0.0, 100.0),
    HYQ_OFF_OR_IN(joint.torque_bandwidth, 1.0, 1000.0),
    HYQ_IN(joint.swing_crossover_fraction, 0.01, 1.0),
    HYQ_IN(joint.stance_kd, 0.0, 100.0),

    HYQ_IN(stance.force_on, 0.0, 1000.0),
    HYQ_IN(stance.joint_stop_margin, 0.0, 0.5),
    HYQ_IN(stance.force_watch, 0.0, 1000.0),
    HYQ_IN(stance.force_watch_release, 0.0, 1000.0),  // and at most stance.force_watch
    HYQ_IN(stance.watch_approach_speed, 0.01, 10.0),  // landed feet move along the normal at up to 0.07 m/s
    HYQ_BOOL(stance.press_landing_along_normal),

    // Divides the accelerometer-bias gain.
    HYQ_TICKS_IN(estimator.vel_filter_tau, 0.001, 10.0),
    HYQ_TICKS_OFF_OR_IN(estimator.gyro_bias_time, 0.01, 100.0),  // gains 2 / T and 1 / T^2
    HYQ_IN(estimator.gyro_bias_limit, 0.0, 1.0),
    HYQ_TICKS_OFF_OR_IN(estimator.acc_bias_time, 0.01, 1000.0),  // divides the gain once learnt
    HYQ_IN(estimator.acc_bias_start_time, 0.0, 1000.0),  // and at least 4 x estimator.vel_filter_tau
    HYQ_IN(estimator.acc_bias_limit, 0.0, 5.0),
    HYQ_TICKS_OFF_OR_IN(estimator.torque_bias_time, 0.01, 100.0),  // alpha = dt / T
    HYQ_IN(estimator.torque_bias_settle, 0.0, 10.0),
    HYQ_IN(estimator.torque_bias_limit, 0.0, 50.0),
    HYQ_IN(estimator.torque_bias_start_weight, 0.0, 1e6),
    HYQ_TICKS_OFF_OR_IN(estimator.com_offset_time, 0.01, 1000.0),  // alpha = dt / T
    HYQ_TICKS_IN(estimator.com_offset_start_time, 0.0, 1000.0),
    HYQ_IN(estimator.com_offset_limit, 0.0, 0.2),
    HYQ_IN(estimator.com_offset_weight_tolerance, 0.0, 1.0),
    HYQ_IN(estimator.torque_offset_sigma, 0.0, 50.0),
    HYQ_PARAM(estimator.imu_position, 0, -1.0, 1.0, 0.0, "each in [-1, 1] m"),
    HYQ_BOOL(estimator.grf_leg_dynamics),
    HYQ_BOOL(estimator.grf_base_rotation),
    HYQ_BOOL(estimator.grf_leg_motion),
    // The GRF delay line holds (window - 1) / 2 ticks, at most kMaxGrfDelay.
    HYQ_IN(estimator.grf_accel_window, 2, 17),
    HYQ_BOOL(estimator.grf_estimate_aligned),
    HYQ_BOOL(estimator.grf_contact_point),

    // Velocity thresholds and tolerances at or below the feet's velocity
    // noise (0.02 m/s rms) flag or split every foot every tick: at least 0.01.
    HYQ_IN(slip.threshold, 0.01, 1.0),
    HYQ_IN(slip.holding_agreement, 0.01, 1.0),
    HYQ_IN(slip.debounce_ticks, 1, 100),
    HYQ_IN(slip.landing_debounce_extra, 0, 100),
    HYQ_IN(slip.release_ticks, 1, 1000),
    HYQ_OFF_BELOW_OR_IN(slip.creep_threshold, -1.0, 0.01, 1.0),
    HYQ_IN(slip.creep_filter_ticks, 1, 1000),
    HYQ_IN(slip.landing_drag_allowance, 0.0, 1.0),
    HYQ_OFF_BELOW_OR_IN(slip.landing_drag_travel, -1.0, 0.0001, 1.0),  // [m] 3 ticks of excess at 0.03 m/s
    HYQ_IN(slip.multi_leg_consistency, 0.01, 1.0),
    HYQ_TICKS_IN(slip.imu_integration_window, 0.001, 10.0),
    HYQ_IN(slip.imu_anchor_agreement, 0.01, 1.0),
    HYQ_IN(slip.estimate_samples_mu, 1, 32),
    HYQ_IN(slip.estimate_samples_n, 1, 32),
    HYQ_IN(slip.min_slip_speed, 0.0, 1.0),
    HYQ_IN(slip.ending_slip_fraction, 0.0, 1.0),
    HYQ_TICKS_OFF_OR_IN(slip.ending_peak_hold, 0.001, 10.0),
    HYQ_IN(slip.min_estimate_samples, 1, 32),
    HYQ_IN(slip.min_estimate_force, 0.0, 2000.0),
    // Sample gates whose 0 is "off": just above 0 they refuse every sample.
    HYQ_OFF_OR_IN(slip.max_estimate_force_sigma, 0.001, 1.0),
    HYQ_OFF_OR_IN(slip.max_slide_acceleration, 0.1, 1000.0),
    HYQ_IN(slip.min_force_slip_angle, 0.0, 3.15),
    HYQ_OFF_OR_IN(slip.max_friction_slip_angle, 0.01, 3.15),
    HYQ_IN(slip.max_normal_tilt, 0.0, 3.15),
    HYQ_IN(slip.max_slip_elevation, 0.0, 1.58),
    HYQ_IN(slip.max_mu_estimate, 0.1, 10.0),
    HYQ_OFF_OR_IN(slip.max_slide_stiffness, 100.0, 1e7),  // the force estimate's noise alone reads 5e3 N/m
    HYQ_IN(slip.slide_travel, 0.0, 0.01),
    HYQ_IN(slip.slide_window, 2, 16),  // kMaxSlideWindow
    HYQ_IN(slip.normal_mean_iterations, 1, 20),
    HYQ_IN(slip.normal_mean_tolerance, 0.0, 1e-3),
    // Squared: a sigma whose square is 0 is no prior's weight but all of it.
    HYQ_OFF_OR_IN(slip.normal_prior_sigma, 0.001, 1.0),
    HYQ_OFF_OR_IN(slip.prior_local_length, 0.01, 10.0),  // weights exp(-d^2 / 2 L^2): 0 / 0 at d = 0 if L^2 is 0
    HYQ_IN(slip.prior_inlier_distance, 0.0001, 0.1),
    HYQ_OFF_OR_IN(slip.prior_turn_margin, 0.001, 0.5),  // leg odometry knows a foot's height to a millimetre
    HYQ_BOOL(slip.turn_sets_ground),
    HYQ_BOOL(slip.prior_agreed_ground),
    HYQ_IN(slip.prior_switch_angle, 0.0, 1.0),
    HYQ_IN(slip.prior_switch_travel, 0.0, 0.1),
    // Their squares keep the slip normal's variance positive.
    HYQ_IN(slip.slip_direction_sigma, 0.001, 3.15),
    HYQ_IN(slip.estimate_force_sigma, 0.01, 1000.0),
    HYQ_IN(slip.slip_velocity_sigma, 0.0, 1.0),

    HYQ_BOOL(recovery.enabled),
    HYQ_IN(recovery.k_normal, 0.0, 1000.0),
    HYQ_IN(recovery.k_mu, 0.0, 1000.0),
    HYQ_IN(recovery.pyramid_scale, 0.1, 1.0),  // divides the slope floor
    HYQ_IN(recovery.mu_default, 0.01, 2.0),
    HYQ_BOOL(recovery.freeze),
    HYQ_TICKS_IN(recovery.freeze_after, 0.001, 100.0),
    HYQ_IN(recovery.freeze_hold, 0.0, 100.0),
    HYQ_TICKS_IN(recovery.unfreeze_blend, 0.0, 10.0),  // divides the time since the freeze ended
    HYQ_IN(recovery.freeze_min_load, 0.0, 2000.0),
    HYQ_IN(recovery.freeze_max, 0.0, 1000.0),
    HYQ_IN(recovery.estimate_margin, 0.1, 1.0),
    HYQ_IN(recovery.brake_margin, 0.1, 1.0),
    HYQ_IN(recovery.slip_damping, 0.0, 1000.0),
    HYQ_BOOL(recovery.guess_floor_before_estimate),
    HYQ_BOOL(recovery.guess_holds_for_stance),
    HYQ_IN(recovery.cone_force_offset, 0.0, 1000.0),
    HYQ_IN(recovery.mu_rise_rate, 0.0, 10.0),
    HYQ_IN(recovery.mu_rise_delay, 0.0, 100.0),
    HYQ_IN(recovery.mu_rise_ceiling, 0.0, 2.0),
    HYQ_IN(recovery.mu_floor, 0.0, 1.0),
    HYQ_IN(recovery.slope_floor_factor, 0.0, 10.0),
    HYQ_IN(recovery.ground_plane_min_angle, 0.0, 3.15),
    HYQ_BOOL(recovery.map.enabled),
    HYQ_IN(recovery.map.cell_size, 0.05, 2.0),          // a foot's footprint at least; the torus spans 12 cells
    HYQ_IN(recovery.map.max_age, 0.001, 1.0e6),
    HYQ_IN(recovery.map.disagreement, 0.0, 10.0),
    HYQ_BOOL(recovery.probe.enabled),
    HYQ_IN(recovery.probe.min_load, 1.0, 2000.0),       // a foot must press for its ratio to mean anything
    HYQ_IN(recovery.probe.settle_time, 0.0, 10.0),
    HYQ_IN(recovery.probe.quiet_time, 0.0, 10.0),
    HYQ_IN(recovery.probe.rate, 1.0, 1.0e5),
    HYQ_IN(recovery.probe.max_force, 0.0, 1000.0),
    HYQ_IN(recovery.probe.max_ratio, 0.0, 2.0),
    HYQ_IN(recovery.probe.partner_margin, 0.0, 1.0),
    HYQ_IN(recovery.probe.max_normal_angle, 0.0, 3.2),
    HYQ_IN(recovery.probe.break_release_rate, 1.0, 1.0e6),

    // Limits below what the crawl reads reject its frames: joints at up to
    // 2.6 rad/s and 140 N m, the trunk at 0.5 rad/s and 13 m/s^2 (gravity's
    // 9.81 included), a quaternion's norm 1 to 1e-7 in single precision.
    HYQ_IN(safety.max_joint_velocity, 5.0, 1000.0),
    HYQ_IN(safety.max_joint_torque, 150.0, 10000.0),
    HYQ_IN(safety.max_gyro, 1.0, 1000.0),
    HYQ_IN(safety.max_acc, 20.0, 10000.0),
    HYQ_IN(safety.quat_norm_tol, 0.001, 1.0),
    HYQ_IN(safety.joint_range_margin, 0.0, 3.0),
};

#undef HYQ_PARAM
#undef HYQ_IN
#undef HYQ_ABOVE
#undef HYQ_OFF_OR_IN
#undef HYQ_OFF_BELOW_OR_IN
#undef HYQ_TICKS_IN
#undef HYQ_TICKS_OFF_OR_IN
#undef HYQ_BOOL

constexpr size_t kNumParamFields = sizeof(kParamFields) / sizeof(kParamFields[0]);
static_assert(sizeof(Params) <= UINT16_MAX, "ParamField::offset holds every offset in Params");

// A struct of Params (Params itself, or a member struct at any depth): its
// bytes and the initializers its aggregate takes.
struct ParamGroup {
  size_t offset;        // [bytes] in Params
  size_t size;          // [bytes]
  size_t initializers;  // [-] param_detail::initializerCount
};

#define HYQ_GROUP(path)                                                                                       \
  ParamGroup {                                                                                                \
    offsetof(Params, path), sizeof(decltype(std::declval<Params&>().path)),                                   \
        param_detail::initializerCount<decltype(std::declval<Params&>().path)>()                              \
  }
inline constexpr ParamGroup kParamGroups[] = {
    {0, sizeof(Params), param_detail::initializerCount<Params>()},
    HYQ_GROUP(qp),
    HYQ_GROUP(gait),
    HYQ_GROUP(gait.trot),
    HYQ_GROUP(gait.schedule),
    HYQ_GROUP(trunk),
    HYQ_GROUP(joint),
    HYQ_GROUP(stance),
    HYQ_GROUP(estimator),
    HYQ_GROUP(slip),
    HYQ_GROUP(recovery),
    HYQ_GROUP(recovery.map),
    HYQ_GROUP(recovery.probe),
    HYQ_GROUP(safety),
};
#undef HYQ_GROUP

constexpr size_t kNumParamGroups = sizeof(kParamGroups) / sizeof(kParamGroups[0]);

namespace param_detail {

constexpr size_t alignUp(size_t at, size_t align) { return (at + align - 1) / align * align; }

// The fields, walked in order of their offsets, follow each other with no
// gap but the padding their alignment asks for, and end where Params does
// (up to its own alignment). n steps, each taking the field at the lowest
// offset not yet passed.
constexpr bool fieldsTile(const ParamField* fields, size_t n, size_t size, size_t align) {
  size_t end = 0;  // [bytes] where the fields so far end
  for (size_t step = 0; step < n; ++step) {
    size_t next = n;
    for (size_t k = 0; k < n; ++k) {
      if (fields[k].offset < end) continue;
      if (next == n || fields[k].offset < fields[next].offset) {
        next = k;
      } else if (fields[k].offset == fields[next].offset) {
        return false;  // two fields at one offset
      }
    }
    if (next == n) return false;  // a field overlaps another
    const ParamField& f = fields[next];
    if (f.offset != alignUp(end, paramElementAlign(f.type))) return false;  // a gap where no padding can be
    end = f.offset + paramElementSize(f.type) * f.count;
  }
  return alignUp(end, align) == size;
}

constexpr bool inside(size_t offset, const ParamGroup& g) { return offset >= g.offset && offset < g.offset + g.size; }

// The smallest group that holds `offset` and is larger than `above` bytes.
constexpr size_t innermostGroup(size_t offset, size_t above, const ParamGroup* groups, size_t m) {
  size_t best = m;
  for (size_t j = 0; j < m; ++j)
    if (inside(offset, groups[j]) && groups[j].size > above && (best == m || groups[j].size < groups[best].size))
      best = j;
  return best;
}

// Each group takes as many initializers as its own fields' elements and its
// member groups add up to: a member that lies in padding (where the tiling
// cannot see it) is counted here.
constexpr bool groupsCounted(const ParamField* fields, size_t n, const ParamGroup* groups, size_t m) {
  for (size_t j = 0; j < m; ++j) {
    size_t counted = 0;
    for (size_t k = 0; k < n; ++k)
      if (innermostGroup(fields[k].offset, 0, groups, m) == j) counted += fields[k].count;
    for (size_t h = 0; h < m; ++h)
      if (h != j && innermostGroup(groups[h].offset, groups[h].size, groups, m) == j) ++counted;
    if (counted != groups[j].initializers) return false;
  }
  return true;
}

}  // namespace param_detail

// True when `fields` cover every member of Params exactly once (the tiling
// and the member counts of kParamGroups).
constexpr bool fieldsCoverParams(const ParamField* fields, size_t n) {
  return param_detail::fieldsTile(fields, n, sizeof(Params), alignof(Params)) &&
         param_detail::groupsCounted(fields, n, kParamGroups, kNumParamGroups);
}

static_assert(fieldsCoverParams(kParamFields, kNumParamFields),
              "kParamFields must list every member of Params (params.hpp), each once");

// The range checks of every field, in table order, on the bytes of a Params
// (sizeof(Params) of them): true when all hold, else false with the first
// field that breaks its range. Bools and the gait kind are read as their
// byte, never as bool.
bool checkParamFields(const uint8_t* bytes, ParamIssue& issue);

// Only the bools: each byte 0 or 1. The board checks this on the bytes it
// received before they may become a Params.
bool checkBoolBytes(const uint8_t* bytes, ParamIssue& issue);

}  // namespace hyq
