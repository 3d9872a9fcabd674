// Lens calibration and the metric scale of the measurement plane (docs/calibration.md).
//
// Checkerboard corners are found with cv::findChessboardCorners and refined with cv::cornerSubPix
// (gradient-orthogonality estimator, Foerstner & Guelch 1987); ChArUco corners from the ArUco
// markers (cv::aruco::detectMarkers, Garrido-Jurado et al. 2014, doi:10.1016/j.patcog.2014.01.005)
// and circle-grid centres by cv::findCirclesGrid (board_detection.cc). The camera is calibrated
// with cv::calibrateCamera (Zhang 2000, IEEE TPAMI 22(11):1330, doi:10.1109/34.888718):
// intrinsics fx, fy, cx, cy and the distortion of a LensModel (Brown-Conrady k1, k2, p1, p2, k3 by
// default, Brown 1966; the model is written out in synth/checkerboard.h), chosen by the held-out
// reprojection error (lens_model.cc). The plane scale is the homography from undistorted image
// pixels to millimetres on the panel, fitted to the corners of one view of the board lying on the
// panel (Hartley & Zisserman 2004, ch. 4, DLT + Levenberg-Marquardt refinement in
// cv::findHomography).
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

#include "impactdic/core/enum_names.h"
#include "impactdic/core/numeric.h"
#include "impactdic/core/range.h"
#include "impactdic/io/json.h"
#include "impactdic/io/yaml.h"

namespace impactdic {

// The kinds of calibration target.
enum class BoardKind {
  kChessboard,         // cv::findChessboardCorners: the whole board must be in view.
  kCharuco,            // Chessboard with ArUco markers in the white squares: partial views count.
  kCircles,            // Symmetric grid of dark circles (cv::findCirclesGrid).
  kAsymmetricCircles,  // Asymmetric (staggered) circle grid.
};
inline constexpr EnumNames<BoardKind, 4> kBoardKindNames{
    {{{BoardKind::kChessboard, "chessboard"},
      {BoardKind::kCharuco, "charuco"},
      {BoardKind::kCircles, "circles"},
      {BoardKind::kAsymmetricCircles, "asymmetric_circles"}}}};

// Where the ArUco markers of a ChArUco board sit (boards with an even number of square rows
// differ; with an odd number both layouts are the same board). Squares (x, y) counted from the
// top-left of the printed board, y down; the markers fill the white squares, ids row by row from
// the top-left.
//   kCurrent: the top-left square is black (OpenCV >= 4.7's CharucoBoard, and 4.6 with an odd
//             number of rows).
//   kLegacy: the bottom-left square is black (OpenCV <= 4.6 contrib, setLegacyPattern(true)).
//   kAuto: the layout under which the detected markers are mutually consistent (each marker's
//          homography predicts its neighbours' centres; docs/calibration.md).
enum class CharucoLayout { kAuto, kCurrent, kLegacy };
inline constexpr EnumNames<CharucoLayout, 3> kCharucoLayoutNames{
    {{{CharucoLayout::kAuto, "auto"},
      {CharucoLayout::kCurrent, "current"},
      {CharucoLayout::kLegacy, "legacy"}}}};

// A calibration target. Chessboard and ChArUco: cols x rows INNER corners (9x6 for a board of
// 10x7 squares), corner (i, j) at (i, j) * square_mm. Circle grids: cols x rows circles (OpenCV's
// pattern size), circle (i, j) at (i, j) * square_mm (symmetric) or ((2i + j % 2), j) * square_mm
// (asymmetric: square_mm is the row pitch, half the centre distance within a row).
struct BoardSpec {
  int cols = 9;           // Inner corners (circles) along the board's X axis, >= 2.
  int rows = 6;           // Inner corners (circles) along Y, >= 2.
  double square_mm = 25;  // Side of one square (circle spacing) [mm], in kSquareRange.
  BoardKind kind = BoardKind::kChessboard;  // (After the sizes: {cols, rows, square_mm} works.)
  // ChArUco only: the side of the ArUco markers [mm], in (0, square_mm); the dictionary
  // (an OpenCV predefined name such as DICT_4X4_50, ArucoDictionaryNames()) and the layout.
  double marker_mm = 0;
  std::string dictionary = "DICT_4X4_50";
  CharucoLayout layout = CharucoLayout::kAuto;
  // Printed boards from 0.01 mm (microscope targets) to 10 m squares; beyond, the corner
  // coordinates (float) lose their meaning and OpenCV fails with an assertion.
  static constexpr ValueRange kSquareRange{0.01, 1e4, "mm"};
  void Check() const;
  cv::Size PatternSize() const { return {cols, rows}; }
  // Every point of the board (corner or circle centre) in id order (id = j * cols + i), Z = 0.
  std::vector<cv::Point3f> ObjectPoints() const;
  // "9x6 inner corners" / "ChArUco 11x8 squares" / "4x11 asymmetric circles".
  std::string Describe() const;
  bool IsPartialViewBoard() const { return kind == BoardKind::kCharuco; }
};

// Parses "COLSxROWS" (e.g. "9x6", inner corners) into a board with the given square size.
// Error(kInvalidValue, where, text, ...) for anything else and for fewer than 2 corners a side
// (`where`: CalibrationOptions::board); Error naming board.square_mm for a square_mm outside
// BoardSpec::kSquareRange.
BoardSpec ParseBoard(const std::string& text, double square_mm, const std::string& where = "board");
// A ChArUco board of COLSxROWS SQUARES (as printed and as OpenCV counts them: "11x8" has 10x7
// inner corners), `square_mm` squares, `marker_mm` markers from `dictionary`.
BoardSpec ParseCharucoBoard(const std::string& text, double square_mm, double marker_mm,
                            const std::string& dictionary, const std::string& where = "charuco");
// A circle grid of COLSxROWS circles (OpenCV's pattern size; asymmetric: circles per row x rows).
BoardSpec ParseCircleGrid(const std::string& text, double spacing_mm, bool asymmetric,
                          const std::string& where = "circles");
// The names of OpenCV's predefined ArUco dictionaries (DICT_4X4_50 ... DICT_ARUCO_ORIGINAL).
std::vector<std::string> ArucoDictionaryNames();

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

// The lens distortion models (docs/calibration.md):
//   kBrown: Brown-Conrady k1, k2, p1, p2, k3 (cv::calibrateCamera's default; Brown 1966).
//   kRational: k1..k6 with the radial factor (1 + k1 r^2 + k2 r^4 + k3 r^6) /
//              (1 + k4 r^2 + k5 r^4 + k6 r^6), and p1, p2 (cv::CALIB_RATIONAL_MODEL).
//   kFisheye: the equidistant-type model of cv::fisheye, theta_d = theta (1 + k1 theta^2 +
//             k2 theta^4 + k3 theta^6 + k4 theta^8), theta the angle of the ray to the axis
//             (Kannala & Brandt 2006, doi:10.1109/TPAMI.2006.153).
//   kAuto (options only): the model with the lowest held-out reprojection RMS (leave-some-out
//          over the views; CalibrationOptions::model and docs/calibration.md).
enum class LensModel { kAuto, kBrown, kRational, kFisheye };
inline constexpr EnumNames<LensModel, 4> kLensModelNames{{{{LensModel::kAuto, "auto"},
                                                           {LensModel::kBrown, "brown"},
                                                           {LensModel::kRational, "rational"},
                                                           {LensModel::kFisheye, "fisheye"}}}};

// Where the board of the plane view lies relative to a viewing window (a glass or acrylic panel
// between the camera and the soil).
enum class BoardPosition {
  kOuterFace,  // On the panel's outer face (camera side): the soil is t behind it, refracted.
  kSoil,       // At the soil plane (against the inner face, seen through the panel).
};
inline constexpr EnumNames<BoardPosition, 2> kBoardPositionNames{
    {{{BoardPosition::kOuterFace, "outer_face"}, {BoardPosition::kSoil, "soil"}}}};

// A plane-parallel viewing window of thickness t and refractive index n, the soil touching its
// inner face. With the board on the outer face, the plane scale is carried to the soil plane by
// tracing each pixel's ray: refracted at the outer face (Snell), straight through the panel to
// the inner face, where it meets the soil (window.h, docs/calibration.md).
struct WindowOptions {
  double thickness_mm = 0;  // Panel thickness [mm], in kThicknessRange; 0 = no window.
  double refractive_index =
      1.49;  // Panel index n (PMMA 1.49, soda-lime glass 1.52), in kIndexRange.
  BoardPosition board_position = BoardPosition::kOuterFace;
  static constexpr ValueRange kThicknessRange{0, 1e3, "mm"};
  static constexpr ValueRange kIndexRange{1, 3, ""};
  bool Active() const { return thickness_mm > 0; }
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
  // The distortion model; kAuto chooses it by the held-out views' reprojection RMS
  // (ChooseLensModel): Brown-Conrady unless another model beats it by kModelMargin.
  LensModel model = LensModel::kAuto;
  // ChArUco: a view with fewer detected corners than this is rejected (>= 6: a homography
  // needs 4, and the corners should span the view).
  int min_corners = 12;
  WindowOptions window;  // The viewing window between the camera and the soil (plane scale).
  static constexpr ValueRange kMinViewsRange{3, 1e4, ""};
  static constexpr ValueRange kMaxRmsRange{0, 1e3, "px", /*min_open=*/true};
  static constexpr ValueRange kDuplicateToleranceRange{0, 100, "px"};
  static constexpr ValueRange kMinCornersRange{6, 1e6, ""};
  // kAuto keeps Brown-Conrady unless a model's held-out RMS is lower by more than this fraction
  // (a more flexible model always fits its own views better; held out, noise alone moves the
  // RMS by a few per cent).
  static constexpr double kModelMargin = 0.05;
  void Check() const;
};

// The options of `impactdic calibrate` as option tables (io/yaml.h), the keys named as in
// CalibrationOptions::Check's errors: calibration.min_views, max_rms_px, fix_k3, zero_tangential,
// duplicate_tolerance_px, model, min_corners, charuco_layout, calibration.detection.* and
// calibration.window.* (the board is --board/--charuco/--circles and their sizes).
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
  // The viewing window the scale was carried through (thickness 0: none). With the board on the
  // outer face, mm_from_px and mm_per_px refer to the soil plane behind the panel and
  // board_mm_per_px is the scale measured on the outer face.
  WindowOptions window;
  double board_mm_per_px = kNaN;
  // Largest distance [mm] over the image between the traced soil point and the homography fitted
  // to the traced points: the part of the refraction one homography does not carry (off-axis).
  double window_nonlinearity_mm = 0;

  // Maps an undistorted pixel to plane millimetres.
  cv::Point2d ToMm(cv::Point2d undistorted_px) const;
};

struct ViewRecord {
  std::string image;
  double rms_px = kNaN;  // Per-view reprojection RMS.
  int corners = 0;       // Points (corners or circle centres) used from the view.
};

// One candidate of the lens model choice: the held-out reprojection RMS (each view predicted by
// the intrinsics fitted without it, its pose fitted alone) and the fit to all views.
struct ModelCandidate {
  LensModel model = LensModel::kBrown;
  double heldout_rms_px = kNaN;
  double fit_rms_px = kNaN;
  std::string failure;  // Not empty: the fit failed (why).
};
struct RejectedView {
  std::string image;
  std::string reason;
};

// The reprojection residuals over the image: RMS [px] in each cell of a cols x rows grid
// (row-major; NaN where no point falls), to show where the model misfits (the corners, for a
// wide-angle lens under a too-stiff model).
struct ResidualMap {
  int cols = 4;
  int rows = 3;
  std::vector<double> rms_px;
  std::vector<int> points;
  std::string Text() const;  // One line per grid row.
};

struct CameraCalibration {
  int image_width = 0;  // [px] The frames must have this size (CheckFrameSize).
  int image_height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;           // [px]
  LensModel model = LensModel::kBrown;             // Never kAuto.
  std::array<double, 5> dist{0, 0, 0, 0, 0};       // Brown / rational: k1, k2, p1, p2, k3
  std::array<double, 3> dist_rational{0, 0, 0};    // Rational: k4, k5, k6
  std::array<double, 4> dist_fisheye{0, 0, 0, 0};  // Fisheye: k1, k2, k3, k4 (cv::fisheye)
  double rms_px = kNaN;                            // Overall reprojection RMS.
  std::vector<ModelCandidate> candidates;          // The model choice (kAuto), empty when given.
  ResidualMap residual_map;
  BoardSpec board;
  std::vector<ViewRecord> views;       // The views used, with their RMS.
  std::vector<RejectedView> rejected;  // The views not used, with the reason.
  std::optional<PlaneScale> plane;

  cv::Size ImageSize() const { return {image_width, image_height}; }
  cv::Matx33d CameraMatrix() const { return {fx, 0, cx, 0, fy, cy, 0, 0, 1}; }
  // The model's coefficients in OpenCV's order, CV_64F: 1x5 (brown), 1x8 (rational: k1 k2 p1 p2
  // k3 k4 k5 k6) or 1x4 (fisheye).
  cv::Mat DistCoeffs() const;
  bool HasDistortion() const;  // Any coefficient non-zero.
  // Distorted pixel -> undistorted pixel (same camera matrix), by cv::undistortPoints or
  // cv::fisheye::undistortPoints (iterative; accurate to ~1e-6 px for mild distortion).
  std::vector<cv::Point2d> UndistortPixels(const std::vector<cv::Point2d>& distorted) const;
  // Board points -> distorted pixels for a pose (cv::projectPoints or cv::fisheye::projectPoints).
  std::vector<cv::Point2f> Project(const std::vector<cv::Point3f>& points, const cv::Vec3d& rvec,
                                   const cv::Vec3d& tvec) const;
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
// is not found (or, ChArUco, if no corner is found: DetectBoardPoints gives partial views).
std::optional<std::vector<cv::Point2f>> DetectBoard(const cv::Mat& image, const BoardSpec& board,
                                                    const DetectionOptions& options);

// The points of one view: image positions and their ids (indices into board.ObjectPoints()).
// Chessboards and circle grids: all points or none. ChArUco (board_detection.cc): the ArUco
// markers (cv::aruco::detectMarkers) give the squares in view; each inner corner with both
// neighbouring markers detected is predicted from their homographies and refined with
// cv::cornerSubPix (half-window below the marker's distance from the corner).
struct BoardDetection {
  std::vector<cv::Point2f> image_points;
  std::vector<int> ids;
  int markers = 0;                              // ChArUco: markers detected.
  CharucoLayout layout = CharucoLayout::kAuto;  // ChArUco: the layout used.
  std::string failure;                          // Why nothing was found.
  std::vector<cv::Point3f> ObjectPoints(const BoardSpec& board) const;
};
BoardDetection DetectBoardPoints(const cv::Mat& image, const BoardSpec& board,
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
// With a window (window.Active()) and the board on its outer face, the scale is carried to the
// soil plane (TraceToSoil over a grid of the image, homography fitted to the traced points).
// Error if the size differs from the calibration or the board is not found.
PlaneScale MeasurePlaneScale(const cv::Mat& image, const std::string& name,
                             const CameraCalibration& calibration,
                             const DetectionOptions& options = {},
                             const WindowOptions& window = {});

// The point of the soil plane [mm, board axes] seen at `undistorted_px` through the window, for
// the camera at (rvec, tvec) of the board lying on the panel's outer face (X_cam = R X + t).
// The pixel's ray meets the outer face (Z = 0), is refracted (Snell's law in vector form,
// n_air = 1), crosses the panel and meets the soil at the inner face, Z = t on the far side
// from the camera. False if the ray does not reach the panel.
bool TraceToSoil(const CameraCalibration& calibration, const cv::Vec3d& rvec, const cv::Vec3d& tvec,
                 const WindowOptions& window, cv::Point2d undistorted_px, cv::Point2d* soil_mm);

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
