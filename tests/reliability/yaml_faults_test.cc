// Fault injection: YAML inputs (scene files, calibration files, synthetic scene specs) that are
// broken in ways yaml-cpp alone accepts or reports poorly. All three go through io LoadYaml.
#include <gtest/gtest.h>

#include <cstddef>
#include <filesystem>
#include <string>

#include "../core/expect_error.h"
#include "../core/test_paths.h"
#include "../io/test_dir.h"
#include "fault_util.h"
#include "impactdic/calib/calibration.h"
#include "impactdic/io/yaml.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/synth/impact_scene.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

// Line 3 and line 6 both set test.mass_kg: yaml-cpp keeps both entries and node["mass_kg"] is the
// first (10), so the 12 kg the user added last was silently ignored before.
constexpr const char* kDuplicateScene = R"(inputs: {frames: frames/*.png, mm_per_px: 0.5}
test:
  mass_kg: 10
  drop_height_m: 0.7
  width_m: 0.15
  mass_kg: 12
)";

TEST(YamlFaults, DuplicateSceneKeyNamesBothLines) {
  TestDir dir;
  const std::string scene = dir.Write("scene.yaml", kDuplicateScene);
  ExpectCliFailure("run " + scene,
                   {scene + ":6", "test.mass_kg", "'mass_kg' a second time at line 6",
                    "first at line 3", "each key at most once"});
  // The library says the same (ParseScene is what `run`, `analyze` and `campaign` use).
  ExpectErrorContaining([&] { ParseScene(kDuplicateScene, scene); }, "first at line 3");
}

TEST(YamlFaults, DuplicateKeyInsideListsAndFlowMapsIsFound) {
  // The key path names list items; flow maps count as maps.
  ExpectErrorContaining(
      [] { LoadYaml("dic:\n  roi_polygon: [[1, 2], {a: 1, b: 2, a: 3}]\n", "s.yaml", "a scene"); },
      "dic.roi_polygon[1].a");
  // The same key in two different maps, and a key equal to a value, are fine.
  EXPECT_NO_THROW(LoadYaml("a: {x: 1}\nb: {x: 2}\nc: a\n", "s.yaml", "a scene"));
  // Anchors and aliases are not expanded by the check (a "billion laughs" document stays cheap).
  EXPECT_NO_THROW(LoadYaml("a: &x [1, 2]\nb: [*x, *x, *x]\nc: *x\n", "s.yaml", "a scene"));
}

TEST(YamlFaults, DuplicateCalibrationKeyNamesBothLines) {
  TestDir dir;
  std::string text = ReadBytes(std::string(impactdic::SourceDir()) + "/calibration/camera.yaml");
  const std::size_t fy = text.find("\nfy:");
  ASSERT_NE(fy, std::string::npos);
  text.insert(fy + 1, "fx: 900\n");  // A second fx right after the first.
  const std::string path = dir.Write("camera.yaml", text);
  const std::string message = ErrorText([&] { LoadCalibration(path); });
  EXPECT_NE(message.find(path), std::string::npos) << message;
  EXPECT_NE(message.find("fx"), std::string::npos) << message;
  EXPECT_NE(message.find("a second time at line"), std::string::npos) << message;
  EXPECT_NE(message.find("first at line"), std::string::npos) << message;
}

TEST(YamlFaults, DuplicateSpecKeyNamesBothLines) {
  TestDir dir;
  const std::string spec =
      dir.Write("spec.yaml", "preset: small\ncamera:\n  fps: 1600\n  fps: 800\n");
  ExpectCliFailure("synth " + spec + " -o " + dir.File("out"),
                   {spec + ":4", "camera.fps", "at line 4 (first at line 3)"});
  ExpectErrorContaining([&] { LoadImpactSceneSpec(spec); }, "camera.fps");
}

TEST(YamlFaults, PngGivenAsCalibrationIsNamedAsAnImage) {
  TestDir dir;
  WriteFrames(dir, "frames", "f_", 0, 4);
  const std::string png = dir.File("frames/f_0000.png");
  const std::string scene =
      dir.Write("scene.yaml", "inputs: {frames: frames/*.png, calibration: frames/f_0000.png}\n");
  ExpectCliFailure("run " + scene + " -o " + dir.File("out"),
                   {png, "got a PNG image", "expected a calibration file (YAML"});
  EXPECT_FALSE(fs::exists(dir.File("out/results.h5")));
}

TEST(YamlFaults, FolderGivenAsSceneIsRefused) {
  TestDir dir;
  const std::string folder = dir.path().string();
  ExpectCliFailure("run " + folder,
                   {folder, "is a folder, not a regular file", "expected a scene file (YAML)"});
  // A device is refused the same way, before anything is read.
  ExpectCliFailure("run /dev/zero", {"/dev/zero", "character device", "a scene file (YAML)"});
}

}  // namespace
}  // namespace impactdic
