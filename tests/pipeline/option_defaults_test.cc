// Each option is defined once: a scene that leaves a key out, and a CLI command that is not given
// the flag, get the library's default. These tests fail if a scene or CLI default drifts from the
// library option structs (docs/architecture.md, "Options").
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <opencv2/core.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "../cli/cli_runner.h"
#include "../core/test_paths.h"
#include "impactdic/calib/calibration.h"
#include "impactdic/core/error.h"
#include "impactdic/dic/bspline.h"
#include "impactdic/dic/options.h"
#include "impactdic/io/yaml.h"
#include "impactdic/model/impact_model.h"
#include "impactdic/momentum/momentum.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/preprocess/preprocess.h"
#include "impactdic/render/animation.h"
#include "impactdic/sensor/sensor.h"

namespace impactdic {
namespace {

// NaN == NaN for "unset" defaults.
void ExpectSame(double scene, double library, const char* field) {
  if (std::isnan(library)) {
    EXPECT_TRUE(std::isnan(scene)) << field << ": " << scene;
  } else {
    EXPECT_EQ(scene, library) << field;
  }
}

Scene MinimalScene() { return ParseScene("inputs: {frames: f/*.png}\n", "x/scene.yaml"); }

TEST(OptionDefaults, SceneDicKeysDefaultToDicOptions) {
  const DicOptions& s = MinimalScene().dic.options;
  const DicOptions d;
  EXPECT_EQ(s.mode, d.mode);
  EXPECT_EQ(s.grid.subset_size, d.grid.subset_size);
  EXPECT_EQ(s.grid.step, d.grid.step);
  EXPECT_EQ(s.grid.roi, d.grid.roi);
  EXPECT_TRUE(s.grid.mask.empty());
  EXPECT_EQ(s.init.search_radius_px, d.init.search_radius_px);
  EXPECT_EQ(s.init.seed_spacing, d.init.seed_spacing);
  EXPECT_EQ(s.init.min_search_zncc, d.init.min_search_zncc);
  EXPECT_EQ(s.icgn.interpolation, d.icgn.interpolation);
  EXPECT_EQ(s.icgn.shape, d.icgn.shape);
  EXPECT_EQ(s.icgn.convergence_px, d.icgn.convergence_px);
  EXPECT_EQ(s.icgn.max_iterations, d.icgn.max_iterations);
  EXPECT_EQ(s.icgn.min_zncc, d.icgn.min_zncc);
  EXPECT_EQ(s.icgn.min_contrast, d.icgn.min_contrast);
  EXPECT_EQ(s.icgn.max_saturated_fraction, d.icgn.max_saturated_fraction);
  EXPECT_EQ(s.icgn.max_uncertainty_px, d.icgn.max_uncertainty_px);
  EXPECT_EQ(s.update.policy, d.update.policy);
  EXPECT_EQ(s.update.auto_min_zncc, d.update.auto_min_zncc);
  EXPECT_EQ(s.update.auto_rescue_decorrelation, d.update.auto_rescue_decorrelation);
}

TEST(OptionDefaults, SceneModelAndTestKeysDefaultToImpactModelParameters) {
  const Scene scene = MinimalScene();
  const ImpactModelParameters& s = scene.model;
  const ImpactModelParameters d;
  ExpectSame(s.pounder_mass_kg, d.pounder_mass_kg, "pounder_mass_kg");
  ExpectSame(s.width_m, d.width_m, "width_m");
  ExpectSame(s.depth_m, d.depth_m, "depth_m");
  ExpectSame(s.added_mass_kg, d.added_mass_kg, "added_mass_kg");
  ExpectSame(s.friction_K, d.friction_K, "friction_K");
  ExpectSame(s.damping_exponent_n, d.damping_exponent_n, "damping_exponent_n");
  ExpectSame(s.damping_factor_u, d.damping_factor_u, "damping_factor_u");
  ExpectSame(s.sigmoid_delay_T_s, d.sigmoid_delay_T_s, "sigmoid_delay_T_s");
  ExpectSame(s.sigmoid_rate_b_per_s, d.sigmoid_rate_b_per_s, "sigmoid_rate_b_per_s");
  ExpectSame(s.density_kg_m3, d.density_kg_m3, "density_kg_m3");
  ExpectSame(s.gravity_m_s2, d.gravity_m_s2, "gravity_m_s2");
  ExpectSame(s.bed_height_m, d.bed_height_m, "bed_height_m");
  // The default drop height gives the library's default impact velocity (0.7 m, g = 9.81).
  EXPECT_NEAR(scene.ImpactVelocity(), d.impact_velocity_m_s, 1e-12);
  const ImpactSolverOptions& so = scene.solver;
  const ImpactSolverOptions sd;
  EXPECT_EQ(so.solver, sd.solver);
  ExpectSame(so.rtol, sd.rtol, "rtol");
  ExpectSame(so.atol, sd.atol, "atol");
  EXPECT_EQ(so.error_estimator, sd.error_estimator);
}

TEST(OptionDefaults, ScenePreprocessSensorAndMomentumKeysDefaultToTheirLibraries) {
  const Scene scene = MinimalScene();
  const PreprocessOptions pd;
  EXPECT_EQ(scene.preprocess.gaussian.mode, pd.gaussian.mode);
  EXPECT_EQ(scene.preprocess.gaussian.auto_threshold_px, pd.gaussian.auto_threshold_px);
  EXPECT_EQ(scene.preprocess.gaussian.sigma_px, pd.gaussian.sigma_px);
  EXPECT_EQ(scene.preprocess.gaussian.kernel_size, pd.gaussian.kernel_size);
  EXPECT_EQ(scene.preprocess.clahe.enabled, pd.clahe.enabled);
  EXPECT_EQ(scene.preprocess.clahe.clip_limit, pd.clahe.clip_limit);
  EXPECT_EQ(scene.preprocess.clahe.tile_grid, pd.clahe.tile_grid);
  EXPECT_EQ(scene.preprocess.undistort, pd.undistort);
  EXPECT_EQ(scene.preprocess.undistortion.skip_threshold_px, pd.undistortion.skip_threshold_px);
  EXPECT_EQ(scene.preprocess.undistortion.interpolation, pd.undistortion.interpolation);

  const SensorOptions s = MakeSensorOptions(scene), sd;
  EXPECT_EQ(s.columns.time, sd.columns.time);
  EXPECT_EQ(s.columns.accel, sd.columns.accel);
  EXPECT_EQ(s.columns.accel_unit, sd.columns.accel_unit);
  EXPECT_EQ(s.columns.exposure, sd.columns.exposure);
  EXPECT_EQ(s.g_m_s2, sd.g_m_s2);
  EXPECT_EQ(s.cutoff_hz, sd.cutoff_hz);
  EXPECT_EQ(s.offset_reference, sd.offset_reference);
  EXPECT_EQ(s.quiet_window_s, sd.quiet_window_s);
  EXPECT_EQ(s.integrate_from, sd.integrate_from);
  EXPECT_EQ(s.impact_threshold_g, sd.impact_threshold_g);
  EXPECT_EQ(s.quiet_guard_s, sd.quiet_guard_s);
  EXPECT_EQ(s.noise_band_sigma, sd.noise_band_sigma);
  EXPECT_EQ(s.stop_velocity_m_s, sd.stop_velocity_m_s);
  EXPECT_EQ(s.columns.force, sd.columns.force);

  // The pounder and soil reach the momentum stage from test.*: the same defaults as the
  // momentum library's own.
  Scene with_grid = scene;
  with_grid.momentum.pounder_center_x_px = 100;
  with_grid.momentum.surface_y_px = 50;
  const MomentumOptions m = MakeMomentumOptions(with_grid, /*mm_per_px=*/1), md;
  EXPECT_EQ(m.pounder_mass_kg, md.pounder_mass_kg);
  EXPECT_EQ(m.pounder_width_m, md.pounder_width_m);
  EXPECT_EQ(m.depth_m, md.depth_m);
  EXPECT_EQ(m.density_kg_m3, md.density_kg_m3);
  EXPECT_EQ(m.grid_cols, md.grid_cols);
  EXPECT_EQ(m.grid_rows, md.grid_rows);
  EXPECT_EQ(m.rect_mm, md.rect_mm);
  EXPECT_EQ(m.min_valid_fraction, md.min_valid_fraction);
  EXPECT_EQ(m.velocity_match_tolerance, md.velocity_match_tolerance);
  EXPECT_EQ(m.sand_accel_tolerance, md.sand_accel_tolerance);
  EXPECT_EQ(m.fit_sigmoid, md.fit_sigmoid);
  EXPECT_EQ(m.sigmoid.confidence, md.sigmoid.confidence);
}

// What CLI11 shows as an option's default ("--subset INT=25") for `value` (it formats with a
// stream).
template <typename T>
std::string Shown(const T& value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

// `impactdic SUB --help` shows `flag` with the default `value`.
void ExpectHelpDefault(const std::string& help, const std::string& flag, const std::string& value) {
  const std::string shown = " " + flag + " ";
  std::size_t at = help.find(shown);
  ASSERT_NE(at, std::string::npos) << flag << " not in:\n" << help;
  const std::size_t eq = help.find('=', at);
  const std::size_t end = help.find_first_of(" \n", eq);
  ASSERT_NE(eq, std::string::npos) << flag;
  EXPECT_EQ(help.substr(eq + 1, end - eq - 1), value) << flag << " in:\n" << help;
}

TEST(OptionDefaults, CliCommandsShowTheLibraryDefaults) {
  const CliResult correlate = RunCli("correlate --help");
  ASSERT_EQ(correlate.exit_code, 0) << correlate.output;
  const DicOptions d;
  ExpectHelpDefault(correlate.output, "--subset", Shown(d.grid.subset_size));
  ExpectHelpDefault(correlate.output, "--step", Shown(d.grid.step));
  ExpectHelpDefault(correlate.output, "--interp", ToString(d.icgn.interpolation));
  ExpectHelpDefault(correlate.output, "--shape", ToString(d.icgn.shape));
  ExpectHelpDefault(correlate.output, "--reference-update", ReferenceUpdateText(d.update));
  ExpectHelpDefault(correlate.output, "--search-radius", Shown(d.init.search_radius_px));
  ExpectHelpDefault(correlate.output, "--min-zncc", Shown(d.icgn.min_zncc));
  ExpectHelpDefault(correlate.output, "--max-uncertainty",
                    MaxUncertaintyText(d.icgn.max_uncertainty_px));
  ExpectHelpDefault(correlate.output, "--outlier-check", d.outliers.enabled ? "on" : "off");
  ExpectHelpDefault(correlate.output, "--outlier-threshold", Shown(d.outliers.threshold));
  ExpectHelpDefault(correlate.output, "--outlier-noise", Shown(d.outliers.noise_px));
  ExpectHelpDefault(correlate.output, "--outlier-sigma-factor", Shown(d.outliers.sigma_factor));
  ExpectHelpDefault(correlate.output, "--mode", ToString(d.mode));

  const CliResult model = RunCli("model --help");
  ASSERT_EQ(model.exit_code, 0) << model.output;
  const ImpactModelParameters p;
  ExpectHelpDefault(model.output, "--depth", Shown(p.depth_m));
  ExpectHelpDefault(model.output, "--K", Shown(p.friction_K));
  ExpectHelpDefault(model.output, "--n", Shown(p.damping_exponent_n));
  ExpectHelpDefault(model.output, "--u", Shown(p.damping_factor_u));
  ExpectHelpDefault(model.output, "--T", Shown(p.sigmoid_delay_T_s));
  ExpectHelpDefault(model.output, "--b", Shown(p.sigmoid_rate_b_per_s));
  ExpectHelpDefault(model.output, "--rho", Shown(p.density_kg_m3));
  ExpectHelpDefault(model.output, "--g", Shown(p.gravity_m_s2));
  ExpectHelpDefault(model.output, "--bed-height", Shown(p.bed_height_m));
  ExpectHelpDefault(model.output, "--solver", ToString(ImpactSolverOptions{}.solver));

  const CliResult analyze = RunCli("analyze --help");
  ASSERT_EQ(analyze.exit_code, 0) << analyze.output;
  const SensorOptions s;
  ExpectHelpDefault(analyze.output, "--cutoff", Shown(s.cutoff_hz));
  ExpectHelpDefault(analyze.output, "--time-column", s.columns.time);
  ExpectHelpDefault(analyze.output, "--accel-unit", ToString(s.columns.accel_unit));
  ExpectHelpDefault(analyze.output, "--exposure-column", s.columns.exposure);
  ExpectHelpDefault(analyze.output, "--offset-reference", ToString(s.offset_reference));
  ExpectHelpDefault(analyze.output, "--quiet-window", Shown(s.quiet_window_s));
  ExpectHelpDefault(analyze.output, "--impact-threshold", Shown(s.impact_threshold_g));

  const CliResult calibrate = RunCli("calibrate --help");
  ASSERT_EQ(calibrate.exit_code, 0) << calibrate.output;
  ExpectHelpDefault(calibrate.output, "--max-rms", Shown(CalibrationOptions{}.max_rms_px));
  ExpectHelpDefault(calibrate.output, "--min-views", Shown(CalibrationOptions{}.min_views));

  const CliResult render = RunCli("render --help");
  ASSERT_EQ(render.exit_code, 0) << render.output;
  ExpectHelpDefault(render.output, "--fps", Shown(AnimationOptions{}.fps));
  ExpectHelpDefault(render.output, "--codec", ToString(AnimationOptions{}.codec));
}

// The scene keys that are not one field of an option table (ParseScene reads them itself): the
// key, a value as YAML, its default and its meaning. docs/scene_keys.md lists them after the
// tables' keys, so that page is the one place every key is.
struct ExtraKey {
  std::string section, key, example, default_text, meaning;
};

std::vector<ExtraKey> ExtraKeys() {
  std::string stages;
  for (const std::string& s : AllSceneStages()) stages += (stages.empty() ? "" : ", ") + s;
  return {
      {"", "name", "t10-h07-d15", "the file's stem", "Free-form name of the test"},
      {"", "stages", "[" + stages + "]", "all whose inputs exist",
       "The stages to run, a list of " + stages +
           " (correlate needs frames; frames alone reads and checks them)"},
      {"dic", "roi", "[10, 10, 200, 150]", "the whole image less margins",
       "Region of interest [x0, y0, x1, y1] in px of the first frame, inside it"},
      {"dic", "roi_polygon", "[[10, 10], [200, 10], [100, 150]]", "none",
       "Only subsets centred inside this polygon ([[x, y], ...] in px, >= 3 vertices)"},
      {"momentum", "rect_mm", "[0, 0, 50, 20]", "from the pounder's position",
       "Momentum grid rectangle [x0, y0, x1, y1] in panel mm instead of the pounder's position"},
  };
}

// Each key the page adds to the tables' is one ParseScene reads: its example parses, and the same
// key misspelt is refused (so the check can fail).
TEST(OptionDefaults, TheSceneReferencesExtraKeysAreRead) {
  for (const ExtraKey& k : ExtraKeys()) {
    const auto yaml = [&](const std::string& key) {
      std::string text = "inputs: {frames: f/*.png}\n";
      return text + (k.section.empty() ? key + ": " + k.example + "\n"
                                       : k.section + ":\n  " + key + ": " + k.example + "\n");
    };
    EXPECT_NO_THROW(ParseScene(yaml(k.key), "x/scene.yaml")) << k.key;
    EXPECT_THROW(ParseScene(yaml(k.key + "_x"), "x/scene.yaml"), Error) << k.key;
  }
}

// docs/scene_keys.md is the scene's one reference: the format, then every key of the scene tables
// (YamlOptionTable::Reference: key, default = the bound struct's value, expected values, meaning)
// and the keys ParseScene reads itself. Run with IMPACTDIC_UPDATE_DOCS=1 to rewrite it after
// changing an option.
TEST(OptionDefaults, SceneKeyReferenceIsGeneratedFromTheBindings) {
  Scene scene;
  std::string expected =
      "# Scene keys\n\n"
      "<!-- Generated from the scene's option tables (`SceneOptionTables`, src/pipeline/scene.cc) "
      "by\n`IMPACTDIC_UPDATE_DOCS=1 build/release/tests/pipeline/pipeline_test "
      "--gtest_filter='OptionDefaults.*'`;\nthe test fails when this page is out of date. -->\n\n"
      "A scene is a YAML file naming one test's inputs and parameters; `impactdic run "
      "SCENE.yaml` runs it.\n`impactdic init DIR` writes DIR/scene.yaml with every key below at "
      "its default, its range and\nmeaning as comments (pipeline/scene_template.h); fill in the "
      "lines marked `# REQUIRED` (the frames,\nthe frame rate, the scale: a calibration or "
      "`inputs.mm_per_px`; with a sensor CSV, the pounder's\nposition). The sample's scene is "
      "`sample_frames/scene.yaml`; the guide ([guide.md](guide.md)) writes one\nstep by step.\n\n"
      "Every key is optional except `inputs.frames`; a key left out has the default of the "
      "library option\nstruct it is bound to (the paper's values; where each is defined: "
      "[architecture.md](architecture.md#options)).\nEvery value is checked when the scene is "
      "loaded, before any frame is read, and relative paths\nresolve against the scene file's "
      "folder. Loading reports every problem at once with the file, line,\nkey path, the value "
      "found and what is expected; unknown keys are errors with a \"did you mean\"\nsuggestion, "
      "and a key given twice in one map is an error naming both lines. Every key is also a\n"
      "flag of the commands that use it (`--dic.subset_size 31`: "
      "[command_line.md](command_line.md#options-and-errors)).\n\n"
      "## Keys of the option tables\n\n"
      "| key | default | expected | meaning |\n|---|---|---|---|\n";
  for (const YamlOptionTable& table : SceneOptionTables(&scene)) expected += table.Reference();
  expected +=
      "\n## Keys that are not one option field\n\n"
      "| key | example | default | meaning |\n|---|---|---|---|\n";
  for (const ExtraKey& k : ExtraKeys()) {
    expected += "| `" + (k.section.empty() ? "" : k.section + ".") + k.key + "` | `" + k.example +
                "` | " + k.default_text + " | " + k.meaning + " |\n";
  }
  const std::string path = std::string(impactdic::SourceDir()) + "/docs/scene_keys.md";
  if (std::getenv("IMPACTDIC_UPDATE_DOCS")) std::ofstream(path) << expected;
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), expected)
      << "docs/scene_keys.md is out of date; regenerate it (see the test)";
}

}  // namespace
}  // namespace impactdic
