#include "impactdic/synth/impact_scene.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>

#include "../cli/cli_runner.h"
#include "impactdic/core/error.h"
#include "impactdic/dic/options.h"
#include "impactdic/io/csv.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/pipeline/scene.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

std::string TempDir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("impactdic_synth_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

// A tiny scene (160x120, ideal lens, 5 mm/px) with two frames before the impact.
ImpactSceneSpec TinySpec() {
  ImpactSceneSpec spec = ImpactScenePreset("tiny");
  spec.frames_before_impact = 2;
  spec.frames = 6;
  return spec;
}

TEST(ImpactSceneSpec, PresetsPassCheckAndRoundTripThroughYaml) {
  for (const char* name : {"small", "full", "tiny"}) {
    const ImpactSceneSpec spec = ImpactScenePreset(name);
    EXPECT_NO_THROW(spec.Check()) << name;
    const ImpactSceneSpec back = ParseImpactSceneSpec(ImpactSceneSpecToYaml(spec), "spec.yaml");
    EXPECT_EQ(back.width, spec.width);
    EXPECT_EQ(back.height, spec.height);
    EXPECT_DOUBLE_EQ(back.mm_per_px, spec.mm_per_px);
    EXPECT_EQ(back.lens, spec.lens);
    EXPECT_EQ(back.step, spec.step);
    EXPECT_EQ(back.frames, spec.frames);
    EXPECT_DOUBLE_EQ(back.speckle.blob_radius_px, spec.speckle.blob_radius_px);
    EXPECT_EQ(back.render_calibration, spec.render_calibration);
  }
  const ImpactSceneSpec full = ParseImpactSceneSpec("preset: full\nframes: {count: 9}\n", "s");
  EXPECT_EQ(full.width, 1920);
  EXPECT_EQ(full.height, 1440);
  EXPECT_EQ(full.frames, 9);
}

// The spec is read by the shared YAML section reader (io/yaml.h): every problem at once, unknown
// keys with the closest valid key.
TEST(ImpactSceneSpec, UnknownKeysSuggestTheClosestAndEveryProblemIsReported) {
  try {
    ParseImpactSceneSpec("dic: {subset_sise: 21}\ncamera: {widht: 640, fps: fast}\n", "spec.yaml");
    FAIL() << "no error";
  } catch (const Error& e) {
    const std::string what = e.what();
    for (const char* expected :
         {"3 problems in synthetic scene spec spec.yaml:",
          "spec.yaml:1: dic.subset_sise: unknown key (did you mean 'subset_size'?)",
          "spec.yaml:2: camera.widht: unknown key (did you mean 'width'?)",
          "spec.yaml:2: camera.fps: got 'fast'; expected a number"}) {
      EXPECT_NE(what.find(expected), std::string::npos) << "missing: " << expected << "\n" << what;
    }
  }
}

// Each bad value is reported with its key path, the value and what is expected.
TEST(ImpactSceneSpec, BadValuesGiveClearErrors) {
  struct Case {
    std::string yaml, where, found;
  };
  const Case cases[] = {
      {"camera: {width: 20}", "camera.width", "20"},
      {"frames: {bits: 12}", "frames.bits", "12"},
      {"test: {mass_kg: -3}", "test.mass_kg", "-3"},
      {"test: {mass_kg: heavy}", "test.mass_kg", "heavy"},
      {"dic: {subset_size: 24}", "dic.subset_size", "24"},
      {"camera: {lens: fisheye}", "camera.lens", "fisheye"},
      {"camera: {widht: 640}", "camera.widht", "unknown"},
      {"model: {added_mass: lots}", "model.added_mass", "lots"},
      {"preset: huge", "preset", "huge"},
      {"sensor: {exposure_s: 0.01}", "sensor.exposure_s", "0.01"},
  };
  for (const Case& c : cases) {
    try {
      ParseImpactSceneSpec(c.yaml, "spec.yaml");
      ADD_FAILURE() << "no error for " << c.yaml;
    } catch (const Error& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(c.where), std::string::npos) << what;
      EXPECT_NE(what.find(c.found), std::string::npos) << what;
      EXPECT_NE(what.find("spec.yaml"), std::string::npos) << what;
    }
  }
  // A grid too wide for the footprint is refused (its subsets would not be under the pounder).
  ImpactSceneSpec spec = TinySpec();
  spec.grid_cols = 40;
  try {
    ImpactScene scene(spec);
    ADD_FAILURE() << "no error for a grid wider than the footprint";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("momentum.grid_cols"), std::string::npos) << e.what();
  }
}

// Before the impact nothing in the soil moves: a pre-impact frame equals the reference except
// where the falling pounder is.
// Base force sensors (the wave model of impact_scene.h): the spec round-trips, bad lists name
// their key, and each noise-free record is the pounder's contact force delayed by r / c and
// scaled by stress_ratio (d / r)^spreading_exponent.
TEST(ImpactSceneSpec, BaseSensorsRoundTripAndBadListsNameTheKey) {
  ImpactSceneSpec spec = TinySpec();
  spec.base_sensors.columns = {"b0_N", "b1_N"};
  spec.base_sensors.offset_mm = {0, 300};
  spec.base_sensors.depth_mm = {600, 500};
  spec.base_sensors.area_mm2 = {2000, 1000};
  const ImpactSceneSpec back = ParseImpactSceneSpec(ImpactSceneSpecToYaml(spec), "spec.yaml");
  EXPECT_EQ(back.base_sensors.columns, spec.base_sensors.columns);
  EXPECT_EQ(back.base_sensors.depth_mm, spec.base_sensors.depth_mm);
  EXPECT_DOUBLE_EQ(back.base_sensors.stress_ratio, spec.base_sensors.stress_ratio);
  spec.base_sensors.depth_mm = {600};
  try {
    spec.Check();
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("base_sensors.depths_mm"), std::string::npos) << e.what();
  }
}

TEST(ImpactScene, BaseSensorRecordIsTheDelayedScaledContactForce) {
  ImpactSceneSpec spec = TinySpec();
  spec.base_sensors.columns = {"b0_N", "b1_N"};
  spec.base_sensors.offset_mm = {0, 400};
  spec.base_sensors.depth_mm = {600, 300};
  spec.base_sensors.area_mm2 = {2000, 1000};
  spec.sensor.tail_s = 0.06;  // Past the arrivals and the stop.
  const ImpactScene scene(spec);
  const ImpactScene::SensorRecord rec = scene.MakeSensorRecord();
  ASSERT_EQ(rec.base_force_true_n.size(), 2u);
  const double dt = rec.time_s[1] - rec.time_s[0];
  const double area_m2 = spec.width_m * spec.depth_m;
  for (std::size_t k = 0; k < 2; ++k) {
    const double r_mm = std::hypot(spec.base_sensors.offset_mm[k], spec.base_sensors.depth_mm[k]);
    const double delay = 1e-3 * r_mm / spec.soil.wave_speed_m_s;
    const double ratio = spec.base_sensors.stress_ratio *
                         std::sqrt(spec.base_sensors.depth_mm[k] / r_mm);  // Exponent 1/2.
    const double to_force =
        ratio * 1e-6 * spec.base_sensors.area_mm2[k] * spec.pounder_mass_kg * spec.g_m_s2 / area_m2;
    // Where the delay is a whole number of samples the record is the reading shifted exactly.
    const auto shift = static_cast<std::size_t>(std::floor(delay / dt));
    int compared = 0;
    for (std::size_t i = 0; i + shift < rec.time_s.size(); i += 7) {
      const double t_after = rec.time_s[i] - rec.impact_daq_time_s;
      if (t_after < dt) continue;  // Before the contact the force is 0, the reading free fall.
      ++compared;
      const double frac = delay / dt - static_cast<double>(shift);
      // Linear between the two readings that bracket the delayed time (the cell averages of a
      // smooth reading): within 1 % of the peak force.
      const double reading = (1 - frac) * rec.accel_true_g[i] +
                             frac * (i > 0 ? rec.accel_true_g[i - 1] : rec.accel_true_g[i]);
      EXPECT_NEAR(rec.base_force_true_n[k][i + shift], to_force * reading, 0.01 * to_force * 60)
          << "sensor " << k << " at " << t_after << " s";
    }
    EXPECT_GT(compared, 150) << "the record ends too soon after the impact";
    // Before the wave arrives the record reads its offset and noise only.
    const auto arrival =
        static_cast<std::size_t>(std::floor((rec.impact_daq_time_s + delay) / dt - 0.5));
    for (std::size_t i = 0; i < arrival; ++i) ASSERT_EQ(rec.base_force_true_n[k][i], 0.0) << i;
  }
}

TEST(ImpactScene, PreImpactFrameEqualsReferenceWhereNothingMoved) {
  const ImpactScene scene(TinySpec());
  ASSERT_LT(scene.FrameTime(1), 0.0);
  ASSERT_GT(scene.FrameTime(2), 0.0);
  const cv::Mat f0 = scene.RenderFrame(0, /*with_noise=*/false);
  const cv::Mat f1 = scene.RenderFrame(1, /*with_noise=*/false);
  const double a_px = scene.spec().width_m * 500 / scene.sx_mm_per_px();
  const double z1_px =
      scene.surface_px() + scene.Pounder(scene.FrameTime(1)).z_m * 1000 / scene.sy_mm_per_px();
  int compared = 0, differing_in_pounder = 0;
  for (int r = 0; r < f0.rows; ++r) {
    for (int c = 0; c < f0.cols; ++c) {
      const bool near_pounder = std::abs(c - scene.axis_px()) <= a_px + 1.5 && r <= z1_px + 1.5;
      if (near_pounder) {
        differing_in_pounder += f0.at<std::uint8_t>(r, c) != f1.at<std::uint8_t>(r, c);
        continue;
      }
      ASSERT_EQ(f0.at<std::uint8_t>(r, c), f1.at<std::uint8_t>(r, c)) << r << "," << c;
      ++compared;
    }
  }
  EXPECT_GT(compared, f0.rows * f0.cols / 2);
  EXPECT_GT(differing_in_pounder, 0);  // The pounder did move between the frames.
}

// The renderer is exact: under a pure translation of the soil it reproduces RenderImage of the
// same pattern (both evaluate the analytic speckle at the same sub-pixel samples). Tolerance: one
// grey level, only where a value sits on a rounding boundary (ideal lens: identical samples).
TEST(ImpactScene, RenderingUnderTranslationMatchesRenderImage) {
  ImpactSceneSpec spec = TinySpec();
  spec.noise_sigma = 0;
  const ImpactScene scene(spec);
  const DisplacementField shift = Translation(0.37, 1.6);
  const cv::Mat mine = scene.RenderWithField(shift, /*pounder_z_m=*/-1.0, 1, false);
  RenderOptions options;
  options.bits = 8;
  options.supersampling = spec.supersampling;
  const cv::Mat ref = RenderImage(scene.pattern(), spec.width, spec.height, shift, options);
  int compared = 0, off_by_one = 0;
  for (int r = static_cast<int>(scene.surface_px() + 4); r < ref.rows; ++r) {
    for (int c = 0; c < ref.cols; ++c) {
      const int d = std::abs(mine.at<std::uint8_t>(r, c) - ref.at<std::uint8_t>(r, c));
      ASSERT_LE(d, 1) << r << "," << c;
      off_by_one += d;
      ++compared;
    }
  }
  EXPECT_GT(compared, 8000);
  EXPECT_LE(off_by_one, compared / 1000);
  // Above the surface the renderer shows the plain background.
  EXPECT_EQ(mine.at<std::uint8_t>(2, 2), static_cast<int>(std::round(spec.background_level * 255)));
}

// p_pounder + p_gran = p_max through the peak stage, from the field definition at the grid
// points (velocity of each material point), the model's v_p, and an independent p_max. Relative
// 1e-9: both sides are evaluated from the same dense output, so only rounding remains.
TEST(ImpactScene, MomentumBalanceHoldsThroughThePeakStage) {
  const ImpactScene scene(TinySpec());
  const SceneMomentumTruth& mt = scene.momentum();
  const double mp = scene.spec().pounder_mass_kg;
  const ImpactSolution& sol = scene.model_run().solution;
  // p_max independently: the largest m_p v_p on a fine sampling is not above it.
  double sampled_max = 0;
  for (int i = 0; i <= 20000; ++i)
    sampled_max = std::max(sampled_max, mp * sol.StateAt(sol.t_end_s * i / 20000).v_m_s);
  EXPECT_GE(mt.p_max_Ns, sampled_max * (1 - 1e-12));
  EXPECT_LE(mt.p_max_Ns, sampled_max * (1 + 1e-6));
  ASSERT_GT(mt.t_e_s, 0);
  ASSERT_LT(mt.t_e_s, sol.t_end_s);
  EXPECT_EQ(mt.centres_px.size(), 12u);

  const double step = scene.spec().step;
  auto mean_velocity = [&](double t, double dx_px, double dy_px) {
    double sum = 0;
    for (const auto& c : mt.centres_px) {
      const cv::Point2d m = scene.PanelFromIdeal({c.x + dx_px, c.y + dy_px});
      sum += scene.SoilVelocityMmS(m.x, m.y, t)[1] / 1000;
    }
    return sum / static_cast<double>(mt.centres_px.size());
  };
  for (int i = 1; i <= 200; ++i) {
    const double t = mt.t_e_s * i / 200;
    const double p_p = mp * sol.StateAt(t).v_m_s;
    const double p_gran = mt.m_grid_kg * mean_velocity(t, 0, 0);
    EXPECT_NEAR((p_p + p_gran - mt.p_max_Ns) / mt.p_max_Ns, 0, 1e-9) << "t = " << t;
    // Any 6 x 2 block under the footprint (shifted by a fraction of a step) has the same mean.
    EXPECT_NEAR(mean_velocity(t, 0.3 * step, 0.5 * step), mean_velocity(t, 0, 0),
                1e-12 * mt.p_max_Ns / mt.m_grid_kg);
  }
  // At t_e soil and pounder move together, and afterwards too.
  EXPECT_NEAR(mean_velocity(mt.t_e_s, 0, 0), sol.StateAt(mt.t_e_s).v_m_s,
              1e-9 * sol.StateAt(mt.t_e_s).v_m_s);
  EXPECT_NEAR(mt.m_add_max_kg, mt.m_grid_kg, 1e-9 * mt.m_grid_kg);
  EXPECT_LT(mt.conservation_error, 1e-12);
  for (double f : {1.2, 2.0, 5.0}) {
    const double t = std::min(mt.t_e_s * f, 0.999 * sol.t_end_s);
    EXPECT_NEAR(mean_velocity(t, 0, 0), sol.StateAt(t).v_m_s, 1e-12);
  }
  // The displacement is the time integral of the velocity (central differences, h = 1e-6 s:
  // truncation ~ h^2 |v''| / 6 far below the tolerance).
  const cv::Point2d m = scene.PanelFromIdeal(mt.centres_px[3]);
  for (double t : {0.3 * mt.t_e_s, 0.9 * mt.t_e_s, 1.5 * mt.t_e_s}) {
    const double h = 1e-6;
    const double fd = (scene.SoilDisplacementMm(m.x, m.y, t + h)[1] -
                       scene.SoilDisplacementMm(m.x, m.y, t - h)[1]) /
                      (2 * h);
    EXPECT_NEAR(fd, scene.SoilVelocityMmS(m.x, m.y, t)[1], 1e-5 * std::abs(fd)) << t;
  }
}

// The Jacobian used by the Newton inversion matches finite differences, outside the core too.
TEST(ImpactScene, SoilGradientMatchesFiniteDifferences) {
  ImpactSceneSpec spec = TinySpec();
  spec.soil.wave_amplitude_mm = 3;
  const ImpactScene scene(spec);
  const double t = 2.5 * scene.momentum().t_e_s;
  const double D = spec.width_m * 1000;
  for (const cv::Point2d p : {cv::Point2d(0.8 * D, 0.1 * D), cv::Point2d(-0.7 * D, 0.9 * D),
                              cv::Point2d(0.1 * D, 1.2 * D), cv::Point2d(0.3 * D, 0.05 * D)}) {
    const cv::Vec4d g = scene.SoilGradient(p.x, p.y, t);
    const double h = 1e-4;
    const cv::Vec2d dx =
        (scene.SoilDisplacementMm(p.x + h, p.y, t) - scene.SoilDisplacementMm(p.x - h, p.y, t)) /
        (2 * h);
    const cv::Vec2d dy =
        (scene.SoilDisplacementMm(p.x, p.y + h, t) - scene.SoilDisplacementMm(p.x, p.y - h, t)) /
        (2 * h);
    EXPECT_NEAR(g[0], dx[0], 1e-6);
    EXPECT_NEAR(g[1], dy[0], 1e-6);
    EXPECT_NEAR(g[2], dx[1], 1e-6);
    EXPECT_NEAR(g[3], dy[1], 1e-6);
  }
  // Strains stay small enough for subsets to correlate.
  for (int i = 0; i < 50; ++i) {
    const double X = -2 * D + 4 * D * i / 49.0;
    for (double Y : {0.0, 0.2 * D, 0.6 * D, 1.2 * D}) {
      const cv::Vec4d g = scene.SoilGradient(X, Y, scene.t_end_s());
      EXPECT_LT(std::max({std::abs(g[0]), std::abs(g[1]), std::abs(g[2]), std::abs(g[3])}), 0.5);
    }
  }
}

TEST(ImpactScene, RenderingDoesNotDependOnTheThreadCount) {
  const ImpactScene scene(TinySpec());
  const cv::Mat many = scene.RenderFrame(4);
  cv::Mat one;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = scene.RenderFrame(4);
  }
  EXPECT_EQ(cv::norm(many, one, cv::NORM_INF), 0.0);
}

// The written scene: the CSV reads back and matches the model, the scene YAML parses, the truth
// file has the documented layout.
TEST(ImpactScene, WrittenSceneIsConsistent) {
  const std::string dir = TempDir("written");
  ImpactSceneSpec spec = TinySpec();
  spec.frames = 24;  // 13 ms: the core has moved by ~4 px.
  const ImpactScene scene(spec);
  const ImpactSceneReport report = WriteImpactScene(scene, dir);
  EXPECT_EQ(report.frames, scene.frame_count());
  for (int k = 0; k < scene.frame_count(); ++k)
    EXPECT_TRUE(fs::exists(fs::path(dir) / "frames" / fmt::format("frame_{:04d}.png", k)));

  // Sensor CSV.
  CsvReadOptions ro;
  ro.required_columns = {"time_s", "accel_g", "exposure"};
  ro.increasing_column = "time_s";
  const CsvTable csv = ReadCsv(report.sensor_csv, ro);
  const auto& time = csv.Column("time_s");
  const auto& accel = csv.Column("accel_g");
  const auto& expo = csv.Column("exposure");
  const SceneSensorOptions& so = scene.spec().sensor;
  const double g = scene.spec().g_m_s2;
  const double impact_daq = scene.DaqTime(0), release_daq = scene.DaqTime(scene.release_time_s());
  EXPECT_GT(release_daq, 0.9 * so.pre_release_s);  // The record starts before the release.
  double sum_rest = 0, sum_free = 0, sum_impact = 0, sum2_impact = 0;
  int n_rest = 0, n_free = 0, n_impact = 0;
  const ImpactModelParameters& p = scene.model_parameters();
  const double M = scene.model_run().summary.added_mass_max_kg;
  for (std::size_t i = 0; i < time.size(); ++i) {
    const double a = accel[i] - so.offset_g;
    if (time[i] < release_daq - 1e-3) {
      sum_rest += a - 1;
      ++n_rest;
    } else if (time[i] > release_daq + 1e-3 && time[i] < impact_daq - 1e-3) {
      sum_free += a;
      ++n_free;
    } else if (time[i] > impact_daq + 2e-4 && time[i] < impact_daq + scene.t_end_s() - 2e-3) {
      const double t = time[i] - impact_daq;
      const ImpactState s = scene.model_run().solution.StateAt(t);
      const double model = 1 - EvaluateImpactForces(p, M, t, s.z_m, s.v_m_s).dv_dt_m_s2 / g;
      sum_impact += a - model;
      sum2_impact += (a - model) * (a - model);
      ++n_impact;
    }
  }
  ASSERT_GT(n_rest, 100);
  ASSERT_GT(n_free, 1000);
  ASSERT_GT(n_impact, 100);
  // Means within 5 standard errors of the noise; the impact residual's rms is the noise level
  // (+- 15 %: sampling spread of the rms for > 100 samples plus the cell-average/instant gap).
  EXPECT_NEAR(sum_rest / n_rest, 0, 5 * so.noise_g / std::sqrt(n_rest));
  EXPECT_NEAR(sum_free / n_free, 0, 5 * so.noise_g / std::sqrt(n_free));
  EXPECT_NEAR(sum_impact / n_impact, 0, 5 * so.noise_g / std::sqrt(n_impact));
  EXPECT_NEAR(std::sqrt(sum2_impact / n_impact), so.noise_g, 0.15 * so.noise_g);
  // Exposure: one rising edge per frame, within one sample after the frame time.
  std::vector<double> edges;
  for (std::size_t i = 1; i < expo.size(); ++i)
    if (expo[i] > 0.5 && expo[i - 1] < 0.5) edges.push_back(time[i]);
  if (expo[0] > 0.5) edges.insert(edges.begin(), time[0]);
  ASSERT_EQ(static_cast<int>(edges.size()), scene.frame_count());
  const double dt = 1 / so.rate_hz;
  for (int k = 0; k < scene.frame_count(); ++k) {
    const double tk = scene.DaqTime(scene.FrameTime(k));
    EXPECT_GE(edges[k], tk - 1e-9) << k;
    EXPECT_LT(edges[k], tk + dt) << k;
  }
  EXPECT_NEAR(edges[0], scene.DaqTime(scene.FrameTime(0)), 1e-9);  // frame 0 on a sample
  EXPECT_GT(time.back(), scene.DaqTime(scene.FrameTime(scene.frame_count() - 1)) + 0.01);

  // Scene YAML.
  const Scene parsed = LoadScene(report.scene_yaml);
  EXPECT_DOUBLE_EQ(parsed.inputs.fps, scene.spec().fps);
  EXPECT_DOUBLE_EQ(parsed.inputs.mm_per_px, scene.spec().mm_per_px);  // tiny: no calibration
  EXPECT_TRUE(parsed.inputs.calibration.empty());
  EXPECT_TRUE(fs::exists(parsed.inputs.sensor));
  EXPECT_TRUE(fs::exists(parsed.inputs.truth));
  EXPECT_EQ(parsed.dic.options.grid.subset_size, scene.spec().subset_size);
  EXPECT_EQ(parsed.dic.options.grid.step, scene.spec().step);
  EXPECT_EQ(parsed.dic.roi, scene.dic_grid().roi);
  ASSERT_TRUE(parsed.momentum.pounder_center_x_px.has_value());
  EXPECT_DOUBLE_EQ(*parsed.momentum.pounder_center_x_px, scene.axis_px());
  EXPECT_DOUBLE_EQ(*parsed.momentum.surface_y_px, scene.surface_px());
  ASSERT_FALSE(std::isnan(parsed.model.added_mass_kg));
  EXPECT_NEAR(parsed.model.added_mass_kg, M, 1e-9 * M);
  EXPECT_DOUBLE_EQ(parsed.model.pounder_mass_kg, scene.spec().pounder_mass_kg);

  // Truth file.
  H5Reader truth(report.truth_h5);
  Dims dims;
  const std::vector<double> u = truth.ReadDouble("soil/u_px", &dims);
  ASSERT_EQ(dims.size(), 3u);
  EXPECT_EQ(dims[0], static_cast<std::size_t>(scene.frame_count()));
  EXPECT_EQ(dims[1], static_cast<std::size_t>(scene.dic_grid().rows));
  EXPECT_EQ(dims[2], static_cast<std::size_t>(scene.dic_grid().cols));
  for (std::size_t i = 0; i < dims[1] * dims[2]; ++i) EXPECT_EQ(u[i], 0.0);  // reference frame
  EXPECT_DOUBLE_EQ(truth.ReadDouble("momentum/p_max_Ns")[0], scene.momentum().p_max_Ns);
  EXPECT_DOUBLE_EQ(truth.ReadDouble("momentum/t_e_s")[0], scene.momentum().t_e_s);
  EXPECT_EQ(truth.ReadDouble("momentum/grid_x_px").size(), 12u);
  const std::vector<double> v = truth.ReadDouble("soil/v_px");
  const std::size_t last = (dims[0] - 1) * dims[1] * dims[2];
  double v_max = 0;
  for (std::size_t i = last; i < v.size(); ++i) v_max = std::max(v_max, v[i]);
  EXPECT_GT(v_max, 2.0);  // The soil visibly moves (px).
}

TEST(ImpactScene, CliWritesASceneAndRejectsBadSpecs) {
  const std::string dir = TempDir("cli");
  const CliResult ok = RunCli("synth --preset tiny --frames 4 -o " + dir + "/out");
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
  EXPECT_TRUE(fs::exists(dir + "/out/scene.yaml")) << ok.output;
  EXPECT_TRUE(fs::exists(dir + "/out/truth.h5"));
  EXPECT_TRUE(fs::exists(dir + "/out/frames/frame_0003.png"));

  {
    std::ofstream bad(dir + "/bad.yaml");
    bad << "preset: tiny\nframes:\n  bits: 10\n";
  }
  const CliResult r = RunCli("synth " + dir + "/bad.yaml -o " + dir + "/bad_out");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("frames.bits"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("10"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir + "/bad_out/scene.yaml"));

  const CliResult missing = RunCli("synth " + dir + "/nope.yaml -o " + dir + "/x");
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.output.find("nope.yaml"), std::string::npos) << missing.output;
  const CliResult frames = RunCli("synth --preset tiny --frames 1 -o " + dir + "/y");
  EXPECT_NE(frames.exit_code, 0);
  EXPECT_NE(frames.output.find("--frames"), std::string::npos) << frames.output;
}

}  // namespace
}  // namespace impactdic
