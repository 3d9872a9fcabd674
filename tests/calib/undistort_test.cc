#include "impactdic/calib/undistort.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <utility>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/synth/checkerboard.h"

namespace impactdic {
namespace {

CameraCalibration FromCamera(const SynthCamera& camera) {
  CameraCalibration c;
  c.image_width = camera.width;
  c.image_height = camera.height;
  c.fx = camera.fx;
  c.fy = camera.fy;
  c.cx = camera.cx;
  c.cy = camera.cy;
  c.dist = camera.dist;
  return c;
}

// Largest |source(p) - p| over the image computed in double precision with the synth camera
// model (independent of OpenCV's maps).
double TrueMaxShift(const SynthCamera& camera, cv::Rect roi) {
  double worst = 0;
  for (int v = roi.y; v < roi.y + roi.height; ++v)
    for (int u = roi.x; u < roi.x + roi.width; ++u) {
      const cv::Point2d n((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy);
      worst = std::max(worst, cv::norm(camera.Distort(n) - cv::Point2d(u, v)));
    }
  return worst;
}

TEST(Undistort, NoDistortionIsSkippedAndApplyIsANoOp) {
  SynthCamera camera = SampleCamera();
  camera.dist = {0, 0, 0, 0, 0};
  const Undistorter undistort(FromCamera(camera), UndistortOptions{});
  EXPECT_FALSE(undistort.active());
  EXPECT_EQ(undistort.max_shift_px(), 0);
  EXPECT_NE(undistort.reason().find("skipped"), std::string::npos) << undistort.reason();
  const cv::Mat frame(480, 640, CV_8U, cv::Scalar(77));
  const cv::Mat out = undistort.Apply(frame);
  EXPECT_EQ(out.data, frame.data);  // the very same pixels, no copy
}

TEST(Undistort, NegligibleDistortionIsSkipped) {
  SynthCamera camera = SampleCamera();
  // k1 = 1e-5 moves the image corner (r_n ~ 0.49) by 1e-5 * 0.49^3 * 820 ~ 1e-3 px < 0.01 px.
  camera.dist = {1e-5, 0, 0, 0, 0};
  const Undistorter undistort(FromCamera(camera), UndistortOptions{});
  EXPECT_FALSE(undistort.active()) << undistort.reason();
  EXPECT_GT(undistort.max_shift_px(), 0);
  EXPECT_LT(undistort.max_shift_px(), 0.01);
  // ... and a lens just above the threshold is applied: 2e-4 -> ~0.02 px.
  camera.dist = {2e-4, 0, 0, 0, 0};
  EXPECT_TRUE(Undistorter(FromCamera(camera), UndistortOptions{}).active());
}

TEST(Undistort, MaxShiftMatchesTheModel) {
  const SynthCamera camera = SampleCamera();
  const cv::Rect full(0, 0, camera.width, camera.height);
  const double truth = TrueMaxShift(camera, full);
  // The maps are float: ~1e-4 px at 640 px coordinates.
  EXPECT_NEAR(MaxDistortionShift(FromCamera(camera)), truth, 2e-4);
  EXPECT_GT(truth, 3.0);  // the sample lens moves the corners by several pixels
}

// Only the region of interest counts: a small ROI at the principal point of a distorted lens
// needs no undistortion, the whole frame does.
TEST(Undistort, SkipRuleLooksAtTheRoiOnly) {
  const SynthCamera camera = SampleCamera();
  UndistortOptions options;
  options.roi = cv::Rect(313, 227, 20, 20);
  const Undistorter centre(FromCamera(camera), options);
  EXPECT_FALSE(centre.active()) << centre.reason();
  EXPECT_NEAR(centre.max_shift_px(), TrueMaxShift(camera, options.roi), 2e-4);
  options.roi = {};
  const Undistorter whole(FromCamera(camera), options);
  EXPECT_TRUE(whole.active());
  EXPECT_NE(whole.reason().find("applied"), std::string::npos);
}

// Real distortion: applied, and it corrects. Corners found in the undistorted image sit at the
// ideal pinhole positions within the detector's accuracy, while in the raw image they are
// pixels away.
TEST(Undistort, CorrectsARenderedDistortedView) {
  const SynthCamera camera = SampleCamera();
  const CheckerboardSpec board;
  const BoardPose pose = CalibrationPoses(camera, board, 1, /*seed=*/4)[0];
  const cv::Mat raw = RenderCheckerboard(camera, board, pose, CheckerboardRenderOptions{});
  const Undistorter undistort(FromCamera(camera), UndistortOptions{});
  ASSERT_TRUE(undistort.active());
  const cv::Mat fixed = undistort.Apply(raw);
  ASSERT_EQ(fixed.type(), raw.type());
  const auto truth = ProjectCornersPinhole(camera, board, pose);
  auto errors = [&](const cv::Mat& image) {
    std::vector<cv::Point2f> found;
    EXPECT_TRUE(cv::findChessboardCorners(image, {board.cols, board.rows}, found));
    cv::cornerSubPix(image, found, {5, 5}, {-1, -1},
                     {cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 100, 1e-4});
    double forward = 0, backward = 0, worst = 0;
    for (std::size_t i = 0; i < truth.size(); ++i) {
      forward += cv::norm(cv::Point2d(found[i]) - truth[i]);
      backward += cv::norm(cv::Point2d(found[truth.size() - 1 - i]) - truth[i]);
    }
    for (std::size_t i = 0; i < truth.size(); ++i)
      worst = std::max(
          worst,
          cv::norm(cv::Point2d(found[forward <= backward ? i : truth.size() - 1 - i]) - truth[i]));
    return std::pair{std::min(forward, backward) / truth.size(), worst};
  };
  const auto [raw_mean, raw_worst] = errors(raw);
  const auto [fixed_mean, fixed_worst] = errors(fixed);
  std::printf("corner error raw: mean %.3f max %.3f px; undistorted: mean %.4f max %.4f px\n",
              raw_mean, raw_worst, fixed_mean, fixed_worst);
  EXPECT_GT(raw_worst, 0.5);
  EXPECT_GT(raw_mean, 5 * fixed_mean);
  // Detector accuracy on this renderer: ~0.03 px mean, < 0.1 px worst (synth tests).
  EXPECT_LT(fixed_mean, 0.05);
  EXPECT_LT(fixed_worst, 0.12);
}

// Both interpolations reproduce a linear ramp exactly (to integer rounding) at the exact map
// coordinates (Keys' a = -0.5 kernel reproduces polynomials up to degree 2); cv::remap with
// INTER_LINEAR on the same maps deviates by up to (50 + 20) / 64 levels more because it quantises
// the position to 1/32 px.
TEST(Undistort, RemapReproducesLinearRampsExactly) {
  const SynthCamera camera = SampleCamera();
  const CameraCalibration c = FromCamera(camera);
  cv::Mat ramp(480, 640, CV_16U);
  for (int v = 0; v < 480; ++v)
    for (int u = 0; u < 640; ++u)
      ramp.at<std::uint16_t>(v, u) = static_cast<std::uint16_t>(50 * u + 20 * v + 1000);
  cv::Mat map_x, map_y;
  const cv::Matx33d k = c.CameraMatrix();
  cv::initUndistortRectifyMap(k, c.DistCoeffs(), cv::noArray(), k, c.ImageSize(), CV_32FC1, map_x,
                              map_y);
  cv::Mat ocv;
  cv::remap(ramp, ocv, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  for (auto interpolation : {UndistortInterpolation::kBilinear, UndistortInterpolation::kBicubic}) {
    UndistortOptions options;
    options.interpolation = interpolation;
    const cv::Mat out = Undistorter(c, options).Apply(ramp);
    ASSERT_EQ(out.type(), CV_16U);
    double worst = 0, worst_ocv = 0;
    for (int v = 20; v < 460; ++v)
      for (int u = 20; u < 620; ++u) {
        const double expected = 50.0 * map_x.at<float>(v, u) + 20.0 * map_y.at<float>(v, u) + 1000;
        worst = std::max(worst, std::abs(out.at<std::uint16_t>(v, u) - expected));
        worst_ocv = std::max(worst_ocv, std::abs(ocv.at<std::uint16_t>(v, u) - expected));
      }
    EXPECT_LE(worst, 0.5 + 1e-6) << ToString(interpolation);  // rounding to integers only
    EXPECT_LE(worst_ocv, 0.5 + 70.0 / 64 + 1e-6);
  }
}

TEST(Undistort, BadFramesAndOptions) {
  const CameraCalibration c = FromCamera(SampleCamera());
  const Undistorter undistort(c, UndistortOptions{});
  EXPECT_THROW(undistort.Apply(cv::Mat(240, 320, CV_8U)), Error);
  EXPECT_THROW(undistort.Apply(cv::Mat(480, 640, CV_8UC3)), Error);
  UndistortOptions bad;
  bad.skip_threshold_px = -1;
  EXPECT_THROW(bad.Check(), Error);
  EXPECT_EQ(UndistortInterpolationFromString("bilinear"), UndistortInterpolation::kBilinear);
  EXPECT_STREQ(ToString(UndistortInterpolation::kBicubic), "bicubic");
  EXPECT_THROW(UndistortInterpolationFromString("nearest"), Error);
}

}  // namespace
}  // namespace impactdic
