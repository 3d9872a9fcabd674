// The velocity-field overlay: sizes, colour scale, exact colours on a uniform field, and no crash
// on extreme data (all NaN, all zero, one subset, Lagrangian motion, 16-bit and float frames).
#include "impactdic/render/velocity_field.h"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "impactdic/core/error.h"
#include "impactdic/core/numeric.h"
#include "test_util.h"

namespace impactdic {
namespace {

using test::IsPngOfSize;
using test::MakeSequence;
using test::ScratchDir;

// The blend the overlay should produce at a pixel of grey `g` and colour-table index `idx`.
cv::Vec3d ExpectedBlend(double g, int idx, double alpha) {
  const cv::Vec3b c = ViridisLut().at<cv::Vec3b>(idx);
  return {g * (1 - alpha) + c[0] * alpha, g * (1 - alpha) + c[1] * alpha,
          g * (1 - alpha) + c[2] * alpha};
}

TEST(VelocityField, CanvasSizeAndScale) {
  const auto seq = MakeSequence(2, 320, 240, 12);
  VelocityFieldRenderer r(seq, {});
  // 320 px frames are enlarged to the minimum display width 960 (factor 3) plus the colour bar.
  EXPECT_GT(r.canvas_size().width, 960);
  EXPECT_GE(r.canvas_size().height, 720);
  EXPECT_EQ(r.canvas_size().width % 2, 0);
  EXPECT_EQ(r.canvas_size().height % 2, 0);
  EXPECT_NEAR(r.grid_spacing_px(), 12.0, 1e-9);
  const cv::Mat img = r.RenderFrame(1);
  EXPECT_EQ(img.type(), CV_8UC3);
  EXPECT_EQ(img.size(), r.canvas_size());
  const cv::Mat titled = r.RenderFrame(1, "a title");
  EXPECT_EQ(titled.cols, img.cols);
  EXPECT_GT(titled.rows, img.rows);
}

TEST(VelocityField, ColourScaleIsNiceAndUnitsFollowTheRange) {
  auto seq = MakeSequence(3, 320, 240, 12);
  VelocityOverlayOptions o;
  o.max_speed_mm_s = 730.0;
  VelocityFieldRenderer r(seq, o);
  EXPECT_DOUBLE_EQ(r.color_max_mm_s(), 800.0);  // rounded up to a multiple of the tick step 200
  EXPECT_EQ(r.unit_label(), "mm/s");
  EXPECT_DOUBLE_EQ(r.reference_speed_mm_s(), 500.0);  // largest 1-2-5 value <= 0.8 x top
  o.max_speed_mm_s = 2600.0;
  VelocityFieldRenderer r2(seq, o);
  EXPECT_EQ(r2.unit_label(), "m/s");
  o.unit = VelocityDisplayUnit::kMmPerS;
  VelocityFieldRenderer r3(seq, o);
  EXPECT_EQ(r3.unit_label(), "mm/s");
}

TEST(VelocityField, UniformFieldHasTheTopColourInsideTheGrid) {
  // Uniform speed = the colour-scale top: normalised convolution reproduces a constant exactly,
  // so inside the grid every pixel is the blend of grey and the last viridis entry.
  auto seq = MakeSequence(1, 320, 240, 10);
  for (auto& v : seq.vx_mm_s) v = 300.0;
  for (auto& v : seq.vy_mm_s) v = 400.0;  // |v| = 500 mm/s
  seq.frames[0].setTo(100);
  VelocityOverlayOptions o;
  o.arrows = false;
  o.max_speed_mm_s = 500.0;
  VelocityFieldRenderer r(seq, o);
  ASSERT_DOUBLE_EQ(r.color_max_mm_s(), 500.0);
  const cv::Mat img = r.RenderFrame(0);
  // Display scale 3: image point (160, 160) lies inside the grid (x 53..266, y 80..235).
  const cv::Vec3b got = img.at<cv::Vec3b>(480, 480);
  const cv::Vec3d want = ExpectedBlend(100, 255, o.opacity);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(got[k], want[k], 1.5) << k;  // rounding of 8-bit blend
  // Far above the grid (image y = 20) the frame is plain grey.
  const cv::Vec3b grey = img.at<cv::Vec3b>(60, 480);
  EXPECT_EQ(grey, cv::Vec3b(100, 100, 100));
}

TEST(VelocityField, AllNanVelocitiesDrawThePlainFrame) {
  auto seq = MakeSequence(2, 320, 240, 12);
  for (auto& v : seq.vx_mm_s) v = kNaN;
  seq.frames[0].setTo(90);
  VelocityFieldRenderer r(seq, {});
  EXPECT_EQ(r.valid_speed_count(), 0u);
  EXPECT_DOUBLE_EQ(r.color_max_mm_s(), 1.0);
  const cv::Mat img = r.RenderFrame(0);
  // The grid centre (image 160, 160) is not coloured.
  EXPECT_EQ(img.at<cv::Vec3b>(480, 480), cv::Vec3b(90, 90, 90));
}

TEST(VelocityField, ZeroVelocityEverywhere) {
  auto seq = MakeSequence(2, 320, 240, 12);
  for (auto& v : seq.vx_mm_s) v = 0.0;
  for (auto& v : seq.vy_mm_s) v = 0.0;
  VelocityFieldRenderer r(seq, {});
  EXPECT_DOUBLE_EQ(r.color_max_mm_s(), 1.0);
  const cv::Mat img = r.RenderFrame(1);
  EXPECT_EQ(img.size(), r.canvas_size());
}

TEST(VelocityField, SingleSubsetAndNoSubsets) {
  auto seq = MakeSequence(2, 320, 240, 12);
  seq.num_subsets = 1;
  seq.x_px = {160};
  seq.y_px = {120};
  seq.vx_mm_s = {10.0, kNaN};
  seq.vy_mm_s = {20.0, kNaN};
  seq.frames[0].setTo(50);
  VelocityOverlayOptions o;
  o.arrows = false;
  VelocityFieldRenderer r(seq, o);
  const cv::Mat img = r.RenderFrame(0);
  EXPECT_NE(img.at<cv::Vec3b>(360, 480), cv::Vec3b(50, 50, 50));  // coloured at the subset
  EXPECT_NO_THROW(r.RenderFrame(1));
  seq.num_subsets = 0;
  seq.x_px.clear();
  seq.y_px.clear();
  seq.vx_mm_s.clear();
  seq.vy_mm_s.clear();
  VelocityFieldRenderer empty(seq, {});
  EXPECT_NO_THROW(empty.RenderFrame(0));
}

TEST(VelocityField, LagrangianPositionsMoveTheColour) {
  auto seq = MakeSequence(2, 320, 240, 12);
  seq.num_subsets = 1;
  seq.x_px = {60, 260};  // frame 0 at x = 60, frame 1 at x = 260
  seq.y_px = {120, 120};
  seq.vx_mm_s = {0.0, 0.0};
  seq.vy_mm_s = {50.0, 50.0};
  for (auto& f : seq.frames) f.setTo(40);
  VelocityOverlayOptions o;
  o.arrows = false;
  VelocityFieldRenderer r(seq, o);
  const cv::Mat f0 = r.RenderFrame(0), f1 = r.RenderFrame(1);
  const cv::Vec3b plain(40, 40, 40);
  EXPECT_NE(f0.at<cv::Vec3b>(360, 180), plain);
  EXPECT_EQ(f0.at<cv::Vec3b>(360, 780), plain);
  EXPECT_EQ(f1.at<cv::Vec3b>(360, 180), plain);
  EXPECT_NE(f1.at<cv::Vec3b>(360, 780), plain);
}

TEST(VelocityField, SixteenBitAndFloatFrames) {
  for (int depth : {CV_16U, CV_32F}) {
    const auto seq = MakeSequence(2, 320, 240, 12, depth);
    VelocityFieldRenderer r(seq, {});
    const cv::Mat img = r.RenderFrame(0);
    // The contrast stretch spreads the speckle over most of the 8-bit range above the grid.
    double lo = 0, hi = 0;
    cv::Mat top_grey;
    cv::cvtColor(img(cv::Rect(0, 150, 900, 60)), top_grey, cv::COLOR_BGR2GRAY);
    cv::minMaxLoc(top_grey, &lo, &hi);
    EXPECT_LT(lo, 40) << depth;
    EXPECT_GT(hi, 215) << depth;
  }
}

TEST(VelocityField, TwelveBitFramesInSixteenBitImagesGetTheFullContrast) {
  // 12-bit camera data in 16-bit images (0..4095): stretched by its own percentiles, not shown at
  // 1/16 of the brightness a fixed 0..65535 scale would give.
  auto seq = MakeSequence(2, 320, 240, 12, CV_16U);
  for (cv::Mat& f : seq.frames) f /= 16;
  double max_value = 0;
  cv::minMaxLoc(seq.frames[0], nullptr, &max_value);
  ASSERT_LE(max_value, 4095);
  VelocityFieldRenderer r(seq, {});
  const cv::Mat img = r.RenderFrame(0);
  double lo = 0, hi = 0;
  cv::Mat top_grey;
  cv::cvtColor(img(cv::Rect(0, 150, 900, 60)), top_grey, cv::COLOR_BGR2GRAY);
  cv::minMaxLoc(top_grey, &lo, &hi);
  EXPECT_LT(lo, 40);
  EXPECT_GT(hi, 215);
}

TEST(VelocityField, CheckNamesTheBrokenField) {
  auto seq = MakeSequence(2, 320, 240, 12);
  seq.vy_mm_s.pop_back();
  try {
    seq.Check();
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("vx_mm_s/vy_mm_s"), std::string::npos) << e.what();
  }
  seq = MakeSequence(2, 320, 240, 12);
  seq.time_ms.pop_back();
  EXPECT_THROW(seq.Check(), Error);
  seq = MakeSequence(2, 320, 240, 12);
  seq.frames[1] = cv::Mat(100, 100, CV_8U, cv::Scalar(0));
  EXPECT_THROW(seq.Check(), Error);
  VelocityOverlayOptions o;
  o.opacity = 2;
  EXPECT_THROW(o.Check(), Error);
}

TEST(VelocityField, HelpersNiceStepAndNearestFrame) {
  EXPECT_DOUBLE_EQ(NiceStep(1000, 5), 200);
  EXPECT_DOUBLE_EQ(NiceStep(7, 5), 1);  // 1.4 per interval rounds to 1
  EXPECT_DOUBLE_EQ(NiceStep(8, 5), 2);
  EXPECT_DOUBLE_EQ(NiceStep(0.3, 5), 0.05);
  EXPECT_DOUBLE_EQ(NiceStep(0, 5), 1);
  auto seq = MakeSequence(5, 320, 240, 12);  // t = 0, 0.625, 1.25, 1.875, 2.5 ms
  EXPECT_EQ(FrameNearestTime(seq, 1.3), 2u);
  EXPECT_EQ(FrameNearestTime(seq, 99), 4u);
  EXPECT_EQ(ToString(VelocityDisplayUnit::kMPerS), std::string("m/s"));
  EXPECT_EQ(VelocityDisplayUnitFromString("mm/s"), VelocityDisplayUnit::kMmPerS);
}

TEST(VelocityField, SnapshotPng) {
  ScratchDir dir("vf");
  const auto seq = MakeSequence(4, 320, 240, 12);
  const cv::Size size = RenderVelocitySnapshot(seq, 3, dir / "snap.png", {}, "snapshot");
  EXPECT_TRUE(IsPngOfSize(dir / "snap.png", 640, 480));
  const cv::Mat back = cv::imread(dir / "snap.png");
  EXPECT_EQ(back.size(), size);
}

}  // namespace
}  // namespace impactdic
