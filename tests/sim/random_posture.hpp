// Joint angles drawn uniformly within each joint's limits, for the physics
// tests that place a model at many postures and compare it with the
// controller's kinematics.
#pragma once
#include <array>
#include <random>

#include "firmware/controller/model/robot_params.hpp"

namespace hyq::sim {

inline std::array<double, 12> randomPosture(std::mt19937_64& rng) {
  std::array<double, 12> q{};
  for (int leg = 0; leg < 4; ++leg)
    for (int joint = 0; joint < 3; ++joint) {
      double lo, hi;
      robot::jointLimits(leg, joint, lo, hi);
      q[3 * leg + joint] = std::uniform_real_distribution<double>(lo, hi)(rng);
    }
  return q;
}

}  // namespace hyq::sim
