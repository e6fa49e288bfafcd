// Fixed-size Eigen types used across the controller. No dynamic sizes.
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>

#include "hal/frames.hpp"

// A helper split out of a function for reading, but compiled into its one
// caller: on the board a call costs 10-30 instructions of the tick's budget
// (GCC and Clang).
#define HYQ_INLINE [[gnu::always_inline]] inline

// A hot function compiled with every call in its body inlined, the small
// Eigen kernels included (GCC's heuristics leave some of them out of line
// in a large file, a call per coefficient of a 3x3 product). Only calls
// whose definition is in the same file are inlined.
#define HYQ_FLATTEN [[gnu::flatten]]

namespace hyq {

// The one definition of each is in hal/frames.hpp.
using hal::kNumLegs;     // LF, RF, LH, RH
using hal::kNumJoints;   // 3 per leg: HAA, HFE, KFE
using hal::kTickPeriod;  // [s] one control tick

// A set of legs: bit i for leg i. Only the four legs' bits are ever set.
class LegMask {
 public:
  static constexpr uint32_t kAllBits = (1u << kNumLegs) - 1u;
  constexpr LegMask() = default;
  constexpr explicit LegMask(uint32_t bits) : bits_(bits & kAllBits) {}
  static constexpr LegMask all() { return LegMask(kAllBits); }
  static constexpr LegMask only(int leg) { return LegMask(1u << leg); }

  constexpr bool has(int leg) const { return ((bits_ >> leg) & 1u) != 0u; }
  constexpr bool any() const { return bits_ != 0u; }
  constexpr bool none() const { return bits_ == 0u; }
  constexpr uint32_t bits() const { return bits_; }
  void set(int leg) { bits_ |= 1u << leg; }

  constexpr LegMask operator&(LegMask o) const { return LegMask(bits_ & o.bits_); }
  constexpr LegMask operator|(LegMask o) const { return LegMask(bits_ | o.bits_); }
  constexpr LegMask operator~() const { return LegMask(~bits_); }
  LegMask& operator|=(LegMask o) { bits_ |= o.bits_; return *this; }
  constexpr bool operator==(LegMask o) const { return bits_ == o.bits_; }
  constexpr bool operator!=(LegMask o) const { return bits_ != o.bits_; }

 private:
  uint32_t bits_ = 0u;
};

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
