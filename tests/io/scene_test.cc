#include "impactdic/io/scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "impactdic/core/error.h"
#include "test_dir.h"

namespace impactdic {
namespace {

std::string LoadError(const std::string& yaml) {
  try {
    ParseScene(yaml, "/data/tests/scene.yaml");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(Scene, ValidSceneWithDefaultsAndRelativePaths) {
  TestDir dir;
  std::filesystem::create_directories(dir.path() / "sub");
  const std::string path = dir.Write("sub/scene.yaml", R"(
name: test-a
inputs:
  frames: frames/*.png
  fps: 1600
  sensor: ../daq/sensor.csv
  calibration: /abs/cal.yaml
test:
  mass_kg: 13
  drop_height_m: 1.2
  width_m: 0.2
dic:
  subset_size: 31
  reference_update: every:5
  roi: [10, 20, 300, 200]
  roi_polygon: [[20, 30], [280, 30], [150, 190.5]]
  mask: masks/soil.png
)");
  const Scene s = LoadScene(path);
  EXPECT_EQ(s.name, "test-a");
  EXPECT_EQ(s.inputs.frames, (dir.path() / "sub/frames/*.png").string());
  EXPECT_EQ(s.inputs.sensor, (dir.path() / "daq/sensor.csv").string());
  EXPECT_EQ(s.inputs.calibration, "/abs/cal.yaml");
  EXPECT_EQ(s.outputs.folder, (dir.path() / "sub/results").string());
  EXPECT_DOUBLE_EQ(s.test.mass_kg, 13);
  EXPECT_DOUBLE_EQ(s.test.depth_m, 0.192);       // paper default t_z
  EXPECT_DOUBLE_EQ(s.test.density_kg_m3, 1550);  // paper default rho_d
  EXPECT_NEAR(s.test.ImpactVelocity(), std::sqrt(2 * 9.81 * 1.2), 1e-12);
  EXPECT_NEAR(s.test.ContactArea(), 0.2 * 0.192, 1e-15);
  EXPECT_EQ(s.dic.subset_size, 31);
  EXPECT_EQ(s.dic.step, 10);
  EXPECT_EQ(s.dic.reference_update, "every:5");
  EXPECT_EQ(s.dic.roi[2], 300);
  ASSERT_EQ(s.dic.roi_polygon.size(), 3u);
  EXPECT_DOUBLE_EQ(s.dic.roi_polygon[2][1], 190.5);
  EXPECT_EQ(s.dic.mask, (dir.path() / "sub/masks/soil.png").string());
  EXPECT_DOUBLE_EQ(s.model.K, 50);
  EXPECT_DOUBLE_EQ(s.model.b_per_s, 2500);
  EXPECT_DOUBLE_EQ(s.sensor.cutoff_hz, 1500);
  EXPECT_EQ(s.momentum.grid_cols, 6);
  EXPECT_EQ(s.momentum.grid_rows, 2);
  EXPECT_EQ(s.stages, AllSceneStages());
  EXPECT_NE(s.yaml_text.find("test-a"), std::string::npos);
}

TEST(Scene, ImpactVelocityOverridesHeightAndStagesKeepPipelineOrder) {
  const Scene s = ParseScene(R"(
inputs: {frames: f}
test: {impact_velocity_m_s: 3.5, drop_height_m: 0.2}
stages: [momentum, correlate]
)",
                             "x/scene.yaml");
  EXPECT_DOUBLE_EQ(s.test.ImpactVelocity(), 3.5);
  EXPECT_EQ(s.stages, (std::vector<std::string>{"correlate", "momentum"}));
  EXPECT_TRUE(s.HasStage("momentum"));
  EXPECT_FALSE(s.HasStage("model"));
}

TEST(Scene, EachKindOfInvalidValueIsReportedWithKeyPathValueAndExpectation) {
  const std::string msg = LoadError(R"(
inputs:
  frames: f
  fps: -3
test:
  mass_kg: heavy
  width_m: 0
dic:
  subset_size: 24
  interpolation: bicubik
  reference_update: every:0
  roi: [1, 2, 3]
  roi_polygon: [[0, 0], [5, -1]]
model:
  n: 1.5
outputs:
  figures: maybe
stages: [correlate, momentun]
)");
  EXPECT_NE(msg.find("/data/tests/scene.yaml"), std::string::npos) << msg;
  for (const char* expected :
       {"inputs.fps: got '-3'; expected a camera frame rate in [1, 1e+07] 1/s",
        "test.mass_kg: got 'heavy'; expected a pounder mass in [0.01, 100000] kg",
        "test.width_m: got '0'", "dic.subset_size: got '24'; expected an odd subset size >= 5",
        "dic.interpolation: got 'bicubik'; expected one of bicubic, biquintic (did you mean "
        "'bicubic'?)",
        "dic.reference_update: got 'every:0'", "dic.roi: got a list of 3",
        "dic.roi_polygon: got a list of 2; expected a list of at least 3 vertices",
        "model.n: got '1.5'", "outputs.figures: got 'maybe'; expected true or false",
        "unknown stage 'momentun' (did you mean 'momentum'?)"}) {
    EXPECT_NE(msg.find(expected), std::string::npos) << "missing: " << expected << "\nin:\n" << msg;
  }
  EXPECT_NE(msg.find("11 problems"), std::string::npos) << msg;
  // Line numbers are given: the subset_size is on line 9 of the text.
  EXPECT_NE(msg.find("scene.yaml:9: dic.subset_size"), std::string::npos) << msg;
}

TEST(Scene, UnknownKeyIsAnErrorWithSuggestion) {
  const std::string msg = LoadError(R"(
inputs: {frames: f}
dic:
  subset_sise: 25
tset: {}
)");
  EXPECT_NE(msg.find("dic.subset_sise: unknown key (did you mean 'subset_size'?)"),
            std::string::npos)
      << msg;
  EXPECT_NE(msg.find("tset: unknown key (did you mean 'test'?)"), std::string::npos) << msg;
}

TEST(Scene, MissingFramesAndBadYamlAndMissingFile) {
  EXPECT_NE(LoadError("test: {mass_kg: 10}\n").find("inputs.frames: missing"), std::string::npos);
  const std::string bad = LoadError("inputs: [unclosed\n");
  EXPECT_NE(bad.find("scene.yaml:"), std::string::npos) << bad;
  EXPECT_NE(bad.find("YAML"), std::string::npos) << bad;
  try {
    LoadScene("/nonexistent/scene.yaml");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kFileNotFound);
    EXPECT_NE(std::string(e.what()).find("/nonexistent/scene.yaml"), std::string::npos);
  }
}

TEST(Scene, ClosestMatchOnlySuggestsCloseWords) {
  EXPECT_EQ(ClosestMatch("subset_sise", {"subset_size", "step"}), "subset_size");
  EXPECT_EQ(ClosestMatch("zzzzzz", {"subset_size", "step"}), "");
}

}  // namespace
}  // namespace impactdic
