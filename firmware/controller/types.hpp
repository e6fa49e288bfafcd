// Fixed-size Eigen types used across the controller. No dynamic sizes.
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace hyq {

using Vec3 = Eigen::Matrix<double, 3, 1>;
using Vec4 = Eigen::Matrix<double, 4, 1>;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Vec12 = Eigen::Matrix<double, 12, 1>;
using Mat3 = Eigen::Matrix<double, 3, 3>;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using Mat12 = Eigen::Matrix<double, 12, 12>;
using Mat6x12 = Eigen::Matrix<double, 6, 12>;
using Quat = Eigen::Quaternion<double>;

// Four legs' worth of 3-vectors, e.g. foot positions (column i = leg i).
using Mat3x4 = Eigen::Matrix<double, 3, 4>;

// x limited to [-limit, limit] (limit >= 0).
inline double clampAbs(double x, double limit) { return x > limit ? limit : (x < -limit ? -limit : x); }

inline Mat3 skew(const Vec3& v) {
  Mat3 s;
  s << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return s;
}

}  // namespace hyq
