// The noise and the grey-level range a reference image uses, for the contrast tests of its
// subsets (icgn.h: ImageLevelsOf).
#include <algorithm>
#include <cmath>
#include <numbers>
#include <opencv2/core.hpp>
#include <vector>

#include "icgn.h"

namespace impactdic::internal {

namespace {

// Output rows per sampled band, and the number of pixels the bands hold at most (about).
constexpr int kBandRows = 16;
constexpr double kSampledPixels = 262144;

// Every kValueStride-th pixel of the bands enters the range's percentiles.
constexpr int kValueStride = 4;
// The range's percentiles: hot pixels and specular dots do not widen it.
constexpr double kRangeTail = 0.001;
// The noise is the block means' 10th percentile: a 16 x 16 block's mean scatters by about 6 %
// in pure noise, so the flattest tenth reads it about 8 % low.
constexpr double kNoiseQuantile = 0.1;

// The mean of |I * N| (N the 3 x 3 difference of two Laplacians, 1 -2 1 / -2 4 -2 / 1 -2 1) in
// each kBandRows x kBandRows block of band's interior, appended to `blocks`; band's values (every
// kValueStride-th) appended to `values`.
void BandBlocks(const cv::Mat& band, std::vector<double>* blocks, std::vector<float>* values) {
  cv::Mat f;
  band.convertTo(f, CV_32F);
  const int width = f.cols - 2, count = width / kBandRows;
  if (count < 1) return;
  std::vector<double> sums(static_cast<std::size_t>(count), 0.0);
  for (int r = 1; r + 1 < f.rows; ++r) {
    const float* a = f.ptr<float>(r - 1);
    const float* b = f.ptr<float>(r);
    const float* c = f.ptr<float>(r + 1);
    for (int x = 1; x <= count * kBandRows; ++x) {
      const float outer = a[x - 1] + a[x + 1] + c[x - 1] + c[x + 1];
      const float edges = a[x] + c[x] + b[x - 1] + b[x + 1];
      sums[static_cast<std::size_t>((x - 1) / kBandRows)] += std::abs(outer - 2 * edges + 4 * b[x]);
      if (x % kValueStride == 0) values->push_back(b[x]);
    }
  }
  for (const double s : sums) blocks->push_back(s / (double(kBandRows) * (f.rows - 2)));
}

}  // namespace

ImageLevels ImageLevelsOf(const cv::Mat& image, const cv::Rect& region_in) {
  const cv::Rect region = region_in & cv::Rect(0, 0, image.cols, image.rows);
  if (region.width < 3 || region.height < 3 || image.channels() != 1) return {};
  const int rows = region.height - 2;  // Output rows.
  const int bands =
      std::clamp(static_cast<int>(std::ceil(kSampledPixels / (double(kBandRows) * region.width))),
                 1, (rows + kBandRows - 1) / kBandRows);
  std::vector<double> blocks;
  std::vector<float> values;
  for (int k = 0; k < bands; ++k) {
    // Band k's output rows start at an even spread over the region's output rows.
    const int first = static_cast<int>(
        (static_cast<long long>(rows - std::min(rows, kBandRows)) * k) / std::max(1, bands - 1));
    const int height = std::min(kBandRows, rows - first) + 2;
    BandBlocks(image(cv::Rect(region.x, region.y + first, region.width, height)), &blocks, &values);
    if (bands == 1) break;
  }
  ImageLevels levels;
  // The noise: the kNoiseQuantile-th quantile of the blocks' means (the flattest blocks hold
  // noise alone; texture raises the others). E|n * N| = sqrt(2 / pi) * 6 sigma for white
  // Gaussian noise (the sum of N's squared weights is 36).
  if (!blocks.empty()) {
    const auto k =
        static_cast<std::ptrdiff_t>(kNoiseQuantile * static_cast<double>(blocks.size() - 1));
    std::nth_element(blocks.begin(), blocks.begin() + k, blocks.end());
    levels.noise = std::sqrt(std::numbers::pi / 2) * blocks[static_cast<std::size_t>(k)] / 6;
  }
  if (!values.empty()) {
    const auto at = [&values](double q) {
      const auto k = static_cast<std::ptrdiff_t>(q * static_cast<double>(values.size() - 1));
      std::nth_element(values.begin(), values.begin() + k, values.end());
      return static_cast<double>(values[static_cast<std::size_t>(k)]);
    };
    const double low = at(kRangeTail);
    levels.range = at(1 - kRangeTail) - low;
  }
  return levels;
}

}  // namespace impactdic::internal
