#include "impactdic/dic/bspline.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "impactdic/core/error.h"

namespace impactdic {
namespace {

// p(x, y) with all monomials x^i y^j, i, j <= degree (the tensor-product spline space), scaled
// so that values stay O(100) on the image (float coefficients: relative precision ~1e-7).
struct Poly {
  int degree;
  double Value(double x, double y, double* gx, double* gy) const {
    const double u = x / 50 - 1, v = y / 40 - 1;  // In [-1, 1.x] over the image.
    double s = 0, sx = 0, sy = 0;
    for (int i = 0; i <= degree; ++i) {
      for (int j = 0; j <= degree; ++j) {
        const double c = 7.0 * std::cos(1.3 * i + 2.1 * j + 0.4);  // Arbitrary coefficients.
        s += c * std::pow(u, i) * std::pow(v, j);
        if (i > 0) sx += c * i * std::pow(u, i - 1) * std::pow(v, j) / 50;
        if (j > 0) sy += c * j * std::pow(u, i) * std::pow(v, j - 1) / 40;
      }
    }
    *gx = sx;
    *gy = sy;
    return 100 + s;
  }
};

void ExpectReproduces(Interpolation kind, int degree) {
  const Poly poly{degree};
  cv::Mat image(90, 110, CV_64F);
  double gx, gy;
  for (int r = 0; r < image.rows; ++r)
    for (int c = 0; c < image.cols; ++c) image.at<double>(r, c) = poly.Value(c, r, &gx, &gy);
  BsplineImage spline;
  spline.Build(image, kind);
  // Away from the mirror boundary (>= 30 px: its influence decays like 0.43^d for the quintic
  // spline's larger pole, < 1e-10 here), the interpolant equals the polynomial up to float
  // rounding of the coefficients: tolerance 2e-4 on values O(100) (~1e-6 relative), 1e-5 on
  // gradients O(1).
  for (double y = 30.25; y < 60; y += 3.3) {
    for (double x = 30.1; x < 80; x += 2.7) {
      double v, sx, sy;
      spline.ValueGradient(x, y, &v, &sx, &sy);
      const double expected = poly.Value(x, y, &gx, &gy);
      EXPECT_NEAR(v, expected, 2e-4) << x << "," << y;
      EXPECT_NEAR(sx, gx, 1e-5) << x << "," << y;
      EXPECT_NEAR(sy, gy, 1e-5) << x << "," << y;
    }
  }
  // Node gradients agree with the continuous evaluation.
  cv::Mat ngx, ngy;
  spline.NodeGradients(&ngx, &ngy);
  double v, sx, sy;
  spline.ValueGradient(45, 40, &v, &sx, &sy);
  EXPECT_NEAR(ngx.at<float>(40, 45), sx, 1e-5);
  EXPECT_NEAR(ngy.at<float>(40, 45), sy, 1e-5);
}

TEST(Bspline, BicubicReproducesCubicPolynomials) { ExpectReproduces(Interpolation::kBicubic, 3); }

TEST(Bspline, BiquinticReproducesQuinticPolynomials) {
  ExpectReproduces(Interpolation::kBiquintic, 5);
}

TEST(Bspline, InterpolatesPixelsAndHonoursTheRegion) {
  cv::Mat image(64, 80, CV_8U);
  cv::randu(image, 0, 255);
  BsplineImage spline;
  spline.Build(image, Interpolation::kBiquintic, cv::Rect(20, 10, 30, 30), /*guard_px=*/8);
  EXPECT_EQ(spline.region(), cv::Rect(12, 2, 46, 46));
  EXPECT_TRUE(spline.Inside(30.5, 20.5));
  EXPECT_FALSE(spline.Inside(5, 20));
  // Deep inside the region (>= 10 px from its edges) the interpolant passes through the pixels.
  for (int r = 15; r < 35; r += 4)
    for (int c = 25; c < 45; c += 3)
      EXPECT_NEAR(spline.Value(c, r), image.at<std::uint8_t>(r, c), 2e-3);
}

// The interpolation condition at every node the spline can evaluate, for images whose sides are
// and are not multiples of the prefilter's line groups (8 rows, 32 columns), shorter and longer
// than its causal horizon (21 samples for the bicubic pole, 33 for the quintic's larger one: the
// short lines take the exact mirror-boundary initial value), for every pixel depth Build reads.
// A sample filtered with another line's data, or one left unfiltered, misses by grey levels.
TEST(Bspline, InterpolatesEveryPixelForEverySizeAndDepth) {
  for (const Interpolation kind : {Interpolation::kBicubic, Interpolation::kBiquintic}) {
    for (const int rows : {8, 9, 15, 21, 22, 33, 34, 40, 71}) {
      for (const int cols : {8, 9, 21, 22, 33, 34, 40, 65, 97}) {
        cv::Mat grey(rows, cols, CV_8U);
        cv::randu(grey, 0, 256);
        for (const int depth : {CV_8U, CV_16U, CV_32F, CV_64F}) {
          const double scale = depth == CV_16U ? 200 : 1;  // 16-bit data up to 51000.
          cv::Mat image;
          grey.convertTo(image, depth, scale);
          BsplineImage spline;
          spline.Build(image, kind);
          double worst = 0;
          for (int r = 0; r < rows; ++r) {
            for (int c = 0; c < cols; ++c) {
              if (!spline.Inside(c, r)) continue;
              worst = std::max(worst,
                               std::abs(spline.Value(c, r) / scale - grey.at<std::uint8_t>(r, c)));
            }
          }
          // Float coefficients of values up to 255: rounding ~1e-4 grey levels.
          EXPECT_LT(worst, 2e-3) << ToString(kind) << " " << cols << "x" << rows << " depth "
                                 << depth;
        }
      }
    }
  }
  BsplineImage spline;
  EXPECT_THROW(spline.Build(cv::Mat(16, 16, CV_8S, cv::Scalar(1)), Interpolation::kBicubic), Error);
}

TEST(Bspline, NamesRoundTrip) {
  EXPECT_EQ(InterpolationFromString(ToString(Interpolation::kBicubic)), Interpolation::kBicubic);
  EXPECT_EQ(InterpolationFromString("biquintic"), Interpolation::kBiquintic);
  EXPECT_THROW(InterpolationFromString("bilinear"), Error);
}

}  // namespace
}  // namespace impactdic
