// Every scene key is a command-line flag named as the key (pipeline/scene_flags.h): the keys of
// dic.* and preprocess.* in `correlate`, of test.* and model.* in `model`, and each command's short
// aliases; a key flag's value is the key's, and it reaches the library (dic.max_iterations,
// dic.convergence_px change the correlation).
#include "impactdic/pipeline/scene_flags.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <functional>
#include <numeric>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "../core/test_paths.h"
#include "../io/test_dir.h"
#include "../reliability/fault_util.h"
#include "cli_runner.h"
#include "impactdic/core/error.h"
#include "impactdic/dic/options.h"
#include "impactdic/io/csv.h"
#include "impactdic/io/image_io.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/synth/speckle.h"

namespace impactdic {
namespace {

// The help text of `command` names every key of `sections` as "--KEY", and each alias.
void ExpectEveryKeyInHelp(const std::string& command, const std::vector<std::string>& sections) {
  const CliResult help = RunCli(command + " --help");
  ASSERT_EQ(help.exit_code, 0) << help.output;
  const std::vector<SceneKeyFlag> flags = SceneKeyFlags(sections);
  ASSERT_FALSE(flags.empty());
  for (const SceneKeyFlag& f : flags)
    EXPECT_NE(help.output.find("--" + f.key + " "), std::string::npos)
        << "--" << f.key << " not in `impactdic " << command << " --help`";
  for (const SceneFlagAlias& a : SceneFlagAliases()) {
    if (command == a.command) {
      EXPECT_NE(help.output.find(std::string(a.alias) + " "), std::string::npos) << a.alias;
    }
  }
}

TEST(SceneFlags, EveryKeyOfTheTablesIsAFlagOfItsCommand) {
  // The sections of the keys each command runs on (run and analyze take a scene file).
  ExpectEveryKeyInHelp("correlate", {"dic", "preprocess"});
  ExpectEveryKeyInHelp("model", {"test", "model"});
  ExpectEveryKeyInHelp("analyze", {"sensor", "momentum"});
  ExpectEveryKeyInHelp("run", {"sensor", "momentum", "outputs"});
  // Every section of the table: the lists above are checked against it.
  Scene scene;
  std::vector<std::string> keys;
  for (const YamlOptionTable& t : SceneOptionTables(&scene))
    for (const auto& e : t.entries()) keys.push_back(t.section() + "." + e.key);
  for (const char* key : {"dic.max_iterations", "dic.convergence_px", "model.K", "test.mass_kg",
                          "preprocess.gaussian.sigma", "preprocess.clahe.enabled",
                          "sensor.cutoff_hz", "momentum.grid_cols", "outputs.figures"})
    EXPECT_NE(std::find(keys.begin(), keys.end(), key), keys.end()) << key;
}

// The number of fields of the aggregate T: the most initializers T{...} takes.
struct AnyField {
  template <typename T>
  operator T() const;  // NOLINT(google-explicit-constructor): only in unevaluated contexts.
};
template <typename T, typename... Fields>
constexpr std::size_t FieldCount() {
  if constexpr (requires { T{Fields{}..., AnyField{}}; }) {
    return FieldCount<T, Fields..., AnyField>();
  } else {
    return sizeof...(Fields);
  }
}

// A field of a library's options, by its path in the struct after the library's name
// (InternalOption), and the scene key that reaches it with a value other than the default (none:
// InternalLibraryOptions). `changed` says whether the options the stage takes differ from the
// default scene's: a field the pipeline sets from another key (sensor.g_m_s2 from test.g_m_s2)
// is reached by that key.
struct LibraryField {
  const char* field;
  const char* key;
  const char* value;
  std::function<bool(const Scene&)> changed;
};

// Equal, NaN equal to NaN (an unset tolerance or release time).
template <typename T>
bool Same(const T& a, const T& b) {
  if constexpr (std::is_floating_point_v<T>) {
    if (std::isnan(a) && std::isnan(b)) return true;
  }
  return a == b;
}

// `changed` of a field `get` of the options `make` builds from a scene: differs from the default
// scene's.
template <typename Make, typename Get>
std::function<bool(const Scene&)> Differs(Make make, Get get) {
  return [make, get](const Scene& s) {
    const Scene defaults;
    return !Same(get(make(s)), get(make(defaults)));
  };
}

// Every field of DicOptions (the static_asserts fail when one is added: list it here, with its
// scene key or in InternalLibraryOptions; the same for the lists below).
std::vector<LibraryField> DicFields() {
  static_assert(FieldCount<GridOptions>() == 4);
  static_assert(FieldCount<InitialGuessOptions>() == 3);
  static_assert(FieldCount<IcgnOptions>() == 10);
  static_assert(FieldCount<UpdateOptions>() == 3);
  static_assert(FieldCount<ContinuityCheckOptions>() == 6);
  static_assert(FieldCount<OutlierCheckOptions>() == 5);
  static_assert(FieldCount<DicOptions>() == 9);
  static const DicOptions d;  // Static: the predicates outlive this call.
  static constexpr auto o = [](const Scene& s) -> const DicOptions& { return s.dic.options; };
  return {
      {"dic.mode", "dic.mode", "pairs", [&](const Scene& s) { return o(s).mode != d.mode; }},
      {"dic.grid.subset_size", "dic.subset_size", "31",
       [&](const Scene& s) { return o(s).grid.subset_size != d.grid.subset_size; }},
      {"dic.grid.step", "dic.step", "7",
       [&](const Scene& s) { return o(s).grid.step != d.grid.step; }},
      // A scene's roi and mask become the grid's in the frames stage (the frames' size known).
      {"dic.grid.roi", "dic.roi", "1,2,30,40",
       [](const Scene& s) { return s.dic.roi != std::array<int, 4>{}; }},
      {"dic.grid.mask", "dic.mask", "/m.png", [](const Scene& s) { return !s.dic.mask.empty(); }},
      {"dic.init.search_radius_px", "dic.search_radius_px", "9",
       [&](const Scene& s) { return o(s).init.search_radius_px != d.init.search_radius_px; }},
      {"dic.init.seed_spacing", nullptr, nullptr, nullptr},
      {"dic.init.min_search_zncc", nullptr, nullptr, nullptr},
      {"dic.icgn.interpolation", "dic.interpolation", "biquintic",
       [&](const Scene& s) { return o(s).icgn.interpolation != d.icgn.interpolation; }},
      {"dic.icgn.shape", "dic.shape", "quadratic",
       [&](const Scene& s) { return o(s).icgn.shape != d.icgn.shape; }},
      {"dic.icgn.convergence_px", "dic.convergence_px", "0.01",
       [&](const Scene& s) { return o(s).icgn.convergence_px != d.icgn.convergence_px; }},
      {"dic.icgn.convergence_sigma_fraction", "dic.convergence_sigma_fraction", "0.5",
       [&](const Scene& s) {
         return o(s).icgn.convergence_sigma_fraction != d.icgn.convergence_sigma_fraction;
       }},
      {"dic.icgn.max_iterations", "dic.max_iterations", "7",
       [&](const Scene& s) { return o(s).icgn.max_iterations != d.icgn.max_iterations; }},
      {"dic.icgn.min_zncc", "dic.min_zncc", "0.5",
       [&](const Scene& s) { return o(s).icgn.min_zncc != d.icgn.min_zncc; }},
      {"dic.icgn.max_predicted_uncertainty_px", "dic.max_predicted_uncertainty_px", "0.25",
       [&](const Scene& s) {
         return o(s).icgn.max_predicted_uncertainty_px != d.icgn.max_predicted_uncertainty_px;
       }},
      {"dic.icgn.min_contrast", "dic.min_contrast", "9",
       [&](const Scene& s) { return o(s).icgn.min_contrast != d.icgn.min_contrast; }},
      {"dic.icgn.max_saturated_fraction", "dic.max_saturated_fraction", "0.5",
       [&](const Scene& s) {
         return o(s).icgn.max_saturated_fraction != d.icgn.max_saturated_fraction;
       }},
      {"dic.icgn.max_uncertainty_px", "dic.max_uncertainty_px", "0.1",
       [&](const Scene& s) { return o(s).icgn.max_uncertainty_px != d.icgn.max_uncertainty_px; }},
      {"dic.update.policy", "dic.reference_update", "incremental",
       [&](const Scene& s) { return o(s).update.policy != d.update.policy; }},
      {"dic.update.auto_min_zncc", "dic.auto_min_zncc", "0.9",
       [&](const Scene& s) { return o(s).update.auto_min_zncc != d.update.auto_min_zncc; }},
      {"dic.update.auto_rescue_decorrelation", "dic.auto_rescue_decorrelation", "0.5",
       [&](const Scene& s) {
         return o(s).update.auto_rescue_decorrelation != d.update.auto_rescue_decorrelation;
       }},
      {"dic.continuity.enabled", "dic.continuity_check", "true",
       [&](const Scene& s) { return o(s).continuity.enabled != d.continuity.enabled; }},
      {"dic.continuity.misfit_ratio", "dic.continuity_misfit_ratio", "3",
       [&](const Scene& s) { return o(s).continuity.misfit_ratio != d.continuity.misfit_ratio; }},
      {"dic.continuity.min_misfit", "dic.continuity_min_misfit", "0.5",
       [&](const Scene& s) { return o(s).continuity.min_misfit != d.continuity.min_misfit; }},
      {"dic.continuity.max_second_difference_px", "dic.continuity_max_second_difference_px", "1",
       [&](const Scene& s) {
         return o(s).continuity.max_second_difference_px != d.continuity.max_second_difference_px;
       }},
      {"dic.continuity.max_neighbour_difference_px", "dic.continuity_max_neighbour_difference_px",
       "1",
       [&](const Scene& s) {
         return o(s).continuity.max_neighbour_difference_px !=
                d.continuity.max_neighbour_difference_px;
       }},
      {"dic.continuity.local_ratio", "dic.continuity_local_ratio", "9",
       [&](const Scene& s) { return o(s).continuity.local_ratio != d.continuity.local_ratio; }},
      {"dic.outliers.enabled", "dic.outlier_check", "false",
       [&](const Scene& s) { return o(s).outliers.enabled != d.outliers.enabled; }},
      {"dic.outliers.threshold", "dic.outlier_threshold", "5",
       [&](const Scene& s) { return o(s).outliers.threshold != d.outliers.threshold; }},
      {"dic.outliers.noise_px", "dic.outlier_noise_px", "0.5",
       [&](const Scene& s) { return o(s).outliers.noise_px != d.outliers.noise_px; }},
      {"dic.outliers.sigma_factor", "dic.outlier_sigma_factor", "5",
       [&](const Scene& s) { return o(s).outliers.sigma_factor != d.outliers.sigma_factor; }},
      {"dic.outliers.min_neighbours", "dic.outlier_min_neighbours", "6",
       [&](const Scene& s) { return o(s).outliers.min_neighbours != d.outliers.min_neighbours; }},
      {"dic.data_bits", nullptr, nullptr, nullptr},
      {"dic.keep_warp_gradient", "dic.keep_warp_gradient", "true",
       [&](const Scene& s) { return o(s).keep_warp_gradient != d.keep_warp_gradient; }},
  };
}

// The preprocessing the frames stage takes (MakePreprocessOptions).
std::vector<LibraryField> PreprocessFields() {
  static_assert(FieldCount<PreprocessOptions>() == 6);
  static_assert(FieldCount<UndistortOptions>() == 3);
  static_assert(FieldCount<GaussianBlurOptions>() == 4);
  static_assert(FieldCount<ClaheOptions>() == 3);
  const auto p = [](const Scene& s) { return MakePreprocessOptions(s); };
  using O = PreprocessOptions;
  return {
      {"preprocess.undistort", "preprocess.undistortion.enabled", "false",
       Differs(p, [](const O& o) { return o.undistort; })},
      // The region the auto Gaussian measures and the undistortion judges: the correlation's.
      {"preprocess.roi", "dic.roi", "1,2,30,40", Differs(p, [](const O& o) { return o.roi; })},
      {"preprocess.subset_size", "dic.subset_size", "31",
       Differs(p, [](const O& o) { return o.subset_size; })},
      {"preprocess.undistortion.skip_threshold_px", "preprocess.undistortion.skip_threshold_px",
       "0.5", Differs(p, [](const O& o) { return o.undistortion.skip_threshold_px; })},
      {"preprocess.undistortion.interpolation", "preprocess.undistortion.interpolation", "bilinear",
       Differs(p, [](const O& o) { return o.undistortion.interpolation; })},
      {"preprocess.undistortion.roi", "dic.roi", "1,2,30,40",
       Differs(p, [](const O& o) { return o.undistortion.roi; })},
      {"preprocess.gaussian.mode", "preprocess.gaussian.enabled", "true",
       Differs(p, [](const O& o) { return o.gaussian.mode; })},
      {"preprocess.gaussian.sigma_px", "preprocess.gaussian.sigma", "1.5",
       Differs(p, [](const O& o) { return o.gaussian.sigma_px; })},
      {"preprocess.gaussian.kernel_size", "preprocess.gaussian.kernel", "7",
       Differs(p, [](const O& o) { return o.gaussian.kernel_size; })},
      {"preprocess.gaussian.auto_threshold_px", "preprocess.gaussian.auto_threshold_px", "0.01",
       Differs(p, [](const O& o) { return o.gaussian.auto_threshold_px; })},
      {"preprocess.clahe.enabled", "preprocess.clahe.enabled", "true",
       Differs(p, [](const O& o) { return o.clahe.enabled; })},
      {"preprocess.clahe.clip_limit", "preprocess.clahe.clip_limit", "3",
       Differs(p, [](const O& o) { return o.clahe.clip_limit; })},
      {"preprocess.clahe.tile_grid", "preprocess.clahe.tile_grid", "4",
       Differs(p, [](const O& o) { return o.clahe.tile_grid; })},
  };
}

// The sensor stage's options (MakeSensorOptions; the test's v0 reaches impact_velocity_m_s with
// integrate_from impact).
std::vector<LibraryField> SensorFields() {
  static_assert(FieldCount<SensorColumns>() == 6);
  static_assert(FieldCount<SensorOptions>() == 16);
  const auto m = [](const Scene& s) { return MakeSensorOptions(s); };
  // The base channels' lists: one key alone is not a valid set (each list as long as
  // base_columns, checked by MakeSensorOptions); the key reaches its field all the same.
  const auto raw = [](const Scene& s) { return s.sensor.options; };
  const auto from_impact = [](const Scene& s) {
    Scene c = s;
    c.sensor.options.integrate_from = IntegrationStart::kImpact;
    return MakeSensorOptions(c);
  };
  using O = SensorOptions;
  return {
      {"sensor.columns.time", "sensor.time_column", "t",
       Differs(m, [](const O& o) { return o.columns.time; })},
      {"sensor.columns.accel", "sensor.accel_column", "a",
       Differs(m, [](const O& o) { return o.columns.accel; })},
      {"sensor.columns.accel_unit", "sensor.accel_unit", "g",
       Differs(m, [](const O& o) { return o.columns.accel_unit; })},
      {"sensor.columns.exposure", "sensor.exposure_column", "",
       Differs(m, [](const O& o) { return o.columns.exposure; })},
      {"sensor.columns.force", "sensor.force_columns", "force_1,force_3",
       Differs(m, [](const O& o) { return o.columns.force; })},
      {"sensor.columns.base_force", "sensor.base_columns", "base_1,base_2",
       Differs(raw, [](const O& o) { return o.columns.base_force; })},
      {"sensor.g_m_s2", "test.g_m_s2", "9.7", Differs(m, [](const O& o) { return o.g_m_s2; })},
      {"sensor.cutoff_hz", "sensor.cutoff_hz", "1000",
       Differs(m, [](const O& o) { return o.cutoff_hz; })},
      {"sensor.offset_reference", "sensor.offset_reference", "rest",
       Differs(m, [](const O& o) { return o.offset_reference; })},
      {"sensor.quiet_window_s", "sensor.quiet_window_s", "0.01",
       Differs(m, [](const O& o) { return o.quiet_window_s; })},
      {"sensor.quiet_guard_s", "sensor.quiet_guard_s", "0.002",
       Differs(m, [](const O& o) { return o.quiet_guard_s; })},
      {"sensor.integrate_from", "sensor.integrate_from", "impact",
       Differs(m, [](const O& o) { return o.integrate_from; })},
      {"sensor.impact_velocity_m_s", "test.impact_velocity_m_s", "3",
       Differs(from_impact, [](const O& o) { return o.impact_velocity_m_s; })},
      {"sensor.release_time_s", "sensor.release_time_s", "0.1",
       Differs(m, [](const O& o) { return o.release_time_s; })},
      {"sensor.impact_threshold_g", "sensor.impact_threshold_g", "8",
       Differs(m, [](const O& o) { return o.impact_threshold_g; })},
      {"sensor.noise_band_sigma", "sensor.noise_band_sigma", "6",
       Differs(m, [](const O& o) { return o.noise_band_sigma; })},
      {"sensor.stop_velocity_m_s", "sensor.stop_velocity_m_s", "0.02",
       Differs(m, [](const O& o) { return o.stop_velocity_m_s; })},
      {"sensor.max_step_deviation", nullptr, nullptr, nullptr},
      {"sensor.expected_impact_velocity_m_s", "test.drop_height_m", "1",
       Differs(m, [](const O& o) { return o.expected_impact_velocity_m_s; })},
      {"sensor.expected_impact_velocity_source", "test.impact_velocity_m_s", "3",
       Differs(m, [](const O& o) { return o.expected_impact_velocity_source; })},
      {"sensor.base.units", "sensor.base_units", "kN,N",
       Differs(raw, [](const O& o) { return o.base.units; })},
      {"sensor.base.offset_mm", "sensor.base_offsets_mm", "0,300",
       Differs(raw, [](const O& o) { return o.base.offset_mm; })},
      {"sensor.base.depth_mm", "sensor.base_depths_mm", "600,600",
       Differs(raw, [](const O& o) { return o.base.depth_mm; })},
      {"sensor.base.area_mm2", "sensor.base_areas_mm2", "2000,2000",
       Differs(raw, [](const O& o) { return o.base.area_mm2; })},
  };
}

// The kinematics stage sets the frame rate from the frames' timeline: a camera file's own rate,
// else inputs.fps (kinematics_stage.cc, SceneFrameClock).
std::vector<LibraryField> KinematicsFields() {
  static_assert(FieldCount<KinematicsOptions>() == 1);
  return {{"kinematics.fps", "inputs.fps", "1000",
           [](const Scene& s) { return s.inputs.fps != SceneInputs{}.fps; }}};
}

// The momentum stage's options (MakeMomentumOptions, with the pounder at (100, 50) px and 1 mm/px
// unless the scene places it).
std::vector<LibraryField> MomentumFields() {
  static_assert(FieldCount<MomentumOptions>() == 14);
  static_assert(FieldCount<PounderFootprint>() == 3);
  static_assert(FieldCount<SigmoidFitOptions>() == 3);
  static_assert(FieldCount<MomentumUncertaintyOptions>() == 5);
  const auto m = [](const Scene& s) {
    Scene c = s;
    if (!c.momentum.pounder_center_x_px) c.momentum.pounder_center_x_px = 100;
    if (!c.momentum.surface_y_px) c.momentum.surface_y_px = 50;
    return MakeMomentumOptions(c, /*mm_per_px=*/1);
  };
  using O = MomentumOptions;
  return {
      {"momentum.pounder_mass_kg", "test.mass_kg", "20",
       Differs(m, [](const O& o) { return o.pounder_mass_kg; })},
      {"momentum.pounder_width_m", "test.width_m", "0.2",
       Differs(m, [](const O& o) { return o.pounder_width_m; })},
      {"momentum.depth_m", "test.depth_m", "0.2", Differs(m, [](const O& o) { return o.depth_m; })},
      {"momentum.density_kg_m3", "test.density_kg_m3", "1600",
       Differs(m, [](const O& o) { return o.density_kg_m3; })},
      {"momentum.grid_cols", "momentum.grid_cols", "4",
       Differs(m, [](const O& o) { return o.grid_cols; })},
      {"momentum.grid_rows", "momentum.grid_rows", "3",
       Differs(m, [](const O& o) { return o.grid_rows; })},
      {"momentum.rect_mm", "momentum.rect_mm", "[0, 0, 10, 5]",
       Differs(m, [](const O& o) { return o.rect_mm; })},
      {"momentum.footprint.x_left_mm", "momentum.pounder_center_x_px", "320",
       Differs(m, [](const O& o) { return o.footprint.x_left_mm; })},
      {"momentum.footprint.x_right_mm", "momentum.pounder_center_x_px", "320",
       Differs(m, [](const O& o) { return o.footprint.x_right_mm; })},
      {"momentum.footprint.bottom_y_mm", "momentum.surface_y_px", "200",
       Differs(m, [](const O& o) { return o.footprint.bottom_y_mm; })},
      {"momentum.velocity_match_tolerance", "momentum.velocity_match_tolerance", "0.1",
       Differs(m, [](const O& o) { return o.velocity_match_tolerance; })},
      {"momentum.sand_accel_tolerance", "momentum.sand_accel_tolerance", "0.1",
       Differs(m, [](const O& o) { return o.sand_accel_tolerance; })},
      {"momentum.min_valid_fraction", "momentum.min_valid_fraction", "0.8",
       Differs(m, [](const O& o) { return o.min_valid_fraction; })},
      {"momentum.fit_sigmoid", "momentum.fit_sigmoid", "false",
       Differs(m, [](const O& o) { return o.fit_sigmoid; })},
      {"momentum.sigmoid.max_iterations", nullptr, nullptr, nullptr},
      {"momentum.sigmoid.step_tolerance", nullptr, nullptr, nullptr},
      {"momentum.sigmoid.confidence", "momentum.sigmoid_confidence", "0.9",
       Differs(m, [](const O& o) { return o.sigmoid.confidence; })},
      {"momentum.uncertainty.draws", "momentum.uncertainty_draws", "10",
       Differs(m, [](const O& o) { return o.uncertainty.draws; })},
      {"momentum.uncertainty.density_u_kg_m3", "test.density_u_kg_m3", "20",
       Differs(m, [](const O& o) { return o.uncertainty.density_u_kg_m3; })},
      {"momentum.uncertainty.depth_u_m", "test.depth_u_m", "0.001",
       Differs(m, [](const O& o) { return o.uncertainty.depth_u_m; })},
      {"momentum.uncertainty.scale_u_fraction", "inputs.mm_per_px_u", "0.01",
       Differs(m, [](const O& o) { return o.uncertainty.scale_u_fraction; })},
      {"momentum.uncertainty.subset_size_mm", "dic.subset_size", "31",
       Differs(m, [](const O& o) { return o.uncertainty.subset_size_mm; })},
  };
}

// The model stage's parameters (MakeModelParameters at the test's v0; the sensor's measured v0
// when there is one) and its solver options (Scene::solver).
std::vector<LibraryField> ModelFields() {
  static_assert(FieldCount<ImpactModelParameters>() == 13);
  static_assert(FieldCount<ImpactSolverOptions>() == 11);
  const auto p = [](const Scene& s) { return MakeModelParameters(s, s.ImpactVelocity()); };
  const auto o = [](const Scene& s) { return s.solver; };
  using P = ImpactModelParameters;
  using O = ImpactSolverOptions;
  return {
      {"model.pounder_mass_kg", "test.mass_kg", "20",
       Differs(p, [](const P& m) { return m.pounder_mass_kg; })},
      {"model.impact_velocity_m_s", "test.drop_height_m", "1",
       Differs(p, [](const P& m) { return m.impact_velocity_m_s; })},
      {"model.width_m", "test.width_m", "0.2", Differs(p, [](const P& m) { return m.width_m; })},
      {"model.depth_m", "test.depth_m", "0.2", Differs(p, [](const P& m) { return m.depth_m; })},
      {"model.added_mass_kg", "model.added_mass_kg", "3",
       Differs(p, [](const P& m) { return m.added_mass_kg; })},
      {"model.friction_K", "model.K", "40", Differs(p, [](const P& m) { return m.friction_K; })},
      {"model.damping_exponent_n", "model.n", "0.3",
       Differs(p, [](const P& m) { return m.damping_exponent_n; })},
      {"model.damping_factor_u", "model.u", "2",
       Differs(p, [](const P& m) { return m.damping_factor_u; })},
      {"model.sigmoid_delay_T_s", "model.T_s", "0.003",
       Differs(p, [](const P& m) { return m.sigmoid_delay_T_s; })},
      {"model.sigmoid_rate_b_per_s", "model.b_per_s", "2000",
       Differs(p, [](const P& m) { return m.sigmoid_rate_b_per_s; })},
      {"model.density_kg_m3", "test.density_kg_m3", "1600",
       Differs(p, [](const P& m) { return m.density_kg_m3; })},
      {"model.gravity_m_s2", "test.g_m_s2", "9.7",
       Differs(p, [](const P& m) { return m.gravity_m_s2; })},
      {"model.bed_height_m", "test.bed_height_m", "0.5",
       Differs(p, [](const P& m) { return m.bed_height_m; })},
      {"solver.solver", "model.solver", "stiff", Differs(o, [](const O& m) { return m.solver; })},
      {"solver.rtol", "model.rtol", "1e-8", Differs(o, [](const O& m) { return m.rtol; })},
      {"solver.atol", "model.atol", "1e-9", Differs(o, [](const O& m) { return m.atol; })},
      {"solver.error_estimator", "model.error_estimator", "local",
       Differs(o, [](const O& m) { return m.error_estimator; })},
      {"solver.ode45_defaults", "model.ode45_defaults", "true",
       Differs(o, [](const O& m) { return m.ode45_defaults; })},
      {"solver.t_max_s", "model.t_max_s", "5", Differs(o, [](const O& m) { return m.t_max_s; })},
      {"solver.sigmoid_window", nullptr, nullptr, nullptr},
      {"solver.sigmoid_step", nullptr, nullptr, nullptr},
      {"solver.switch_velocity_fraction", nullptr, nullptr, nullptr},
      {"solver.max_steps", nullptr, nullptr, nullptr},
      {"solver.error_warning_factor", nullptr, nullptr, nullptr},
  };
}

// The strain stage's options (Scene::strain).
std::vector<LibraryField> StrainFields() {
  static_assert(FieldCount<StrainOptions>() == 5);
  const auto o = [](const Scene& s) { return s.strain; };
  using O = StrainOptions;
  return {
      {"strain.enabled", "strain.enabled", "true",
       Differs(o, [](const O& m) { return m.enabled; })},
      {"strain.gradient", "strain.gradient", "warp",
       Differs(o, [](const O& m) { return m.gradient; })},
      {"strain.window", "strain.window", "5", Differs(o, [](const O& m) { return m.window; })},
      {"strain.compaction_threshold", "strain.compaction_threshold", "0.02",
       Differs(o, [](const O& m) { return m.compaction_threshold; })},
      {"strain.shear_band_threshold", "strain.shear_band_threshold", "0.05",
       Differs(o, [](const O& m) { return m.shear_band_threshold; })},
  };
}

// The default scene with `key` set to `value`: as its flag, or, for a key only a scene file has
// (momentum.rect_mm, a list), read from one.
Scene SceneWithKey(const std::string& key, const std::string& value) {
  if (key == "momentum.rect_mm")
    return ParseScene("inputs: {frames: f}\nmomentum: {rect_mm: " + value + "}\n", "scene.yaml");
  Scene scene;
  SetSceneKey(&scene, key, value, "--" + key);
  return scene;
}

// Every option of the libraries a scene configures is reached by a scene key, which is a flag
// of the commands that run it (the test above; momentum.rect_mm only in a scene file), directly
// or through the options the pipeline builds from it, or is internal with its reason beside the
// scene's tables.
TEST(SceneFlags, EveryLibraryOptionIsASceneKeyOrInternal) {
  // dic.roi and momentum.rect_mm are read by ParseScene itself (dic.roi a flag all the same).
  std::vector<std::string> keys = {"dic.roi", "momentum.rect_mm"};
  Scene defaults;
  for (const YamlOptionTable& t : SceneOptionTables(&defaults))
    for (const auto& e : t.entries()) keys.push_back(t.section() + "." + e.key);
  const std::vector<InternalOption>& internal = InternalLibraryOptions();
  const auto is_internal = [&internal](const std::string& field) {
    return std::any_of(internal.begin(), internal.end(), [&field](const InternalOption& o) {
      return field == o.field && std::string(o.reason).size() > 20;
    });
  };
  std::vector<LibraryField> fields;
  for (auto list : {DicFields, PreprocessFields, SensorFields, KinematicsFields, MomentumFields,
                    ModelFields, StrainFields})
    for (LibraryField& f : list()) fields.push_back(std::move(f));
  for (const LibraryField& f : fields) {
    if (f.key == nullptr) {
      EXPECT_TRUE(is_internal(f.field))
          << f.field << ": no scene key reaches it, and it is not in InternalLibraryOptions";
      continue;
    }
    EXPECT_FALSE(is_internal(f.field)) << f.field << " is a scene key and listed as internal";
    if (std::find(keys.begin(), keys.end(), f.key) == keys.end()) {
      ADD_FAILURE() << f.field << ": no scene key reaches it (" << f.key << " is not a key)";
      continue;
    }
    EXPECT_TRUE(f.changed(SceneWithKey(f.key, f.value)))
        << f.key << ": " << f.value << " leaves " << f.field;
  }
  for (const InternalOption& o : internal) {
    EXPECT_TRUE(
        std::any_of(fields.begin(), fields.end(),
                    [&o](const LibraryField& f) { return f.field == std::string(o.field); }))
        << o.field << " (InternalLibraryOptions) is not a field of a library's options";
  }
}

TEST(SceneFlags, AFlagIsReadAsItsKeyInASceneFile) {
  Scene scene;
  SetSceneKey(&scene, "dic.max_iterations", "7", "--dic.max_iterations");
  SetSceneKey(&scene, "dic.convergence_px", "0.01", "--dic.convergence_px");
  SetSceneKey(&scene, "dic.continuity_check", "on", "--continuity-check");
  EXPECT_EQ(scene.dic.options.icgn.max_iterations, 7);
  EXPECT_EQ(scene.dic.options.icgn.convergence_px, 0.01);
  EXPECT_TRUE(scene.dic.options.continuity.enabled);
  // Refused with the scene key's expected text, naming the flag as given.
  try {
    SetSceneKey(&scene, "dic.subset_size", "24", "--dic.subset_size");
    FAIL() << "an even subset was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.where(), "--dic.subset_size");
    EXPECT_NE(e.expected().find("an odd integer"), std::string::npos) << e.what();
  }
  EXPECT_EQ(SceneFlagNames("correlate", "dic.subset_size"), "--dic.subset_size,--subset");
  EXPECT_EQ(SceneFlagNames("correlate", "dic.max_iterations"), "--dic.max_iterations");
}

class SceneFlagsCorrelate : public ::testing::Test {
 protected:
  void SetUp() override {
    SpeckleOptions speckle;
    speckle.blob_radius_px = 2.0;
    SpecklePattern pattern(speckle, 100, 80);
    RenderOptions render;
    render.noise_sigma = 2;
    render.supersampling = 2;
    WriteImage(dir_.File("ref.png"), RenderImage(pattern, 100, 80, ZeroField(), render));
    render.noise_seed = 8;
    WriteImage(dir_.File("def.png"), RenderImage(pattern, 100, 80, Translation(1.4, -0.7), render));
  }
  // The iterations and u of `correlate` with `flags`.
  CsvTable Correlate(const std::string& flags, const std::string& name) {
    const std::string out = dir_.File(name + ".csv");
    const CliResult r =
        RunCli("-q correlate --reference " + dir_.File("ref.png") + " --deformed " +
               dir_.File("def.png") + " --threads 1 --subset 21 --step 20 " + flags + " -o " + out);
    EXPECT_EQ(r.exit_code, 0) << flags << "\n" << r.output;
    CsvReadOptions options;
    options.text_columns = {"status"};
    options.allow_non_finite = true;  // A subset that did not converge has no u, v.
    return ReadCsv(out, options);
  }
  TestDir dir_{"scene_flags_correlate"};
};

double Sum(const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0); }

TEST_F(SceneFlagsCorrelate, MaxIterationsAndConvergenceChangeTheCorrelation) {
  const CsvTable base = Correlate("", "base");
  // One iteration converges no subset (status max_iterations): written with --allow-partial.
  const CsvTable capped = Correlate("--dic.max_iterations 1 --allow-partial", "capped");
  const CsvTable loose = Correlate("--dic.convergence_px 0.9", "loose");
  ASSERT_GT(base.rows(), 0u);
  ASSERT_EQ(capped.rows(), base.rows());
  ASSERT_EQ(loose.rows(), base.rows());
  const auto& it = capped.Column("iterations");
  EXPECT_EQ(*std::max_element(it.begin(), it.end()), 1);
  EXPECT_GT(*std::max_element(base.Column("iterations").begin(), base.Column("iterations").end()),
            1);
  EXPECT_NE(capped.TextColumn("status"), base.TextColumn("status"));
  EXPECT_LT(Sum(loose.Column("iterations")), Sum(base.Column("iterations")));
  EXPECT_NE(loose.Column("u_px"), base.Column("u_px"));
}

TEST_F(SceneFlagsCorrelate, AKeyFlagIsRefusedAsTheKeyAndTwoNamesOfOneKeyAreRefused) {
  const std::string pair = "correlate --reference " + dir_.File("ref.png") + " --deformed " +
                           dir_.File("def.png") + " -o " + dir_.File("x.csv");
  CliResult r = RunCli(pair + " --dic.max_iterations 0");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("--dic.max_iterations: invalid value (got 0); expected an integer "
                          "iteration cap in [1, 200]"),
            std::string::npos)
      << r.output;
  r = RunCli(pair + " --min-zncc 0.5 --dic.min_zncc 0.6");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("both given"), std::string::npos) << r.output;
}

// `run SCENE --KEY VALUE` and `analyze SCENE --KEY VALUE`: the flag overrides the scene file's
// key (sensor.*, momentum.*, outputs.*); a momentum key is refused with `analyze --sensor`.
TEST(SceneFlags, RunAndAnalyzeFlagsOverrideTheSceneFile) {
  TestDir dir("scene_flags_run");
  const std::string scene = SampleScene(dir, {});  // outputs.folder: results; xdmf, csv: true.
  const std::string out = dir.File("from_flag");
  CliResult r = RunCli("-q run " + scene + " --outputs.folder " + out +
                       " --outputs.xdmf off --outputs.csv false");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(std::filesystem::exists(out + "/results.h5"));
  EXPECT_FALSE(std::filesystem::exists(out + "/results.xdmf"));
  EXPECT_FALSE(std::filesystem::exists(out + "/summary.csv"));
  EXPECT_FALSE(std::filesystem::exists(dir.File("results")));
  r = RunCli("run " + scene + " --outputs.frames some");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("--outputs.frames: invalid value (got 'some')"), std::string::npos)
      << r.output;

  // analyze SCENE: --cutoff (alias of sensor.cutoff_hz) and the momentum keys reach the analysis.
  const std::string analyze = "analyze " + scene + " --results " + out + "/results.h5";
  r = RunCli(analyze + " --output " + dir.File("a.h5") + " --cutoff 1000");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("1000.0 Hz"), std::string::npos) << r.output;
  r = RunCli(analyze + " --output " + dir.File("b.h5") + " --momentum.grid_cols 0");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("--momentum.grid_cols: invalid value (got 0)"), std::string::npos)
      << r.output;
  r = RunCli("analyze --sensor " + std::string(impactdic::SourceDir()) +
             "/sample_frames/sensor.csv --from-release --momentum.grid_cols 3");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("--momentum.grid_cols only with the SCENE.yaml form"), std::string::npos)
      << r.output;
}

}  // namespace
}  // namespace impactdic
