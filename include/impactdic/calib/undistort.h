// Undistortion of frames with precomputed maps, skipped where the lens does not need it
// (docs/calibration.md: "leave out what a scene does not need").
//
// The undistorted image keeps the calibration's camera matrix K: output pixel p takes the input
// value at K * distort(K^-1 p), distort() of the calibration's model. The maps are computed once
// (cv::initUndistortRectifyMap, or cv::fisheye::initUndistortRectifyMap; float precision ~1e-4 px)
// and applied per frame with our own bicubic (Keys 1981, a = -0.5, doi:10.1109/TASSP.1981.1163711)
// interpolation at the exact map coordinates: cv::remap quantises the sub-pixel position to 1/32 px
// (INTER_BITS = 5), an error of up to 0.016 px, larger than the 0.01 px skip threshold itself and
// visible to subpixel DIC.
//
// Skip rule: the largest displacement |map(p) - p| over every pixel p of the region of interest
// is computed from the maps; at or below `skip_threshold_px` (0.01 px) undistortion is skipped
// and Apply() returns the frame unchanged. The decision is logged.
//
//   Undistorter undistort(calibration, UndistortOptions{});
//   cv::Mat frame_u = undistort.Apply(frame);      // same type and size
#ifndef IMPACTDIC_CALIB_UNDISTORT_H_
#define IMPACTDIC_CALIB_UNDISTORT_H_

#include <opencv2/core.hpp>
#include <string>

#include "impactdic/calib/calibration.h"
#include "impactdic/core/enum_names.h"
#include "impactdic/core/range.h"

namespace impactdic {

enum class UndistortInterpolation { kBilinear, kBicubic };
inline constexpr EnumNames<UndistortInterpolation, 2> kUndistortInterpolationNames{
    {{{UndistortInterpolation::kBilinear, "bilinear"},
      {UndistortInterpolation::kBicubic, "bicubic"}}}};
const char* ToString(UndistortInterpolation interpolation);
// A name of kUndistortInterpolationNames; Error(kInvalidValue) otherwise.
UndistortInterpolation UndistortInterpolationFromString(const std::string& text);

// The skip thresholds UndistortOptions::Check() accepts (the scene's
// preprocess.undistortion.skip_threshold_px).
inline constexpr ValueRange kUndistortSkipThresholdRange{0, 1e300, "px"};

struct UndistortOptions {
  // Skip if no ROI pixel moves by more than this [px], kUndistortSkipThresholdRange.
  double skip_threshold_px = 0.01;
  UndistortInterpolation interpolation = UndistortInterpolation::kBicubic;
  cv::Rect roi;  // Region of interest [px] in the frame; empty = the whole frame.
  void Check() const;
};

// Largest |map(p) - p| [px] over all pixels of `roi` (empty = whole image) for the calibration's
// distortion, computed exactly per pixel.
double MaxDistortionShift(const CameraCalibration& calibration, cv::Rect roi = {});

class Undistorter {
 public:
  Undistorter(const CameraCalibration& calibration, const UndistortOptions& options);

  // True if frames are remapped; false if the rule skipped undistortion.
  bool active() const { return active_; }
  double max_shift_px() const { return max_shift_px_; }
  // Why it is active or skipped (one line, for summaries and logs).
  const std::string& reason() const { return reason_; }
  cv::Size size() const { return size_; }

  // Undistorts an 8/16-bit (or 32F) single-channel frame of the calibration's size; returns the
  // input itself (no copy) when inactive. Values are rounded and clamped to the input depth.
  // Pixels whose source lies outside the frame repeat the border.
  cv::Mat Apply(const cv::Mat& frame) const;

 private:
  UndistortOptions options_;
  cv::Size size_;
  bool active_ = false;
  double max_shift_px_ = 0;
  std::string reason_;
  cv::Mat map_x_, map_y_;  // CV_32F source coordinates of each output pixel
};

}  // namespace impactdic

#endif  // IMPACTDIC_CALIB_UNDISTORT_H_
