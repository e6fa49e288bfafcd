// sinCos against the host's libm (glibc's sin and cos, correctly rounded in
// practice): within one unit in the last place over the joints' range and
// beyond, on a million random angles and on the quadrant edges.
#include "firmware/controller/model/sincos.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace hyq {
namespace {

// Distance in units in the last place of the reference (0: the same bits),
// the smaller spacing on either side of it (just below a power of two the
// spacing halves).
double ulps(double got, double expected) {
  if (got == expected) return 0.0;
  const double a = std::fabs(expected);
  const double ulp = std::fmin(std::nextafter(a, INFINITY) - a, a - std::nextafter(a, 0.0));
  return std::fabs(got - expected) / (ulp > 0.0 ? ulp : std::nextafter(0.0, 1.0));
}

void expectClose(double x, double& worst, int& exact) {
  const SinCos sc = sinCos(x);
  const double es = ulps(sc.s, std::sin(x)), ec = ulps(sc.c, std::cos(x));
  worst = std::fmax(worst, std::fmax(es, ec));
  exact += (es == 0.0) + (ec == 0.0);
  ASSERT_LE(es, 1.0) << "sin(" << x << ")";
  ASSERT_LE(ec, 1.0) << "cos(" << x << ")";
}

TEST(SinCos, WithinOneUlpOfLibmOverTwoTurns) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-4.0 * M_PI, 4.0 * M_PI);
  double worst = 0.0;
  int exact = 0;
  const int n = 1000000;
  for (int i = 0; i < n; ++i) expectClose(u(rng), worst, exact);
  // Most results are the correctly rounded ones themselves.
  EXPECT_GT(exact, static_cast<int>(0.95 * 2 * n)) << "worst " << worst << " ulp";
}

TEST(SinCos, SmallAnglesAndQuadrantEdges) {
  double worst = 0.0;
  int exact = 0;
  for (double x : {0.0, -0.0, 1e-300, 1e-9, -1e-9, 0.1, std::nextafter(0.3, 0.0), 0.3, std::nextafter(0.78125, 1.0),
                   0.78125, 0.7853981633974483}) {
    expectClose(x, worst, exact);
    expectClose(-x, worst, exact);
  }
  for (int k = -8; k <= 8; ++k) {
    const double edge = k * M_PI / 4.0;
    for (double d : {-1e-12, 0.0, 1e-12}) expectClose(edge + d, worst, exact);
  }
  EXPECT_EQ(sinCos(0.0).s, 0.0);
  EXPECT_EQ(sinCos(0.0).c, 1.0);
}

TEST(SinCos, FarOutToTheStatedRange) {
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> u(-kSinCosRange, kSinCosRange);
  double worst = 0.0;
  int exact = 0;
  for (int i = 0; i < 100000; ++i) expectClose(u(rng), worst, exact);
}

}  // namespace
}  // namespace hyq
