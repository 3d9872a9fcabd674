// Fault injection: physically absurd or inconsistent values in scene files and CLI options. Each
// is refused up front, naming the key or option, the value and the allowed range, with the range
// defined once (core/range.h, the options' Check()) for the scene and the CLI alike.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "../core/expect_error.h"
#include "../core/test_paths.h"
#include "../io/test_dir.h"
#include "fault_util.h"
#include "impactdic/core/range.h"
#include "impactdic/model/impact_model.h"
#include "impactdic/pipeline/scene.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

// Four 96x80 frames and a scene using them; `extra` is appended to the scene file.
std::string FrameScene(const TestDir& dir, const std::string& extra) {
  WriteFrames(dir, "frames", "f_", 0, 10);
  return dir.Write("scene.yaml",
                   "inputs: {frames: frames/*.png, mm_per_px: 0.5}\n"
                   "stages: [frames, correlate, kinematics, outputs]\n"
                   "outputs: {figures: false, animation: false}\n" +
                       extra);
}

TEST(ValueFaults, AbsurdSceneMassIsRefusedAtLoadWithTheRange) {
  TestDir dir;
  // Ran the whole pipeline and failed at the end with a gnuplot parse error.
  const std::string scene = FrameScene(dir, "test: {mass_kg: 1e308}\n");
  ExpectCliFailure("run " + scene + " -o " + dir.File("out"),
                   {scene + ":4", "test.mass_kg", "got '1e308'",
                    "expected a pounder mass in [0.01, 100000] kg"});
  EXPECT_FALSE(fs::exists(dir.File("out")));
}

TEST(ValueFaults, EverySceneTestKeyHasItsRange) {
  const struct {
    const char* yaml;
    const char* key;
    const char* expected;
  } cases[] = {
      {"test: {drop_height_m: 1e4}", "test.drop_height_m", "in [0, 100] m"},
      {"test: {impact_velocity_m_s: 1e-9}", "test.impact_velocity_m_s", "in [0.001, 100] m/s"},
      {"test: {width_m: 1e3}", "test.width_m", "in [0.0001, 10] m"},
      {"test: {depth_m: 0}", "test.depth_m", "in [0.0001, 10] m"},
      {"test: {density_kg_m3: 1e9}", "test.density_kg_m3", "in [1, 1e+06] kg/m^3"},
      {"test: {bed_height_m: 1e6}", "test.bed_height_m", "in [0.001, 100] m"},
      {"inputs: {frames: f/*.png, fps: 0.001}", "inputs.fps",
       "a camera frame rate in [1, 1e+07] 1/s"},
      {"inputs: {frames: f/*.png, mm_per_px: 1e308}", "inputs.mm_per_px",
       "in [0.0001, 10000] mm/px"},
      {"model: {added_mass_kg: 1e300}", "model.added_mass_kg", "in [0, 1e+06] kg"},
  };
  for (const auto& c : cases) {
    std::string yaml = std::string(c.yaml) + "\n";
    if (yaml.rfind("inputs", 0) != 0) yaml = "inputs: {frames: f/*.png}\n" + yaml;
    const std::string message = ErrorText([&] { ParseScene(yaml, "s.yaml"); });
    EXPECT_NE(message.find(c.key), std::string::npos) << c.yaml << ": " << message;
    EXPECT_NE(message.find(c.expected), std::string::npos) << c.yaml << ": " << message;
  }
  // The paper's values and the model's extreme cases (docs/model.md) are inside.
  EXPECT_NO_THROW(
      ParseScene("inputs: {frames: f/*.png}\ntest: {mass_kg: 0.1, width_m: 0.001}\n", "s.yaml"));
  EXPECT_NO_THROW(ParseScene(
      "inputs: {frames: f/*.png}\ntest: {mass_kg: 1000, drop_height_m: 18}\n", "s.yaml"));
}

TEST(ValueFaults, ModelOptionsShareTheSceneRanges) {
  ExpectCliFailure("model --mass 1e308 --height 0.7 --width 0.15",
                   {"--mass", "1e+308", "a pounder mass in [0.01, 100000] kg"});
  ExpectCliFailure("model --mass 10 --velocity 1e5 --width 0.15",
                   {"--velocity", "100000", "[0.001, 100] m/s"});
  ExpectCliFailure("model --mass 10 --height 0.7 --width 0.15 --rho 1e12",
                   {"--rho", "[1, 1e+06] kg/m^3"});
  // The library checks the same ranges under its own field names.
  ImpactModelParameters p;
  p.pounder_mass_kg = 1e308;
  ExpectErrorContaining([&] { p.Check(); }, "pounder_mass_kg");
  EXPECT_EQ(kPounderMassRange.Text(), "[0.01, 100000] kg");
}

TEST(ValueFaults, CalibrateSquareAndRenderFpsAreRefusedWithTheirRanges) {
  TestDir dir;
  // Was a raw OpenCV assertion "fabs(sc) > DBL_EPSILON" after detecting every board.
  ExpectCliFailure("calibrate --board 9x6 --square 1e308 " + std::string(impactdic::SourceDir()) +
                       "/calibration/view_00.png -o " + dir.File("cam.yaml"),
                   {"--square", "1e+308", "a square size in [0.01, 10000] mm"});
  // Was accepted and failed in the video writer ("Could not open codec mjpeg").
  const std::string results = dir.Write("results.h5", "");
  ExpectCliFailure("render " + results + " --fps 0.001 -o " + dir.File("render"),
                   {"--fps", "0.001", "a playback frame rate in [0.1, 240] 1/s"});
  EXPECT_FALSE(fs::exists(dir.File("render")));
}

TEST(ValueFaults, RoiOutsideTheFramesNamesTheSceneKeyAndValues) {
  TestDir dir;
  // Was "undistort.roi: invalid value (got a rectangle outside the frame)": no key, no values.
  const std::string scene = FrameScene(dir, "dic: {roi: [5000, 5000, 6000, 6000]}\n");
  ExpectCliFailure("run " + scene + " -o " + dir.File("out"),
                   {scene, "dic.roi", "[5000, 5000, 6000, 6000], entirely outside the frames",
                    "inside the 96x80 frames (x1 <= 96, y1 <= 80)"});
  EXPECT_FALSE(fs::exists(dir.File("out/results.h5")));
  const std::string partly = FrameScene(dir, "dic: {roi: [10, 10, 200, 60]}\n");
  ExpectCliFailure("run " + partly + " -o " + dir.File("out"),
                   {"dic.roi", "[10, 10, 200, 60], partly outside"});
}

TEST(ValueFaults, FirstFrameBeyondTheSequenceNamesTheKey) {
  TestDir dir;
  // Was "frames: invalid value (got -490 frames from 500 to 9)".
  const std::string scene = FrameScene(dir, "dic: {first_frame: 500}\n");
  const std::string output = ExpectCliFailure(
      "run " + scene + " -o " + dir.File("out"),
      {scene, "dic.first_frame", "got 500", "a frame index <= 7", "holds 10 frames (0..9)"});
  EXPECT_EQ(output.find("-490"), std::string::npos) << output;
  const std::string with_last = FrameScene(dir, "dic: {first_frame: 6, last_frame: 7}\n");
  ExpectCliFailure("run " + with_last + " -o " + dir.File("out"),
                   {"dic.first_frame", "got 6", "a frame index <= 5", "dic.last_frame is 7"});
}

TEST(ValueFaults, ThreadCountsFollowOneRuleEverywhere) {
  TestDir dir;
  const std::string expected = "expected 0 (all cores) or a number of threads >= 1";
  // `run --threads -1` was accepted (meaning "the scene's"), `correlate --threads -1` refused.
  ExpectCliFailure("run scene.yaml --threads -1", {"--threads", "got -1", expected});
  ExpectCliFailure("correlate --frames 'f/*.png' --threads -1 -o " + dir.File("o.csv"),
                   {"--threads", "got -1", expected});
  ExpectCliFailure("campaign s.yaml --threads -1", {"--threads", "got -1", expected});
  ExpectErrorContaining(
      [] { ParseScene("inputs: {frames: f/*.png}\ndic: {threads: -1}\n", "s.yaml"); },
      "dic.threads: got '-1'; expected 0 (all cores) or a number of threads >= 1");
}

}  // namespace
}  // namespace impactdic
