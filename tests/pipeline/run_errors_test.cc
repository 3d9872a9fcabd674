// Bad input to `impactdic run`: clear errors, non-zero exit, and no results that look complete.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "../cli/cli_runner.h"
#include "../io/test_dir.h"
#include "impactdic/core/error.h"
#include "impactdic/dic/options.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/image_io.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/scene.h"

namespace impactdic {
namespace {

TEST(RunErrors, InvalidOptionsNameTheOptionAndValue) {
  const CliResult threads = RunCli("run scene.yaml --threads -3");
  EXPECT_EQ(threads.exit_code, 1);
  EXPECT_NE(threads.output.find("--threads"), std::string::npos) << threads.output;
  EXPECT_NE(threads.output.find("-3"), std::string::npos) << threads.output;
  const CliResult format = RunCli("run scene.yaml --format xml");
  EXPECT_EQ(format.exit_code, 1);
  EXPECT_NE(format.output.find("--format"), std::string::npos) << format.output;
  EXPECT_NE(format.output.find("text or json"), std::string::npos) << format.output;
  const CliResult missing = RunCli("run /nonexistent/scene.yaml");
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.output.find("/nonexistent/scene.yaml"), std::string::npos) << missing.output;
}

TEST(RunErrors, SceneWithMissingFramesFailsBeforeWritingResults) {
  TestDir dir;
  const std::string scene = dir.Write("scene.yaml", R"(
inputs: {frames: frames/*.png, mm_per_px: 0.5}
stages: [frames, correlate, kinematics, outputs]
outputs: {folder: out}
)");
  const CliResult r = RunCli("run " + scene);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("frames"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir.File("out/results.h5")));
  EXPECT_FALSE(std::filesystem::exists(dir.File("out/summary.json")));
}

TEST(RunErrors, TruncatedFrameIsNamed) {
  TestDir dir;
  std::filesystem::create_directories(dir.path() / "frames");
  cv::Mat image(64, 64, CV_8U);
  cv::randu(image, 0, 255);
  for (int k = 0; k < 4; ++k) WriteImage(dir.File("frames/f" + std::to_string(k) + ".png"), image);
  dir.Write("frames/f4.png", "\x89PNG\r\n\x1a\n truncated");
  const Scene scene = ParseScene(R"(
inputs: {frames: frames, mm_per_px: 0.5}
stages: [frames, correlate, kinematics, outputs]
dic: {subset_size: 15, step: 8}
outputs: {folder: out, figures: false, animation: false}
)",
                                 dir.File("scene.yaml"));
  try {
    RunScene(scene, PipelineOptions{});
    FAIL() << "expected an error for the truncated frame";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("f4.png"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir.File("out/results.h5")));
}

// Good 64x64 frames f0..f4 (f2 left out if `gap`) and a scene that correlates them.
Scene SmallFrameScene(const TestDir& dir, bool gap, bool figures) {
  std::filesystem::create_directories(dir.path() / "frames");
  cv::Mat image(64, 64, CV_8U);
  cv::randu(image, 0, 255);
  for (int k = 0; k < 5; ++k)
    if (!(gap && k == 2)) WriteImage(dir.File("frames/f" + std::to_string(k) + ".png"), image);
  return ParseScene(std::string(R"(
inputs: {frames: frames, mm_per_px: 0.5}
stages: [frames, correlate, kinematics, outputs]
dic: {subset_size: 15, step: 8}
outputs: {folder: out, animation: false, figures: )") +
                        (figures ? "true" : "false") + "}\n",
                    dir.File("scene.yaml"));
}

TEST(RunErrors, MissingFrameInTheSequenceIsNamedAndNoFolderIsLeft) {
  TestDir dir;
  const Scene scene = SmallFrameScene(dir, true, false);
  try {
    RunScene(scene, PipelineOptions{});
    FAIL() << "expected an error for the missing frame f2";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("f1.png to f3.png"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("1 frame(s) missing"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir.File("out")));
  // Nor the nested folders of an output path that did not exist.
  PipelineOptions nested;
  nested.output_folder = dir.File("new/a/b");
  EXPECT_THROW(RunScene(scene, nested), Error);
  EXPECT_FALSE(std::filesystem::exists(dir.File("new")));
}

TEST(RunErrors, MissingGnuplotIsReportedBeforeWork) {
  TestDir dir;
  const Scene scene = SmallFrameScene(dir, false, true);
  {
    // Set for this block only, also when an assertion leaves it early.
    struct EnvGuard {
      EnvGuard() { setenv("IMPACTDIC_GNUPLOT", "/nonexistent/gnuplot", 1); }
      ~EnvGuard() { unsetenv("IMPACTDIC_GNUPLOT"); }
    } guard;
    EXPECT_THROW(
        {
          try {
            RunScene(scene, PipelineOptions{});
          } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find("/nonexistent/gnuplot"), std::string::npos)
                << e.what();
            throw;
          }
        },
        Error);
  }
  EXPECT_FALSE(std::filesystem::exists(dir.File("out")));
  // The same scene runs once gnuplot is found. Without a sensor record the kinematics stage
  // still runs (frame times k / fps) and says so; momentum is skipped with the reason.
  const PipelineSummary ok = RunScene(scene, PipelineOptions{});
  EXPECT_TRUE(std::filesystem::exists(dir.File("out/summary.json")));
  EXPECT_GT(ok.outputs.size(), 2u);
  bool kinematics_ran = false, momentum_skipped = false;
  for (const StageReport& s : ok.stages) {
    kinematics_ran = kinematics_ran || (s.name == "kinematics" && s.ran);
    momentum_skipped = momentum_skipped || (s.name == "momentum" && !s.ran &&
                                            s.note.find("sensor") != std::string::npos);
  }
  EXPECT_TRUE(kinematics_ran);
  EXPECT_TRUE(momentum_skipped);
  EXPECT_TRUE(H5Reader(dir.File("out/results.h5")).Exists("/kinematics/vy_mm_s"));
}

// The scene's polygon and mask image limit the correlated subsets (status `masked` elsewhere);
// a mask of the wrong size is named.
TEST(RunRegion, PolygonAndMaskLimitTheCorrelatedSubsets) {
  TestDir dir;
  SmallFrameScene(dir, false, false);  // Writes frames f0..f4 (64x64).
  cv::Mat mask(64, 64, CV_8U, cv::Scalar(255));
  mask(cv::Rect(0, 0, 32, 64)).setTo(0);  // Only x >= 32.
  WriteImage(dir.File("mask.png"), mask);
  WriteImage(dir.File("small_mask.png"), cv::Mat(32, 32, CV_8U, cv::Scalar(255)));
  auto scene = [&](const std::string& region) {
    return ParseScene(R"(
inputs: {frames: frames, mm_per_px: 0.5}
stages: [frames, correlate, kinematics, outputs]
dic: {subset_size: 15, step: 8, )" +
                          region +
                          R"(}
outputs: {folder: out, animation: false, figures: false}
)",
                      dir.File("scene.yaml"));
  };
  // Upper-left triangle x + y <= 63, then the right half by the mask image.
  for (const std::string& region :
       {std::string("roi_polygon: [[0, 0], [63, 0], [0, 63]]"), std::string("mask: mask.png")}) {
    RunScene(scene(region), PipelineOptions{});
    H5Reader h5(dir.File("out/results.h5"));
    const auto x = h5.ReadDouble("/dic/x_px"), y = h5.ReadDouble("/dic/y_px");
    Dims dims;
    const auto status = h5.ReadInt("/dic/status", &dims);
    const std::size_t n = x.size();
    int inside = 0, outside = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const bool in = region[0] == 'r' ? x[i] + y[i] <= 62 : x[i] >= 33;
      const bool out = region[0] == 'r' ? x[i] + y[i] >= 64 : x[i] <= 31;
      const int s = status[(dims[0] - 1) * n + i];  // Last frame.
      if (in) {
        EXPECT_EQ(s, static_cast<int>(SubsetStatus::kConverged)) << region << " " << i;
        ++inside;
      } else if (out) {
        EXPECT_EQ(s, static_cast<int>(SubsetStatus::kMasked)) << region << " " << i;
        ++outside;
      }
    }
    EXPECT_GT(inside, 0) << region;
    EXPECT_GT(outside, 0) << region;
  }
  EXPECT_THROW(RunScene(scene("roi: [0, 0, 20, 20], roi_polygon: [[40, 40], [60, 40], [60, 60]]"),
                        PipelineOptions{}),
               Error);
  try {
    RunScene(scene("mask: small_mask.png"), PipelineOptions{});
    FAIL() << "expected an error for the mask size";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("small_mask.png"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("64x64"), std::string::npos) << e.what();
  }
}

TEST(RunErrors, UnwritableOutputFolderIsReportedBeforeWork) {
  // CI runs as root, who can write anywhere: a folder below a regular file cannot be created by
  // anyone.
  TestDir dir;
  dir.Write("file", "x");
  const Scene scene = ParseScene("inputs: {frames: nothing}\noutputs: {folder: file/out}\n",
                                 dir.File("scene.yaml"));
  try {
    RunScene(scene, PipelineOptions{});
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kIo) << e.what();
    EXPECT_NE(std::string(e.what()).find("file/out"), std::string::npos) << e.what();
  }
}

TEST(RunErrors, SensorRecordEndingBeforeTheLastFrameIsNamed) {
  // A tiny synthetic scene whose DAQ record is cut just before the last frame's exposure pulse.
  TestDir dir;
  const CliResult synth = RunCli("synth --preset tiny --no-calibrate -o " + dir.File("scene"));
  ASSERT_EQ(synth.exit_code, 0) << synth.output;
  std::ifstream in(dir.File("scene/sensor.csv"));
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  auto exposure = [&](std::size_t i) { return lines[i].substr(lines[i].rfind(',') + 1); };
  std::size_t last_edge = 0;
  for (std::size_t i = 2; i < lines.size(); ++i)
    if (exposure(i) != "0" && exposure(i - 1) == "0") last_edge = i;
  ASSERT_GT(last_edge, 10u);
  std::ofstream out(dir.File("scene/sensor.csv"), std::ios::trunc);
  for (std::size_t i = 0; i + 5 < last_edge; ++i) out << lines[i] << "\n";
  out.close();

  const CliResult r = RunCli("run " + dir.File("scene/scene.yaml") + " -o " + dir.File("out"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("sensor.csv"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("does not cover the frames"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir.File("out/results.h5")));
  EXPECT_FALSE(std::filesystem::exists(dir.File("out/summary.json")));
}

TEST(RunErrors, MoreExposureEdgesThanFramesIsAWarning) {
  // The last frame file of a tiny synthetic scene removed: its exposure edge has no frame.
  TestDir dir;
  const CliResult synth = RunCli("synth --preset tiny --no-calibrate -o " + dir.File("scene"));
  ASSERT_EQ(synth.exit_code, 0) << synth.output;
  const auto frames = ListFrames(dir.File("scene/frames"));
  ASSERT_GT(frames.size(), 5u);
  std::filesystem::remove(frames.back());
  const CliResult r = RunCli("run " + dir.File("scene/scene.yaml") + " -o " + dir.File("out"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("edge(s) are unused"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace impactdic
