// Band-limited translation by the DFT, sharp speckle and 8/16-bit rounding (see fourier_shift.h).
#include "impactdic/synth/fourier_shift.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstddef>
#include <numbers>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/synth/speckle.h"
#include "random.h"

namespace impactdic {
namespace {

// exp(-2 pi i f d) for the DFT bins of a periodic signal of n samples (n even): f = k / n for
// k < n / 2, (k - n) / n above; cos(pi d) at the Nyquist bin k = n / 2.
std::vector<std::complex<double>> PhaseFactors(int n, double d) {
  std::vector<std::complex<double>> out(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) {
    if (2 * k == n) {
      out[k] = std::cos(std::numbers::pi * d);
      continue;
    }
    const double f = (2 * k < n ? k : k - n) / static_cast<double>(n);
    out[k] = std::polar(1.0, -2 * std::numbers::pi * f * d);
  }
  return out;
}

}  // namespace

cv::Mat FourierShift(const cv::Mat& image, double dx_px, double dy_px) {
  CheckValue(image.channels() == 1 && !image.empty(), "FourierShift image",
             std::to_string(image.channels()) + " channel(s)", "a non-empty one-channel image");
  CheckValue(std::isfinite(dx_px) && std::isfinite(dy_px), "FourierShift shift",
             std::to_string(dx_px) + ", " + std::to_string(dy_px), "finite");
  cv::Mat grey;
  image.convertTo(grey, CV_64F);
  // Mirror extension (x -> 2W - 1 - x): periodic with period 2W and continuous.
  cv::Mat flipped_x, flipped_y, flipped_xy, top, bottom, extended;
  cv::flip(grey, flipped_x, 1);
  cv::flip(grey, flipped_y, 0);
  cv::flip(grey, flipped_xy, -1);
  cv::hconcat(grey, flipped_x, top);
  cv::hconcat(flipped_y, flipped_xy, bottom);
  cv::vconcat(top, bottom, extended);
  cv::Mat spectrum;
  cv::dft(extended, spectrum, cv::DFT_COMPLEX_OUTPUT);
  const auto fx = PhaseFactors(extended.cols, dx_px), fy = PhaseFactors(extended.rows, dy_px);
  for (int r = 0; r < spectrum.rows; ++r) {
    auto* row = spectrum.ptr<std::complex<double>>(r);
    for (int c = 0; c < spectrum.cols; ++c) row[c] *= fy[r] * fx[c];
  }
  cv::Mat shifted;
  cv::dft(spectrum, shifted, cv::DFT_INVERSE | cv::DFT_SCALE | cv::DFT_COMPLEX_OUTPUT);
  cv::Mat planes[2];
  cv::split(shifted, planes);
  return planes[0](cv::Rect(0, 0, grey.cols, grey.rows)).clone();
}

cv::Mat SharpSpeckle(int width, int height, double dot_radius_px, std::uint64_t seed) {
  CheckValue(width > 0 && height > 0, "SharpSpeckle size",
             std::to_string(width) + "x" + std::to_string(height), "positive width and height");
  CheckValue(dot_radius_px > 0 && std::isfinite(dot_radius_px), "SharpSpeckle dot_radius_px",
             std::to_string(dot_radius_px), "> 0");
  SpeckleOptions speckle;
  speckle.seed = seed;
  speckle.blob_radius_px = dot_radius_px / 2;
  speckle.density = 1.2;
  const SpecklePattern pattern(speckle, width, height);
  constexpr int kFine = 4;
  cv::Mat fine(height * kFine, width * kFine, CV_64F);
  tbb::parallel_for(0, fine.rows, [&](int r) {
    auto* row = fine.ptr<double>(r);
    const double y = (r + 0.5) / kFine - 0.5;
    for (int c = 0; c < fine.cols; ++c) row[c] = pattern.Intensity((c + 0.5) / kFine - 0.5, y);
  });
  std::vector<double> values(fine.begin<double>(), fine.end<double>());
  auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  const double median = *middle;
  cv::Mat binary = cv::Mat(fine <= median) / 255;  // 1 = white background, 0 = dot.
  cv::Mat binary64, out;
  binary.convertTo(binary64, CV_64F);
  cv::resize(binary64, out, cv::Size(width, height), 0, 0, cv::INTER_AREA);
  return out;
}

cv::Mat QuantiseWithNoise(const cv::Mat& grey, double noise_sigma, int bits,
                          std::uint64_t noise_seed) {
  CheckValue(bits == 8 || bits == 16, "QuantiseWithNoise bits", std::to_string(bits), "8 or 16");
  CheckValue(noise_sigma >= 0 && std::isfinite(noise_sigma), "QuantiseWithNoise noise_sigma",
             std::to_string(noise_sigma), ">= 0 grey levels");
  cv::Mat in;
  grey.convertTo(in, CV_64F);
  const double full = bits == 8 ? 255.0 : 65535.0;
  cv::Mat out(in.size(), bits == 8 ? CV_8U : CV_16U);
  tbb::parallel_for(0, in.rows, [&](int r) {
    synth_detail::Rng rng(noise_seed * 0x100000001B3ull + static_cast<std::uint64_t>(r));
    const auto* src = in.ptr<double>(r);
    for (int c = 0; c < in.cols; ++c) {
      double value = src[c];
      if (noise_sigma > 0) value += noise_sigma * rng.Normal();
      value = std::clamp(std::round(value), 0.0, full);
      if (bits == 8) {
        out.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(value);
      } else {
        out.at<std::uint16_t>(r, c) = static_cast<std::uint16_t>(value);
      }
    }
  });
  return out;
}

}  // namespace impactdic
