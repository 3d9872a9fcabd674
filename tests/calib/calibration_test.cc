#include "impactdic/calib/calibration.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>

#include "../core/expect_error.h"
#include "../core/test_paths.h"
#include "impactdic/core/error.h"
#include "impactdic/synth/checkerboard.h"

namespace impactdic {
namespace {

BoardSpec ToBoardSpec(const CheckerboardSpec& c) { return {c.cols, c.rows, c.square_mm}; }

// 20 rendered views of the sample camera (640x480, k1 = -0.08, k2 = 0.05, p1, p2 != 0), noise
// sigma = 1 grey level, 8-bit, calibrated once for the suite.
struct RenderedCalibration {
  SynthCamera camera_;
  CheckerboardSpec board_;
  std::vector<BoardPose> poses_;
  std::vector<cv::Mat> images_;
  std::vector<std::string> names_;
  CameraCalibration calibration_;
  CalibrationSummary summary_;
};

const RenderedCalibration& Rendered() {
  static const RenderedCalibration data = [] {
    RenderedCalibration d;
    d.camera_ = SampleCamera();
    d.poses_ = CalibrationPoses(d.camera_, d.board_, /*count=*/20, /*seed=*/21);
    CheckerboardRenderOptions render;
    render.noise_sigma = 1.0;
    for (std::size_t k = 0; k < d.poses_.size(); ++k) {
      render.seed = 100 + k;
      d.images_.push_back(RenderCheckerboard(d.camera_, d.board_, d.poses_[k], render));
      d.names_.push_back("view_" + std::to_string(k));
    }
    CalibrationOptions options;
    options.board = ToBoardSpec(d.board_);
    d.calibration_ = CalibrateCamera(d.images_, d.names_, options, &d.summary_);
    return d;
  }();
  return data;
}

void CheckIntrinsicsWithinHalfPercent() {
  const RenderedCalibration& d = Rendered();
  const CameraCalibration& c = d.calibration_;
  EXPECT_EQ(d.summary_.images_used, 20);
  EXPECT_EQ(c.image_width, 640);
  EXPECT_EQ(c.image_height, 480);
  // Done-when tolerance: 0.5 % (measured errors are ~0.05 %).
  EXPECT_NEAR(c.fx, d.camera_.fx, 0.005 * d.camera_.fx);
  EXPECT_NEAR(c.fy, d.camera_.fy, 0.005 * d.camera_.fy);
  EXPECT_NEAR(c.cx, d.camera_.cx, 0.005 * d.camera_.cx);
  EXPECT_NEAR(c.cy, d.camera_.cy, 0.005 * d.camera_.cy);
  std::printf("fx %.3f (%.3f) fy %.3f (%.3f) cx %.3f (%.3f) cy %.3f (%.3f) rms %.4f\n", c.fx,
              d.camera_.fx, c.fy, d.camera_.fy, c.cx, d.camera_.cx, c.cy, d.camera_.cy, c.rms_px);
  std::printf("dist %.5f %.5f %.6f %.6f %.5f\n", c.dist[0], c.dist[1], c.dist[2], c.dist[3],
              c.dist[4]);
  ASSERT_EQ(c.views.size(), 20u);
  for (const ViewRecord& v : c.views) EXPECT_LT(v.rms_px, 0.1) << v.image;
}

// "RMS at the noise level": the reprojection RMS is that of the corner detector's own errors
// (detected vs. true corners, measured on the same images), not larger.
void CheckRmsIsAtTheCornerNoiseLevel() {
  const RenderedCalibration& d = Rendered();
  double sq = 0;
  std::size_t n = 0;
  for (std::size_t k = 0; k < d.images_.size(); ++k) {
    const auto found = DetectBoard(d.images_[k], ToBoardSpec(d.board_), DetectionOptions{});
    ASSERT_TRUE(found);
    const auto truth = ProjectCorners(d.camera_, d.board_, d.poses_[k]);
    // The detector may number the corners from the opposite end (180-degree symmetry).
    double forward = 0, backward = 0;
    for (std::size_t i = 0; i < truth.size(); ++i) {
      forward += cv::norm(cv::Point2d((*found)[i]) - truth[i]);
      backward += cv::norm(cv::Point2d((*found)[truth.size() - 1 - i]) - truth[i]);
    }
    for (std::size_t i = 0; i < truth.size(); ++i) {
      const cv::Point2d e =
          cv::Point2d((*found)[forward <= backward ? i : truth.size() - 1 - i]) - truth[i];
      sq += e.dot(e);
      ++n;
    }
  }
  const double detection_rms = std::sqrt(sq / n);
  std::printf("detection RMS %.4f px, reprojection RMS %.4f px\n", detection_rms,
              d.calibration_.rms_px);
  // The fit absorbs part of the detection error (and the pose-correlated part of its bias), so
  // the RMS lies below the detection RMS, but not far below; both are a few hundredths of a px.
  EXPECT_LT(d.calibration_.rms_px, 1.2 * detection_rms);
  EXPECT_GT(d.calibration_.rms_px, 0.3 * detection_rms);
  EXPECT_LT(d.calibration_.rms_px, 0.1);
}

// The estimated lens model undistorts the true corner positions to within 0.05 px of their true
// pinhole positions, over all corners of all views (the area the boards covered, out to the image
// corners), as they are: the intrinsics error included. For information it also reports the
// residual after removing the global affine map K_est K_true^-1 (the intrinsics difference), i.e.
// the error of the distortion model alone.
void CheckUndistortedCornersWithinFiveHundredthsOfAPixel() {
  const RenderedCalibration& d = Rendered();
  std::vector<cv::Point2d> estimated, truth;
  for (const BoardPose& pose : d.poses_) {
    const auto undistorted =
        d.calibration_.UndistortPixels(ProjectCorners(d.camera_, d.board_, pose));
    const auto pinhole = ProjectCornersPinhole(d.camera_, d.board_, pose);
    estimated.insert(estimated.end(), undistorted.begin(), undistorted.end());
    truth.insert(truth.end(), pinhole.begin(), pinhole.end());
  }
  const int n = static_cast<int>(truth.size());
  cv::Mat a = cv::Mat::zeros(2 * n, 6, CV_64F), b(2 * n, 1, CV_64F), x;
  for (int i = 0; i < n; ++i) {
    a.at<double>(2 * i, 0) = estimated[i].x;
    a.at<double>(2 * i, 1) = estimated[i].y;
    a.at<double>(2 * i, 2) = 1;
    a.at<double>(2 * i + 1, 3) = estimated[i].x;
    a.at<double>(2 * i + 1, 4) = estimated[i].y;
    a.at<double>(2 * i + 1, 5) = 1;
    b.at<double>(2 * i) = truth[i].x;
    b.at<double>(2 * i + 1) = truth[i].y;
  }
  ASSERT_TRUE(cv::solve(a, b, x, cv::DECOMP_SVD));
  double worst_raw = 0, worst = 0, sq = 0;
  for (int i = 0; i < n; ++i) {
    worst_raw = std::max(worst_raw, cv::norm(estimated[i] - truth[i]));
    const cv::Point2d aligned(
        x.at<double>(0) * estimated[i].x + x.at<double>(1) * estimated[i].y + x.at<double>(2),
        x.at<double>(3) * estimated[i].x + x.at<double>(4) * estimated[i].y + x.at<double>(5));
    const double e = cv::norm(aligned - truth[i]);
    worst = std::max(worst, e);
    sq += e * e;
  }
  std::printf(
      "undistorted corners: raw max error %.4f px; after the K_est/K_true affine: max "
      "%.4f px, RMS %.4f px\n",
      worst_raw, worst, std::sqrt(sq / n));
  EXPECT_LT(worst_raw, 0.05);
  EXPECT_LT(worst, worst_raw + 1e-12);
}

void CheckPlaneScaleWithinTwoTenthsOfAPercent() {
  const RenderedCalibration& d = Rendered();
  const double distance = 420;
  const BoardPose pose = PanelPose(d.camera_, d.board_, distance, /*roll_deg=*/3);
  CheckerboardRenderOptions render;
  render.seed = 999;
  const cv::Mat plane = RenderCheckerboard(d.camera_, d.board_, pose, render);
  const double truth = distance / std::sqrt(d.camera_.fx * d.camera_.fy);
  const PlaneScale scale = MeasurePlaneScale(plane, "plane", d.calibration_);
  std::printf("mm/px %.6f +- %.6f, truth %.6f (rel error %.4f %%)\n", scale.mm_per_px,
              scale.mm_per_px_uncertainty, truth, 100 * (scale.mm_per_px / truth - 1));
  EXPECT_NEAR(scale.mm_per_px, truth, 0.002 * truth);
  EXPECT_GT(scale.mm_per_px_uncertainty, 0);
  EXPECT_LT(scale.mm_per_px_uncertainty, 0.002 * truth);
  EXPECT_EQ(scale.corners, 54);
  // Homography consistency: a corner's undistorted pixel maps to its board millimetres (up to the
  // detector's ~0.03 px error times the scale, and the 180-degree numbering ambiguity).
  EXPECT_LT(scale.residual_rms_mm, 0.05 * truth * 2);
}

// One test (one process under ctest) for the accuracy checks on the 20 rendered views, so the
// views are rendered and calibrated once.
TEST(Calibration, RecoversTheRenderedCamera) {
  {
    SCOPED_TRACE("intrinsics");
    CheckIntrinsicsWithinHalfPercent();
  }
  {
    SCOPED_TRACE("RMS");
    CheckRmsIsAtTheCornerNoiseLevel();
  }
  {
    SCOPED_TRACE("undistortion");
    CheckUndistortedCornersWithinFiveHundredthsOfAPixel();
  }
  {
    SCOPED_TRACE("plane scale");
    CheckPlaneScaleWithinTwoTenthsOfAPercent();
  }
}

TEST(Calibration, PlaneScaleWithTheTrueCameraIsExact) {
  const SynthCamera camera = SampleCamera();
  const CheckerboardSpec board;
  CameraCalibration exact;
  exact.image_width = camera.width;
  exact.image_height = camera.height;
  exact.fx = camera.fx;
  exact.fy = camera.fy;
  exact.cx = camera.cx;
  exact.cy = camera.cy;
  exact.dist = camera.dist;
  exact.board = ToBoardSpec(board);
  const double distance = 500;
  const cv::Mat plane = RenderCheckerboard(camera, board, PanelPose(camera, board, distance, 0),
                                           CheckerboardRenderOptions{});
  const PlaneScale scale = MeasurePlaneScale(plane, "plane", exact);
  const double truth = distance / std::sqrt(camera.fx * camera.fy);
  // Only the corner detector's error remains: ~0.03 px over a ~300 px board, i.e. 1e-4 relative.
  EXPECT_NEAR(scale.mm_per_px, truth, 5e-4 * truth);
  EXPECT_LT(scale.local_scale_spread_rel, 1e-3);
}

// `count` views of the sample camera (noise 1 grey level), named view_0 ...
std::vector<cv::Mat> RenderViews(int count, std::vector<std::string>* names) {
  const SynthCamera camera = SampleCamera();
  const CheckerboardSpec board;
  std::vector<cv::Mat> images;
  CheckerboardRenderOptions render;
  const auto poses = CalibrationPoses(camera, board, count, /*seed=*/21);
  for (int k = 0; k < count; ++k) {
    render.seed = 100 + k;
    images.push_back(RenderCheckerboard(camera, board, poses[k], render));
    if (names) names->push_back("view_" + std::to_string(k));
  }
  return images;
}

// A calibration made by hand (640x480, the sample lens), for tests that need no fit.
CameraCalibration HandMadeCalibration() {
  const SynthCamera camera = SampleCamera();
  CameraCalibration c;
  c.image_width = camera.width;
  c.image_height = camera.height;
  c.fx = camera.fx;
  c.fy = camera.fy;
  c.cx = camera.cx;
  c.cy = camera.cy;
  c.dist = camera.dist;
  c.rms_px = 0.0312345678901234;
  c.views = {{"view_0.png", 0.03}, {"view_1.png", 0.029}};
  return c;
}

TEST(Calibration, RejectsViewsWithoutTheBoardAndRefusesImplausibleRms) {
  std::vector<std::string> names;
  std::vector<cv::Mat> images = RenderViews(7, &names);
  images.push_back(cv::Mat(480, 640, CV_8U, cv::Scalar(128)));
  names.push_back("blank.png");
  CalibrationOptions options;
  CalibrationSummary summary;
  const CameraCalibration c = CalibrateCamera(images, names, options, &summary);
  EXPECT_EQ(summary.images_used, 7);
  EXPECT_EQ(summary.images_rejected, 1);
  ASSERT_EQ(c.rejected.size(), 1u);
  EXPECT_EQ(c.rejected[0].image, "blank.png");
  EXPECT_NE(c.rejected[0].reason.find("not found"), std::string::npos);
  EXPECT_NE(summary.FullReport(c).find("rejected blank.png"), std::string::npos);
  EXPECT_LT(c.rms_px, 0.1);
  // The same views with an RMS limit below what they achieve are refused.
  CalibrationOptions strict = options;
  strict.max_rms_px = 1e-4;
  ExpectErrorContaining([&] { CalibrateCamera(images, names, strict); },
                        "implausible calibration: reprojection RMS");
}

TEST(Calibration, BadInputGivesClearErrors) {
  CalibrationOptions options;
  // No images at all.
  ExpectErrorContaining([&] { CalibrateCamera({}, {}, options); }, "calibration images");
  // No board in any image.
  std::vector<cv::Mat> blank(6, cv::Mat(120, 160, CV_8U, cv::Scalar(100)));
  ExpectErrorContaining([&] { CalibrateCamera(blank, {}, options); },
                        "no board found in any of the 6");
  // Mixed image sizes (checked before any detection): names the odd image and both sizes.
  std::vector<cv::Mat> mixed(6, cv::Mat(480, 640, CV_8U, cv::Scalar(100)));
  mixed[3] = cv::Mat(240, 320, CV_8U, cv::Scalar(100));
  const std::vector<std::string> names = {"a.png", "b.png", "c.png", "d.png", "e.png", "f.png"};
  ExpectErrorContaining([&] { CalibrateCamera(mixed, names, options); },
                        "mixed image sizes: d.png is 320x240 but a.png is 640x480");
  // Too few usable views.
  std::vector<cv::Mat> few = RenderViews(3, nullptr);
  few.push_back(mixed[0]);
  ExpectErrorContaining([&] { CalibrateCamera(few, {}, options); },
                        "too few calibration images: the board was found in 3 of 4");
  // Colour images.
  ExpectErrorContaining(
      [&] {
        CalibrateCamera({cv::Mat(480, 640, CV_8UC3, cv::Scalar::all(0))}, {"c.png"}, options);
      },
      "c.png");
}

TEST(Calibration, FrameSizeMismatchIsAClearError) {
  const CameraCalibration c = HandMadeCalibration();
  EXPECT_NO_THROW(CheckFrameSize(c, {640, 480}));
  ExpectErrorContaining(
      [&] {
        CheckFrameSize(c, {1920, 1440}, "frame_0007.png");
      },
      "frame_0007.png has size 1920x1440 but the calibration was made for "
      "640x480 images");
  // The plane view must match too.
  ExpectErrorContaining(
      [&] { MeasurePlaneScale(cv::Mat(240, 320, CV_8U, cv::Scalar(0)), "p.png", c); },
      "plane image p.png has size 320x240");
}

TEST(CalibrationYaml, RoundTrip) {
  CameraCalibration c = HandMadeCalibration();
  PlaneScale plane;
  plane.image = "plane.png";
  plane.mm_per_px = 0.61;
  plane.mm_per_px_uncertainty = 1e-4;
  plane.mm_from_px = cv::Matx33d(0.6, 0.01, -3, 0.002, 0.61, -4, 1e-6, 2e-6, 1);
  plane.corners = 54;
  c.plane = plane;
  c.rejected.push_back({"blank.png", "not found"});
  const std::string path = ::testing::TempDir() + "/impactdic_calib_roundtrip.yaml";
  SaveCalibration(c, path);
  const CameraCalibration back = LoadCalibration(path);
  EXPECT_EQ(back.image_width, c.image_width);
  EXPECT_EQ(back.image_height, c.image_height);
  EXPECT_DOUBLE_EQ(back.fx, c.fx);
  EXPECT_DOUBLE_EQ(back.cy, c.cy);
  for (int k = 0; k < 5; ++k) EXPECT_DOUBLE_EQ(back.dist[k], c.dist[k]);
  EXPECT_DOUBLE_EQ(back.rms_px, c.rms_px);
  EXPECT_EQ(back.board.cols, 9);
  ASSERT_EQ(back.views.size(), 2u);
  EXPECT_EQ(back.views[1].image, "view_1.png");
  ASSERT_EQ(back.rejected.size(), 1u);
  EXPECT_EQ(back.rejected[0].reason, "not found");
  ASSERT_TRUE(back.plane);
  EXPECT_DOUBLE_EQ(back.plane->mm_per_px, 0.61);
  EXPECT_DOUBLE_EQ(back.plane->mm_from_px(2, 1), 2e-6);
  EXPECT_EQ(back.plane->image, "plane.png");
}

TEST(CalibrationYaml, BadFilesNameTheKey) {
  const std::string path = ::testing::TempDir() + "/impactdic_calib_bad.yaml";
  auto write = [&](const std::string& text) { std::ofstream(path) << text; };
  const std::string good_head =
      "format: impactdic-calibration-1\nimage_width: 640\nimage_height: 480\n"
      "board: {cols: 9, rows: 6, square_mm: 25}\n";
  write(good_head + "fx: 800\nfy: 800\ncx: 320\ncy: 240\ndist: [0, 0, 0, 0]\n");
  ExpectErrorContaining([&] { LoadCalibration(path); }, "dist");
  write(good_head + "fx: abc\nfy: 800\ncx: 320\ncy: 240\ndist: [0, 0, 0, 0, 0]\n");
  ExpectErrorContaining([&] { LoadCalibration(path); }, "fx");
  write(good_head + "fy: 800\ncx: 320\ncy: 240\ndist: [0, 0, 0, 0, 0]\n");
  ExpectErrorContaining([&] { LoadCalibration(path); }, "fx: missing; expected a focal length");
  // Every problem at once (the shared section reader, io/yaml.h), unknown keys with a suggestion.
  write(good_head + "fx: abc\nfy: 800\ncx: 320\ncy: 240\ndist: [0, 0, 0, 0, 0]\nrms_pz: 1\n");
  ExpectErrorContaining([&] { LoadCalibration(path); }, "2 problems in calibration file");
  ExpectErrorContaining([&] { LoadCalibration(path); }, ":5: fx: got 'abc'");
  ExpectErrorContaining([&] { LoadCalibration(path); },
                        ":10: rms_pz: unknown key (did you mean 'rms_px'?)");
  write(good_head + "fx: 800\nfy: 800\ncx: 320\ncy: 240\ndist: [0, 0, 0, 0, 0]\nfocal: 3\n");
  ExpectErrorContaining([&] { LoadCalibration(path); }, "focal");
  write(good_head + "fx: 800\nfy: 800\ncx: 320\ncy: 240\ndist: [0, 0, 0, 0, 0]\n");
  const CameraCalibration c = LoadCalibration(path);
  EXPECT_FALSE(c.plane);
  EXPECT_FALSE(c.HasDistortion());
  ExpectErrorContaining([&] { LoadCalibration(path + ".missing"); }, ".missing");
}

TEST(Calibration, ParseBoard) {
  const BoardSpec b = ParseBoard("9x6", 25);
  EXPECT_EQ(b.cols, 9);
  EXPECT_EQ(b.rows, 6);
  EXPECT_EQ(b.square_mm, 25);
  EXPECT_EQ(ParseBoard("7X5", 10).rows, 5);
  // The library names the field, CalibrationOptions::board (the CLI maps it to --board:
  // calibrate_cli_test).
  try {
    ParseBoard("9-6", 25);
    ADD_FAILURE() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.where(), "board") << e.what();
  }
  ExpectErrorContaining([] { ParseBoard("9x", 25); }, "COLSxROWS");
  ExpectErrorContaining([] { ParseBoard("1x6", 25); }, "at least 2x2");
  ExpectErrorContaining([] { ParseBoard("9x6", 0); }, "board.square_mm");
  ExpectErrorContaining([] { ParseBoard("9x6", -3); }, "board.square_mm");
}

TEST(Calibration, OptionsCheckNamesTheField) {
  EXPECT_NO_THROW(CalibrationOptions{}.Check());
  CalibrationOptions o;
  o.min_views = 2;
  ExpectErrorContaining([&] { o.Check(); }, "calibration.min_views");
  o = {};
  o.max_rms_px = 0;
  ExpectErrorContaining([&] { o.Check(); }, "calibration.max_rms_px");
  o = {};
  o.detection.subpix_half_window = 1;
  ExpectErrorContaining([&] { o.Check(); }, "detection.subpix_half_window");
  o = {};
  o.board.square_mm = -1;
  ExpectErrorContaining([&] { o.Check(); }, "board.square_mm");
}

// 16-bit frames: the detector works on a stretched 8-bit copy and refines on the full depth;
// the corners agree with those of the same view rendered in 8 bit.
TEST(Calibration, Detects16BitBoards) {
  const SynthCamera camera = SampleCamera();
  const CheckerboardSpec board;
  const BoardPose pose = CalibrationPoses(camera, board, 1, /*seed=*/5)[0];
  CheckerboardRenderOptions render;
  render.noise_sigma = 0;
  const cv::Mat image8 = RenderCheckerboard(camera, board, pose, render);
  render.bits = 16;
  const cv::Mat image16 = RenderCheckerboard(camera, board, pose, render);
  const auto c8 = DetectBoard(image8, ToBoardSpec(board), {});
  const auto c16 = DetectBoard(image16, ToBoardSpec(board), {});
  ASSERT_TRUE(c8 && c16);
  const auto truth = ProjectCorners(camera, board, pose);
  double e16 = 0;
  for (std::size_t i = 0; i < truth.size(); ++i)
    e16 = std::max(e16, std::min(cv::norm(cv::Point2d((*c16)[i]) - truth[i]),
                                 cv::norm(cv::Point2d((*c16)[truth.size() - 1 - i]) - truth[i])));
  EXPECT_LT(e16, 0.1);
}

}  // namespace
}  // namespace impactdic

namespace impactdic {
namespace {

// The committed sample (calibration/camera.yaml, made from calibration/*.png by the calibrate
// stage) matches the camera that rendered the images (SampleCamera, board on the panel at
// 613.93 mm: 0.747786537 mm/px; see calibration/board.yaml).
TEST(SampleCalibration, MatchesTheRenderedCamera) {
  const CameraCalibration c =
      LoadCalibration(std::string(SourceDir()) + "/calibration/camera.yaml");
  const SynthCamera truth = SampleCamera();
  EXPECT_EQ(c.ImageSize(), cv::Size(640, 480));
  EXPECT_NEAR(c.fx, truth.fx, 0.005 * truth.fx);
  EXPECT_NEAR(c.fy, truth.fy, 0.005 * truth.fy);
  EXPECT_NEAR(c.cx, truth.cx, 0.005 * truth.cx);
  EXPECT_NEAR(c.cy, truth.cy, 0.005 * truth.cy);
  EXPECT_LT(c.rms_px, 0.1);
  EXPECT_GE(c.views.size(), 12u);
  ASSERT_TRUE(c.plane);
  EXPECT_NEAR(c.plane->mm_per_px, 0.747786537, 0.002 * 0.747786537);
}

}  // namespace
}  // namespace impactdic
