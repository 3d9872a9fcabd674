// Helpers shared by the calib module's sources (not installed).
#ifndef IMPACTDIC_SRC_CALIB_CALIB_INTERNAL_H_
#define IMPACTDIC_SRC_CALIB_CALIB_INTERNAL_H_

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "impactdic/calib/calibration.h"

namespace impactdic::calib_detail {

// 16-bit images stretched to the full 8-bit range for the detectors (a 12-bit camera's data
// would otherwise sit in the lowest 16th of the range); 8-bit images as they are.
cv::Mat To8Bit(const cv::Mat& image);

// Error(kInvalidValue) naming `name` unless an 8/16-bit single-channel image.
void CheckImage(const cv::Mat& image, const std::string& name);

// The views of one calibration, in cv::calibrateCamera's form.
struct ViewPoints {
  std::vector<std::vector<cv::Point3f>> object;
  std::vector<std::vector<cv::Point2f>> image;
};

// One model fitted to the views (lens_model.cc).
struct LensFit {
  CameraCalibration camera;  // Intrinsics and distortion (model set).
  std::vector<cv::Vec3d> rvecs, tvecs;
  double rms_px = 0;
};

// Fits `model` (not kAuto) to all views (held_out: the looser iteration limits of the model
// choice). Error(kNumerical) when OpenCV fails or returns non-finite values.
LensFit FitLens(const ViewPoints& views, cv::Size image_size, LensModel model,
                const CalibrationOptions& options, bool held_out = false);

// The held-out reprojection RMS [px] of `model`: the views split into `folds` groups; each group's
// views are predicted by the lens fitted to the others (pose of each held-out view fitted alone,
// cv::solvePnP on the undistorted points, then reprojected through the lens).
ModelCandidate HeldOutError(const ViewPoints& views, cv::Size image_size, LensModel model,
                            const CalibrationOptions& options, int folds);

// Local isotropic scale sqrt|det J| of the homography `h` at image point p [mm/px].
double LocalScale(const cv::Matx33d& h, cv::Point2d p);

// With the board on the window's outer face: replaces scale->mm_from_px and mm_per_px (at
// `centroid_px`) by those of the soil plane (window.cc), keeping the relative uncertainty;
// `object` and `undistorted_px` are the plane view's points (the camera's pose from them).
void CarryToSoil(const CameraCalibration& calibration, const std::vector<cv::Point3f>& object,
                 const std::vector<cv::Point2d>& undistorted_px, cv::Point2d centroid_px,
                 const WindowOptions& window, PlaneScale* scale);

}  // namespace impactdic::calib_detail

#endif  // IMPACTDIC_SRC_CALIB_CALIB_INTERNAL_H_
