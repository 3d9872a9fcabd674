// Fault injection: scene files, calibration views and validate-dem inputs that were
// accepted silently or reported poorly: a second YAML document, empty or repeated stages,
// non-finite numbers (one problem, naming the list element), repeated calibration views, and a
// file of the wrong kind given to validate-dem.
#include <gtest/gtest.h>

#include <cstddef>
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "../core/expect_error.h"
#include "../core/test_paths.h"
#include "../io/test_dir.h"
#include "fault_util.h"
#include "impactdic/calib/calibration.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/yaml.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/synth/checkerboard.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

const std::string kSource = impactdic::SourceDir();

// Ten 96x80 frames and a scene using them (figures and animation off); `extra` is appended.
std::string FrameScene(const TestDir& dir, const std::string& extra) {
  WriteFrames(dir, "frames", "f_", 0, 10);
  return dir.Write("scene.yaml",
                   "inputs: {frames: frames/*.png, mm_per_px: 0.5}\n"
                   "stages: [frames, correlate, kinematics, outputs]\n"
                   "outputs: {figures: false, animation: false}\n" +
                       extra);
}

// Number of problems ParseScene reports ("N problems in scene file"), and their text.
std::string SceneProblems(const std::string& yaml) {
  return ErrorText([&] { ParseScene(yaml, "s.yaml"); });
}

// Before: yaml-cpp read the first document and ignored the rest, so the 99 kg of the second one
// were silently dropped.
TEST(SceneInputFaults, SecondYamlDocumentIsRefusedNamingTheLine) {
  TestDir dir;
  const std::string scene = FrameScene(dir, "---\ntest: {mass_kg: 99}\n");
  ExpectCliFailure("run " + scene + " -o " + dir.File("out"),
                   {scene + ":4", "a second document starting at line 4", "one document per file",
                    "delete the '---'"});
  EXPECT_FALSE(fs::exists(dir.File("out")));
  // Calibration files and synth specs go through the same loader.
  std::string calibration = ReadBytes(kSource + "/calibration/camera.yaml");
  calibration += "---\nfx: 900\n";
  const std::string path = dir.Write("camera.yaml", calibration);
  const std::string message = ErrorText([&] { LoadCalibration(path); });
  EXPECT_NE(message.find(path + ":"), std::string::npos) << message;
  EXPECT_NE(message.find("a second document"), std::string::npos) << message;
  // One document, with or without its explicit start '---' or end '...', is fine.
  EXPECT_NO_THROW(LoadYaml("---\na: 1\n", "s.yaml", "a scene"));
  EXPECT_NO_THROW(LoadYaml("a: 1\n...\n", "s.yaml", "a scene"));
}

TEST(SceneInputFaults, EmptyOrRepeatedStagesAreRefused) {
  TestDir dir;
  // `stages: []` ran nothing and exited 0.
  const std::string scene = FrameScene(dir, "");
  std::string text = ReadBytes(scene);
  text.replace(text.find("stages: [frames, correlate, kinematics, outputs]"), 48, "stages: []");
  WriteBytes(scene, text);
  ExpectCliFailure("run " + scene + " -o " + dir.File("out"),
                   {scene + ":2", "stages: got an empty list",
                    "expected at least one of calibrate, frames, correlate"});
  EXPECT_FALSE(fs::exists(dir.File("out")));
  // A stage listed twice ran once, silently.
  const std::string message =
      SceneProblems("inputs: {frames: f/*.png}\nstages: [frames, correlate, frames]\n");
  EXPECT_NE(message.find("1 problem in scene file"), std::string::npos) << message;
  EXPECT_NE(message.find("s.yaml:2: stages[2]: got 'frames' a second time (first as stages[0])"),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("each stage at most once"), std::string::npos) << message;
}

// Before: "got '.nan'; expected a pixel row >= 0 px" and "surface_y_px: missing; expected both
// ..." for one key that was given.
TEST(SceneInputFaults, NonFiniteNumberIsOneProblemSayingSo) {
  const std::string message = SceneProblems(
      "inputs: {frames: f/*.png}\nmomentum: {pounder_center_x_px: 320, surface_y_px: .nan}\n");
  EXPECT_NE(message.find("1 problem in scene file"), std::string::npos) << message;
  EXPECT_NE(message.find("momentum.surface_y_px: got '.nan'; must be a finite number: a pixel row"),
            std::string::npos)
      << message;
  EXPECT_EQ(message.find("missing"), std::string::npos) << message;
  // Every number key says so, integer keys and the library tables' keys alike.
  for (const char* yaml : {"test: {mass_kg: .inf}", "dic: {step: .nan}", "dic: {min_zncc: -.inf}",
                           "model: {added_mass_kg: .nan}", "sensor: {cutoff_hz: .NaN}"}) {
    const std::string m = SceneProblems(std::string("inputs: {frames: f/*.png}\n") + yaml + "\n");
    EXPECT_NE(m.find("1 problem in scene file"), std::string::npos) << yaml << ": " << m;
    EXPECT_NE(m.find("must be a finite number"), std::string::npos) << yaml << ": " << m;
  }
  // A value that is a number but outside the range keeps its message.
  const std::string range = SceneProblems("inputs: {frames: f/*.png}\ntest: {mass_kg: 1e308}\n");
  EXPECT_EQ(range.find("finite"), std::string::npos) << range;
  // The CLI gives the one message too.
  TestDir dir;
  const std::string scene =
      FrameScene(dir, "momentum: {pounder_center_x_px: 320, surface_y_px: .nan}\n");
  const std::string output =
      ExpectCliFailure("run " + scene + " -o " + dir.File("out"),
                       {"1 problem in scene file",
                        scene + ":4: momentum.surface_y_px: got '.nan'; must be a finite"});
  EXPECT_EQ(output.find("missing"), std::string::npos) << output;
}

// Before: "dic.roi: got a list of 4; expected [x0, y0, x1, y1] ...", which hid the NaN.
TEST(SceneInputFaults, BadRoiElementIsNamedWithItsValue) {
  const std::string header = "inputs: {frames: f/*.png}\n";
  std::string m = SceneProblems(header + "dic: {roi: [36, .nan, 605, 444]}\n");
  EXPECT_NE(m.find("dic.roi[1]: got '.nan'; must be a finite number: an integer pixel coordinate"),
            std::string::npos)
      << m;
  m = SceneProblems(header + "dic: {roi: [36, 131, 605.5, 444]}\n");
  EXPECT_NE(m.find("dic.roi[2]: got '605.5'; expected an integer pixel coordinate >= 0"),
            std::string::npos)
      << m;
  // A rule across the elements shows all four values.
  m = SceneProblems(header + "dic: {roi: [605, 131, 36, 444]}\n");
  EXPECT_NE(m.find("dic.roi: got [605, 131, 36, 444]; expected [x0, y0, x1, y1]"),
            std::string::npos)
      << m;
  // The other lists of numbers name their element too.
  m = SceneProblems(header + "dic: {roi_polygon: [[0, 0], [10, .inf], [0, 10]]}\n");
  EXPECT_NE(m.find("dic.roi_polygon[1][1]: got '.inf'; must be a finite number"), std::string::npos)
      << m;
  m = SceneProblems(header + "momentum: {rect_mm: [-50, 0, .nan, 40]}\n");
  EXPECT_NE(m.find("momentum.rect_mm[2]: got '.nan'; must be a finite number"), std::string::npos)
      << m;
  // A list of the wrong length is still described as a whole.
  m = SceneProblems(header + "dic: {roi: [1, 2, 3]}\n");
  EXPECT_NE(m.find("dic.roi: got a list of 3"), std::string::npos) << m;
  // The CLI says the same.
  TestDir dir;
  const std::string scene = FrameScene(dir, "dic: {roi: [36, .nan, 605, 444]}\n");
  ExpectCliFailure("run " + scene + " -o " + dir.File("out"),
                   {scene + ":4: dic.roi[1]: got '.nan'; must be a finite number"});
}

// Before: "truth.h5: dataset momentum/p_gran_fd_Ns: bad file format (got missing)".
TEST(SceneInputFaults, ValidateDemNamesTheKindOfFileItNeeds) {
  TestDir dir;
  const std::string soil_truth = kSource + "/sample_frames/truth.h5";
  const std::string scene = FrameScene(dir, "");
  ASSERT_EQ(RunCli("-q run " + scene + " -o " + dir.File("run")).exit_code, 0);
  const std::string results = dir.File("run/results.h5");
  ExpectCliFailure("validate-dem " + soil_truth + " " + results,
                   {soil_truth + ": is the ground truth of a synthetic scene",
                    "not a DEM truth file", "`impactdic synth --dem` writes"});
  // The arguments swapped: the results file named as such.
  ExpectCliFailure("validate-dem " + results + " " + soil_truth,
                   {results + ": is a run's results file (impactdic run), not a DEM truth file"});
  // A DEM truth file first, then something other than a run's results.
  const std::string dem_truth = dir.File("dem_truth.h5");
  H5Writer out(dem_truth);
  out.CreateGroup("dem");
  out.Commit();
  ExpectCliFailure("validate-dem " + dem_truth + " " + soil_truth,
                   {soil_truth + ": is the ground truth of a synthetic scene",
                    "not a run's results file", "results.h5 of `impactdic run`"});
}

// Before: one view given 12 times calibrated with exit 0: cx 277.7 px (true 323.3), k3 -3.40
// (true 0.12), RMS 0.030 px.
TEST(SceneInputFaults, OneCalibrationViewGivenTwelveTimesIsRefused) {
  TestDir dir;
  const std::string view = kSource + "/calibration/view_00.png";
  std::string same_file, copies;
  for (int k = 0; k < 12; ++k) {
    same_file += " " + view;
    const std::string copy = dir.File("copy_" + std::to_string(k) + ".png");
    fs::copy_file(view, copy);
    copies += " " + copy;
  }
  for (const std::string& images : {same_file, copies}) {
    const std::string output = ExpectCliFailure(
        "calibrate --board 9x6 --square 25" + images + " -o " + dir.File("camera.yaml"),
        {"the board was found in 12 of 12 images, but 11 of them repeat another view",
         "repeated 11 times", "which leaves 1 distinct view", "at least 6 distinct views",
         "2 constraints on the camera matrix", "--min-views"});
    EXPECT_FALSE(fs::exists(dir.File("camera.yaml")));
    // Each dropped image is logged with its reason.
    EXPECT_NE(output.find(images == copies ? "rejected " + dir.File("copy_11.png") +
                                                 ": a repeat of " + dir.File("copy_0.png")
                                           : "rejected " + view + ": given a second time"),
              std::string::npos)
        << output;
  }
  // The 12 distinct sample views plus two copies: the copies count once, the camera is the
  // 12 views' (cx 323.3 px).
  const CliResult r =
      RunCli("calibrate --board 9x6 --square 25 " + Quoted(kSource + "/calibration/view_*.png") +
             " " + dir.File("copy_0.png") + " " + dir.File("copy_1.png") + " -o " +
             dir.File("camera.yaml") + " --format json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* part :
       {"\"images_used\": 12", "\"images_rejected\": 2", "\"images_repeated\": 2"})
    EXPECT_NE(r.output.find(part), std::string::npos) << part << "\n" << r.output;
  EXPECT_NEAR(LoadCalibration(dir.File("camera.yaml")).cx, 323.3, 0.1);
}

// Views of one pose rendered with other noise: different pixels, corners within ~0.05 px.
TEST(SceneInputFaults, NearIdenticalCalibrationViewsCountOnce) {
  const SynthCamera camera = SampleCamera();
  const CheckerboardSpec board;
  const std::vector<BoardPose> poses = CalibrationPoses(camera, board, /*count=*/6, /*seed=*/7);
  CheckerboardRenderOptions render;
  render.supersampling = 4;
  std::vector<cv::Mat> images;
  std::vector<std::string> names;
  for (std::size_t k = 0; k < poses.size(); ++k) {
    render.seed = 10 + k;
    images.push_back(RenderCheckerboard(camera, board, poses[k], render));
    names.push_back("view_" + std::to_string(k));
  }
  CalibrationOptions options;
  const CameraCalibration distinct = CalibrateCamera(images, names, options);
  for (std::uint64_t seed : {50, 51}) {
    render.seed = seed;
    images.push_back(RenderCheckerboard(camera, board, poses[2], render));
    names.push_back("again_" + std::to_string(seed));
  }
  CalibrationSummary summary;
  const CameraCalibration c = CalibrateCamera(images, names, options, &summary);
  EXPECT_EQ(summary.images_used, 6);
  EXPECT_EQ(summary.images_repeated, 2);
  ASSERT_EQ(c.rejected.size(), 2u);
  EXPECT_EQ(c.rejected[0].image, "again_50");
  EXPECT_NE(c.rejected[0].reason.find("a repeat of view_2 (every corner within 0.0"),
            std::string::npos)
      << c.rejected[0].reason;
  // The same calibration as from the distinct views alone.
  EXPECT_EQ(c.fx, distinct.fx);
  EXPECT_EQ(c.cx, distinct.cx);
  // A tolerance of 0 keeps them (only identical pixels are then repeats).
  options.duplicate_tolerance_px = 0;
  EXPECT_EQ(CalibrateCamera(images, names, options).views.size(), 8u);
  // Too few distinct views: the repeats do not make up the number.
  options.duplicate_tolerance_px = 1;
  std::vector<cv::Mat> few(images.begin(), images.begin() + 3);
  std::vector<std::string> few_names(names.begin(), names.begin() + 3);
  few.insert(few.end(), images.end() - 2, images.end());
  few_names.insert(few_names.end(), names.end() - 2, names.end());
  few.push_back(images[3]);
  few_names.push_back(names[3]);
  ExpectErrorContaining([&] { CalibrateCamera(few, few_names, options); },
                        "found in 6 of 6 images, but 2 of them repeat another view (view_2 "
                        "repeated 2 times), which leaves 4 distinct views; at least 6");
}

}  // namespace
}  // namespace impactdic
