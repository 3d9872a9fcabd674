// One frame timeline (sensor/frame_timeline.h): every route to a number times a frame the same way.
// `analyze SCENE --results X` of a `correlate` result gives the summary of `run` of the same scene
// (the same frames: dic.first_frame_number = correlate's --first) to 1e-12, or the same refusal.
// `correlate` numbers its rows from the reference, so analyze must find which frames they are;
// it used to time row k by exposure edge k (frames one step early: m_add -27 %, exit 0) and so
// also missed that frames starting after the impact cannot measure the peak stage. And a grep:
// no code but the timeline computes a frame time.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "../cli/cli_runner.h"
#include "../core/route_compare.h"
#include "../core/test_paths.h"
#include "../io/test_dir.h"
#include "fault_util.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/yaml.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

// The JSON object of a command's output (the text from its first '{' to its last '}').
YAML::Node JsonOf(const std::string& out) {
  const std::size_t a = out.find('{'), b = out.rfind('}');
  if (a == std::string::npos || b == std::string::npos) return YAML::Node();
  return YAML::Load(out.substr(a, b + 1 - a));
}

// The message of a refusal: its "error" lines, without the file paths of the route's outputs.
std::string Refusal(const std::string& out) {
  std::istringstream in(out);
  std::string line, text;
  while (std::getline(in, line))
    if (line.find("error") != std::string::npos) text += line + "\n";
  return text;
}

class TimelineRoutes : public ::testing::TestWithParam<int> {};

TEST_P(TimelineRoutes, AnalyzeOfACorrelateResultEqualsTheRun) {
  const int first = GetParam();
  const TestDir dir;
  const std::string scene = SampleScene(dir, {{"xdmf: true", "xdmf: false"}});
  const std::string sample = std::string(SourceDir()) + "/sample_frames";
  const std::string n = std::to_string(first);

  const CliResult run = RunCli("-q run " + scene + " --dic.first_frame_number " + n + " -o " +
                               dir.File("run") + " --format json");
  // The scene's correlation alone, by correlate's flags (the scene's dic keys).
  const CliResult correlate = RunCli(
      "-q correlate --frames '" + sample + "/frames/frame_*.png' --inputs.calibration " + sample +
      "/../calibration/camera.yaml --subset 25 --step 32 --roi 36,131,605,444 --search-radius 12 "
      "--dic.max_iterations 30 --gaussian none --first " +
      n + " --warp-gradient -o " + dir.File("c.h5"));
  ASSERT_EQ(correlate.exit_code, 0) << correlate.output;
  const CliResult analyze = RunCli("-q analyze " + scene + " --results " + dir.File("c.h5") +
                                   " --output " + dir.File("a.h5") + " --format json");
  if (run.exit_code != 0) {  // The same refusal.
    EXPECT_NE(analyze.exit_code, 0) << "run refused:\n"
                                    << run.output << "\nanalyze did not:\n"
                                    << analyze.output;
    EXPECT_EQ(Refusal(analyze.output), Refusal(run.output)) << run.output << analyze.output;
    EXPECT_FALSE(fs::exists(dir.File("a.h5")));
    return;
  }
  ASSERT_EQ(analyze.exit_code, 0) << "run:\n" << run.output << "\nanalyze:\n" << analyze.output;
  const YAML::Node run_summary = LoadYamlFile(dir.File("run/summary.json"), "summary.json");
  const YAML::Node analysis = JsonOf(analyze.output);
  ASSERT_TRUE(analysis["summary"]) << analyze.output;
  EXPECT_EQ(Differences(analysis["summary"], run_summary, "summary"), "");
  EXPECT_GE(run_summary.size(), 20u);

  // Both files say which frames the rows are and when they were taken.
  const H5Reader ran(dir.File("run/results.h5")), analysed(dir.File("a.h5"));
  for (const char* path : {"/time/t_ms", "/time/frame_index", "/time/frame_number",
                           "/time/camera_time_s", "/time/daq_time_s"}) {
    ASSERT_TRUE(analysed.Exists(path)) << path;
    const std::vector<double> a = ran.ReadDouble(path), b = analysed.ReadDouble(path);
    ASSERT_EQ(a.size(), b.size()) << path;
    for (std::size_t i = 0; i < a.size(); ++i) EXPECT_TRUE(Equal(a[i], b[i])) << path << i;
  }
  EXPECT_EQ(ran.ReadDouble("/time/frame_number").front(), first);
}

INSTANTIATE_TEST_SUITE_P(FirstFrame, TimelineRoutes, ::testing::Values(0, 1, 5));

// A correlate result whose frame numbers are not among the scene's frames is refused, naming the
// number and the frames (not timed by position).
TEST(TimelineRoutes, ACorrelateResultOfOtherFramesIsRefused) {
  const TestDir dir;
  const std::string sample = std::string(SourceDir()) + "/sample_frames";
  // The scene's frames are 0..53; the correlation's are numbered 0.. too, but the scene only
  // lists frames 10..19 (a glob of its own).
  const std::string scene = SampleScene(
      dir, {{"xdmf: true", "xdmf: false"},
            {"\"" + sample + "/frames/frame_*.png\"", "\"" + sample + "/frames/frame_001?.png\""}});
  const CliResult correlate = RunCli("-q correlate --frames '" + sample +
                                     "/frames/frame_000[0-4].png' --subset 25 --step 64 "
                                     "--roi 36,131,605,444 -o " +
                                     dir.File("c.h5"));
  ASSERT_EQ(correlate.exit_code, 0) << correlate.output;
  const CliResult analyze = RunCli("-q analyze " + scene + " --results " + dir.File("c.h5") +
                                   " --output " + dir.File("a.h5"));
  EXPECT_NE(analyze.exit_code, 0) << analyze.output;
  EXPECT_NE(analyze.output.find("/dic/frame_number[0]"), std::string::npos) << analyze.output;
  EXPECT_NE(analyze.output.find("frame_001?.png"), std::string::npos) << analyze.output;
  EXPECT_FALSE(fs::exists(dir.File("a.h5")));
}

// The source text of src/ and include/, file by file.
std::vector<std::pair<std::string, std::string>> Sources() {
  std::vector<std::pair<std::string, std::string>> files;
  for (const char* top : {"src", "include"}) {
    for (const auto& e : fs::recursive_directory_iterator(std::string(SourceDir()) + "/" + top)) {
      const std::string ext = e.path().extension().string();
      if (ext != ".cc" && ext != ".h") continue;
      std::ifstream in(e.path());
      std::stringstream text;
      text << in.rdbuf();
      files.emplace_back(fs::relative(e.path(), SourceDir()).string(), text.str());
    }
  }
  return files;
}

// Frame times are computed in one place: sensor FrameTimes (the DAQ clock) is called by
// MakeFrameTimeline alone, and no stage, writer or analysis keeps a series of frame times of its
// own (the names the four earlier computations used are gone).
TEST(OneTimeline, FrameTimesAreComputedInOnePlace) {
  const std::vector<std::pair<std::string, std::string>> files = Sources();
  ASSERT_GT(files.size(), 100u);
  for (const auto& [path, text] : files) {
    std::size_t at = 0;
    while ((at = text.find("FrameTimes(", at)) != std::string::npos) {
      const bool definition =
          path == "src/sensor/camera_timing.cc" || path == "include/impactdic/sensor/sensor.h";
      EXPECT_TRUE(definition || path == "src/sensor/frame_timeline.cc")
          << path << " calls FrameTimes: read a FrameTimeline (sensor/frame_timeline.h)";
      at += 11;
    }
    for (const char* gone : {"frame_times_s", "AnalysedFrameTimesMs", "SceneFrameClock("}) {
      if (std::string(gone) == "SceneFrameClock(" &&
          (path == "src/pipeline/frame_stream.cc" || path == "src/pipeline/stages/stage.cc" ||
           path == "include/impactdic/pipeline/frame_stream.h"))
        continue;  // Its definition, and TimeSceneFrames, its one caller.
      EXPECT_EQ(text.find(gone), std::string::npos) << path << " uses " << gone;
    }
  }
}

// One driver: `run`, `analyze` (both forms) and `correlate` build their stage context, apply the
// failure rule and write through RunRoute (src/pipeline/route.h) alone, so a rule added there
// holds for every route.
TEST(OneDriver, EveryRouteRunsThroughRunRoute) {
  for (const auto& [path, text] : Sources()) {
    if (path == "src/pipeline/route.cc" || path.rfind("src/pipeline/stages/", 0) == 0) continue;
    for (const char* own :
         {"StageContext context{", "StageContext context(", "throw PartialResultsError("})
      EXPECT_EQ(text.find(own), std::string::npos) << path << " has its own " << own;
  }
  for (const char* route : {"src/pipeline/pipeline.cc", "src/pipeline/scene_analysis.cc",
                            "src/pipeline/correlate_scene.cc"}) {
    std::ifstream in(std::string(SourceDir()) + "/" + route);
    std::stringstream text;
    text << in.rdbuf();
    EXPECT_NE(text.str().find("RunRoute("), std::string::npos) << route;
  }
}

}  // namespace
}  // namespace impactdic
