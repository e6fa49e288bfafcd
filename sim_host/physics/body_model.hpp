// The bodies the simulator builds (both engines), and where its IMU sits.
// Two descriptions: the controller's own nominal model
// (firmware/controller/model/robot_params.hpp: link masses at mid-link,
// solid-cylinder inertias, the 0.341 m lower leg), and the published HyQ
// description's inertial parameters (the one place for those numbers is
// body_model.cpp). Both share the controller's joint frames: HAA positions
// and axes, the 0.08 m hip and the 0.35 m upper leg.
//
// Link frames (the simulator's, robot.hpp): origin at the link's joint,
// axes those of B when the leg's angles are zero (the link then hangs along
// -z), turning with the joint.
#pragma once
#include <array>

#include "firmware/controller/model/types.hpp"
#include "sim_host/physics/plant_params.hpp"

namespace hyq::sim {

struct LinkInertial {
  double mass = 0.0;                  // [kg]
  Vec3 com = Vec3::Zero();            // [m] centre of mass in the link frame
  Mat3 inertia = Mat3::Zero();        // [kg m^2] about the centre of mass, in the link frame
};

struct RobotBody {
  BodyModel model = BodyModel::nominal;
  double trunk_mass = 0.0;            // [kg]
  Vec3 trunk_com = Vec3::Zero();      // [m] in B
  Mat3 trunk_inertia = Mat3::Zero();  // [kg m^2] about the trunk's centre of mass, in B
  std::array<std::array<LinkInertial, 3>, 4> links{};  // [leg][HAA, HFE, KFE link]
  double lower_length = 0.0;          // [m] KFE -> foot centre
  double total_mass = 0.0;            // [kg] without a payload
  // The links are the nominal solid cylinders of radius
  // robot::kLinkInertiaRadius (the engines then build them with their own
  // cylinder routines, as the nominal model always was).
  bool cylinder_links = false;
};

// The controller's nominal model, as the simulator builds it.
const RobotBody& nominalBody();
// The published HyQ description's inertial parameters (86.756 kg).
const RobotBody& publishedBody();
const RobotBody& robotBody(BodyModel model);
// The bodies a plant simulates: its body model with the trunk's mass and
// inertia tensor scaled by plant.trunk_mass_scale, trunk_inertia_scale.
RobotBody plantBody(const PlantSpec& plant);
const char* bodyModelName(BodyModel model);

// HyQ's IMU: at (0.290, 0.000, 0.0999) m in B, turned upside down (rpy 0,
// -pi, 0), from the published description.
struct ImuPlacement {
  Vec3 position = Vec3::Zero();       // [m] in B
  Mat3 rotation = Mat3::Identity();   // the IMU's axes in B
};
ImuPlacement imuPlacement(ImuMount mount);

}  // namespace hyq::sim
