#include "impactdic/pipeline/scene.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "../cli/cli_runner.h"
#include "../io/test_dir.h"
#include "impactdic/core/error.h"

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
momentum: {pounder_center_x_px: 150, surface_y_px: 40}
)");
  const Scene s = LoadScene(path);
  EXPECT_EQ(s.name, "test-a");
  EXPECT_EQ(s.inputs.frames, (dir.path() / "sub/frames/*.png").string());
  EXPECT_EQ(s.inputs.sensor, (dir.path() / "daq/sensor.csv").string());
  EXPECT_EQ(s.inputs.calibration, "/abs/cal.yaml");
  EXPECT_EQ(s.outputs.folder, (dir.path() / "sub/results").string());
  EXPECT_DOUBLE_EQ(s.model.pounder_mass_kg, 13);
  EXPECT_DOUBLE_EQ(s.model.depth_m, 0.192);       // paper default t_z
  EXPECT_DOUBLE_EQ(s.model.density_kg_m3, 1550);  // paper default rho_d
  EXPECT_NEAR(s.ImpactVelocity(), std::sqrt(2 * 9.81 * 1.2), 1e-12);
  EXPECT_NEAR(s.model.impact_velocity_m_s, s.ImpactVelocity(), 0);
  EXPECT_NEAR(s.model.ContactArea_m2(), 0.2 * 0.192, 1e-15);
  EXPECT_EQ(s.dic.options.grid.subset_size, 31);
  EXPECT_EQ(s.dic.options.grid.step, 10);
  EXPECT_EQ(s.dic.options.update.policy, "every:5");
  EXPECT_EQ(s.dic.roi[2], 300);
  ASSERT_EQ(s.dic.roi_polygon.size(), 3u);
  EXPECT_DOUBLE_EQ(s.dic.roi_polygon[2][1], 190.5);
  EXPECT_EQ(s.dic.mask, (dir.path() / "sub/masks/soil.png").string());
  EXPECT_DOUBLE_EQ(s.model.friction_K, 50);
  EXPECT_DOUBLE_EQ(s.model.sigmoid_rate_b_per_s, 2500);
  EXPECT_DOUBLE_EQ(s.sensor.options.cutoff_hz, 1500);
  EXPECT_EQ(s.momentum.options.grid_cols, 6);
  EXPECT_EQ(s.momentum.options.grid_rows, 2);
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
  EXPECT_DOUBLE_EQ(s.ImpactVelocity(), 3.5);
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
        "test.width_m: got '0'",
        "dic.subset_size: got '24'; expected an odd integer in [5, 201] px",
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

// outputs.plot/.video/.velocity_map/.strain_map: how the figures and animations are drawn, read
// into the render options of the run (and of `impactdic render`, the same keys as flags).
TEST(Scene, DrawingKeysReachTheRenderOptions) {
  const Scene defaults = ParseScene("inputs: {frames: f}\ntest: {drop_height_m: 1}\n", "s.yaml");
  const RenderResultsOptions d = SceneRenderOptions(defaults);
  EXPECT_EQ(d.plot.width_px, PlotOptions{}.width_px);
  EXPECT_TRUE(std::isnan(d.snapshot_overlay.max_speed_mm_s));
  EXPECT_TRUE(std::isnan(d.strain_overlay.eps_v_limit));
  const Scene s = ParseScene(R"(
inputs: {frames: f}
test: {drop_height_m: 1}
outputs:
  png_frames: true
  plot: {width_px: 640, font: Liberation Sans}
  video: {fps: 10, codec: mjpg, h264_fourccs: [avc1]}
  velocity_map: {max_speed_mm_s: 500, unit: m/s, arrows: false, max_width_px: 1000}
  strain_map: {eps_v_limit: 0.02, gamma_max_limit: auto, shear_bands: false}
)",
                             "s.yaml");
  const RenderResultsOptions r = SceneRenderOptions(s);
  EXPECT_EQ(r.plot.width_px, 640);
  EXPECT_EQ(r.plot.font, "Liberation Sans");
  EXPECT_EQ(r.animation_options.fps, 10);
  EXPECT_EQ(r.animation_options.codec, VideoCodec::kMjpg);
  EXPECT_EQ(r.animation_options.h264_fourccs, std::vector<std::string>{"avc1"});
  EXPECT_TRUE(r.png_frames);
  for (const VelocityOverlayOptions& v : {r.snapshot_overlay, r.animation_options.overlay}) {
    EXPECT_EQ(v.max_speed_mm_s, 500);
    EXPECT_EQ(v.unit, VelocityDisplayUnit::kMPerS);
    EXPECT_FALSE(v.arrows);
    EXPECT_EQ(v.max_width_px, 1000);
  }
  EXPECT_EQ(r.strain_overlay.eps_v_limit, 0.02);
  EXPECT_TRUE(std::isnan(r.strain_overlay.gamma_max_limit));
  EXPECT_FALSE(r.strain_overlay.shear_bands);

  const std::string base = "inputs: {frames: f}\ntest: {drop_height_m: 1}\noutputs:\n";
  std::string msg = LoadError(base + "  plot: {widht_px: 640}\n");
  EXPECT_NE(msg.find("outputs.plot.widht_px: unknown key (did you mean 'width_px'?)"),
            std::string::npos)
      << msg;
  msg = LoadError(base + "  velocity_map: {max_speed_mm_s: -1}\n");
  EXPECT_NE(msg.find("outputs.velocity_map.max_speed_mm_s"), std::string::npos) << msg;
  EXPECT_NE(msg.find("auto or a speed > 0 mm/s"), std::string::npos) << msg;
  msg = LoadError(base + "  strain_map: {min_width_px: 900, max_width_px: 800}\n");
  EXPECT_NE(msg.find("max_width_px"), std::string::npos) << msg;
  msg = LoadError(base + "  video: {h264_fourccs: avc}\n");
  EXPECT_NE(msg.find("outputs.video.h264_fourccs"), std::string::npos) << msg;
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

// dic.min_zncc is the validity threshold; the auto reference update has its own key, bound to
// UpdateOptions::auto_min_zncc (docs/scene_keys.md says so).
TEST(Scene, MinZnccAndAutoMinZnccSetTheirOwnLibraryFields) {
  const Scene s =
      ParseScene("inputs: {frames: f}\ndic: {min_zncc: 0.7, auto_min_zncc: 0.9}\n", "x/scene.yaml");
  EXPECT_DOUBLE_EQ(s.dic.options.icgn.min_zncc, 0.7);
  EXPECT_DOUBLE_EQ(s.dic.options.update.auto_min_zncc, 0.9);
}

// The model requires u >= 1 (F_dyn must resist the motion): the scene refuses u = 0.5 at load,
// naming model.u, its line and the model's range.
TEST(Scene, ModelParameterOutsideTheModelsRangeIsRefusedAtLoad) {
  const std::string msg = LoadError("inputs: {frames: f}\nmodel:\n  u: 0.5\n");
  EXPECT_NE(msg.find("scene.yaml:3: model.u: got '0.5'; expected a damping factor u (>= 1: F_dyn "
                     "must resist the motion) in [1, 1000]"),
            std::string::npos)
      << msg;
  EXPECT_EQ(msg.find("damping_factor_u"), std::string::npos) << msg;
}

// The momentum stage runs after the correlation: without the pounder's position (or rect_mm) it
// could not select its grid, so a scene with a sensor record is refused at load, not after
// minutes of correlation.
TEST(Scene, MomentumGridPositionIsRequiredAtLoadWhenTheMomentumStageRuns) {
  const std::string msg = LoadError("inputs: {frames: f, sensor: daq.csv}\n");
  EXPECT_NE(msg.find("momentum.pounder_center_x_px / surface_y_px: missing"), std::string::npos)
      << msg;
  EXPECT_NE(LoadError("inputs: {frames: f, sensor: daq.csv}\nmomentum: {surface_y_px: 3}\n")
                .find("momentum.pounder_center_x_px: missing"),
            std::string::npos);
  // Not needed without a sensor record, or when the momentum stage is not run, or with rect_mm.
  EXPECT_EQ(LoadError("inputs: {frames: f}\n"), "");
  EXPECT_EQ(LoadError("inputs: {frames: f, sensor: daq.csv}\nstages: [correlate, sensor]\n"), "");
  EXPECT_EQ(LoadError("inputs: {frames: f, sensor: daq.csv}\nmomentum: {rect_mm: [0, 0, 9, 9]}\n"),
            "");
}

// ... and `impactdic run` stops there, before any frame is read: the frames folder does not
// exist, yet the only error is model.u, and no output folder is made.
TEST(Scene, RunRefusesABadModelParameterBeforeReadingAnyFrame) {
  TestDir dir;
  const std::string scene = dir.Write("scene.yaml",
                                      "inputs: {frames: no_such_folder/*.png, mm_per_px: 1}\n"
                                      "model: {u: 0.5}\n");
  const CliResult r = RunCli("run " + scene + " -o " + dir.File("out"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("model.u: got '0.5'"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("no_such_folder"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir.File("out")));
}

}  // namespace
}  // namespace impactdic
