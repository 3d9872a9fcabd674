// Stage names in a scene's `stages` mean what they say: `frames` reads and checks the frames (it
// was accepted but never checked), `correlate` without `frames` is refused before any work.
#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "../core/expect_error.h"
#include "../io/test_dir.h"
#include "impactdic/io/image_io.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/scene.h"

namespace impactdic {
namespace {

// Frames f0..f4 (64 x 64 random speckle) in dir/frames.
void WriteFrames(const TestDir& dir) {
  std::filesystem::create_directories(dir.path() / "frames");
  cv::Mat image(64, 64, CV_8U);
  cv::randu(image, 0, 255);
  for (int k = 0; k < 5; ++k) WriteImage(dir.File("frames/f" + std::to_string(k) + ".png"), image);
}

Scene FramesScene(const TestDir& dir, const std::string& stages) {
  return ParseScene("inputs: {frames: frames, mm_per_px: 0.5}\nstages: " + stages +
                        "\ndic: {subset_size: 15, step: 8}\n"
                        "outputs: {folder: out, figures: false, animation: false}\n",
                    dir.File("scene.yaml"));
}

const StageReport* Find(const PipelineSummary& s, const std::string& name) {
  for (const StageReport& r : s.stages)
    if (r.name == name) return &r;
  return nullptr;
}

TEST(Stages, FramesAloneReadsAndChecksTheFrames) {
  TestDir dir;
  WriteFrames(dir);
  const PipelineSummary s = RunScene(FramesScene(dir, "[frames]"), PipelineOptions{});
  const StageReport* frames = Find(s, "frames");
  ASSERT_NE(frames, nullptr);
  EXPECT_TRUE(frames->ran) << frames->note;
  EXPECT_NE(frames->note.find("5 of 5 frames (64x64, 8-bit)"), std::string::npos) << frames->note;
  const StageReport* correlate = Find(s, "correlate");
  ASSERT_NE(correlate, nullptr);
  EXPECT_FALSE(correlate->ran);
  EXPECT_EQ(correlate->note, "not among the scene's stages");
  // Checked: a frame of another size is an error naming it, though nothing is correlated.
  WriteImage(dir.File("frames/f5.png"), cv::Mat(32, 32, CV_8U, cv::Scalar(7)));
  ExpectErrorContaining([&] { RunScene(FramesScene(dir, "[frames]"), PipelineOptions{}); },
                        "f5.png");
}

TEST(Stages, CorrelateWithoutFramesIsRefusedBeforeAnyWork) {
  TestDir dir;  // No frames at all: the stage list is refused before they are looked for.
  const Scene scene = FramesScene(dir, "[correlate, kinematics, outputs]");
  const std::string message = ErrorText([&] { RunScene(scene, PipelineOptions{}); });
  EXPECT_NE(message.find("stages"), std::string::npos) << message;
  EXPECT_NE(message.find("[correlate, kinematics, outputs]"), std::string::npos) << message;
  EXPECT_NE(message.find("frames listed with correlate"), std::string::npos) << message;
  EXPECT_FALSE(std::filesystem::exists(dir.File("out")));
}

TEST(Stages, EveryStageReportsOnceInPipelineOrder) {
  TestDir dir;
  WriteFrames(dir);
  const PipelineSummary s =
      RunScene(FramesScene(dir, "[frames, correlate, kinematics, outputs]"), PipelineOptions{});
  std::vector<std::string> names;
  for (const StageReport& r : s.stages) names.push_back(r.name);
  EXPECT_EQ(names,
            (std::vector<std::string>{"calibrate", "sensor", "frames", "correlate", "kinematics",
                                      "momentum", "model", "strain", "outputs"}));
  EXPECT_EQ(Find(s, "momentum")->note, "needs the sensor record (pounder velocity)");
  EXPECT_TRUE(Find(s, "kinematics")->ran);
  EXPECT_EQ(Find(s, "strain")->note, "strain.enabled is false");
}

}  // namespace
}  // namespace impactdic
