// The analysed frames of `run` (FrameStream): the scene's preprocessing applies to every frame,
// the first one (the correlation's reference) included.
#include "impactdic/pipeline/frame_stream.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "../io/test_dir.h"
#include "impactdic/io/image_io.h"

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

}  // namespace
}  // namespace impactdic
