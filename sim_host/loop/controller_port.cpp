#include "sim_host/loop/controller_port.hpp"

#include "firmware/controller/model/kinematics.hpp"
#include "firmware/controller/model/robot_params.hpp"
#include "sim_host/loop/qemu_controller.hpp"
#include "sim_host/loop/wbc_controller.hpp"

namespace hyq::sim {

ControllerPort::~ControllerPort() = default;

namespace {

// Holds the stand posture with the joint loop's PD, plus the torques that
// carry a quarter of the (nominal) weight on each foot and the legs' own
// weight, so the PD only corrects small errors instead of sagging.
class PostureController final : public ControllerPort {
 public:
  explicit PostureController(const hyq::Params& params) : params_(params) {}

  void step(const hal::SensorFrame& s, hal::CommandFrame& c) override {
    c = hal::CommandFrame{};
    c.tick = s.tick;
    const Quat q_wb(s.imu_quat[0], s.imu_quat[1], s.imu_quat[2], s.imu_quat[3]);
    const Mat3 r_bw = q_wb.normalized().toRotationMatrix().transpose();
    const Vec3 gravity_base = r_bw * Vec3(0.0, 0.0, -robot::kGravity);
    const Vec3 foot_force_base =
        r_bw * Vec3(0.0, 0.0, robot::kTotalMass * robot::kGravity / robot::kNumLegs);
    for (int leg = 0; leg < robot::kNumLegs; ++leg) {
      const Vec3 q_leg(s.q[3 * leg], s.q[3 * leg + 1], s.q[3 * leg + 2]);
      const Vec3 tau = legGravityTorque(leg, q_leg, gravity_base) -
                       footJacobianBase(leg, q_leg).transpose() * foot_force_base;
      for (int joint = 0; joint < 3; ++joint) {
        const int j = 3 * leg + joint;
        c.tau_ff[j] = tau[joint];
        c.q_ref[j] = robot::standAngle(leg, joint);
        c.kp[j] = params_.joint.posture_kp;
        c.kd[j] = params_.joint.posture_kd;
      }
      c.telemetry.mu_used[leg] = params_.recovery.mu_default;
    }
    c.telemetry.stance_mask = 0xF;
    c.telemetry.swing_leg = robot::kNumLegs;
  }

 private:
  hyq::Params params_;
};

using Factory = std::unique_ptr<ControllerPort> (*)(const Scenario&);
struct Kind {
  const char* name;
  Factory make;
};

// To add a controller: one line here and its factory.
const Kind kKinds[] = {
    {"posture", [](const Scenario& s) -> std::unique_ptr<ControllerPort> {
       return std::make_unique<PostureController>(s.controller_params);
     }},
    {"wbc", makeWbcController},
    {"qemu", makeQemuController},
};

}  // namespace

std::unique_ptr<ControllerPort> makeController(const std::string& kind, const Scenario& scenario) {
  for (const Kind& k : kKinds)
    if (kind == k.name) return k.make(scenario);
  return nullptr;
}

std::vector<std::string> controllerKinds() {
  std::vector<std::string> names;
  for (const Kind& k : kKinds) names.push_back(k.name);
  return names;
}

}  // namespace hyq::sim
