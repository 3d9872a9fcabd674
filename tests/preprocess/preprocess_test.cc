#include "impactdic/preprocess/preprocess.h"

#include <gtest/gtest.h>

#include <array>
#include <opencv2/imgproc.hpp>

#include "../core/expect_error.h"
#include "impactdic/synth/checkerboard.h"

namespace impactdic {
namespace {

// A seeded, textured test frame (uniform noise smoothed to speckle-like grain), 8 or 16 bit.
cv::Mat TestFrame(int depth, cv::Size size = {160, 120}) {
  cv::Mat noise(size, CV_32F);
  cv::RNG rng(12345);
  rng.fill(noise, cv::RNG::UNIFORM, 0.0, 1.0);
  cv::GaussianBlur(noise, noise, cv::Size(0, 0), 1.5);
  cv::normalize(noise, noise, 0, 1, cv::NORM_MINMAX);
  cv::Mat out;
  noise.convertTo(out, depth, depth == CV_8U ? 200.0 : 50000.0, depth == CV_8U ? 20.0 : 4000.0);
  return out;
}

bool Identical(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

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

class PreprocessDepth : public ::testing::TestWithParam<int> {};

TEST_P(PreprocessDepth, EverythingOffIsAnExactNoOp) {
  const cv::Mat frame = TestFrame(GetParam());
  PreprocessOptions off;
  off.gaussian.mode = GaussianMode::kOff;
  Preprocessor pre(off, /*calibration=*/nullptr, frame.size());
  EXPECT_FALSE(pre.active());
  const cv::Mat out = pre.Apply(frame);
  EXPECT_EQ(out.data, frame.data);  // the input pixels themselves
  ASSERT_EQ(pre.summary().steps.size(), 3u);
  EXPECT_EQ(pre.summary().steps[0].reason, "no calibration given");
  EXPECT_EQ(pre.summary().steps[1].reason, "off in the options");
  EXPECT_EQ(pre.summary().steps[2].reason, "off in the options");
  EXPECT_EQ(pre.summary().frames, 1);
  EXPECT_NE(pre.summary().BriefReport().find("applied: none"), std::string::npos);
}

TEST_P(PreprocessDepth, GaussianIsOpenCvsGaussianBlurAsConfigured) {
  const cv::Mat frame = TestFrame(GetParam());
  PreprocessOptions options;
  options.gaussian.mode = GaussianMode::kOn;
  options.gaussian.sigma_px = 1.3;
  options.gaussian.kernel_size = 7;
  Preprocessor pre(options, nullptr, frame.size());
  const cv::Mat out = pre.Apply(frame);
  cv::Mat expected;
  cv::GaussianBlur(frame, expected, cv::Size(7, 7), 1.3, 1.3, cv::BORDER_REFLECT_101);
  EXPECT_TRUE(Identical(out, expected));
  EXPECT_FALSE(Identical(out, frame));
  // A different sigma gives a different image: the setting is really used.
  cv::Mat other;
  cv::GaussianBlur(frame, other, cv::Size(7, 7), 2.0, 2.0, cv::BORDER_REFLECT_101);
  EXPECT_FALSE(Identical(out, other));
  EXPECT_TRUE(pre.summary().steps[1].applied);
  EXPECT_NE(pre.summary().steps[1].reason.find("sigma 1.3 px, kernel 7x7"), std::string::npos);
}

TEST_P(PreprocessDepth, ClaheIsOpenCvsClaheAsConfigured) {
  const cv::Mat frame = TestFrame(GetParam());
  PreprocessOptions options;
  options.clahe.enabled = true;
  options.clahe.clip_limit = 3.0;
  options.clahe.tile_grid = 4;
  Preprocessor pre(options, nullptr, frame.size());
  const cv::Mat out = pre.Apply(frame);
  cv::Mat expected;
  cv::createCLAHE(3.0, cv::Size(4, 4))->apply(frame, expected);
  EXPECT_TRUE(Identical(out, expected));
  EXPECT_FALSE(Identical(out, frame));
  EXPECT_EQ(out.type(), frame.type());
  EXPECT_FALSE(pre.summary().steps[1].applied);
  EXPECT_TRUE(pre.summary().steps[2].applied);
}

// The documented order: undistort -> Gaussian -> CLAHE.
TEST_P(PreprocessDepth, OrderIsUndistortThenGaussianThenClahe) {
  SynthCamera camera = SampleCamera();
  camera.width = 160;
  camera.height = 120;
  camera.cx = 80.3;
  camera.cy = 59.1;
  camera.fx = camera.fy = 200;
  const CameraCalibration calibration = FromCamera(camera);
  const cv::Mat frame = TestFrame(GetParam());
  PreprocessOptions options;
  options.gaussian.mode = GaussianMode::kOn;
  options.clahe.enabled = true;
  Preprocessor pre(options, &calibration, frame.size());
  ASSERT_TRUE(pre.summary().steps[0].applied) << pre.summary().steps[0].reason;
  EXPECT_GT(pre.summary().max_distortion_px, 0.01);
  const cv::Mat out = pre.Apply(frame);

  const double sigma = GaussianBlurOptions{}.sigma_px;
  cv::Mat expected = Undistorter(calibration, UndistortOptions{}).Apply(frame);
  cv::GaussianBlur(expected, expected, cv::Size(5, 5), sigma, sigma, cv::BORDER_REFLECT_101);
  cv::createCLAHE(2.0, cv::Size(8, 8))->apply(expected, expected);
  EXPECT_TRUE(Identical(out, expected));
  // The other order gives a different image, so the test can tell.
  cv::Mat reversed;
  cv::createCLAHE(2.0, cv::Size(8, 8))->apply(frame, reversed);
  cv::GaussianBlur(reversed, reversed, cv::Size(5, 5), sigma, sigma, cv::BORDER_REFLECT_101);
  reversed = Undistorter(calibration, UndistortOptions{}).Apply(reversed);
  EXPECT_FALSE(Identical(out, reversed));
  EXPECT_NE(pre.summary().FullReport().find("undistort"), std::string::npos);
}

// The default (auto) measures the first frame: a smooth one is left untouched, exactly.
TEST_P(PreprocessDepth, AutoLeavesASmoothFrameUntouched) {
  const cv::Mat frame = TestFrame(GetParam());  // Noise smoothed by a 1.5 px Gaussian.
  Preprocessor pre(PreprocessOptions{}, /*calibration=*/nullptr, frame.size());
  const cv::Mat out = pre.Apply(frame);
  EXPECT_EQ(out.data, frame.data);
  const GaussianDecision& d = pre.summary().gaussian;
  EXPECT_EQ(d.mode, GaussianMode::kAuto);
  EXPECT_FALSE(d.applied);
  ASSERT_TRUE(d.figure.measured());
  EXPECT_LT(d.figure.bias_px, GaussianBlurOptions{}.auto_threshold_px);
  EXPECT_NE(pre.summary().steps[1].reason.find("auto, skipped: near-Nyquist bias figure"),
            std::string::npos)
      << pre.summary().steps[1].reason;
  EXPECT_FALSE(pre.summary().steps[1].applied);
}

// ...and a sharp one (white noise, all of its content up to the Nyquist frequency) decides the
// blur of every later frame, smooth or not, as `on` would.
TEST_P(PreprocessDepth, AutoBlursEveryFrameWhenTheReferenceIsSharp) {
  cv::Mat sharp(120, 160, GetParam());
  cv::RNG rng(7);
  rng.fill(sharp, cv::RNG::UNIFORM, 20, GetParam() == CV_8U ? 230 : 60000);
  const cv::Mat smooth = TestFrame(GetParam());
  Preprocessor pre(PreprocessOptions{}, /*calibration=*/nullptr, sharp.size());
  pre.DecideFrom(sharp);
  const GaussianDecision& d = pre.summary().gaussian;
  EXPECT_TRUE(d.applied);
  EXPECT_GT(d.figure.bias_px, d.threshold_px);
  EXPECT_TRUE(pre.active());
  EXPECT_NE(d.Text().find("auto, Gaussian sigma 0.7 px (kernel 5x5) applied: near-Nyquist bias "
                          "figure "),
            std::string::npos)
      << d.Text();
  GaussianBlurOptions on;
  on.mode = GaussianMode::kOn;
  for (const cv::Mat& frame : {sharp, smooth}) {
    cv::Mat expected;
    cv::GaussianBlur(frame, expected, cv::Size(5, 5), 0.7, 0.7, cv::BORDER_REFLECT_101);
    EXPECT_TRUE(Identical(pre.Apply(frame), expected));
    EXPECT_TRUE(Identical(GaussianBlurFrame(on, frame), expected));
  }
  // Switched off, the same frame is untouched; on and off still report the figure.
  PreprocessOptions off;
  off.gaussian.mode = GaussianMode::kOff;
  Preprocessor pre_off(off, nullptr, sharp.size());
  EXPECT_EQ(pre_off.Apply(sharp).data, sharp.data);
  EXPECT_FALSE(pre_off.summary().gaussian.applied);
  EXPECT_NEAR(pre_off.summary().gaussian.figure.bias_px, d.figure.bias_px, 1e-15);
  EXPECT_EQ(pre_off.summary().steps[1].reason, "off in the options");
  EXPECT_NE(pre_off.summary().gaussian.Text().find("off (set), skipped; near-Nyquist"),
            std::string::npos);
}

INSTANTIATE_TEST_SUITE_P(EightAndSixteenBit, PreprocessDepth, ::testing::Values(CV_8U, CV_16U),
                         [](const auto& p) {
                           return std::string(p.param == CV_8U ? "u8" : "u16");
                         });

TEST(Preprocess, UndistortionSkippedWithoutDistortionAndWhenOff) {
  SynthCamera camera;
  camera.width = 160;
  camera.height = 120;
  CameraCalibration calibration = FromCamera(camera);  // zero distortion
  const cv::Mat frame = TestFrame(CV_8U);
  Preprocessor pre(PreprocessOptions{}, &calibration, frame.size());
  EXPECT_FALSE(pre.summary().steps[0].applied);
  EXPECT_NE(pre.summary().steps[0].reason.find("skipped"), std::string::npos);
  EXPECT_EQ(pre.Apply(frame).data, frame.data);

  calibration.dist = {-0.1, 0, 0, 0, 0};
  PreprocessOptions off;
  off.undistort = false;
  Preprocessor pre_off(off, &calibration, frame.size());
  EXPECT_FALSE(pre_off.summary().steps[0].applied);
  EXPECT_EQ(pre_off.summary().steps[0].reason, "off in the options");
  Preprocessor pre_on(PreprocessOptions{}, &calibration, frame.size());
  EXPECT_TRUE(pre_on.summary().steps[0].applied);
}

TEST(Preprocess, FramesMustMatchTheCalibrationAndEachOther) {
  SynthCamera camera = SampleCamera();  // 640x480
  const CameraCalibration calibration = FromCamera(camera);
  ExpectErrorContaining(
      [&] { Preprocessor(PreprocessOptions{}, &calibration, cv::Size(160, 120)); },
      "has size 160x120 but the calibration was made for 640x480 images");
  Preprocessor pre(PreprocessOptions{}, nullptr, cv::Size(160, 120));
  ExpectErrorContaining([&] { pre.Apply(TestFrame(CV_8U, {100, 100})); }, "frame has size 100x100");
  ExpectErrorContaining([&] { pre.Apply(cv::Mat(120, 160, CV_8UC3)); }, "frame type");
}

TEST(Preprocess, OptionsCheckNamesTheField) {
  EXPECT_NO_THROW(PreprocessOptions{}.Check());
  PreprocessOptions o;
  o.gaussian.mode = GaussianMode::kOn;
  o.gaussian.kernel_size = 4;
  ExpectErrorContaining([&] { o.Check(); }, "preprocess.gaussian_kernel");
  o = {};
  o.gaussian.mode = GaussianMode::kOn;
  o.gaussian.sigma_px = 0;
  ExpectErrorContaining([&] { o.Check(); }, "preprocess.gaussian_sigma");
  o = {};
  o.clahe.enabled = true;
  o.clahe.clip_limit = -1;
  ExpectErrorContaining([&] { o.Check(); }, "preprocess.clahe_clip_limit");
  o = {};
  o.clahe.enabled = true;
  o.clahe.tile_grid = 0;
  ExpectErrorContaining([&] { o.Check(); }, "preprocess.clahe_tile_grid");
  o = {};
  o.gaussian.auto_threshold_px = -1;
  ExpectErrorContaining([&] { o.Check(); }, "preprocess.gaussian_auto_threshold_px");
  o.gaussian.mode = GaussianMode::kOff;  // Not checked when off.
  EXPECT_NO_THROW(o.Check());
  o = {};
  o.undistortion.skip_threshold_px = -0.5;
  ExpectErrorContaining([&] { o.Check(); }, "undistort.skip_threshold_px");
}

// `correlate --gaussian` and the scene's preprocess.gaussian.enabled read the same names.
TEST(Preprocess, GaussianFlagAndModeNames) {
  EXPECT_EQ(GaussianFromString("auto", "--gaussian").mode, GaussianMode::kAuto);
  for (const char* off : {"none", "off", "false", "NONE"})
    EXPECT_EQ(GaussianFromString(off, "--gaussian").mode, GaussianMode::kOff) << off;
  const GaussianBlurOptions on = GaussianFromString("on", "--gaussian");
  EXPECT_EQ(on.mode, GaussianMode::kOn);
  EXPECT_EQ(on.sigma_px, GaussianBlurOptions{}.sigma_px);
  const GaussianBlurOptions set = GaussianFromString("1.2,7", "--gaussian");
  EXPECT_EQ(set.mode, GaussianMode::kOn);
  EXPECT_EQ(set.sigma_px, 1.2);
  EXPECT_EQ(set.kernel_size, 7);
  EXPECT_EQ(GaussianFromString("0.6", "--gaussian").kernel_size, GaussianBlurOptions{}.kernel_size);
  for (const char* bad : {"0", "-1", "25", "abc", "0.8,4", "0.8,x", "0.8,", ",5", ""})
    ExpectErrorContaining([&] { GaussianFromString(bad, "--gaussian"); }, "--gaussian");
  EXPECT_EQ(GaussianModeFromString("TRUE", "k"), GaussianMode::kOn);
  EXPECT_STREQ(ToString(GaussianMode::kAuto), "auto");
  EXPECT_EQ(GaussianBlurOptions{}.mode, GaussianMode::kAuto);  // The default.
}

}  // namespace
}  // namespace impactdic
