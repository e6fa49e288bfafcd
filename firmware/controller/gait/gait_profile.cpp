#include "firmware/controller/gait/gait_profile.hpp"

namespace hyq {

GaitProfile gaitProfile(GaitKind kind, const Params& p) {
  GaitProfile g;
  g.kind = kind;
  const bool trot = kind == GaitKind::kTrot;
  const bool crawl = !trot;
  g.imu_integration_window = trot ? p.gait.trot.imu_integration_window : p.slip.imu_integration_window;
  g.anchor_on_two_feet = trot;
  g.landing_approach_test = crawl || p.joint.torque_bandwidth > 0.0;
  g.hold_landing_dips = crawl;
  g.grf_base_rotation = trot && p.estimator.grf_leg_dynamics && p.estimator.grf_base_rotation;
  g.grf_fast_turn = crawl && p.estimator.grf_leg_dynamics && p.estimator.grf_base_rotation;
  g.plane_through_loaded_feet = trot;
  g.prior_from_feet_now = trot && p.gait.trot.prior_from_feet_now;
  g.peak_of_loaded_samples = trot && p.gait.trot.peak_of_loaded_samples;
  g.carry_over = trot;
  g.slip_along_ground = trot && p.gait.trot.slip_along_ground;
  g.guess_delay = trot ? p.gait.trot.guess_delay : 0.0;
  g.guess_holds = crawl && p.recovery.guess_holds_for_stance;
  g.guess_light_feet_only = trot && p.joint.torque_bandwidth > 0.0;
  g.guess_from_stance_ratio = crawl && p.joint.torque_bandwidth > 0.0;
  g.cone_force_offset = crawl && p.recovery.enabled ? p.recovery.cone_force_offset : 0.0;
  g.stop_is_not_touchdown = trot;
  g.drag_is_touchdown = crawl;
  g.early_touchdown_on_known_ice = crawl;
  g.switches_to_trot = crawl && p.gait.schedule.trot_at > 0.0;
  g.press_landing_along_normal = crawl && p.stance.press_landing_along_normal;
  g.stance_hold = p.joint.torque_bandwidth > 0.0;
  g.stance_hold_unloaded_only = trot;
  g.swing_inertia_feedforward = trot;
  g.landing_force_press = trot && p.joint.torque_bandwidth > 0.0;
  return g;
}

}  // namespace hyq
