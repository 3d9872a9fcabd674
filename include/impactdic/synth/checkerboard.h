// Checkerboard calibration views rendered through a known camera (docs/synth.md), the ground
// truth of the calib module's tests and of the sample data in calibration/.
//
// Camera model (the OpenCV / Brown-Conrady model, Brown 1966, Photogramm. Eng. 32(3):444-462;
// Conrady 1919, MNRAS 79:384): a board point (X, Y, 0) [mm] goes to the camera frame by
// Xc = R(rvec) X + t, to normalised coordinates (x, y) = (Xc/Zc, Yc/Zc), is distorted with
//   r2 = x^2 + y^2,  radial = 1 + k1 r2 + k2 r2^2 + k3 r2^3,
//   xd = x radial + 2 p1 x y + p2 (r2 + 2 x^2),  yd = y radial + p1 (r2 + 2 y^2) + 2 p2 x y,
// and mapped to pixels by u = fx xd + cx, v = fy yd + cy (pixel centres at integer coordinates).
//
// Rendering runs the model backwards: for each sample point of the image, the distortion is
// inverted by Newton iteration, the ray is intersected with the board plane and the board's
// reflectance is evaluated there. Pixels whose four corners fall in the same board cell are
// uniform; the others (edge pixels) are averaged over supersampling^2 samples (a sheared lattice),
// which gives anti-aliased edges. A Gaussian point-spread function of the optics, Gaussian noise
// and 8/16-bit quantisation follow.
//
//   SynthCamera camera = SampleCamera();              // 640x480, k1 = -0.08
//   CheckerboardSpec board;                           // 9x6 inner corners, 25 mm squares
//   auto poses = CalibrationPoses(camera, board, /*count=*/14, /*seed=*/7);
//   cv::Mat view = RenderCheckerboard(camera, board, poses[0], CheckerboardRenderOptions{});
//   std::vector<cv::Point2d> truth = ProjectCorners(camera, board, poses[0]);
#ifndef IMPACTDIC_SYNTH_CHECKERBOARD_H_
#define IMPACTDIC_SYNTH_CHECKERBOARD_H_

#include <array>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace impactdic {

// A pinhole camera with Brown-Conrady distortion (model in the header comment), optionally with
// the rational model's denominator 1 + k4 r2 + k5 r2^2 + k6 r2^3 under the radial factor, or the
// fisheye model instead (cv::fisheye's: theta = atan(r), theta_d = theta (1 + k1 theta^2 +
// k2 theta^4 + k3 theta^6 + k4 theta^8), xd = (theta_d / r) x; no tangential terms).
struct SynthCamera {
  int width = 640;   // Image width [px], >= 16.
  int height = 480;  // Image height [px], >= 16.
  double fx = 820;   // Focal lengths [px], > 0.
  double fy = 820;
  double cx = 319.5;  // Principal point [px] (pixel centres at integers).
  double cy = 239.5;
  std::array<double, 5> dist{0, 0, 0, 0, 0};    // k1, k2, p1, p2, k3 (OpenCV order).
  std::array<double, 3> rational{0, 0, 0};      // k4, k5, k6 (rational model's denominator).
  bool fisheye = false;                         // Use the fisheye model (fisheye_k) instead.
  std::array<double, 4> fisheye_k{0, 0, 0, 0};  // k1..k4 of the fisheye model.
  void Check() const;

  // Normalised (undistorted) coordinates -> distorted pixel coordinates.
  cv::Point2d Distort(cv::Point2d normalised) const;
  // Distorted pixel coordinates -> normalised undistorted coordinates (Newton iteration to
  // ~1e-12). Returns false if the iteration does not converge (far outside the image).
  bool Undistort(cv::Point2d pixel, cv::Point2d* normalised) const;
  // Ideal pinhole pixel of a normalised point: (fx x + cx, fy y + cy).
  cv::Point2d Pinhole(cv::Point2d normalised) const {
    return {fx * normalised.x + cx, fy * normalised.y + cy};
  }
};

// The camera of the sample data (calibration/ and sample_frames/): 640x480, f = 820 px, mild
// barrel distortion k1 = -0.08, k2 = 0.05, small tangential terms.
SynthCamera SampleCamera();

// A checkerboard with cols x rows INNER corners (a 9x6 board has 10x7 squares), surrounded by a
// white margin (OpenCV's detector needs a quiet zone), lying in the board plane Z = 0. Inner corner
// (i, j) sits at (i * square_mm, j * square_mm), i = 0..cols-1 along X, j = 0..rows-1 along Y;
// the squares span [-square, cols*square] x [-square, rows*square].
//
// Other targets on the same lattice (the calib module's BoardSpec conventions):
//   kCharuco: the same squares with ArUco markers (side marker_mm, OpenCV dictionary number
//     `dictionary`, cv::aruco::PREDEFINED_DICTIONARY_NAME) centred in the white squares, ids row by
//     row from the top-left; the top-left square is black, or with legacy_layout the bottom-left
//     one (OpenCV <= 4.6 with an even number of square rows).
//   kCircles: cols x rows dark circles of radius circle_radius_mm at (i, j) * square_mm on white.
//   kAsymmetricCircles: cols circles per row at ((2 i + j % 2), j) * square_mm.
enum class TargetKind { kChessboard, kCharuco, kCircles, kAsymmetricCircles };

struct CheckerboardSpec {
  int cols = 9;                  // Inner corners (circles) along X, >= 2.
  int rows = 6;                  // Inner corners (circles) along Y, >= 2.
  double square_mm = 25;         // Square side (circle spacing) [mm], > 0.
  double margin_squares = 0.75;  // White margin around the squares [squares], >= 0.
  TargetKind kind = TargetKind::kChessboard;
  double marker_mm = 0;         // kCharuco: marker side [mm], in (0, square_mm).
  int dictionary = 0;           // kCharuco: cv::aruco predefined dictionary (0 = DICT_4X4_50).
  bool legacy_layout = false;   // kCharuco: OpenCV <= 4.6's layout.
  double circle_radius_mm = 0;  // Circle grids: radius [mm], in (0, 0.45 square_mm].
  void Check() const;
  // Board extent including the margin [mm]: X in [XMin(), XMax()], Y likewise.
  double XMin() const { return -(1 + margin_squares) * square_mm; }
  double YMin() const { return XMin(); }
  double XMax() const {
    return (kind == TargetKind::kAsymmetricCircles ? 2 * cols : cols + margin_squares) * square_mm;
  }
  double YMax() const { return (rows + margin_squares) * square_mm; }
  // Every corner (circle centre) in id order, id = j * cols + i [mm, Z = 0].
  std::vector<cv::Point2d> Points() const;
};

// Board-to-camera pose: X_camera = R(rvec) X_board + tvec (OpenCV convention; tvec in mm).
struct BoardPose {
  cv::Vec3d rvec{0, 0, 0};
  cv::Vec3d tvec{0, 0, 500};
};

struct CheckerboardRenderOptions {
  int supersampling = 16;     // Samples per pixel side on edge pixels, in [1, 32].
  double black = 0.12;        // Reflectance of black squares, fraction of full scale [0, 1].
  double white = 0.88;        // Reflectance of white squares and the margin [0, 1].
  double background = 0.45;   // Level outside the board [0, 1].
  double psf_sigma_px = 1.0;  // Gaussian point-spread function of the optics [px], in [0, 5];
                              // 0 = ideal box-filtered pixels (cornerSubPix is biased by up to
                              // 0.1 px on such unrealistically sharp corners).
  double noise_sigma = 1.0;   // Gaussian noise [grey levels of the output bit depth], >= 0.
  int bits = 8;               // 8 (CV_8U) or 16 (CV_16U).
  std::uint64_t seed = 1;     // Noise seed.
  // A plane-parallel panel (viewing window) in front of the board, touching it: the rays are
  // refracted at its outer face (Snell's law) and cross it to the board. 0 = none.
  double panel_thickness_mm = 0;        // [mm], >= 0.
  double panel_refractive_index = 1.5;  // >= 1.
  void Check() const;
};

// Renders one view (CV_8U or CV_16U, camera.height x camera.width).
cv::Mat RenderCheckerboard(const SynthCamera& camera, const CheckerboardSpec& board,
                           const BoardPose& pose, const CheckerboardRenderOptions& options);

// The point of the board plane [mm] seen along the ray of normalised point (x, y) for the pose,
// through the panel of `options` (refracted at its outer face, Snell's law). False if the ray
// misses the plane.
bool BoardPointOnRay(const BoardPose& pose, const CheckerboardRenderOptions& options,
                     cv::Point2d normalised, cv::Point2d* board_mm);

// True distorted pixel positions of the inner corners, row-major (j outer, i inner), the order of
// cv::findChessboardCorners' object points.
std::vector<cv::Point2d> ProjectCorners(const SynthCamera& camera, const CheckerboardSpec& board,
                                        const BoardPose& pose);
// Same corners projected by the ideal pinhole (no distortion): the truth of undistortion.
std::vector<cv::Point2d> ProjectCornersPinhole(const SynthCamera& camera,
                                               const CheckerboardSpec& board,
                                               const BoardPose& pose);

// `count` varied, seeded poses (tilts of 15-40 degrees about random axes, in-plane rotations up
// to 20 degrees, boards 40-65 % of the image width, cycling through the four image corners and
// the centre) whose whole board including the margin stays inside the image with a 6 px border.
// Deterministic for a given seed.
std::vector<BoardPose> CalibrationPoses(const SynthCamera& camera, const CheckerboardSpec& board,
                                        int count, std::uint64_t seed);

// The board lying on the panel, fronto-parallel (board plane parallel to the sensor), centred on
// the optical axis at distance `distance_mm`, rotated in-plane by `roll_deg`. The plane scale of
// the true camera there is distance_mm / f [mm per undistorted px].
BoardPose PanelPose(const SynthCamera& camera, const CheckerboardSpec& board, double distance_mm,
                    double roll_deg = 0);

struct CalibrationSetOptions {
  int views = 14;                // Calibration views, >= 1.
  std::uint64_t seed = 7;        // Pose seed (noise seeds are derived from it).
  double panel_distance_mm = 0;  // Distance of the panel view; 0 = the board fills ~60 % of the
                                 // image width.
  int partial_every = 0;         // Every n-th view (n >= 2) is moved sideways by 45 % of the
                                 // board's width so that it runs out of the image; 0 = none.
  CheckerboardRenderOptions render;
  void Check() const;
};

struct CalibrationSet {
  std::vector<std::string> view_paths;  // view_00.png ... (PNG, 8- or 16-bit)
  std::string plane_path;               // plane.png: the board on the panel
  std::string board_path;               // board.yaml: the board definition
  std::vector<BoardPose> poses;         // Pose of each view
  BoardPose plane_pose;
  double plane_mm_per_px = 0;  // True scale of the plane view: distance / f
  std::string soil_path;       // window preset: soil.png, the board behind the panel
  BoardPose soil_pose;
  double soil_mm_per_px = 0;  // window preset: true scale of the soil plane at (cx, cy)
};

// Renders a calibration set into `out_dir` (created if missing): the views, the plane view and a
// board definition YAML (keys: cols, rows, square_mm, margin_squares; plus the true camera under
// `truth:` for reference). Used for calibration/ and by the synthetic scene generator so its
// frames and its calibration come through the same lens.
CalibrationSet RenderCalibrationSet(const SynthCamera& camera, const CheckerboardSpec& board,
                                    const CalibrationSetOptions& options,
                                    const std::string& out_dir);

// The named calibration sets of `impactdic synth --calibration-set NAME` (docs/calibration.md),
// each with its true camera and board in DIR/board.yaml:
//   charuco, charuco_legacy: a ChArUco board of 8x6 squares (30 mm, 21 mm DICT_4X4_50 markers)
//     in 12 views of the sample lens at 1280x960 (f = 1640 px), every third view with the board
//     running out of the image (charuco_legacy: OpenCV <= 4.6's marker layout);
//   circles, asymmetric_circles: a 7x5 circle grid (30 mm) / 4x9 asymmetric grid (20 mm pitch);
//   wide_angle: the charuco board through a fisheye lens (f = 600 px at 1280x960, 156 degrees
//     across the diagonal, theta_d = theta (1 - 0.02 theta^2 + 0.004 theta^4)), whole views;
//   window: the sample lens (12 chessboard views), the board on the outer face of a 20 mm panel of
//     n = 1.5 seen from 1 m (plane.png), and the same board at the soil plane behind the panel
//     (soil.png), with the true soil-plane scale.
inline constexpr const char* kCalibrationSetNames[] = {
    "charuco", "charuco_legacy", "circles", "asymmetric_circles", "wide_angle", "window"};
struct CalibrationPreset {
  SynthCamera camera;
  CheckerboardSpec board;
  CalibrationSetOptions options;  // window: options.panel_distance_mm, camera to outer face
  double panel_thickness_mm = 0;  // window: the panel
  double panel_refractive_index = 1.5;
};
// Error(kInvalidValue, "--calibration-set") for another name.
CalibrationPreset CalibrationPresetNamed(const std::string& name);
// Renders the preset into out_dir (as RenderCalibrationSet; window: also soil.png, and the soil
// truth in board.yaml: soil_mm_per_px, the scale at the principal point).
CalibrationSet RenderCalibrationPreset(const CalibrationPreset& preset, const std::string& out_dir);

}  // namespace impactdic

#endif  // IMPACTDIC_SYNTH_CHECKERBOARD_H_
