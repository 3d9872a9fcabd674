// The near-Nyquist bias figure (preprocess/nyquist_bias.h): the model against the dic module's
// own B-spline, and the properties of the measure.
#include "impactdic/preprocess/nyquist_bias.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "impactdic/dic/bspline.h"
#include "impactdic/preprocess/preprocess.h"
#include "impactdic/synth/fourier_shift.h"

namespace impactdic {
namespace {

constexpr double kPi = std::numbers::pi;

// For one frequency the predicted bias is -phi / w, phi the phase error of the cubic B-spline
// interpolant at fractional position t. Checked against the dic module's BsplineImage (the
// interpolant the correlation uses): the samples of cos(w x) interpolated at x + t are
// |T| cos(w (x + t) + phi); phi is fitted over whole periods.
TEST(NyquistBias, OneFrequencyMatchesTheEnginesBsplineInterpolant) {
  constexpr int kN = 64;
  for (int k : {8, 16, 24, 28}) {
    const double w = 2 * kPi * k / kN;
    cv::Mat image(16, 4 * kN + 64, CV_64F);
    for (int y = 0; y < image.rows; ++y)
      for (int x = 0; x < image.cols; ++x) image.at<double>(y, x) = std::cos(w * x);
    BsplineImage spline;
    spline.Build(image, Interpolation::kBicubic);
    std::vector<double> power(kN / 2 + 1, 0.0);
    power[static_cast<std::size_t>(k)] = 1;
    for (double t : {0.1, 0.25, 0.5, 0.7, 0.9}) {
      double a = 0, b = 0;
      for (int x = 32; x < 32 + 4 * kN; ++x) {  // Whole periods, far from the borders.
        const double h = spline.Value(x + t, 8), phase = w * (x + t);
        a += h * std::cos(phase);
        b += h * std::sin(phase);
      }
      const double phi = std::atan2(-b, a);  // h = |T| cos(phase + phi).
      EXPECT_NEAR(PredictedBicubicBiasPx(power, kN, t), -phi / w, 1e-5) << "k " << k << ", t " << t;
    }
  }
}

// The bias is odd about half a pixel and zero at 0 and 0.5 px; it grows with the frequency.
TEST(NyquistBias, ShapeOfThePrediction) {
  constexpr int kN = 64;
  std::vector<double> low(kN / 2 + 1, 0.0), high = low;
  low[8] = high[24] = 1;
  EXPECT_NEAR(PredictedBicubicBiasPx(high, kN, 0.5), 0, 1e-12);
  EXPECT_NEAR(PredictedBicubicBiasPx(high, kN, 0.3), -PredictedBicubicBiasPx(high, kN, 0.7), 1e-12);
  EXPECT_GT(std::abs(PredictedBicubicBiasPx(high, kN, 0.25)),
            10 * std::abs(PredictedBicubicBiasPx(low, kN, 0.25)));
  EXPECT_EQ(PredictedBicubicBiasPx(std::vector<double>(kN / 2 + 1, 0.0), kN, 0.25), 0);
}

// Painted-style dots, 256 x 256, grey levels 30..220 (made once: ~1 s).
const cv::Mat& Sharp() {
  static const cv::Mat sharp = SharpSpeckle(256, 256, /*dot_radius_px=*/2.0, /*seed=*/5) * 190 + 30;
  return sharp;
}

TEST(NyquistBias, MeasureOfAnImage) {
  const cv::Mat& sharp = Sharp();
  const NyquistBias b = MeasureNyquistBias(sharp);
  ASSERT_TRUE(b.measured());
  EXPECT_EQ(b.tile_size, 64);
  EXPECT_EQ(b.tiles, 16);  // 4 x 4 tiles of 64 px, no overlap.
  EXPECT_EQ(b.bias_px, std::max(b.bias_x_px, b.bias_y_px));
  // Sharp dots: far above the threshold; a 0.8 px blur (the pre-filter) divides it by > 5.
  EXPECT_GT(b.bias_px, 0.005);
  cv::Mat blurred;
  cv::GaussianBlur(sharp, blurred, cv::Size(5, 5), 0.8, 0.8, cv::BORDER_REFLECT_101);
  const NyquistBias after = MeasureNyquistBias(blurred);
  EXPECT_LT(after.bias_px, b.bias_px / 5);
  cv::GaussianBlur(sharp, blurred, cv::Size(0, 0), 1.5);
  EXPECT_LT(MeasureNyquistBias(blurred).bias_px, after.bias_px);
  // A property of the image's content: grey-level gain and offset and the depth do not matter.
  cv::Mat scaled = sharp * 0.25 + 40, sixteen;
  EXPECT_NEAR(MeasureNyquistBias(scaled).bias_px, b.bias_px, 1e-9 * b.bias_px);
  sharp.convertTo(sixteen, CV_16U, 200);
  EXPECT_NEAR(MeasureNyquistBias(sixteen).bias_px, b.bias_px, 1e-3 * b.bias_px);
  // The ROI: a region of the image is its own image.
  const cv::Rect roi(40, 30, 150, 130);
  EXPECT_EQ(MeasureNyquistBias(sharp, roi).bias_px, MeasureNyquistBias(sharp(roi).clone()).bias_px);
  // Small regions use smaller tiles, down to 16 px; below that nothing is measured.
  EXPECT_EQ(MeasureNyquistBias(sharp, cv::Rect(0, 0, 40, 200)).tile_size, 32);
  EXPECT_EQ(MeasureNyquistBias(sharp, cv::Rect(0, 0, 20, 20)).tile_size, 16);
  EXPECT_FALSE(MeasureNyquistBias(sharp, cv::Rect(0, 0, 15, 200)).measured());
  EXPECT_FALSE(MeasureNyquistBias(cv::Mat()).measured());
  // A flat image has no content: 0.
  EXPECT_EQ(MeasureNyquistBias(cv::Mat(100, 100, CV_8U, cv::Scalar(77))).bias_px, 0);
}

// The cost is bounded: at most kMaxNyquistTiles tiles whatever the image size.
TEST(NyquistBias, TileCountIsBounded) {
  cv::Mat big;
  cv::repeat(Sharp(), 5, 5, big);  // 1280 x 1280.
  const NyquistBias b = MeasureNyquistBias(big);
  EXPECT_LE(b.tiles, kMaxNyquistTiles);
  EXPECT_GE(b.tiles, kMaxNyquistTiles / 2);
  // Spread over the image, the tiles see the same texture as all of it would.
  EXPECT_NEAR(b.bias_px, MeasureNyquistBias(Sharp()).bias_px, 0.1 * b.bias_px);
}

// A pair of known noise: `texture` shifted by a sub-pixel amount (exact Fourier shift), 8-bit,
// with noise of standard deviation `noise` in each image.
struct Pair {
  cv::Mat reference, deformed;
};
Pair NoisyPair(const cv::Mat& texture, double noise) {
  return {QuantiseWithNoise(texture, noise, 8, 11),
          QuantiseWithNoise(FourierShift(texture, 0.37, -0.21), noise, 8, 12)};
}
PrefilterTrade Trade(const Pair& p, int subset_size) {
  return MeasurePrefilterTrade(p.reference, p.deformed, {}, cv::getGaussianKernel(5, 0.7, CV_64F),
                               subset_size);
}

// The sharp dots blurred (sigma 1.5 px): no content near the Nyquist frequency, so a sub-pixel
// shift is a phase shift of every component.
const cv::Mat& Smooth() {
  static const cv::Mat smooth = [] {
    cv::Mat m;
    cv::GaussianBlur(Sharp(), m, cv::Size(0, 0), 1.5, 1.5, cv::BORDER_REFLECT_101);
    return m;
  }();
  return smooth;
}

// The noise from the pair (the shift undone per tile) is the noise put in; the random error is
// the least-squares one of white noise, sqrt(2 noise^2 / (M <g^2>)) per axis (g the image's
// central-difference gradient, M the subset's pixels), within the spline's and the window's
// effects (15 %); a filter never lowers the random error of white noise (least squares is
// optimal then).
TEST(PrefilterTrade, NoiseAndRandomErrorOfAPairOfKnownNoise) {
  cv::Mat gx, gy;
  cv::Sobel(Smooth(), gx, CV_64F, 1, 0, 1, 0.5);  // Central differences.
  cv::Sobel(Smooth(), gy, CV_64F, 0, 1, 1, 0.5);
  const cv::Rect inner(2, 2, Smooth().cols - 4, Smooth().rows - 4);
  const double g2 = (gx(inner).dot(gx(inner)) + gy(inner).dot(gy(inner))) / (2.0 * inner.area());
  for (const double noise : {1.0, 4.0}) {
    SCOPED_TRACE("noise " + std::to_string(noise));
    const PrefilterTrade t = Trade(NoisyPair(Smooth(), noise), 21);
    ASSERT_TRUE(t.measured());
    // 4 x 4 tiles; at the image's border the Fourier shift wraps a mirrored copy in, which is
    // no shift: those tiles' residual is over twice the median and they are left out.
    EXPECT_GE(t.tiles, 12);
    EXPECT_LE(t.tiles, 16);
    const double var = noise * noise + 1.0 / 12;  // Quantisation adds 1/12 grey level^2.
    EXPECT_NEAR(t.noise_grey, std::sqrt(var), 0.08 * noise);
    const double expected = std::sqrt(2 * (2 * var / (21 * 21 * g2)));  // u and v.
    EXPECT_NEAR(t.random_px, expected, 0.15 * expected);
    EXPECT_GE(t.random_filtered_px, t.random_px);
  }
}

// Bias-limited (sharp dots, little noise): the filter lowers the expected error; noise-limited
// (much noise, a small subset): it raises it, and DecideGaussian (auto) leaves the frames alone,
// saying why. On sharp content the pair's mismatch near the Nyquist frequency (not a phase
// shift when sampled) counts as noise, as it does for the correlation.
TEST(PrefilterTrade, TheFilterIsWorthItOnlyWhenTheBiasDominates) {
  const Pair clean = NoisyPair(Sharp(), 0.5), noisy = NoisyPair(Sharp(), 20.0);
  const PrefilterTrade bias_limited = Trade(clean, 41);
  EXPECT_GT(bias_limited.bias_px, 0.005);
  EXPECT_LT(bias_limited.bias_filtered_px, bias_limited.bias_px / 3);
  EXPECT_LT(bias_limited.Error(true), bias_limited.Error(false));
  const PrefilterTrade noise_limited = Trade(noisy, 11);
  EXPECT_GT(noise_limited.Error(true), noise_limited.Error(false));
  const GaussianBlurOptions options;                              // auto
  EXPECT_TRUE(DecideGaussian(options, noisy.reference).applied);  // The bias figure alone.
  const GaussianDecision weighed = DecideGaussian(
      options, noisy.reference, {}, [&] { return noisy.deformed; }, 11);
  EXPECT_FALSE(weighed.applied);
  EXPECT_NE(weighed.Text().find("noise-limited"), std::string::npos) << weighed.Text();
  EXPECT_TRUE(DecideGaussian(
                  options, clean.reference, {}, [&] { return clean.deformed; }, 41)
                  .applied);
  // Without a second frame, or with one of another size: the bias figure alone, no trade.
  EXPECT_TRUE(DecideGaussian(
                  options, noisy.reference, {}, [] { return cv::Mat(); }, 11)
                  .applied);
  EXPECT_FALSE(MeasurePrefilterTrade(noisy.reference, noisy.deformed(cv::Rect(0, 0, 100, 100)), {},
                                     cv::getGaussianKernel(5, 0.7, CV_64F), 11)
                   .measured());
}

}  // namespace
}  // namespace impactdic
