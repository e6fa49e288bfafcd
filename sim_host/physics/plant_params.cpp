#include "sim_host/physics/plant_params.hpp"

#include <cstdio>

namespace hyq::sim {

PlantSpec idealPlant() { return PlantSpec{}; }

PlantSpec hyqPlant() {
  PlantSpec p;
  p.model = PlantModel::hyq;
  p.actuator.model = true;
  p.actuator.velocity_limit = kHyqJointVelocityLimit;
  p.encoder.resolution = kHyqEncoderResolution;
  p.encoder.velocity = VelocitySource::differentiated;
  p.delay = kHyqDelays;
  p.body = BodyModel::published;
  p.imu = ImuMount::mounted;
  return p;
}

const char* plantModelName(PlantModel m) { return m == PlantModel::hyq ? "hyq" : "ideal"; }

bool parsePlantModelName(const std::string& name, PlantModel& out) {
  if (name == "ideal")
    out = PlantModel::ideal;
  else if (name == "hyq")
    out = PlantModel::hyq;
  else
    return false;
  return true;
}

namespace {
std::string number(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.10g", v);
  return b;
}
}  // namespace

std::string plantJson(const PlantSpec& p) {
  const ActuatorParams& a = p.actuator;
  std::string actuator = "{\"model\": \"ideal\"}";
  if (a.model)
    actuator = "{\"model\": \"second_order_torque_loop\", \"pd_rate_hz\": " + number(a.pd_rate) +
               ", \"bandwidth_hz\": " + number(a.bandwidth) + ", \"damping_ratio\": " + number(a.damping_ratio) +
               ", \"rate_limit_nm_per_s\": " + number(a.rate_limit) +
               ", \"torque_sensor_cutoff_hz\": " + number(a.torque_sensor_cutoff) +
               ", \"velocity_limit_rad_per_s\": " + number(a.velocity_limit) + "}";
  const EncoderParams& e = p.encoder;
  std::string encoder = "{\"resolution_rad\": " + number(e.resolution) + ", \"velocity\": \"";
  encoder += e.velocity == VelocitySource::differentiated
                 ? "differentiated\", \"velocity_cutoff_hz\": " + number(e.velocity_cutoff) + "}"
                 : "truth\"}";
  const DelayParams& d = p.delay;
  const std::string delays = "{\"sensor\": " + std::to_string(d.sensor_ticks) +
                             ", \"command\": " + std::to_string(d.command_ticks) +
                             ", \"imu\": " + std::to_string(d.imu_ticks) + "}";
  return "{\"model\": \"" + std::string(plantModelName(p.model)) + "\", \"actuator\": " + actuator +
         ", \"delay_ticks\": " + delays + ", \"encoder\": " + encoder + ", \"imu\": \"" +
         (p.imu == ImuMount::mounted ? "mounted" : "origin") + "\", \"body\": \"" +
         (p.body == BodyModel::published ? "published" : "nominal") + "\", \"trunk_mass_scale\": " +
         number(p.trunk_mass_scale) + ", \"trunk_inertia_scale\": " + number(p.trunk_inertia_scale) + "}";
}

}  // namespace hyq::sim
