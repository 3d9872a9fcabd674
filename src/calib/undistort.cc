#include "impactdic/calib/undistort.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/utility.hpp>

#include "impactdic/core/error.h"
#include "impactdic/core/log.h"

namespace impactdic {
namespace {

// The model's maps: Brown-Conrady and rational by cv::initUndistortRectifyMap (5 or 8
// coefficients), fisheye by cv::fisheye::initUndistortRectifyMap.
void ComputeMaps(const CameraCalibration& c, cv::Mat* map_x, cv::Mat* map_y) {
  const cv::Matx33d k = c.CameraMatrix();
  if (c.model == LensModel::kFisheye) {
    cv::fisheye::initUndistortRectifyMap(k, c.DistCoeffs(), cv::Matx33d::eye(), k, c.ImageSize(),
                                         CV_32FC1, *map_x, *map_y);
    return;
  }
  cv::initUndistortRectifyMap(k, c.DistCoeffs(), cv::noArray(), k, c.ImageSize(), CV_32FC1, *map_x,
                              *map_y);
}

cv::Rect ClampRoi(cv::Rect roi, cv::Size size) {
  const cv::Rect full(0, 0, size.width, size.height);
  return roi.empty() ? full : (roi & full);
}

double MaxShift(const cv::Mat& map_x, const cv::Mat& map_y, cv::Rect roi) {
  double worst = 0;
  for (int v = roi.y; v < roi.y + roi.height; ++v) {
    const float* mx = map_x.ptr<float>(v);
    const float* my = map_y.ptr<float>(v);
    for (int u = roi.x; u < roi.x + roi.width; ++u)
      worst = std::max(worst, std::hypot(double(mx[u]) - u, double(my[u]) - v));
  }
  return worst;
}

// Keys' cubic convolution kernel weights (a = -0.5) for fractional offset t in [0, 1).
inline void CubicWeights(double t, double w[4]) {
  const double a = -0.5;
  auto near = [a](double x) { return ((a + 2) * x - (a + 3)) * x * x + 1; };       // |x| <= 1
  auto far = [a](double x) { return ((a * x - 5 * a) * x + 8 * a) * x - 4 * a; };  // 1 < |x| < 2
  w[0] = far(1 + t);
  w[1] = near(t);
  w[2] = near(1 - t);
  w[3] = far(2 - t);
}

template <typename T>
void Remap(const cv::Mat& src, const cv::Mat& map_x, const cv::Mat& map_y, bool bicubic,
           cv::Mat* dst) {
  const int w = src.cols, h = src.rows;
  const double max_value = std::is_same_v<T, std::uint8_t>    ? 255.0
                           : std::is_same_v<T, std::uint16_t> ? 65535.0
                                                              : 0.0;
  cv::parallel_for_(cv::Range(0, h), [&](const cv::Range& range) {
    for (int v = range.start; v < range.end; ++v) {
      const float* mx = map_x.ptr<float>(v);
      const float* my = map_y.ptr<float>(v);
      T* out = dst->ptr<T>(v);
      for (int u = 0; u < w; ++u) {
        const double x = mx[u], y = my[u];
        const double fx = std::floor(x), fy = std::floor(y);
        const int x0 = static_cast<int>(fx), y0 = static_cast<int>(fy);
        const double tx = x - fx, ty = y - fy;
        double value = 0;
        if (bicubic) {
          double wx[4], wy[4];
          CubicWeights(tx, wx);
          CubicWeights(ty, wy);
          for (int j = 0; j < 4; ++j) {
            const T* row = src.ptr<T>(std::clamp(y0 - 1 + j, 0, h - 1));
            double acc = 0;
            for (int i = 0; i < 4; ++i) acc += wx[i] * row[std::clamp(x0 - 1 + i, 0, w - 1)];
            value += wy[j] * acc;
          }
        } else {
          const T* r0 = src.ptr<T>(std::clamp(y0, 0, h - 1));
          const T* r1 = src.ptr<T>(std::clamp(y0 + 1, 0, h - 1));
          const int xa = std::clamp(x0, 0, w - 1), xb = std::clamp(x0 + 1, 0, w - 1);
          value =
              (1 - ty) * ((1 - tx) * r0[xa] + tx * r0[xb]) + ty * ((1 - tx) * r1[xa] + tx * r1[xb]);
        }
        if constexpr (std::is_same_v<T, float>) {
          out[u] = static_cast<float>(value);
        } else {
          out[u] = static_cast<T>(std::clamp(std::round(value), 0.0, max_value));
        }
      }
    }
  });
}

}  // namespace

const char* ToString(UndistortInterpolation interpolation) {
  return kUndistortInterpolationNames.Name(interpolation);
}

UndistortInterpolation UndistortInterpolationFromString(const std::string& text) {
  return kUndistortInterpolationNames.Parse(text, "undistort.interpolation");
}

void UndistortOptions::Check() const {
  CheckValue(
      std::isfinite(skip_threshold_px) && kUndistortSkipThresholdRange.Contains(skip_threshold_px),
      "undistort.skip_threshold_px", fmt::format("{}", skip_threshold_px), ">= 0 px");
  CheckValue(roi.width >= 0 && roi.height >= 0 && roi.x >= 0 && roi.y >= 0, "undistort.roi",
             fmt::format("{}x{} at ({}, {})", roi.width, roi.height, roi.x, roi.y),
             "a rectangle inside the frame (empty = whole frame)");
}

double MaxDistortionShift(const CameraCalibration& calibration, cv::Rect roi) {
  if (!calibration.HasDistortion()) return 0;
  cv::Mat map_x, map_y;
  ComputeMaps(calibration, &map_x, &map_y);
  return MaxShift(map_x, map_y, ClampRoi(roi, calibration.ImageSize()));
}

Undistorter::Undistorter(const CameraCalibration& calibration, const UndistortOptions& options)
    : options_(options), size_(calibration.ImageSize()) {
  options.Check();
  CheckValue(size_.width > 0 && size_.height > 0, "calibration image size",
             fmt::format("{}x{}", size_.width, size_.height), "a calibrated image size");
  const cv::Rect roi = ClampRoi(options.roi, size_);
  CheckValue(!roi.empty(), "undistort.roi",
             fmt::format("{}x{} px at ({}, {}), outside the frame", options.roi.width,
                         options.roi.height, options.roi.x, options.roi.y),
             fmt::format("a rectangle that overlaps the {}x{} frame", size_.width, size_.height));
  if (calibration.HasDistortion()) {
    ComputeMaps(calibration, &map_x_, &map_y_);
    max_shift_px_ = MaxShift(map_x_, map_y_, roi);
  }
  active_ = max_shift_px_ > options.skip_threshold_px;
  reason_ = active_ ? fmt::format(
                          "undistortion applied: the lens moves ROI pixels by up to {:.4f} "
                          "px (> {} px), {} remap",
                          max_shift_px_, options.skip_threshold_px, ToString(options.interpolation))
                    : fmt::format(
                          "undistortion skipped: the lens moves no ROI pixel by more than "
                          "{} px (largest shift {:.2g} px)",
                          options.skip_threshold_px, max_shift_px_);
  if (!active_) map_x_ = map_y_ = cv::Mat();  // not needed
  LogInfo("{}", reason_);
}

cv::Mat Undistorter::Apply(const cv::Mat& frame) const {
  CheckValue(frame.size() == size_, "frame size", fmt::format("{}x{}", frame.cols, frame.rows),
             fmt::format("{}x{} (the calibration's image size)", size_.width, size_.height));
  CheckValue(frame.channels() == 1 &&
                 (frame.depth() == CV_8U || frame.depth() == CV_16U || frame.depth() == CV_32F),
             "frame type",
             fmt::format("{} channel(s), depth code {}", frame.channels(), frame.depth()),
             "a single-channel 8-bit, 16-bit or float frame");
  if (!active_) return frame;
  cv::Mat out(frame.size(), frame.type());
  const bool bicubic = options_.interpolation == UndistortInterpolation::kBicubic;
  switch (frame.depth()) {
    case CV_8U: Remap<std::uint8_t>(frame, map_x_, map_y_, bicubic, &out); break;
    case CV_16U: Remap<std::uint16_t>(frame, map_x_, map_y_, bicubic, &out); break;
    default: Remap<float>(frame, map_x_, map_y_, bicubic, &out); break;
  }
  return out;
}

}  // namespace impactdic
