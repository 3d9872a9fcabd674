// The subset grid: the ROI and mask checked against the first reference, the subset centres, and
// the full scale of the sequence's data.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>

#include "correlator_impl.h"
#include "impactdic/core/error.h"
#include "impactdic/core/memory.h"
#include "impactdic/io/image_io.h"

namespace impactdic {

namespace {
constexpr int kBorderPx = 4;
}  // namespace

double internal::FullScale(const cv::Mat& raw, int data_bits) {
  const int bits = data_bits > 0 ? data_bits : DataBits(raw);
  if (bits > 0) return static_cast<double>((1 << bits) - 1);
  double lo = 0, hi = 0;
  cv::minMaxLoc(raw.reshape(1), &lo, &hi);
  const double magnitude = std::max(std::abs(lo), std::abs(hi));
  return std::isfinite(magnitude) && magnitude > 0 ? magnitude * (1 + 1e-6) : 1.0;
}

void Correlator::Impl::SetUpGrid(const cv::Mat& image) {
  image_size = cv::Size();
  CheckImage(image, "reference image");
  const GridOptions& g = options.grid;
  CheckValue(
      image.cols >= size && image.rows >= size, "subset size", std::to_string(size) + " px",
      "at most the image size " + std::to_string(image.cols) + "x" + std::to_string(image.rows));
  const cv::Rect image_rect(0, 0, image.cols, image.rows);
  cv::Rect roi = g.roi.area() > 0 ? g.roi : image_rect;
  CheckValue((roi & cv::Rect(0, 0, image.cols, image.rows)) == roi, "ROI",
             fmt::format("x {}..{}, y {}..{}", roi.x, roi.x + roi.width, roi.y, roi.y + roi.height),
             fmt::format("inside the image (0..{}, 0..{})", image.cols, image.rows));
  CheckValue(roi.width >= size && roi.height >= size, "ROI",
             fmt::format("{}x{} px", roi.width, roi.height),
             fmt::format("at least one subset ({} px) wide and high", size));
  CheckValue(g.mask.empty() || g.mask.size() == image.size(), "mask",
             fmt::format("{}x{}", g.mask.cols, g.mask.rows), "the image size");
  image_size = image.size();
  depth = image.depth();
  full_scale = internal::FullScale(image, options.data_bits);
  // Subsets keep kBorderPx from the image border: the interpolation support of a subset that
  // moves by a pixel must stay inside the image.
  const cv::Rect inner(kBorderPx, kBorderPx, image.cols - 2 * kBorderPx,
                       image.rows - 2 * kBorderPx);
  roi &= inner;
  CheckValue(roi.width >= size && roi.height >= size, "ROI",
             fmt::format("{}x{} px after keeping {} px from the image border", roi.width,
                         roi.height, kBorderPx),
             fmt::format("room for at least one subset ({} px)", size));
  nx = (roi.width - size) / g.step + 1;
  ny = (roi.height - size) / g.step + 1;
  const int n = nx * ny;
  initial.resize(n);
  // Several MB for a dense grid: allocated, advised, its pages faulted in on the pool's threads,
  // then filled.
  tracks.clear();
  tracks.reserve(n);
  AdviseHugePages(tracks.data(), tracks.capacity() * sizeof(internal::SubsetTrack));
  FaultInParallel(tracks.data(), tracks.capacity() * sizeof(internal::SubsetTrack));
  tracks.assign(n, internal::SubsetTrack{});
  for (int r = 0; r < ny; ++r) {
    for (int c = 0; c < nx; ++c) {
      const int i = r * nx + c;
      initial[i] = cv::Point2d(roi.x + half + c * g.step, roi.y + half + r * g.step);
      tracks[i].ref_pos = initial[i];
      if (!g.mask.empty() && g.mask.at<std::uint8_t>(static_cast<int>(initial[i].y),
                                                     static_cast<int>(initial[i].x)) == 0) {
        tracks[i].active = false;
        tracks[i].permanent = SubsetStatus::kMasked;
      }
    }
  }
}

}  // namespace impactdic
