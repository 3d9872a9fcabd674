// Lens calibration and the metric scale of the measurement plane (docs/calibration.md).
//
// Checkerboard corners are found with cv::findChessboardCorners and refined with cv::cornerSubPix
// (gradient-orthogonality estimator, Foerstner & Guelch 1987); the camera is calibrated with
// cv::calibrateCamera (Zhang 2000, IEEE TPAMI 22(11):1330, doi:10.1109/34.888718): intrinsics
// fx, fy, cx, cy and Brown-Conrady distortion k1, k2, p1, p2, k3 (Brown 1966; the model is written
// out in synth/checkerboard.h). The plane scale is the homography from undistorted image pixels
// to millimetres on the panel, fitted to the corners of one view of the board lying on the panel
// (Hartley & Zisserman 2004, ch. 4, DLT + Levenberg-Marquardt refinement in cv::findHomography).
//
//   CalibrationOptions options;
//   options.board = ParseBoard("9x6", /*square_mm=*/25);
//   CalibrationSummary summary;
//   CameraCalibration calibration = CalibrateCamera(images, names, options, &summary);
//   calibration.plane = MeasurePlaneScale(plane_image, "plane.png", calibration,
//   options.detection); SaveCalibration(calibration, "calibration/camera.yaml");
//   ...
//   CameraCalibration loaded = LoadCalibration("calibration/camera.yaml");
//   CheckFrameSize(loaded, frame.size(), "frame_0001.png");   // throws if the size differs
//
// The YAML keys are documented in docs/calibration.md.
#ifndef IMPACTDIC_CALIB_CALIBRATION_H_
#define IMPACTDIC_CALIB_CALIBRATION_H_

#include <algorithm>
#include <array>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "impactdic/core/numeric.h"
#include "impactdic/core/range.h"
#include "impactdic/io/json.h"
#include "impactdic/io/yaml.h"

namespace impactdic {

// A checkerboard with cols x rows INNER corners (9x6 for a board of 10x7 squares).
struct BoardSpec {
  int cols = 9;           // Inner corners along the board's X axis, >= 2.
  int rows = 6;           // Inner corners along Y, >= 2.
  double square_mm = 25;  // Side of one square [mm], in kSquareRange.
  // Printed boards from 0.01 mm (microscope targets) to 10 m squares; beyond, the corner
  // coordinates (float) lose their meaning and OpenCV fails with an assertion.
  static constexpr ValueRange kSquareRange{0.01, 1e4, "mm"};
  void Check() const;
  cv::Size PatternSize() const { return {cols, rows}; }
  // Corner (i, j) at (i * square_mm, j * square_mm, 0), row-major (j outer), Z = 0.
  std::vector<cv::Point3f> ObjectPoints() const;
};

// Parses "COLSxROWS" (e.g. "9x6", inner corners) into a board with the given square size.
// Error(kInvalidValue, where, text, ...) for anything else and for fewer than 2 corners a side
// (`where`: CalibrationOptions::board); Error naming board.square_mm for a square_mm outside
// BoardSpec::kSquareRange.
BoardSpec ParseBoard(const std::string& text, double square_mm, const std::string& where = "board");

struct DetectionOptions {
  bool adaptive_threshold = true;  // cv::CALIB_CB_ADAPTIVE_THRESH.
  bool normalize_image = true;     // cv::CALIB_CB_NORMALIZE_IMAGE.
  int subpix_half_window = 5;      // cornerSubPix search window half-size [px]; keep it
                                   // below half a square side.
  int subpix_max_iterations = 100;
  double subpix_epsilon_px = 1e-4;  // Stop when a corner moves less than this [px].
  static constexpr ValueRange kHalfWindowRange{2, 30, "px"};
  static constexpr ValueRange kMaxIterationsRange{1, 1e6, ""};
  static constexpr ValueRange kEpsilonRange{0, 1, "px", /*min_open=*/true};
  void Check() const;
};

struct CalibrationOptions {
  BoardSpec board;
  DetectionOptions detection;
  int min_views = 6;        // Fewest distinct views with a detected board, >= 3 (Zhang needs
                            // >= 3 for all five intrinsics; 10-20 are recommended for
                            // distortion). Repeats (duplicate_tolerance_px) count once.
  double max_rms_px = 1.0;  // A calibration whose overall reprojection RMS exceeds this [px]
                            // is refused (Error kNumerical), > 0. Subpixel corners on a sharp
                            // board give 0.02-0.3 px; above 1 px something is wrong.
  bool fix_k3 = false;      // Hold k3 = 0 (cv::CALIB_FIX_K3), for short-focal-length-free lenses.
  bool zero_tangential = false;  // Hold p1 = p2 = 0 (cv::CALIB_ZERO_TANGENT_DIST).
  // A view whose corners all lie within this distance [px] of an earlier view's (in [0, 100])
  // repeats it and is dropped (an image with identical pixels always is): a repeat adds no
  // constraint on the lens but would count as another view, and 12 copies of one view fitted a
  // wrong camera (cx off by 46 px) with an RMS of 0.03 px. The corner detector repeats a still
  // board to about 0.01-0.1 px; views taken on purpose differ by tens of pixels.
  double duplicate_tolerance_px = 1.0;
  static constexpr ValueRange kMinViewsRange{3, 1e4, ""};
  static constexpr ValueRange kMaxRmsRange{0, 1e3, "px", /*min_open=*/true};
  static constexpr ValueRange kDuplicateToleranceRange{0, 100, "px"};
  void Check() const;
};

// The options of `impactdic calibrate` as option tables (io/yaml.h), the keys named as in
// CalibrationOptions::Check's errors: calibration.min_views, max_rms_px, fix_k3, zero_tangential,
// duplicate_tolerance_px and calibration.detection.* (the board is --board and --square).
std::vector<YamlOptionTable> CalibrationOptionTables(CalibrationOptions* options);

// The scale of the measurement plane (the panel).
struct PlaneScale {
  std::string image;  // Name of the plane view.
  // Homography from UNDISTORTED pixel coordinates (u, v, 1) to board-plane millimetres (X, Y, 1).
  // The axes are the board's: origin at the first detected inner corner.
  cv::Matx33d mm_from_px = cv::Matx33d::eye();
  double mm_per_px = kNaN;  // sqrt|det J| at the corners'
                            // centroid [mm/px].
  // 1-sigma uncertainty [mm/px]: the fit's statistical error (residuals over the corners' spread)
  // combined with the standard deviation of the local scale over the board (non-zero when the
  // board is not parallel to the sensor, i.e. one number is not the whole truth).
  double mm_per_px_uncertainty = kNaN;
  double local_scale_spread_rel = 0;  // std / mean of the local scale over the corners.
  double residual_rms_mm = 0;         // RMS distance of the corners from the fitted homography.
  int corners = 0;

  // Maps an undistorted pixel to plane millimetres.
  cv::Point2d ToMm(cv::Point2d undistorted_px) const;
};

struct ViewRecord {
  std::string image;
  double rms_px = kNaN;  // Per-view reprojection RMS.
};
struct RejectedView {
  std::string image;
  std::string reason;
};

struct CameraCalibration {
  int image_width = 0;  // [px] The frames must have this size (CheckFrameSize).
  int image_height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;      // [px]
  std::array<double, 5> dist{0, 0, 0, 0, 0};  // k1, k2, p1, p2, k3
  double rms_px = kNaN;                       // Overall reprojection RMS.
  BoardSpec board;
  std::vector<ViewRecord> views;       // The views used, with their RMS.
  std::vector<RejectedView> rejected;  // The views not used, with the reason.
  std::optional<PlaneScale> plane;

  cv::Size ImageSize() const { return {image_width, image_height}; }
  cv::Matx33d CameraMatrix() const { return {fx, 0, cx, 0, fy, cy, 0, 0, 1}; }
  cv::Mat DistCoeffs() const;  // 1x5 CV_64F
  bool HasDistortion() const;  // Any coefficient non-zero.
  // Distorted pixel -> undistorted pixel (same camera matrix), by cv::undistortPoints
  // (iterative; accurate to ~1e-6 px for mild distortion).
  std::vector<cv::Point2d> UndistortPixels(const std::vector<cv::Point2d>& distorted) const;
};

struct CalibrationSummary {
  int images_total = 0;
  int images_used = 0;
  int images_rejected = 0;  // Not used: no board found, or a repeat of another view.
  int images_repeated = 0;  // Of the rejected: repeats of another view (duplicate_tolerance_px).
  double rms_px = kNaN;
  double worst_view_rms_px = kNaN;
  std::string worst_view;
  double detection_seconds = 0;
  double calibration_seconds = 0;
  std::string BriefReport() const;
  std::string FullReport(const CameraCalibration& calibration) const;
  // What `impactdic calibrate` prints (text, or JSON for --format json): the images used and
  // rejected, the RMS, intrinsics, distortion and scale, and `output`, the calibration written.
  std::string CommandReport(const CameraCalibration& calibration, const std::string& output) const;
  JsonObject ToJson(const CameraCalibration& calibration, const std::string& output) const;
  bool IsUsable(const CalibrationOptions& options) const {
    return images_used >= options.min_views && rms_px <= options.max_rms_px;
  }
};

// Finds the board's inner corners with subpixel refinement. 16-bit images are stretched to 8 bit
// (min..max) for the detector and refined on the full-depth image. Returns nullopt if the board
// is not found.
std::optional<std::vector<cv::Point2f>> DetectBoard(const cv::Mat& image, const BoardSpec& board,
                                                    const DetectionOptions& options);

// Calibrates from views of the board (8/16-bit single-channel, all the same size). Views without
// the board, and repeats of an earlier view (identical pixels, or corners within
// options.duplicate_tolerance_px), are rejected with a message (logged and listed in the
// result). Errors
// (impactdic::Error): no images; images of different sizes (naming the first one that differs); no
// image shows the board; fewer than options.min_views distinct usable views (the message names
// the repeats and why the minimum); overall RMS above
// options.max_rms_px.
CameraCalibration CalibrateCamera(const std::vector<cv::Mat>& images,
                                  const std::vector<std::string>& names,
                                  const CalibrationOptions& options,
                                  CalibrationSummary* summary = nullptr);

// The plane scale from one view of the board lying on the panel (same camera, same size):
// corners detected, undistorted with `calibration`, homography fitted to the board millimetres.
// Error if the size differs from the calibration or the board is not found.
PlaneScale MeasurePlaneScale(const cv::Mat& image, const std::string& name,
                             const CameraCalibration& calibration,
                             const DetectionOptions& options = {});

// Reads the images (io::ReadGreyImage; folders and globs are expanded), calibrates and, if
// `plane_path` is not empty, measures the plane scale. The CLI's library entry point.
CameraCalibration CalibrateFromFiles(const std::vector<std::string>& image_sources,
                                     const std::string& plane_path,
                                     const CalibrationOptions& options,
                                     CalibrationSummary* summary = nullptr);

// `impactdic calibrate`: checks everything before any work (options.Check(); at least one image
// source, "calibration images"; the plane view exists; `output` a .yaml / .yml that is none of
// the images, "output"), then CalibrateFromFiles and SaveCalibration to `output`.
CameraCalibration CalibrateToFile(const std::vector<std::string>& image_sources,
                                  const std::string& plane_path, const CalibrationOptions& options,
                                  const std::string& output, CalibrationSummary* summary);

// YAML (keys in docs/calibration.md). Save is atomic; Load checks every key and reports the file
// and key of a problem.
void SaveCalibration(const CameraCalibration& calibration, const std::string& path);
// How SaveCalibration's file begins (an existing calibrate -o file is replaced, any other kept).
inline constexpr const char* kCalibrationFirstLine = "# impactdic camera calibration";
CameraCalibration LoadCalibration(const std::string& path);

// Throws Error(kInvalidValue) naming both sizes unless frame_size equals the calibration's image
// size; `what` names the frame (file name or "frame 12").
void CheckFrameSize(const CameraCalibration& calibration, cv::Size frame_size,
                    const std::string& what = "frame");

}  // namespace impactdic

#endif  // IMPACTDIC_CALIB_CALIBRATION_H_
