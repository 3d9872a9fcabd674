#include "impactdic/synth/checkerboard.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "impactdic/core/error.h"

namespace impactdic {
namespace {

TEST(SynthCamera, UndistortInvertsDistort) {
  const SynthCamera camera = SampleCamera();
  double worst = 0;
  for (double x = -0.45; x <= 0.45; x += 0.05)
    for (double y = -0.35; y <= 0.35; y += 0.05) {
      const cv::Point2d pixel = camera.Distort({x, y});
      cv::Point2d n;
      ASSERT_TRUE(camera.Undistort(pixel, &n));
      worst = std::max(worst, std::hypot(n.x - x, n.y - y));
    }
  // Newton converges to machine precision; 1e-12 normalised units = 1e-9 px.
  EXPECT_LT(worst, 1e-12);
}

TEST(SynthCamera, ZeroDistortionIsPinhole) {
  SynthCamera camera;
  const cv::Point2d p = camera.Distort({0.1, -0.2});
  EXPECT_DOUBLE_EQ(p.x, camera.fx * 0.1 + camera.cx);
  EXPECT_DOUBLE_EQ(p.y, camera.fy * -0.2 + camera.cy);
}

TEST(Checkerboard, OptionsCheckNamesField) {
  EXPECT_NO_THROW(CheckerboardRenderOptions{}.Check());
  EXPECT_NO_THROW(CheckerboardSpec{}.Check());
  CheckerboardRenderOptions bad;
  bad.bits = 12;
  try {
    bad.Check();
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("render.bits"), std::string::npos) << e.what();
  }
  CheckerboardSpec board;
  board.square_mm = 0;
  EXPECT_THROW(board.Check(), Error);
}

TEST(Checkerboard, PosesStayInsideImage) {
  const SynthCamera camera = SampleCamera();
  const CheckerboardSpec board;
  const auto poses = CalibrationPoses(camera, board, 12, /*seed=*/3);
  ASSERT_EQ(poses.size(), 12u);
  for (const BoardPose& pose : poses)
    for (const cv::Point2d& p : ProjectCorners(camera, board, pose)) {
      EXPECT_GT(p.x, 6);
      EXPECT_LT(p.x, camera.width - 7);
      EXPECT_GT(p.y, 6);
      EXPECT_LT(p.y, camera.height - 7);
    }
  // Deterministic for a given seed.
  const auto again = CalibrationPoses(camera, board, 12, /*seed=*/3);
  EXPECT_EQ(again[5].tvec, poses[5].tvec);
}

TEST(Checkerboard, RenderedLevelsAndAntiAliasing) {
  SynthCamera camera;  // no distortion
  const CheckerboardSpec board;
  CheckerboardRenderOptions options;
  options.noise_sigma = 0;
  options.psf_sigma_px = 0;  // ideal pixels: exact levels inside the squares
  const BoardPose pose = PanelPose(camera, board, /*distance_mm=*/517);
  const cv::Mat image = RenderCheckerboard(camera, board, pose, options);
  ASSERT_EQ(image.type(), CV_8U);
  ASSERT_EQ(image.size(), cv::Size(640, 480));
  // Cell (i, j) is black when i + j is even.
  auto pixel_of = [&](double x_mm, double y_mm) {
    const cv::Vec3d c = cv::Vec3d(x_mm, y_mm, 0) + pose.tvec;
    return cv::Point(static_cast<int>(std::lround(camera.fx * c[0] / c[2] + camera.cx)),
                     static_cast<int>(std::lround(camera.fy * c[1] / c[2] + camera.cy)));
  };
  const double s = board.square_mm;
  EXPECT_EQ(image.at<std::uint8_t>(pixel_of(0.5 * s, 0.5 * s)), std::lround(0.12 * 255));
  EXPECT_EQ(image.at<std::uint8_t>(pixel_of(1.5 * s, 0.5 * s)), std::lround(0.88 * 255));
  EXPECT_EQ(image.at<std::uint8_t>(pixel_of(-1.5 * s, 0.5 * s)),
            std::lround(0.88 * 255));                                // margin
  EXPECT_EQ(image.at<std::uint8_t>(5, 5), std::lround(0.45 * 255));  // background
  // An edge at a non-integer position gives intermediate (anti-aliased) values: count levels
  // strictly between black and white along a row through the squares.
  int intermediate = 0;
  const int row = pixel_of(0, 0.5 * s).y;
  for (int u = 0; u < image.cols; ++u) {
    const int v = image.at<std::uint8_t>(row, u);
    if (v > 32 && v < 223 && v != std::lround(0.45 * 255)) ++intermediate;
  }
  EXPECT_GE(intermediate, 5);
}

// The rendered corners are where the camera model says: OpenCV's detector + cornerSubPix finds
// them within 0.1 px on a distorted, tilted, noisy view (measured: 0.02-0.03 px RMS, up to 0.06 px
// for the worst corner, the limit of cornerSubPix's gradient-orthogonality estimator).
TEST(Checkerboard, DetectedCornersMatchProjection) {
  const SynthCamera camera = SampleCamera();
  const CheckerboardSpec board;
  const auto poses = CalibrationPoses(camera, board, 2, /*seed=*/11);
  for (int bits : {8, 16}) {
    CheckerboardRenderOptions options;
    options.bits = bits;
    options.noise_sigma = bits == 8 ? 1.0 : 257.0;
    cv::Mat image = RenderCheckerboard(camera, board, poses[1], options);
    ASSERT_EQ(image.depth(), bits == 8 ? CV_8U : CV_16U);
    if (bits == 16) image.convertTo(image, CV_8U, 1.0 / 257);
    std::vector<cv::Point2f> found;
    ASSERT_TRUE(cv::findChessboardCorners(image, {board.cols, board.rows}, found));
    cv::cornerSubPix(image, found, {5, 5}, {-1, -1},
                     {cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 100, 1e-4});
    const auto truth = ProjectCorners(camera, board, poses[1]);
    ASSERT_EQ(found.size(), truth.size());
    // Detection order may be reversed (180-degree ambiguity of the symmetric pattern).
    double forward = 0, backward = 0;
    for (std::size_t k = 0; k < truth.size(); ++k) {
      forward = std::max(forward, cv::norm(cv::Point2d(found[k]) - truth[k]));
      backward = std::max(backward, cv::norm(cv::Point2d(found[truth.size() - 1 - k]) - truth[k]));
    }
    EXPECT_LT(std::min(forward, backward), 0.1) << "bits " << bits;
  }
}

TEST(Checkerboard, RenderCalibrationSetWritesFiles) {
  CalibrationSetOptions options;
  options.views = 2;
  SynthCamera camera = SampleCamera();
  camera.width = 320;
  camera.height = 240;
  camera.cx = 160;
  camera.cy = 120;
  camera.fx = camera.fy = 400;
  const std::string dir = ::testing::TempDir() + "/impactdic_calibration_set";
  const CalibrationSet set = RenderCalibrationSet(camera, CheckerboardSpec{}, options, dir);
  ASSERT_EQ(set.view_paths.size(), 2u);
  for (const auto& path : set.view_paths) {
    const cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED);
    EXPECT_EQ(image.size(), cv::Size(320, 240)) << path;
  }
  EXPECT_FALSE(cv::imread(set.plane_path, cv::IMREAD_UNCHANGED).empty());
  EXPECT_GT(set.plane_mm_per_px, 0);
}

}  // namespace
}  // namespace impactdic
