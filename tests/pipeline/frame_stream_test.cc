// The analysed frames of `run` (FrameStream): the scene's preprocessing applies to every frame,
// the first one (the correlation's reference) included.
#include "impactdic/pipeline/frame_stream.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "../core/expect_error.h"
#include "../io/cine_test_writer.h"
#include "../io/mraw_test_writer.h"
#include "../io/test_dir.h"
#include "impactdic/io/frame_source.h"
#include "impactdic/io/image_io.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/preprocess/nyquist_bias.h"
#include "impactdic/preprocess/preprocess.h"

namespace impactdic {
namespace {

TEST(FrameStream, GaussianPrefilterAppliesToTheReferenceAndEveryDeformedFrame) {
  TestDir dir;
  std::filesystem::create_directories(dir.path() / "frames");
  std::vector<cv::Mat> raw;
  for (int k = 0; k < 3; ++k) {
    cv::Mat image(48, 64, CV_8U);
    cv::randu(image, 0, 255);
    WriteImage(dir.File("frames/f" + std::to_string(k) + ".png"), image);
    raw.push_back(image);
  }
  PreprocessOptions options;
  options.gaussian.mode = GaussianMode::kOn;
  options.gaussian.sigma_px = 0.8;
  FrameStream frames(dir.File("frames"), options, /*calibration=*/nullptr);
  frames.SetRange(0, 2);
  for (int k = 0; k < 3; ++k) {
    cv::Mat expected;
    cv::GaussianBlur(raw[k], expected, cv::Size(5, 5), 0.8, 0.8, cv::BORDER_REFLECT_101);
    const cv::Mat read = frames.Read(k);
    EXPECT_EQ(cv::norm(read, expected, cv::NORM_INF), 0) << "frame " << k;
    EXPECT_GT(cv::norm(read, raw[k], cv::NORM_INF), 0) << "frame " << k;
  }
}

// The default (auto) decides from the first analysed frame, whichever frame is read first: a
// sharp first frame (white noise) blurs every frame, also the smooth ones after it.
TEST(FrameStream, AutoPrefilterIsDecidedByTheFirstAnalysedFrame) {
  TestDir dir;
  std::filesystem::create_directories(dir.path() / "frames");
  std::vector<cv::Mat> raw;
  for (int k = 0; k < 3; ++k) {
    cv::Mat image(96, 128, CV_8U);
    cv::randu(image, 0, 255);
    if (k > 0) cv::GaussianBlur(image, image, cv::Size(0, 0), 2.0);  // Smooth later frames.
    WriteImage(dir.File("frames/f" + std::to_string(k) + ".png"), image);
    raw.push_back(image);
  }
  FrameStream frames(dir.File("frames"), PreprocessOptions{}, /*calibration=*/nullptr);
  frames.SetRange(0, 2);
  EXPECT_EQ(frames.preprocess_summary(), nullptr);
  for (int k : {2, 0, 1}) {
    cv::Mat expected;
    cv::GaussianBlur(raw[k], expected, cv::Size(5, 5), GaussianBlurOptions{}.sigma_px,
                     GaussianBlurOptions{}.sigma_px, cv::BORDER_REFLECT_101);
    EXPECT_EQ(cv::norm(frames.Read(k), expected, cv::NORM_INF), 0) << "frame " << k;
  }
  ASSERT_NE(frames.preprocess_summary(), nullptr);
  const GaussianDecision& d = frames.preprocess_summary()->gaussian;
  EXPECT_TRUE(d.applied);
  EXPECT_EQ(d.figure.bias_px, MeasureNyquistBias(raw[0]).bias_px);
}

// A camera file read through the stream (what `run` and `correlate` read): the analysed range in
// source indices, each frame named, numbered and timed as the camera's frame, preprocessed.
TEST(FrameStream, ReadsACameraFileWithItsFrameNumbersAndTimes) {
  TestDir dir;
  std::vector<cv::Mat> raw;
  for (int k = 0; k < 5; ++k) {
    cv::Mat image(24, 32, CV_16U);
    cv::randu(image, 0, 1023);
    raw.push_back(image);
  }
  test::MrawWriteOptions o;
  o.color_bit = 10;
  o.start_frame = -3;
  o.fps = 2000;
  const std::string cih = test::WriteMraw(dir.File("rec"), raw, o);
  PreprocessOptions options;
  options.gaussian.mode = GaussianMode::kOn;
  FrameStream frames(OpenFrameSource(cih), options, /*calibration=*/nullptr);
  EXPECT_EQ(frames.source_frames(), 5);
  frames.SetRange(1, 3);
  ASSERT_EQ(frames.frame_count(), 3);
  EXPECT_EQ(frames.FrameNumber(0), -2);
  EXPECT_DOUBLE_EQ(frames.TimeS(2), 0 / 2000.0);
  EXPECT_DOUBLE_EQ(frames.fps(), 2000);
  EXPECT_EQ(frames.data_bits(), 10);
  EXPECT_NE(frames.Name(0).find("frame -2"), std::string::npos) << frames.Name(0);
  cv::Mat expected;
  cv::GaussianBlur(raw[2], expected, cv::Size(5, 5), GaussianBlurOptions{}.sigma_px,
                   GaussianBlurOptions{}.sigma_px, cv::BORDER_REFLECT_101);
  EXPECT_EQ(cv::norm(frames.Read(1), expected, cv::NORM_INF), 0);
  EXPECT_EQ(cv::norm(frames.ReadRaw(0), raw[1], cv::NORM_INF), 0);
}

// A scene whose frames are a 5-image .cine (camera frames -2..2) at 1000 fps, time-stamped.
Scene CineScene(const TestDir& dir, const std::vector<double>& time_s) {
  test::SyntheticCine c;
  c.images.assign(5, std::vector<std::uint8_t>(24, 0));  // 4 x 3 px, 16-bit.
  c.time_s = time_s;
  Scene scene;
  scene.inputs.frames = dir.File("rec.cine");
  test::WriteCineFile(scene.inputs.frames, c);
  scene.path = dir.File("scene.yaml");
  scene.sensor.frame_time_offset_s = 0.25;
  return scene;
}

TEST(SceneFrameClock, ACameraFileGivesItsRateAndTimeStamps) {
  const TestDir dir;
  const std::vector<double> stamps = {-0.002, -0.001, 0, 0.001, 0.002};
  const CameraClock clock = SceneFrameClock(CineScene(dir, stamps));
  EXPECT_EQ(clock.fps, 1000);  // Not inputs.fps's default 1600.
  EXPECT_EQ(clock.offset_s, 0.25);
  ASSERT_EQ(clock.time_s.size(), stamps.size());
  for (std::size_t k = 0; k < stamps.size(); ++k) EXPECT_NEAR(clock.time_s[k], stamps[k], 1e-9);
  EXPECT_NE(clock.fps_name.find("rec.cine"), std::string::npos) << clock.fps_name;
  // Image files: inputs.fps and no time stamps.
  Scene images;
  images.inputs.frames = dir.File("frames/*.png");
  images.inputs.fps = 2000;
  EXPECT_EQ(SceneFrameClock(images).fps, 2000);
  EXPECT_TRUE(SceneFrameClock(images).time_s.empty());
}

TEST(SceneFrameClock, ADroppedFrameInTheTimeStampsIsRefusedNamingBothFrames) {
  const TestDir dir;
  // Camera frames 0 and 1 are 2 ms apart at 1000 fps: one frame is missing between them.
  const Scene scene = CineScene(dir, {-0.002, -0.001, 0, 0.002, 0.003});
  ExpectErrorContaining([&] { SceneFrameClock(scene); }, "frames 0 and 1 0.002 s apart");
  ExpectErrorContaining([&] { SceneFrameClock(scene); }, "rec.cine");
}

TEST(SceneFrameClock, AnInputsFpsThatDisagreesWithTheFileIsRefused) {
  const TestDir dir;
  Scene scene = CineScene(dir, {-0.002, -0.001, 0, 0.001, 0.002});
  scene.inputs.fps = 1100;
  scene.inputs.fps_given = true;
  ExpectErrorContaining([&] { SceneFrameClock(scene); }, "inputs.fps");
  scene.inputs.fps = 1005;  // Within 1 %: the file's rate is used.
  EXPECT_EQ(SceneFrameClock(scene).fps, 1000);
}

}  // namespace
}  // namespace impactdic
