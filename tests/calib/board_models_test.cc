// Calibration targets (chessboard, ChArUco, circle grids), the choice of the distortion model and
// the viewing window, against sets rendered with known truth (synth/checkerboard.h presets, the
// sets of `impactdic synth --calibration-set NAME`). Figures quoted in docs/calibration.md.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "../core/expect_error.h"
#include "../core/test_paths.h"
#include "impactdic/calib/calibration.h"
#include "impactdic/calib/undistort.h"
#include "impactdic/io/image_io.h"
#include "impactdic/synth/checkerboard.h"

namespace impactdic {
namespace {

struct Rendered {
  CalibrationPreset preset;
  CalibrationSet set;
  std::vector<cv::Mat> images;
};

// The preset rendered once per test program into the test's temporary folder.
const Rendered& Preset(const std::string& name) {
  static std::map<std::string, Rendered> cache;
  auto found = cache.find(name);
  if (found != cache.end()) return found->second;
  Rendered r;
  r.preset = CalibrationPresetNamed(name);
  const std::string dir = ::testing::TempDir() + "/impactdic_calibration_set_" + name;
  r.set = RenderCalibrationPreset(r.preset, dir);
  for (const std::string& path : r.set.view_paths) r.images.push_back(ReadGreyImage(path));
  return cache.emplace(name, std::move(r)).first->second;
}

CameraCalibration Calibrate(const Rendered& r, const CalibrationOptions& options,
                            CalibrationSummary* summary = nullptr) {
  return CalibrateCamera(r.images, r.set.view_paths, options, summary);
}

// fx, fy, cx, cy within `relative` of the truth (cx, cy relative to the image size).
void ExpectIntrinsics(const CameraCalibration& c, const SynthCamera& truth, double relative) {
  EXPECT_NEAR(c.fx, truth.fx, relative * truth.fx);
  EXPECT_NEAR(c.fy, truth.fy, relative * truth.fy);
  EXPECT_NEAR(c.cx, truth.cx, relative * truth.width);
  EXPECT_NEAR(c.cy, truth.cy, relative * truth.height);
  std::printf("%s: fx %.3f (%.3f) fy %.3f (%.3f) cx %.3f (%.3f) cy %.3f (%.3f), RMS %.4f px\n",
              kLensModelNames.Name(c.model), c.fx, truth.fx, c.fy, truth.fy, c.cx, truth.cx, c.cy,
              truth.cy, c.rms_px);
}

TEST(SampleViews, TheCriterionKeepsBrownConrady) {
  std::vector<cv::Mat> images;
  std::vector<std::string> names;
  for (int k = 0; k < 12; ++k) {
    char name[64];
    std::snprintf(name, sizeof name, "/calibration/view_%02d.png", k);
    names.push_back(std::string(SourceDir()) + name);
    images.push_back(ReadGreyImage(names.back()));
  }
  CalibrationOptions options;  // model auto
  const CameraCalibration c = CalibrateCamera(images, names, options);
  EXPECT_EQ(c.model, LensModel::kBrown);
  ASSERT_EQ(c.candidates.size(), 3u);
  for (const ModelCandidate& m : c.candidates)
    std::printf("sample views: %s held-out RMS %.4f px, fit %.4f px %s\n",
                kLensModelNames.Name(m.model), m.heldout_rms_px, m.fit_rms_px, m.failure.c_str());
  ExpectIntrinsics(c, SampleCamera(), 0.005);
  for (const ViewRecord& v : c.views) EXPECT_EQ(v.corners, 54);
}

TEST(Charuco, PartialViewsCalibrateTheSampleLens) {
  const Rendered& r = Preset("charuco");
  CalibrationOptions options;
  options.board = ParseCharucoBoard("8x6", 30, 21, "DICT_4X4_50");
  options.model = LensModel::kBrown;
  CalibrationSummary summary;
  const CameraCalibration c = Calibrate(r, options, &summary);
  EXPECT_EQ(summary.images_used, 12);
  EXPECT_EQ(c.board.layout, CharucoLayout::kCurrent);
  ExpectIntrinsics(c, r.preset.camera, 0.005);
  EXPECT_LT(c.rms_px, 0.15);
  // Every third view runs out of the image: fewer than the 35 corners, still used.
  int partial = 0;
  for (std::size_t v = 0; v < c.views.size(); ++v) {
    std::printf("  %s: %d corners, RMS %.4f px\n", c.views[v].image.c_str(), c.views[v].corners,
                c.views[v].rms_px);
    EXPECT_GE(c.views[v].corners, options.min_corners);
    if (v % 3 == 2) {
      EXPECT_LT(c.views[v].corners, 30);
      ++partial;
    } else {
      EXPECT_EQ(c.views[v].corners, 35);
    }
  }
  EXPECT_EQ(partial, 4);
}

TEST(Charuco, LegacyLayoutIsDetected) {
  const Rendered& r = Preset("charuco_legacy");
  CalibrationOptions options;
  options.board = ParseCharucoBoard("8x6", 30, 21, "DICT_4X4_50");
  options.model = LensModel::kBrown;
  const CameraCalibration c = Calibrate(r, options);
  EXPECT_EQ(c.board.layout, CharucoLayout::kLegacy);
  ExpectIntrinsics(c, r.preset.camera, 0.005);
  // Told the wrong layout, the corners are misplaced: no corner (or a wild fit).
  const BoardDetection wrong = [&] {
    BoardSpec board = options.board;
    board.layout = CharucoLayout::kCurrent;
    return DetectBoardPoints(r.images[0], board, DetectionOptions{});
  }();
  const BoardDetection right = DetectBoardPoints(r.images[0], c.board, DetectionOptions{});
  EXPECT_EQ(right.ids.size(), 35u);
  EXPECT_LT(wrong.ids.size(), right.ids.size());
}

TEST(Charuco, ViewsWithTooFewCornersAreRejectedWithTheCount) {
  const Rendered& r = Preset("charuco");
  CalibrationOptions options;
  options.board = ParseCharucoBoard("8x6", 30, 21, "DICT_4X4_50");
  options.model = LensModel::kBrown;
  options.min_corners = 32;  // The partial views have fewer.
  options.min_views = 6;
  const CameraCalibration c = Calibrate(r, options);
  ASSERT_EQ(c.rejected.size(), 4u);
  EXPECT_NE(c.rejected[0].reason.find("ChArUco corners found"), std::string::npos)
      << c.rejected[0].reason;
  EXPECT_NE(c.rejected[0].reason.find("calibration.min_corners"), std::string::npos);
}

TEST(Charuco, BadBoardsNameTheField) {
  ExpectErrorContaining([&] { ParseCharucoBoard("11x8", 20, 25, "DICT_4X4_50"); },
                        "board.marker_mm");
  ExpectErrorContaining([&] { ParseCharucoBoard("11x8", 20, 15, "DICT_4x4"); }, "board.dictionary");
  // 88 squares, 44 markers: DICT_4X4_50 has 50, but a 15x12 board needs 90.
  ExpectErrorContaining([&] { ParseCharucoBoard("15x12", 20, 15, "DICT_4X4_50"); }, "at least 90");
  ExpectErrorContaining([&] { ParseCharucoBoard("2x8", 20, 15, "DICT_4X4_50"); }, "charuco");
}

// cv::findCirclesGrid misses (or misorders, which the detector then rejects) the most tilted
// views: at least 8 of the 12 are used. Blob centroids are not the projected centres under
// perspective (a bias of ~0.05 px here): 1 % tolerance on the intrinsics.
void ExpectCircleGridCalibrates(const std::string& preset, const BoardSpec& board) {
  const Rendered& r = Preset(preset);
  CalibrationOptions options;
  options.board = board;
  options.model = LensModel::kBrown;
  CalibrationSummary summary;
  const CameraCalibration c = Calibrate(r, options, &summary);
  EXPECT_GE(summary.images_used, 8);
  ExpectIntrinsics(c, r.preset.camera, 0.01);
}

TEST(CircleGrid, SymmetricGridCalibratesTheSampleLens) {
  ExpectCircleGridCalibrates("circles", ParseCircleGrid("7x5", 30, /*asymmetric=*/false));
}

TEST(CircleGrid, AsymmetricGridCalibratesTheSampleLens) {
  ExpectCircleGridCalibrates("asymmetric_circles", ParseCircleGrid("4x9", 20, /*asymmetric=*/true));
}

// Largest distance [px] of a board row's or column's corners from their least-squares line.
double WorstLineDeviation(const std::vector<cv::Point2f>& corners, int cols, int rows) {
  double worst = 0;
  const auto fit = [&](const std::vector<cv::Point2f>& line) {
    cv::Vec4f l;
    cv::fitLine(line, l, cv::DIST_L2, 0, 1e-6, 1e-6);
    for (const cv::Point2f& p : line)
      worst = std::max(worst, std::abs(double((p.x - l[2]) * l[1] - (p.y - l[3]) * l[0])));
  };
  for (int j = 0; j < rows; ++j)
    fit(std::vector<cv::Point2f>(corners.begin() + j * cols, corners.begin() + (j + 1) * cols));
  for (int i = 0; i < cols; ++i) {
    std::vector<cv::Point2f> column;
    for (int j = 0; j < rows; ++j) column.push_back(corners[j * cols + i]);
    fit(column);
  }
  return worst;
}

TEST(WideAngle, TheCriterionChoosesAModelThatStraightensTheLines) {
  const Rendered& r = Preset("wide_angle");
  CalibrationOptions options;  // model auto
  options.board = ParseCharucoBoard("8x6", 30, 21, "DICT_4X4_50");
  const CameraCalibration c = Calibrate(r, options);
  ASSERT_EQ(c.candidates.size(), 3u);
  double brown = 0, chosen = 0;
  for (const ModelCandidate& m : c.candidates) {
    std::printf("wide angle: %s held-out RMS %.4f px, fit %.4f px %s\n",
                kLensModelNames.Name(m.model), m.heldout_rms_px, m.fit_rms_px, m.failure.c_str());
    if (m.model == LensModel::kBrown) brown = m.heldout_rms_px;
    if (m.model == c.model) chosen = m.heldout_rms_px;
  }
  EXPECT_NE(c.model, LensModel::kBrown);
  EXPECT_LT(chosen, 0.5 * brown);
  ExpectIntrinsics(c, r.preset.camera, 0.005);
  std::printf("residual map [px]:\n%s", c.residual_map.Text().c_str());

  // The fronto-parallel view (plane.png) before and after undistortion with the chosen model.
  const cv::Mat plane = ReadGreyImage(r.set.plane_path);
  const BoardSpec& board = options.board;
  const auto before = DetectBoard(plane, board, DetectionOptions{});
  ASSERT_TRUE(before);
  ASSERT_EQ(before->size(), 35u);
  const Undistorter undistort(c, UndistortOptions{});
  ASSERT_TRUE(undistort.active());
  const auto after = DetectBoard(undistort.Apply(plane), board, DetectionOptions{});
  ASSERT_TRUE(after);
  ASSERT_EQ(after->size(), 35u);
  const double bent = WorstLineDeviation(*before, board.cols, board.rows);
  const double straight = WorstLineDeviation(*after, board.cols, board.rows);
  std::printf("wide angle: lines deviate by up to %.3f px before, %.3f px after undistortion\n",
              bent, straight);
  EXPECT_GT(bent, 3.0);
  // Corner noise (sigma 1 grey level, PSF 1 px) gives ~0.03 px; 0.15 px bounds it.
  EXPECT_LT(straight, 0.15);
}

// The window preset's lens, calibrated from its views.
CameraCalibration WindowLens(const Rendered& r) {
  CalibrationOptions options;
  options.model = LensModel::kBrown;
  options.board.square_mm = r.preset.board.square_mm;
  return Calibrate(r, options);
}

TEST(Window, SoilPlaneScaleWithinAThousandth) {
  const Rendered& r = Preset("window");
  const CameraCalibration lens = WindowLens(r);
  const cv::Mat plane = ReadGreyImage(r.set.plane_path);
  WindowOptions window;
  window.thickness_mm = 20;
  window.refractive_index = 1.5;
  const PlaneScale without = MeasurePlaneScale(plane, "plane.png", lens, DetectionOptions{});
  const PlaneScale with = MeasurePlaneScale(plane, "plane.png", lens, DetectionOptions{}, window);
  const double truth = r.set.soil_mm_per_px;
  const double error_without = without.mm_per_px / truth - 1;
  const double error_with = with.mm_per_px / truth - 1;
  std::printf(
      "window: soil truth %.6f mm/px; board on the outer face %.6f mm/px (%+.3f %%); through the "
      "window model %.6f mm/px (%+.3f %%); homography residual of the traced map %.4f mm\n",
      truth, without.mm_per_px, 100 * error_without, with.mm_per_px, 100 * error_with,
      with.window_nonlinearity_mm);
  EXPECT_LT(std::abs(error_with), 0.001);
  EXPECT_GT(-error_without, 0.011);
  EXPECT_LT(-error_without, 0.015);
  EXPECT_NEAR(with.board_mm_per_px, without.mm_per_px, 1e-12);

  // The board at the soil plane, seen through the panel: its corners mapped by the soil-plane
  // homography land on their true positions (the board sits straight behind the outer one).
  const cv::Mat soil = ReadGreyImage(r.set.soil_path);
  const auto corners = DetectBoard(soil, lens.board, DetectionOptions{});
  ASSERT_TRUE(corners);
  const std::vector<cv::Point2d> px =
      lens.UndistortPixels(std::vector<cv::Point2d>(corners->begin(), corners->end()));
  const std::vector<cv::Point3f> truth_mm = lens.board.ObjectPoints();
  double worst_with = 0, worst_without = 0;
  for (std::size_t k = 0; k < px.size(); ++k) {
    const cv::Point2d t(truth_mm[k].x, truth_mm[k].y);
    worst_with = std::max(worst_with, cv::norm(with.ToMm(px[k]) - t));
    worst_without = std::max(worst_without, cv::norm(without.ToMm(px[k]) - t));
  }
  std::printf("window: soil corners within %.3f mm (window model), %.3f mm (board scale)\n",
              worst_with, worst_without);
  EXPECT_LT(worst_with, 0.2);
  EXPECT_GT(worst_without, 2.0);
}

// A 640x480 pinhole camera with focal length f [px] and the principal point at (320, 240).
CameraCalibration Pinhole(double f) {
  CameraCalibration c;
  c.image_width = 640;
  c.image_height = 480;
  c.fx = c.fy = f;
  c.cx = 320;
  c.cy = 240;
  return c;
}

TEST(Window, TracedRayMatchesTheParaxialShift) {
  // On the axis of a camera 1 m from the outer face the soil scale is (D + t / n) / D times the
  // board's; the exact trace agrees to second order in the angle.
  const CameraCalibration c = Pinhole(1000);
  WindowOptions window;
  window.thickness_mm = 20;
  window.refractive_index = 1.5;
  const cv::Vec3d rvec(0, 0, 0), tvec(0, 0, 1000);
  cv::Point2d a, b;
  ASSERT_TRUE(TraceToSoil(c, rvec, tvec, window, {320, 240}, &a));
  ASSERT_TRUE(TraceToSoil(c, rvec, tvec, window, {321, 240}, &b));
  EXPECT_NEAR(cv::norm(b - a), (1000 + 20 / 1.5) / 1000, 1e-6);
  // Off the axis (35 degrees): Snell's law in the plane of incidence, x = D tan(i) + t tan(r)
  // with sin(r) = sin(i) / n, below the paraxial D tan(i) (1 + t / (n D)).
  ASSERT_TRUE(TraceToSoil(c, rvec, tvec, window, {320 + 700, 240}, &b));
  const double incidence = std::atan(0.7);
  const double refracted = std::asin(std::sin(incidence) / 1.5);
  EXPECT_NEAR(b.x, 700 + 20 * std::tan(refracted), 1e-9);
  EXPECT_LT(b.x, 700 * (1000 + 20 / 1.5) / 1000);
}

TEST(Window, OptionsAreChecked) {
  CalibrationOptions options;
  options.window.refractive_index = 0.9;
  ExpectErrorContaining([&] { options.Check(); }, "calibration.window.refractive_index");
  options = {};
  options.window.thickness_mm = -1;
  ExpectErrorContaining([&] { options.Check(); }, "calibration.window.thickness_mm");
  options = {};
  options.min_corners = 2;
  ExpectErrorContaining([&] { options.Check(); }, "calibration.min_corners");
}

TEST(LensModelYaml, RationalAndFisheyeRoundTripAndOldFilesAreBrown) {
  CameraCalibration c = Pinhole(500);
  c.board = ParseCharucoBoard("11x8", 20, 15, "DICT_5X5_100");
  c.board.layout = CharucoLayout::kLegacy;
  c.model = LensModel::kRational;
  c.dist = {0.1, 0.01, 1e-4, -1e-4, 0.002};
  c.dist_rational = {0.2, 0.03, 0.004};
  c.rms_px = 0.05;
  c.views = {{"view_00.png", 0.04, 27}};
  const std::string path = ::testing::TempDir() + "/impactdic_rational.yaml";
  SaveCalibration(c, path);
  CameraCalibration back = LoadCalibration(path);
  EXPECT_EQ(back.model, LensModel::kRational);
  EXPECT_EQ(back.DistCoeffs().total(), 8u);
  EXPECT_DOUBLE_EQ(back.dist_rational[2], 0.004);
  EXPECT_EQ(back.board.kind, BoardKind::kCharuco);
  EXPECT_EQ(back.board.layout, CharucoLayout::kLegacy);
  EXPECT_EQ(back.board.dictionary, "DICT_5X5_100");
  ASSERT_EQ(back.views.size(), 1u);
  EXPECT_EQ(back.views[0].corners, 27);
  c.model = LensModel::kFisheye;
  c.dist_fisheye = {0.01, -0.002, 3e-4, -4e-5};
  SaveCalibration(c, path);
  back = LoadCalibration(path);
  EXPECT_EQ(back.model, LensModel::kFisheye);
  EXPECT_DOUBLE_EQ(back.dist_fisheye[3], -4e-5);
  // The committed sample predates the `model` key: Brown-Conrady.
  const CameraCalibration sample =
      LoadCalibration(std::string(SourceDir()) + "/calibration/camera.yaml");
  EXPECT_EQ(sample.model, LensModel::kBrown);
  EXPECT_EQ(sample.board.kind, BoardKind::kChessboard);
}

}  // namespace
}  // namespace impactdic
