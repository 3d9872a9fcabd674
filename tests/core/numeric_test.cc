#include "impactdic/core/numeric.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace impactdic {
namespace {

TEST(GoldenSection, FindsTheVertexOfAParabola) {
  // -(x - 0.3)^2 has its maximum at 0.3; golden section converges to it within ~sqrt(eps) of
  // the width, the resolution of a maximum (the function is flat there to second order).
  int evaluations = 0;
  const double x = GoldenSectionMaximize(
      [&](double t) {
        ++evaluations;
        return -(t - 0.3) * (t - 0.3);
      },
      /*lo=*/-1.0, /*hi=*/2.0, {.max_iterations = 200, .relative_tolerance = 1e-12});
  EXPECT_NEAR(x, 0.3, 1e-7);
  EXPECT_LE(evaluations, 202);
}

TEST(GoldenSection, FindsAnAsymmetricPeak) {
  // t exp(-t) peaks at t = 1.
  const double x = GoldenSectionMaximize([](double t) { return t * std::exp(-t); }, 0.0, 5.0,
                                         {.max_iterations = 300});
  EXPECT_NEAR(x, 1.0, 1e-7);
}

TEST(GoldenSection, BracketShrinksByTheGoldenRatioPerIteration) {
  // With a monotone increasing f the bracket keeps its right end: after n steps it is
  // [hi - r^n (hi - lo), hi], so the midpoint is hi - r^n (hi - lo) / 2.
  const double r = (std::sqrt(5.0) - 1.0) / 2.0;
  const double x =
      GoldenSectionMaximize([](double t) { return t; }, 0.0, 1.0, {.max_iterations = 10});
  EXPECT_NEAR(x, 1.0 - std::pow(r, 10) / 2, 1e-12);
}

TEST(GoldenSection, ToleranceStopsEarly) {
  int evaluations = 0;
  GoldenSectionMaximize(
      [&](double t) {
        ++evaluations;
        return -t * t;
      },
      -1.0, 1.0, {.max_iterations = 1000, .relative_tolerance = 1e-3});
  // 2 r^n <= 1e-3 needs n = 16 reductions.
  EXPECT_EQ(evaluations, 2 + 16);
}

TEST(NaN, IsNotANumber) {
  EXPECT_TRUE(std::isnan(kNaN));
  EXPECT_TRUE(std::isnan(kNaNf));
}

}  // namespace
}  // namespace impactdic
