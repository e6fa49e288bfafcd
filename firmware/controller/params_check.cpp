#include "firmware/controller/params_check.hpp"

#include <cmath>

namespace hyq {
namespace {

class Checker {
 public:
  explicit Checker(ParamIssue& issue) : issue_(issue) {}
  bool ok() const { return ok_; }

  // lo <= value <= hi (finite).
  void in(const char* name, double value, double lo, double hi, const char* rule) {
    if (ok_ && !(std::isfinite(value) && value >= lo && value <= hi)) fail(name, rule);
  }
  // lo < value <= hi (finite).
  void above(const char* name, double value, double lo, double hi, const char* rule) {
    if (ok_ && !(std::isfinite(value) && value > lo && value <= hi)) fail(name, rule);
  }
  void fail(const char* name, const char* rule) {
    if (!ok_) return;
    ok_ = false;
    issue_.name = name;
    issue_.rule = rule;
  }

 private:
  ParamIssue& issue_;
  bool ok_ = true;
};

// "group.field" from the member expression, so a rule names its own key.
#define HYQ_IN(group, field, lo, hi) c.in(#group "." #field, p.group.field, lo, hi, "in [" #lo ", " #hi "]")
#define HYQ_ABOVE(group, field, lo, hi) c.above(#group "." #field, p.group.field, lo, hi, "in (" #lo ", " #hi "]")

}  // namespace

bool checkParams(const Params& p, ParamIssue& issue) {
  Checker c(issue);
  c.in("dt", p.dt, 0.0005, 0.01, "in [0.0005, 0.01] s");

  HYQ_IN(qp, regularisation, 0.0, 1.0);
  HYQ_IN(qp, tangential_weight, 0.0, 1.0);
  HYQ_ABOVE(qp, wrench_weight_lin, 0.0, 1000.0);
  HYQ_ABOVE(qp, wrench_weight_ang, 0.0, 1000.0);
  HYQ_IN(qp, f_normal_min, 0.0, 1000.0);
  HYQ_ABOVE(qp, f_normal_max, 0.0, 10000.0);
  if (p.qp.f_normal_max <= p.qp.f_normal_min) c.fail("qp.f_normal_max", "above qp.f_normal_min");
  HYQ_IN(qp, max_iterations, 1, 256);
  HYQ_IN(qp, force_smoothing, 0.0, 100.0);
  HYQ_ABOVE(qp, feasibility_tolerance, 0.0, 1e-3);

  if (p.gait.kind != GaitKind::kCrawl && p.gait.kind != GaitKind::kTrot)
    c.fail("gait.kind", "crawl (0) or trot (1)");
  HYQ_IN(gait, cycle_time, 0.5, 100.0);
  HYQ_IN(gait, duty_factor, 0.5, 0.99);
  for (double offset : p.gait.phase_offset)
    c.in("gait.phase_offset", offset, 0.0, 1.0, "each in [0, 1]");
  HYQ_IN(gait, speed, -1.0, 1.0);
  HYQ_IN(gait, yaw_rate, -1.0, 1.0);
  if (p.gait.kind == GaitKind::kCrawl && p.gait.yaw_rate != 0.0)
    c.fail("gait.yaw_rate", "0 with the crawl (it walks straight)");
  HYQ_IN(gait, step_height, 0.0, 0.3);
  HYQ_IN(gait, body_height, 0.3, 0.75);
  HYQ_IN(gait, stability_margin, 0.0, 0.2);
  // The shift puts the CoM stability_margin inside the coming triangle: a
  // lift-off that waits for more would wait for ever.
  HYQ_IN(gait, liftoff_margin, -1.0, 0.2);
  if (!(p.gait.liftoff_margin < p.gait.stability_margin))
    c.fail("gait.liftoff_margin", "below gait.stability_margin (the shift's margin)");
  HYQ_IN(gait, liftoff_wait_max, 0.0, 1e6);
  HYQ_ABOVE(gait, crouch_speed, 0.0, 1.0);
  HYQ_IN(gait, crouch_max, 0.0, 0.3);
  HYQ_IN(gait, start_delay, 0.0, 1e6);
  HYQ_ABOVE(gait, reshift_speed, 0.0, 1.0);
  HYQ_IN(gait, min_shift_time, 0.05, 5.0);
  HYQ_IN(gait, max_shift_acceleration, 0.0, 10.0);
  HYQ_IN(gait, initial_phase, 0.0, 1.0);
  HYQ_ABOVE(gait, swing_lift_fraction, 0.0, 0.5);
  HYQ_IN(gait, swing_depth, 0.0, 0.1);
  HYQ_ABOVE(gait, touchdown_search_speed, 0.0, 1.0);
  HYQ_IN(gait, touchdown_search_max, 0.0, 0.3);
  HYQ_ABOVE(gait, freeze_drop_speed, 0.0, 1.0);
  HYQ_IN(gait, touchdown_min_swing, 0.0, 1.0);
  HYQ_IN(gait, load_time, 0.001, 1.0);
  HYQ_IN(gait, unload_time, 0.001, 1.0);
  HYQ_ABOVE(gait, ramp_force, 0.0, 2000.0);
  HYQ_IN(gait, lane_step, 0.0, 0.2);
  HYQ_IN(gait, max_tilt, 0.0, 1.2);
  HYQ_IN(gait, trot.cycle_time, 0.3, 2.0);
  HYQ_IN(gait, trot.duty_factor, 0.5, 0.8);
  HYQ_IN(gait, trot.step_height, 0.0, 0.3);
  HYQ_IN(gait, trot.landing_fraction, 0.0, 0.5);
  HYQ_ABOVE(gait, trot.touchdown_speed, 0.0, 2.0);
  HYQ_IN(gait, trot.load_time, 0.001, 1.0);
  HYQ_IN(gait, trot.unload_time, 0.001, 1.0);
  // Unloading must end before the lift-off it prepares, inside a stance.
  if (!(p.gait.trot.unload_time < p.gait.trot.duty_factor * p.gait.trot.cycle_time))
    c.fail("gait.trot.unload_time", "below the stance time (gait.trot.duty_factor x gait.trot.cycle_time)");
  HYQ_IN(gait, trot.foothold_gain, 0.0, 1.0);
  HYQ_IN(gait, trot.max_foothold_correction, 0.0, 0.5);
  HYQ_ABOVE(gait, trot.acceleration, 0.0, 10.0);
  HYQ_ABOVE(gait, trot.max_com_error, 0.0, 1.0);
  HYQ_ABOVE(gait, trot.imu_integration_window, 0.0, 10.0);
  HYQ_IN(gait, trot.walk_time, 0.0, 1e6);
  HYQ_IN(gait, trot.guess_delay, 0.0, 1.0);
  HYQ_IN(gait, trot.speed_per_mu, 0.0, 100.0);
  HYQ_IN(gait, trot.carry_distance, 0.0, 2.0);
  HYQ_IN(gait, trot.carry_agreement, 0.0, 10.0);
  HYQ_IN(gait, trot.carry_agreement_above, 0.0, 10.0);
  HYQ_IN(gait, trot.carry_max_samples, 0, 32);
  HYQ_IN(gait, trot.prior_row_split, 0.0, 0.5);
  HYQ_IN(gait, trot.prior_row_interior, 0.0, 0.5);
  HYQ_IN(gait, schedule.trot_at, 0.0, 1e6);
  HYQ_IN(gait, schedule.trot_speed, -1.0, 1.0);
  HYQ_ABOVE(gait, schedule.max_com_speed, 0.0, 1.0);
  if (p.gait.schedule.trot_at > 0.0 && p.gait.kind != GaitKind::kCrawl)
    c.fail("gait.schedule.trot_at", "0 unless the run starts with the crawl");

  HYQ_IN(trunk, kp_lin, 0.0, 1e5);
  HYQ_IN(trunk, kd_lin, 0.0, 1e4);
  HYQ_IN(trunk, kp_ang, 0.0, 1e5);
  HYQ_IN(trunk, kd_ang, 0.0, 1e4);

  HYQ_IN(joint, posture_kp, 0.0, 2000.0);
  HYQ_IN(joint, posture_kd, 0.0, 100.0);
  HYQ_IN(joint, swing_kp, 0.0, 2000.0);
  HYQ_IN(joint, swing_kd, 0.0, 100.0);
  HYQ_IN(joint, stance_kd, 0.0, 100.0);

  HYQ_IN(stance, force_on, 0.0, 1000.0);
  HYQ_IN(stance, joint_stop_margin, 0.0, 0.5);
  HYQ_IN(stance, force_watch, 0.0, 1000.0);
  HYQ_IN(stance, force_watch_release, 0.0, 1000.0);
  HYQ_ABOVE(stance, watch_approach_speed, 0.0, 10.0);
  if (p.stance.force_watch_release > p.stance.force_watch)
    c.fail("stance.force_watch_release", "at most stance.force_watch");

  HYQ_ABOVE(estimator, vel_filter_tau, 0.0, 10.0);
  HYQ_IN(estimator, gyro_bias_time, 0.0, 100.0);
  HYQ_IN(estimator, gyro_bias_limit, 0.0, 1.0);
  HYQ_IN(estimator, acc_bias_time, 0.0, 1000.0);
  HYQ_IN(estimator, acc_bias_start_time, 0.0, 1000.0);
  if (p.estimator.acc_bias_time > 0.0 && p.estimator.acc_bias_start_time < 4.0 * p.estimator.vel_filter_tau)
    c.fail("estimator.acc_bias_start_time", "at least 4 x estimator.vel_filter_tau");
  HYQ_IN(estimator, acc_bias_limit, 0.0, 5.0);
  HYQ_IN(estimator, torque_bias_time, 0.0, 100.0);
  HYQ_IN(estimator, torque_bias_settle, 0.0, 10.0);
  HYQ_IN(estimator, torque_bias_limit, 0.0, 50.0);
  HYQ_IN(estimator, torque_bias_start_weight, 0.0, 1e6);
  HYQ_IN(estimator, torque_offset_sigma, 0.0, 50.0);
  // The GRF delay line holds (window - 1) / 2 ticks, at most kMaxGrfDelay.
  HYQ_IN(estimator, grf_accel_window, 2, 17);

  HYQ_ABOVE(slip, threshold, 0.0, 1.0);
  HYQ_ABOVE(slip, holding_agreement, 0.0, 1.0);
  HYQ_IN(slip, debounce_ticks, 1, 100);
  HYQ_IN(slip, landing_debounce_extra, 0, 100);
  HYQ_IN(slip, release_ticks, 1, 1000);
  HYQ_IN(slip, creep_threshold, -1.0, 1.0);
  HYQ_IN(slip, creep_filter_ticks, 1, 1000);
  HYQ_IN(slip, landing_drag_allowance, 0.0, 1.0);
  HYQ_IN(slip, landing_drag_travel, -1.0, 1.0);
  HYQ_ABOVE(slip, multi_leg_consistency, 0.0, 1.0);
  HYQ_ABOVE(slip, imu_integration_window, 0.0, 10.0);
  HYQ_ABOVE(slip, imu_anchor_agreement, 0.0, 1.0);
  HYQ_IN(slip, estimate_samples_mu, 1, 32);
  HYQ_IN(slip, estimate_samples_n, 1, 32);
  HYQ_IN(slip, min_slip_speed, 0.0, 1.0);
  HYQ_IN(slip, min_estimate_samples, 1, 32);
  HYQ_IN(slip, min_estimate_force, 0.0, 2000.0);
  HYQ_IN(slip, max_estimate_force_sigma, 0.0, 1.0);
  HYQ_IN(slip, max_slide_acceleration, 0.0, 1000.0);
  HYQ_IN(slip, min_force_slip_angle, 0.0, 3.15);
  HYQ_IN(slip, max_friction_slip_angle, 0.0, 3.15);
  HYQ_IN(slip, max_normal_tilt, 0.0, 3.15);
  HYQ_IN(slip, max_slip_elevation, 0.0, 1.58);
  HYQ_ABOVE(slip, max_mu_estimate, 0.0, 10.0);
  HYQ_IN(slip, normal_mean_iterations, 1, 20);
  HYQ_IN(slip, normal_mean_tolerance, 0.0, 1e-3);
  HYQ_IN(slip, normal_prior_sigma, 0.0, 1.0);
  HYQ_IN(slip, prior_local_length, 0.0, 10.0);
  HYQ_IN(slip, ending_slip_fraction, 0.0, 1.0);
  HYQ_ABOVE(slip, prior_inlier_distance, 0.0, 0.1);
  HYQ_IN(slip, prior_turn_margin, 0.0, 0.5);
  HYQ_ABOVE(slip, slip_direction_sigma, 0.0, 3.15);
  HYQ_ABOVE(slip, estimate_force_sigma, 0.0, 1000.0);
  HYQ_IN(slip, slip_velocity_sigma, 0.0, 1.0);
  HYQ_IN(slip, max_slide_stiffness, 0.0, 1e7);
  HYQ_IN(slip, prior_switch_angle, 0.0, 1.0);
  HYQ_IN(slip, prior_switch_travel, 0.0, 0.1);
  HYQ_IN(slip, slide_window, 2, 16);  // kMaxSlideWindow
  HYQ_IN(slip, slide_travel, 0.0, 0.01);

  HYQ_IN(recovery, k_normal, 0.0, 1000.0);
  HYQ_IN(recovery, k_mu, 0.0, 1000.0);
  HYQ_ABOVE(recovery, pyramid_scale, 0.0, 1.0);
  HYQ_IN(recovery, mu_default, 0.01, 2.0);
  HYQ_ABOVE(recovery, freeze_after, 0.0, 100.0);
  HYQ_IN(recovery, freeze_hold, 0.0, 100.0);
  HYQ_IN(recovery, unfreeze_blend, 0.0, 10.0);
  HYQ_IN(recovery, freeze_min_load, 0.0, 2000.0);
  HYQ_IN(recovery, freeze_max, 0.0, 1000.0);
  HYQ_ABOVE(recovery, estimate_margin, 0.0, 1.0);
  HYQ_ABOVE(recovery, brake_margin, 0.0, 1.0);
  HYQ_IN(recovery, slip_damping, 0.0, 1000.0);
  HYQ_IN(recovery, mu_rise_rate, 0.0, 10.0);
  HYQ_IN(recovery, mu_rise_delay, 0.0, 100.0);
  HYQ_IN(recovery, mu_rise_ceiling, 0.0, 2.0);
  HYQ_IN(recovery, mu_floor, 0.0, 1.0);
  HYQ_IN(recovery, cone_force_offset, 0.0, 1000.0);
  HYQ_IN(recovery, slope_floor_factor, 0.0, 10.0);
  HYQ_IN(recovery, ground_plane_min_angle, 0.0, 3.15);

  HYQ_ABOVE(safety, max_joint_velocity, 0.0, 1000.0);
  HYQ_ABOVE(safety, max_joint_torque, 0.0, 10000.0);
  HYQ_ABOVE(safety, max_gyro, 0.0, 1000.0);
  HYQ_ABOVE(safety, max_acc, 0.0, 10000.0);
  HYQ_ABOVE(safety, quat_norm_tol, 0.0, 1.0);
  HYQ_IN(safety, joint_range_margin, 0.0, 3.0);
  return c.ok();
}

#undef HYQ_IN
#undef HYQ_ABOVE

}  // namespace hyq
