#include "impactdic/synth/fields.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>

#include "impactdic/core/error.h"

namespace impactdic {
namespace {

TEST(Fields, ExponentialCompressionMatchesItsDefinition) {
  const double e0 = 0.3, L = 120, y_surface = -10, y_fixed = 290;
  const DisplacementField f = ExponentialCompression(e0, L, y_surface, y_fixed);
  // The fixed depth does not move; u = 0 everywhere.
  EXPECT_NEAR(f.u(37, y_fixed)[1], 0, 1e-12);
  EXPECT_EQ(f.u(37, 100)[0], 0);
  // Settlement of the surface: the integral of the strain from the surface to the fixed depth.
  EXPECT_NEAR(f.u(0, y_surface)[1], e0 * L * (1 - std::exp(-(y_fixed - y_surface) / L)), 1e-12);
  for (double Y : {-10.0, 0.0, 55.5, 150.0, 290.0, 330.0}) {
    // Strain e(Y) = e0 exp(-(Y - y_surface) / L), compressive: dv/dY = -e.
    const cv::Vec4d g = f.gradient(12.0, Y);
    EXPECT_NEAR(g[3], -e0 * std::exp(-(Y - y_surface) / L), 1e-15) << Y;
    EXPECT_EQ(g[0], 0);
    EXPECT_EQ(g[1], 0);
    EXPECT_EQ(g[2], 0);
    // The Jacobian is the derivative of u (central differences, error ~ h^2 e0 / L^3).
    const double h = 1e-3;
    const double dvdy = (f.u(12.0, Y + h)[1] - f.u(12.0, Y - h)[1]) / (2 * h);
    const double dvdx = (f.u(12.0 + h, Y)[1] - f.u(12.0 - h, Y)[1]) / (2 * h);
    EXPECT_NEAR(dvdy, g[3], 1e-8) << Y;
    EXPECT_NEAR(dvdx, 0, 1e-12) << Y;
  }
}

TEST(Fields, ExponentialCompressionRejectsANonPositiveLength) {
  EXPECT_THROW(ExponentialCompression(0.2, 0, 0, 100), Error);
}

}  // namespace
}  // namespace impactdic
