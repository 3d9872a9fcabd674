#include "impactdic/synth/speckle.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "impactdic/core/error.h"
#include "impactdic/synth/fields.h"

namespace impactdic {
namespace {

TEST(Speckle, IntensityIsBoundedAndDeterministic) {
  SpeckleOptions o;
  SpecklePattern a(o, 100, 100), b(o, 100, 100);
  double lo = 1, hi = 0;
  for (int k = 0; k < 2000; ++k) {
    const double x = 0.37 * k - 20, y = 0.11 * k - 10;
    const double v = a.Intensity(x, y);
    EXPECT_EQ(v, b.Intensity(x, y));
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  EXPECT_GE(lo, o.background);
  EXPECT_LT(hi, 1.0);
  EXPECT_GT(hi - lo, 0.5);  // A usable speckle: most of the grey range is used.
}

TEST(Speckle, TranslationRendersTheShiftedPatternExactly) {
  SpeckleOptions o;
  SpecklePattern pattern(o, 64, 64);
  RenderOptions r;
  r.supersampling = 1;
  const cv::Mat img = RenderImage(pattern, 64, 64, Translation(0.3, -0.7), r);
  ASSERT_EQ(img.type(), CV_8U);
  for (int y = 0; y < 64; y += 7) {
    for (int x = 0; x < 64; x += 5) {
      // x = X + u  =>  X = x - u.
      const double expected = std::round(255 * pattern.Intensity(x - 0.3, y + 0.7));
      EXPECT_EQ(img.at<std::uint8_t>(y, x), expected) << x << "," << y;
    }
  }
}

TEST(Speckle, NewtonInversionSolvesTheField) {
  const DisplacementField fields[] = {Rotation(0.05, 30, 40), Sinusoidal(2.0, 1.5, 40.0),
                                      Quadratic(1e-3, -5e-4, 2e-3, 50, 50),
                                      Affine(1, 2, 0.01, -0.02, 0.03, -0.2, 10, 10)};
  for (const auto& f : fields) {
    for (double x = 0; x < 100; x += 13.3) {
      double X, Y;
      ASSERT_TRUE(InvertField(f, x, 0.7 * x, &X, &Y));
      const cv::Vec2d u = f.u(X, Y);
      EXPECT_NEAR(X + u[0], x, 1e-9);
      EXPECT_NEAR(Y + u[1], 0.7 * x, 1e-9);
    }
  }
}

TEST(Speckle, FieldGradientsMatchFiniteDifferences) {
  const DisplacementField fields[] = {Rotation(0.05, 30, 40), Sinusoidal(2.0, 1.5, 40.0),
                                      Quadratic(1e-3, -5e-4, 2e-3, 50, 50)};
  const double h = 1e-5;
  for (const auto& f : fields) {
    const cv::Vec4d g = f.gradient(17.0, 23.0);
    const cv::Vec2d dx = (f.u(17 + h, 23) - f.u(17 - h, 23)) / (2 * h);
    const cv::Vec2d dy = (f.u(17, 23 + h) - f.u(17, 23 - h)) / (2 * h);
    EXPECT_NEAR(g[0], dx[0], 1e-8);
    EXPECT_NEAR(g[1], dy[0], 1e-8);
    EXPECT_NEAR(g[2], dx[1], 1e-8);
    EXPECT_NEAR(g[3], dy[1], 1e-8);
  }
}

TEST(Speckle, NoiseDoesNotDependOnThreadCount) {
  SpecklePattern pattern(SpeckleOptions{}, 80, 60);
  RenderOptions r;
  r.noise_sigma = 3;
  r.bits = 16;
  cv::Mat one, two;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = RenderImage(pattern, 80, 60, Rotation(0.01, 40, 30), r);
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    two = RenderImage(pattern, 80, 60, Rotation(0.01, 40, 30), r);
  }
  ASSERT_EQ(one.type(), CV_16U);
  EXPECT_EQ(cv::norm(one, two, cv::NORM_INF), 0);
  // The noise is there: a different seed changes the image.
  r.noise_seed = 8;
  const cv::Mat other = RenderImage(pattern, 80, 60, Rotation(0.01, 40, 30), r);
  EXPECT_GT(cv::norm(one, other, cv::NORM_INF), 0);
}

TEST(Speckle, SequenceRampsTheField) {
  const DisplacementSequence seq = LinearSequence(Translation(2.0, -4.0), 5);
  EXPECT_EQ(seq.frames, 5);
  EXPECT_NEAR(seq.at(0).u(3, 4)[0], 0, 1e-15);
  EXPECT_NEAR(seq.at(2).u(3, 4)[1], -2.0, 1e-15);
  EXPECT_NEAR(seq.at(4).u(3, 4)[0], 2.0, 1e-15);
}

TEST(Speckle, OptionsCheckNamesTheField) {
  SpeckleOptions o;
  EXPECT_NO_THROW(o.Check());
  o.density = 0;
  try {
    o.Check();
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("density"), std::string::npos);
  }
  RenderOptions r;
  EXPECT_NO_THROW(r.Check());
  r.bits = 12;
  EXPECT_THROW(r.Check(), Error);
}

}  // namespace
}  // namespace impactdic
