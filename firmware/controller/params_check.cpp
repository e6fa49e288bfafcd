#include "firmware/controller/params_check.hpp"

#include "firmware/controller/param_table.hpp"

namespace hyq {
namespace {

bool fail(ParamIssue& issue, const char* name, const char* rule) {
  issue.name = name;
  issue.rule = rule;
  return false;
}

// The rules that compare two fields (or a field and the gait), each field
// already within its own range; the first one broken wins.
bool checkCrossFieldRules(const Params& p, ParamIssue& issue) {
  const bool crawl = p.gait.kind == GaitKind::kCrawl;
  if (!(p.qp.f_normal_max > p.qp.f_normal_min)) return fail(issue, "qp.f_normal_max", "above qp.f_normal_min");
  if (crawl && p.gait.yaw_rate != 0.0) return fail(issue, "gait.yaw_rate", "0 with the crawl (it walks straight)");
  // The shift puts the CoM stability_margin inside the coming triangle: a
  // lift-off that waits for more would wait for ever.
  if (!(p.gait.liftoff_margin < p.gait.stability_margin))
    return fail(issue, "gait.liftoff_margin", "below gait.stability_margin (the shift's margin)");
  // Unloading must end before the lift-off it prepares, inside a stance.
  if (!(p.gait.trot.unload_time < p.gait.trot.duty_factor * p.gait.trot.cycle_time))
    return fail(issue, "gait.trot.unload_time",
                "below the stance time (gait.trot.duty_factor x gait.trot.cycle_time)");
  if (p.gait.schedule.trot_at > 0.0 && !crawl)
    return fail(issue, "gait.schedule.trot_at", "0 unless the run starts with the crawl");
  if (p.stance.force_watch_release > p.stance.force_watch)
    return fail(issue, "stance.force_watch_release", "at most stance.force_watch");
  if (p.estimator.acc_bias_time > 0.0 && p.estimator.acc_bias_start_time < 4.0 * p.estimator.vel_filter_tau)
    return fail(issue, "estimator.acc_bias_start_time", "at least 4 x estimator.vel_filter_tau");
  return true;
}

}  // namespace

bool checkParams(const Params& p, ParamIssue& issue) {
  // The bytes of p, not its members: a bool whose byte is neither 0 nor 1
  // is refused without ever being read as a bool.
  if (!checkParamFields(reinterpret_cast<const uint8_t*>(&p), issue)) return false;
  return checkCrossFieldRules(p, issue);
}

}  // namespace hyq
