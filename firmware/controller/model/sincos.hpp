// Sine and cosine of one angle from one argument reduction. The board's
// libm (newlib) reduces the argument once for sin and again for cos; the
// legs stage takes both of three angles per leg every tick. Within
// kSinCosRange the result is within one unit in the last place of the true
// value (tests/unit/sincos_test.cpp); the kernels are the classic fdlibm
// minimax polynomials on [-pi/4, pi/4] (their published coefficients).
// The same code on the host and on the board: the same bits on both.
#pragma once
#include <cmath>
#include <cstdint>
#include <cstring>

#include "firmware/controller/model/types.hpp"

namespace hyq {

struct SinCos {
  double s, c;
};

// [rad] |x| at most this (joint angles are within 2 pi): the reduction
// below takes n pi/2 off exactly for |n| < 2^20.
constexpr double kSinCosRange = 1.0e5;

namespace sincos_detail {

// pi/2 in 33-bit parts (n times a part is exact for |n| < 2^20), each
// with the rest of pi/2 after it: x - n pi/2 to 85 bits with the first,
// 118 with two, 151 with three, where x lies that close to a multiple.
constexpr double kTwoOverPi = 6.36619772367581382433e-01;
constexpr double kPio2_1 = 1.57079632673412561417e+00, kPio2_1t = 6.07710050650619224932e-11;
constexpr double kPio2_2 = 6.07710050630396597660e-11, kPio2_2t = 2.02226624879595063154e-21;
constexpr double kPio2_3 = 2.02226624871116645580e-21, kPio2_3t = 8.47842766036889956997e-32;

// The reduction's next part of pi/2 taken off r - w (w the rest the last
// part left); returns the new leading part.
HYQ_INLINE double nextPart(double& r, double& w, double fn, double part, double rest) {
  const double t = r;
  w = fn * part;
  r = t - w;
  w = fn * rest - ((t - r) - w);
  return r - w;
}

// sin(x + y) for |x| <= pi/4, y the tail of the reduced argument.
HYQ_INLINE double kernelSin(double x, double y) {
  constexpr double S1 = -1.66666666666666324348e-01, S2 = 8.33333333332248946124e-03,
                   S3 = -1.98412698298579493134e-04, S4 = 2.75573137070700676789e-06,
                   S5 = -2.50507602534068634195e-08, S6 = 1.58969099521155010221e-10;
  const double z = x * x, v = z * x;
  const double r = S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)));
  return x - ((z * (0.5 * y - v * r) - y) - v * S1);
}

// cos(x + y) for |x| <= pi/4.
HYQ_INLINE double kernelCos(double x, double y) {
  constexpr double C1 = 4.16666666666666019037e-02, C2 = -1.38888888888741095749e-03,
                   C3 = 2.48015872894767294178e-05, C4 = -2.75573143513906633035e-07,
                   C5 = 2.08757232129817482790e-09, C6 = -1.13596475577881948265e-11;
  const double z = x * x;
  const double r = z * (C1 + z * (C2 + z * (C3 + z * (C4 + z * (C5 + z * C6)))));
  const double ax = x < 0.0 ? -x : x;
  if (ax < 0.3) return 1.0 - (0.5 * z - (z * r - x * y));
  // 1 - z/2 with z/2 split as qx + (z/2 - qx), qx an exact quarter of x^2's
  // scale, so that 1 - qx is exact: x/4 with its low word cleared, or
  // 0.28125 above 0.78125.
  double qx = 0.28125;
  if (ax <= 0.78125) {
    uint64_t bits;
    std::memcpy(&bits, &ax, sizeof bits);
    bits = (bits - (uint64_t{0x00200000} << 32)) & 0xFFFFFFFF00000000ull;
    std::memcpy(&qx, &bits, sizeof qx);
  }
  const double hz = 0.5 * z - qx;
  const double a = 1.0 - qx;
  return a - (hz - (z * r - x * y));
}

}  // namespace sincos_detail

// sin(x) and cos(x) for |x| <= kSinCosRange.
HYQ_INLINE SinCos sinCos(double x) {
  using namespace sincos_detail;
  const double ax = x < 0.0 ? -x : x;
  if (ax <= 0.78539816339744828) return {kernelSin(x, 0.0), kernelCos(x, 0.0)};
  // x = n pi/2 + (hi + lo), n the nearest integer to x 2/pi.
  const int n = static_cast<int>(x * kTwoOverPi + (x < 0.0 ? -0.5 : 0.5));
  const double fn = static_cast<double>(n);
  double r = x - fn * kPio2_1;
  double w = fn * kPio2_1t;
  double hi = r - w;
  // Cancellation of more than 16 bits: the next part of pi/2, and of more
  // than 49 the last.
  if (std::fabs(hi) < ax * 0x1p-16) {
    hi = nextPart(r, w, fn, kPio2_2, kPio2_2t);
    if (std::fabs(hi) < ax * 0x1p-49) hi = nextPart(r, w, fn, kPio2_3, kPio2_3t);
  }
  const double lo = (r - hi) - w;
  const double s = kernelSin(hi, lo), c = kernelCos(hi, lo);
  switch (n & 3) {
    case 0: return {s, c};
    case 1: return {c, -s};
    case 2: return {-s, -c};
    default: return {-c, s};
  }
}

// atan2(s, c) for s >= 0, the angle of a sine and cosine pair. For c > 0 and
// s / c far below 2^60 it is atan(s / c): the path newlib's atan2 takes itself
// there (the same value on the board), without its case analysis, at half
// its cost. Elsewhere atan2.
HYQ_INLINE double angleOfSineCosine(double s, double c) {
  constexpr double kRatioBound = 0x1p50;  // [-] s / c below this: no overflow, atan2's plain path
  return c > 0.0 && s < kRatioBound * c ? std::atan(s / c) : std::atan2(s, c);
}

}  // namespace hyq
