// Synthetic impact scene: the spec YAML, the emitted scene file, and writing a scene to disk
// (frames, sensor CSV, calibration images, truth HDF5). Layout documented in docs/synth.md.
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <opencv2/core.hpp>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

#include "impactdic/core/enum_names.h"
#include "impactdic/core/error.h"
#include "impactdic/core/interrupt.h"
#include "impactdic/core/progress.h"
#include "impactdic/core/timer.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/csv.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/image_io.h"
#include "impactdic/io/input_file.h"
#include "impactdic/io/output_generation.h"
#include "impactdic/io/yaml.h"
#include "impactdic/model/impact_model.h"
#include "impactdic/synth/checkerboard.h"
#include "impactdic/synth/impact_scene.h"
#include "impactdic/synth/speckle.h"
#include "scene_files.h"
#include "spec_keys.h"
#include "strain_truth.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

constexpr const char* kSpecFileWhat = "a synthetic scene spec (YAML)";

using synth_detail::Integer;
using synth_detail::Number;
using synth_detail::NumberList;
using synth_detail::Seed;
using synth_detail::TextList;

YamlOptionTable TestAndModelKeys(ImpactSceneSpec* s, YamlOptionTable* model) {
  YamlOptionTable t("test");
  Number(t, "mass_kg", &s->pounder_mass_kg);
  Number(t, "drop_height_m", &s->drop_height_m);
  Number(t, "impact_velocity_m_s", &s->impact_velocity_m_s);
  Number(t, "width_m", &s->width_m);
  Number(t, "depth_m", &s->depth_m);
  Number(t, "density_kg_m3", &s->density_kg_m3);
  Number(t, "bed_height_m", &s->bed_height_m);
  Number(t, "g_m_s2", &s->g_m_s2);
  model->AddCustom(
      "added_mass", "grid, eq4 or an added mass >= 0 [kg]", ToString(s->added_mass),
      [s](const YAML::Node& n) {
        double v = 0;
        if (n.IsScalar() && n.Scalar() == "grid") {
          s->added_mass = SceneAddedMass::kGrid;
        } else if (n.IsScalar() && n.Scalar() == "eq4") {
          s->added_mass = SceneAddedMass::kEq4;
        } else if (n.IsScalar() && YAML::convert<double>::decode(n, v) && std::isfinite(v) &&
                   v >= 0) {
          s->added_mass = SceneAddedMass::kGiven;
          s->added_mass_kg = v;
        } else {
          return false;
        }
        return true;
      },
      "");
  Number(*model, "K", &s->K);
  Number(*model, "n", &s->n);
  Number(*model, "u", &s->u);
  Number(*model, "T_s", &s->T_s);
  Number(*model, "b_per_s", &s->b_per_s);
  return t;
}

YamlOptionTable CameraKeys(ImpactSceneSpec* s) {
  YamlOptionTable t("camera");
  t.AddChoice(
      "lens", kSceneLensNames.Names(), ToString(s->lens),
      [s](const std::string& v) { s->lens = SceneLensFromString(v, "camera.lens"); }, "");
  Integer(t, "width", &s->width);
  Integer(t, "height", &s->height);
  Number(t, "mm_per_px", &s->mm_per_px);
  Number(t, "fps", &s->fps);
  Number(t, "surface_fraction", &s->surface_fraction);
  return t;
}

YamlOptionTable FramesKeys(ImpactSceneSpec* s) {
  YamlOptionTable t("frames");
  Integer(t, "before_impact", &s->frames_before_impact);
  Integer(t, "count", &s->frames);
  Number(t, "impact_phase", &s->impact_phase);
  Integer(t, "bits", &s->bits);
  Number(t, "noise_sigma", &s->noise_sigma);
  Integer(t, "supersampling", &s->supersampling);
  Number(t, "background_level", &s->background_level);
  Number(t, "pounder_level", &s->pounder_level);
  return t;
}

YamlOptionTable SpeckleKeys(ImpactSceneSpec* s) {
  YamlOptionTable t("speckle");
  Number(t, "blob_radius_px", &s->speckle.blob_radius_px);
  Number(t, "density", &s->speckle.density);
  Number(t, "contrast", &s->speckle.contrast);
  Number(t, "background", &s->speckle.background);
  Seed(t, "seed", &s->speckle.seed);
  return t;
}

YamlOptionTable SoilKeys(SceneSoilOptions* soil) {
  YamlOptionTable t("soil");
  Number(t, "core_depth_mm", &soil->core_depth_mm);
  Number(t, "cone_depth_mm", &soil->cone_depth_mm);
  Number(t, "decay_length_mm", &soil->decay_length_mm);
  Number(t, "wave_speed_m_s", &soil->wave_speed_m_s);
  Number(t, "wave_amplitude_mm", &soil->wave_amplitude_mm);
  Number(t, "wave_decay_length_mm", &soil->wave_decay_length_mm);
  Number(t, "wave_rise_time_s", &soil->wave_rise_time_s);
  return t;
}

YamlOptionTable SensorKeys(SceneSensorOptions* sensor) {
  YamlOptionTable t("sensor");
  Number(t, "rate_hz", &sensor->rate_hz);
  Number(t, "offset_g", &sensor->offset_g);
  Number(t, "noise_g", &sensor->noise_g);
  Number(t, "exposure_s", &sensor->exposure_s);
  Number(t, "pre_release_s", &sensor->pre_release_s);
  Number(t, "tail_s", &sensor->tail_s);
  return t;
}

YamlOptionTable BaseSensorKeys(SceneBaseSensorOptions* b) {
  YamlOptionTable t("base_sensors");
  TextList(t, "columns", &b->columns);
  NumberList(t, "offsets_mm", &b->offset_mm);
  NumberList(t, "depths_mm", &b->depth_mm);
  NumberList(t, "areas_mm2", &b->area_mm2);
  Number(t, "stress_ratio", &b->stress_ratio);
  Number(t, "spreading_exponent", &b->spreading_exponent);
  Number(t, "offset_n", &b->offset_n);
  Number(t, "noise_n", &b->noise_n);
  return t;
}

// The spec's sections (after `preset`, which sets the defaults they override).
std::vector<YamlOptionTable> SpecTables(ImpactSceneSpec* s) {
  YamlOptionTable model("model");
  YamlOptionTable test = TestAndModelKeys(s, &model);
  YamlOptionTable dic("dic");
  Integer(dic, "subset_size", &s->subset_size);
  Integer(dic, "step", &s->step);
  YamlOptionTable momentum("momentum");
  Integer(momentum, "grid_cols", &s->grid_cols);
  Integer(momentum, "grid_rows", &s->grid_rows);
  YamlOptionTable calibration("calibration");
  calibration.Add("render", &s->render_calibration, "");
  Integer(calibration, "views", &s->calibration_views);
  calibration.Add("scene_yaml", &s->calibration_yaml, "");
  return {test,
          model,
          CameraKeys(s),
          FramesKeys(s),
          SpeckleKeys(s),
          SoilKeys(&s->soil),
          SensorKeys(&s->sensor),
          BaseSensorKeys(&s->base_sensors),
          dic,
          momentum,
          calibration};
}

std::string Num(double v) { return fmt::format("{}", v); }

}  // namespace

ImpactSceneSpec ParseImpactSceneSpec(const std::string& yaml_text, const std::string& path) {
  const YAML::Node root = LoadYaml(yaml_text, path, kSpecFileWhat);
  YamlProblems problems(path);
  YamlSection top(root, "", &problems);
  ImpactSceneSpec spec;
  std::string preset;
  top.Read("preset", &preset);
  if (!preset.empty()) {
    try {
      spec = ImpactScenePreset(preset);
    } catch (Error& e) {
      throw e.WithFile(path);
    }
  }
  top.Read("name", &spec.name);
  top.Read("seed", &spec.seed);
  for (const YamlOptionTable& table : SpecTables(&spec)) {
    YamlSection section = top.Sub(table.section());
    table.Read(section);
    section.Finish();
  }
  top.Finish();
  problems.ThrowIfAny("synthetic scene spec");
  try {
    spec.Check();
  } catch (Error& e) {
    throw e.WithFile(path);
  }
  return spec;
}

ImpactSceneSpec LoadImpactSceneSpec(const std::string& path) {
  return ParseImpactSceneSpec(ReadInputFile(path, kSpecFileWhat, kMaxTextFileBytes), path);
}

std::string ImpactSceneSpecToYaml(const ImpactSceneSpec& s) {
  std::ostringstream o;
  o << "# impactdic synth scene spec (keys: docs/synth.md)\n";
  o << fmt::format("name: {}\nseed: {}\n", s.name, s.seed);
  o << "test:\n" << fmt::format("  mass_kg: {}\n", s.pounder_mass_kg);
  if (std::isnan(s.impact_velocity_m_s)) {
    o << fmt::format("  drop_height_m: {}\n", s.drop_height_m);
  } else {
    o << fmt::format("  impact_velocity_m_s: {}\n", s.impact_velocity_m_s);
  }
  o << fmt::format(
      "  width_m: {}\n  depth_m: {}\n  density_kg_m3: {}\n  bed_height_m: {}\n"
      "  g_m_s2: {}\n",
      s.width_m, s.depth_m, s.density_kg_m3, s.bed_height_m, s.g_m_s2);
  o << "model:\n  added_mass: "
    << (s.added_mass == SceneAddedMass::kGiven ? Num(s.added_mass_kg) : ToString(s.added_mass))
    << fmt::format("\n  K: {}\n  n: {}\n  u: {}\n  T_s: {}\n  b_per_s: {}\n", s.K, s.n, s.u, s.T_s,
                   s.b_per_s);
  o << fmt::format(
      "camera:\n  lens: {}\n  width: {}\n  height: {}\n  mm_per_px: {}\n  fps: {}\n"
      "  surface_fraction: {}\n",
      ToString(s.lens), s.width, s.height, s.mm_per_px, s.fps, s.surface_fraction);
  o << fmt::format(
      "frames:\n  before_impact: {}\n  count: {}\n  impact_phase: {}\n  bits: {}\n"
      "  noise_sigma: {}\n  supersampling: {}\n  background_level: {}\n"
      "  pounder_level: {}\n",
      s.frames_before_impact, s.frames, s.impact_phase, s.bits, s.noise_sigma, s.supersampling,
      s.background_level, s.pounder_level);
  o << fmt::format(
      "speckle:\n  blob_radius_px: {}\n  density: {}\n  contrast: {}\n"
      "  background: {}\n  seed: {}\n",
      s.speckle.blob_radius_px, s.speckle.density, s.speckle.contrast, s.speckle.background,
      s.speckle.seed);
  o << fmt::format(
      "soil:\n  core_depth_mm: {}\n  cone_depth_mm: {}\n  decay_length_mm: {}\n"
      "  wave_speed_m_s: {}\n  wave_amplitude_mm: {}\n  wave_decay_length_mm: {}\n"
      "  wave_rise_time_s: {}\n",
      s.soil.core_depth_mm, s.soil.cone_depth_mm, s.soil.decay_length_mm, s.soil.wave_speed_m_s,
      s.soil.wave_amplitude_mm, s.soil.wave_decay_length_mm, s.soil.wave_rise_time_s);
  o << fmt::format(
      "sensor:\n  rate_hz: {}\n  offset_g: {}\n  noise_g: {}\n  exposure_s: {}\n"
      "  pre_release_s: {}\n  tail_s: {}\n",
      s.sensor.rate_hz, s.sensor.offset_g, s.sensor.noise_g, s.sensor.exposure_s,
      s.sensor.pre_release_s, s.sensor.tail_s);
  o << fmt::format("dic:\n  subset_size: {}\n  step: {}\n", s.subset_size, s.step);
  const SceneBaseSensorOptions& b = s.base_sensors;
  if (!b.columns.empty()) {  // Only with base sensors: other specs read as before.
    o << fmt::format(
        "base_sensors:\n  columns: [{}]\n  offsets_mm: [{}]\n  depths_mm: [{}]\n"
        "  areas_mm2: [{}]\n  stress_ratio: {}\n  spreading_exponent: {}\n  offset_n: {}\n"
        "  noise_n: {}\n",
        fmt::join(b.columns, ", "), fmt::join(b.offset_mm, ", "), fmt::join(b.depth_mm, ", "),
        fmt::join(b.area_mm2, ", "), b.stress_ratio, b.spreading_exponent, b.offset_n, b.noise_n);
  }
  o << fmt::format("momentum:\n  grid_cols: {}\n  grid_rows: {}\n", s.grid_cols, s.grid_rows);
  o << fmt::format("calibration:\n  render: {}\n  views: {}\n",
                   s.render_calibration ? "true" : "false", s.calibration_views);
  if (!s.calibration_yaml.empty()) o << fmt::format("  scene_yaml: \"{}\"\n", s.calibration_yaml);
  return o.str();
}

std::string ImpactSceneYaml(const ImpactScene& scene, const std::string& calibration_yaml) {
  const ImpactSceneSpec& s = scene.spec();
  const ImpactModelParameters& p = scene.model_parameters();
  const SceneDicGrid& grid = scene.dic_grid();
  std::ostringstream o;
  o << "# Scene generated by `impactdic synth` (docs/synth.md). Process it with\n"
    << "#   impactdic run scene.yaml\n"
    << "# Pixel positions are in the undistorted first frame.\n";
  o << fmt::format("name: {}\n", s.name);
  o << "inputs:\n  frames: \"frames/frame_*.png\"\n" << fmt::format("  fps: {}\n", s.fps);
  if (!calibration_yaml.empty()) {
    o << fmt::format("  calibration: \"{}\"\n", calibration_yaml);
  } else {
    o << fmt::format("  mm_per_px: {:.12g}\n", s.mm_per_px);
  }
  o << "  sensor: sensor.csv\n  truth: truth.h5\n";
  o << "test:\n" << fmt::format("  mass_kg: {}\n", s.pounder_mass_kg);
  if (std::isnan(s.impact_velocity_m_s)) {
    o << fmt::format("  drop_height_m: {}\n", s.drop_height_m);
  } else {
    o << fmt::format("  drop_height_m: {:.12g}\n  impact_velocity_m_s: {}\n",
                     s.impact_velocity_m_s * s.impact_velocity_m_s / (2 * s.g_m_s2),
                     s.impact_velocity_m_s);
  }
  o << fmt::format(
      "  width_m: {}\n  depth_m: {}\n  density_kg_m3: {}\n  bed_height_m: {}\n"
      "  g_m_s2: {}\n",
      s.width_m, s.depth_m, s.density_kg_m3, s.bed_height_m, s.g_m_s2);
  o << "preprocess:\n  gaussian:\n    enabled: auto\n  clahe:\n    enabled: false\n";
  o << fmt::format("dic:\n  subset_size: {}\n  step: {}\n  roi: [{}, {}, {}, {}]\n", s.subset_size,
                   s.step, grid.roi[0], grid.roi[1], grid.roi[2], grid.roi[3]);
  o << "  interpolation: bicubic\n  shape: affine\n  reference_update: auto\n"
       "  min_zncc: 0.8\n  max_iterations: 30\n  convergence_px: 0.001\n  search_radius_px: 12\n";
  o << "sensor:\n  time_column: time_s\n  accel_column: accel_g\n  accel_unit: g\n"
       "  exposure_column: exposure\n  cutoff_hz: 1500\n  integrate_from: release\n"
    << fmt::format("  quiet_window_s: {}\n",
                   std::min(0.005, 0.8 * s.sensor.pre_release_s > 0 ? 0.8 * s.sensor.pre_release_s
                                                                    : 0.005));
  const SceneBaseSensorOptions& b = s.base_sensors;
  if (!b.columns.empty()) {
    o << fmt::format(
        "  base_columns: [{}]\n  base_units: [{}]\n  base_offsets_mm: [{}]\n"
        "  base_depths_mm: [{}]\n  base_areas_mm2: [{}]\n",
        fmt::join(b.columns, ", "),
        fmt::join(std::vector<std::string>(b.columns.size(), "N"), ", "),
        fmt::join(b.offset_mm, ", "), fmt::join(b.depth_mm, ", "), fmt::join(b.area_mm2, ", "));
  }
  o << fmt::format(
      "momentum:\n  pounder_center_x_px: {}\n  surface_y_px: {}\n  grid_cols: {}\n"
      "  grid_rows: {}\n",
      scene.axis_px(), scene.surface_px(), s.grid_cols, s.grid_rows);
  o << fmt::format(
      "model:\n  added_mass_kg: {:.12g}\n  K: {}\n  n: {}\n  u: {}\n  T_s: {}\n"
      "  b_per_s: {}\n  solver: auto\n  rtol: 1.0e-8\n  atol: 1.0e-12\n",
      scene.model_run().summary.added_mass_max_kg, p.friction_K, p.damping_exponent_n,
      p.damping_factor_u, p.sigmoid_delay_T_s, p.sigmoid_rate_b_per_s);
  o << "outputs:\n  folder: results\n  hdf5: true\n  csv: true\n  figures: true\n"
       "  animation: true\n  png_frames: false\n";
  return o.str();
}

std::string ImpactSceneReport::BriefReport() const {
  return fmt::format(
      "synth: {} frames in {} ({:.1f} s rendering, {:.1f} s total); t_e = {:.4g} ms, "
      "p_max = {:.4g} N s, m_grid = {:.4g} kg, crater depth = {:.4g} mm",
      frames, out_dir, render_seconds, total_seconds, t_e_s * 1e3, p_max_Ns, m_grid_kg,
      crater_depth_m * 1e3);
}

namespace {

// truth.h5, frames/ and pounder/: the frame times (returned), the pounder's path and the model's
// end of motion.
std::vector<double> WriteFrameTruth(const ImpactScene& scene, H5Writer& out) {
  const ImpactSummary& sum = scene.model_run().summary;
  const auto F = static_cast<std::size_t>(scene.frame_count());
  std::vector<double> t(F), daq(F), z(F), v(F), bottom(F);
  for (std::size_t k = 0; k < F; ++k) {
    t[k] = scene.FrameTime(static_cast<int>(k));
    daq[k] = scene.DaqTime(t[k]);
    const PounderState ps = scene.Pounder(t[k]);
    z[k] = ps.z_m;
    v[k] = ps.v_m_s;
    bottom[k] = scene.surface_px() + ps.z_m * 1000 / scene.sy_mm_per_px();
  }
  out.Write("frames/time_s", t, "s", "frame time since impact (rising exposure edge)");
  out.Write("frames/daq_time_s", daq, "s", "frame time on the DAQ clock of sensor.csv");
  out.Write("pounder/z_m", z, "m", "pounder bottom below the undisturbed surface, down positive");
  out.Write("pounder/v_m_s", v, "m/s", "pounder velocity, down positive");
  out.Write("pounder/bottom_y_px", bottom, "px", "pounder bottom row (ideal px)");
  out.Write("pounder/crater_depth_m", std::vector<double>{sum.crater_depth_m}, "m",
            "final penetration (model)");
  out.Write("pounder/t_end_s", std::vector<double>{sum.t_end_s}, "s", "time the pounder stops");
  return t;
}

// truth.h5, soil/: the displacement and velocity of every DIC subset centre in every frame, and
// which subsets the pounder covers.
void WriteSoilTruth(const ImpactScene& scene, const std::vector<double>& t, H5Writer& out) {
  const ImpactSceneSpec& s = scene.spec();
  const SceneDicGrid& grid = scene.dic_grid();
  const std::size_t F = t.size(), n = grid.centres_px.size();
  const Dims gdims{static_cast<std::size_t>(grid.rows), static_cast<std::size_t>(grid.cols)};
  const Dims fdims{F, gdims[0], gdims[1]};
  std::vector<double> gx(n), gy(n), u_px(F * n), v_px(F * n), vel_x(F * n), vel_y(F * n);
  std::vector<std::int32_t> occluded(F * n);
  synth_internal::GradientTruth grad;
  for (auto* c : {&grad.dudx, &grad.dudy, &grad.dvdx, &grad.dvdy}) c->resize(F * n);
  const int half = s.subset_size / 2;
  for (std::size_t i = 0; i < n; ++i) {
    gx[i] = grid.centres_px[i].x;
    gy[i] = grid.centres_px[i].y;
  }
  for (std::size_t k = 0; k < F; ++k) {
    const DisplacementField field = scene.SoilFieldPx(t[k]);
    for (std::size_t i = 0; i < n; ++i) {
      const cv::Point2d m = scene.PanelFromIdeal(grid.centres_px[i]);
      const cv::Vec2d d = scene.SoilDisplacementMm(m.x, m.y, t[k]);
      const cv::Vec2d vel = scene.SoilVelocityMmS(m.x, m.y, t[k]);
      const std::size_t j = k * n + i;
      u_px[j] = d[0] / scene.sx_mm_per_px();
      v_px[j] = d[1] / scene.sy_mm_per_px();
      vel_x[j] = vel[0];
      vel_y[j] = vel[1];
      occluded[j] = scene.PounderCovers(gx[i] + u_px[j], gy[i] + v_px[j], half, t[k]) ? 1 : 0;
      const cv::Vec4d h = field.gradient(gx[i], gy[i]);  // exact: the field's own Jacobian
      grad.dudx[j] = h[0], grad.dudy[j] = h[1], grad.dvdx[j] = h[2], grad.dvdy[j] = h[3];
    }
  }
  out.Write("soil/grid_x_px", gx, gdims, "px", "DIC subset centres in the first frame, x");
  out.Write("soil/grid_y_px", gy, gdims, "px", "DIC subset centres in the first frame, y");
  out.Write("soil/u_px", u_px, fdims, "px", "displacement of the subset centres, x right");
  out.Write("soil/v_px", v_px, fdims, "px", "displacement of the subset centres, y down");
  out.Write("soil/velocity_x_mm_s", vel_x, fdims, "mm/s", "velocity of the subset centres");
  out.Write("soil/velocity_y_mm_s", vel_y, fdims, "mm/s", "velocity of the subset centres, down");
  out.Write("soil/occluded", occluded, fdims, "1",
            "1 where the pounder covers part of the deformed subset");
  synth_internal::WriteStrainTruth(grad, fdims, "analytic Jacobian of the soil field", out);
  out.SetAttribute("soil", "subset_size_px", s.subset_size);
  out.SetAttribute("soil", "step_px", s.step);
  out.SetAttribute("soil", "roi_x0_px", grid.roi[0]);
  out.SetAttribute("soil", "roi_y0_px", grid.roi[1]);
  out.SetAttribute("soil", "roi_x1_px", grid.roi[2]);
  out.SetAttribute("soil", "roi_y1_px", grid.roi[3]);
  out.SetAttribute("soil", "core_depth_mm", scene.core_depth_mm());
  out.SetAttribute("soil", "cone_depth_mm", scene.cone_depth_mm());
  out.SetAttribute("soil", "decay_length_mm", scene.decay_length_mm());
  out.SetAttribute("soil", "wave_speed_m_s", s.soil.wave_speed_m_s);
  out.SetAttribute("soil", "wave_amplitude_mm", s.soil.wave_amplitude_mm);
  out.SetAttribute("soil", "wave_decay_length_mm", s.soil.wave_decay_length_mm);
  out.SetAttribute("soil", "wave_rise_time_s", s.soil.wave_rise_time_s);
}

// truth.h5, momentum/: the default momentum grid, the momenta in every frame and the peak-stage
// figures (Eqs. 3, 11).
void WriteMomentumTruth(const ImpactScene& scene, const std::vector<double>& t, H5Writer& out) {
  const SceneMomentumTruth& mt = scene.momentum();
  const std::size_t F = t.size();
  std::vector<double> W(F), vs(F), pp(F), pg(F), ptot(F), madd(F);
  for (std::size_t k = 0; k < F; ++k) {
    W[k] = scene.CoreDisplacement(t[k]);
    vs[k] = scene.CoreVelocity(t[k]);
    pp[k] = scene.PounderMomentum(t[k]);
    pg[k] = scene.GranularMomentum(t[k]);
    ptot[k] = pp[k] + pg[k];
    madd[k] = t[k] > 0 ? scene.AddedMassEq3(t[k]) : std::nan("");
  }
  std::vector<double> mx, my;
  for (const auto& c : mt.centres_px) {
    mx.push_back(c.x);
    my.push_back(c.y);
  }
  const Dims mdims{static_cast<std::size_t>(mt.rows), static_cast<std::size_t>(mt.cols)};
  out.Write("momentum/grid_x_px", mx, mdims, "px", "default momentum grid subset centres, x");
  out.Write("momentum/grid_y_px", my, mdims, "px", "default momentum grid subset centres, y");
  out.Write("momentum/v_sand_m_s", vs, "m/s", "mean vertical soil velocity over the grid");
  out.Write("momentum/w_sand_m", W, "m", "vertical soil displacement of the grid (rigid core)");
  out.Write("momentum/p_pounder_Ns", pp, "N s", "m_p v_p");
  out.Write("momentum/p_gran_Ns", pg, "N s", "m_grid v_sand");
  out.Write("momentum/p_total_Ns", ptot, "N s", "p_pounder + p_gran");
  out.Write("momentum/m_add_kg", madd, "kg", "Eq. 3: p_max / v_p - m_p (NaN before impact)");
  auto scalar = [&](const std::string& name, double value, const std::string& units,
                    const std::string& what) {
    out.Write("momentum/" + name, std::vector<double>{value}, units, what);
  };
  scalar("p_max_Ns", mt.p_max_Ns, "N s", "maximum pounder momentum");
  scalar("t_pmax_s", mt.t_pmax_s, "s", "time of the maximum pounder momentum");
  scalar("t_e_s", mt.t_e_s, "s", "end of the peak stage: (m_p + m_grid) v_p = p_max");
  scalar("v_te_m_s", mt.v_te_m_s, "m/s", "v_p(t_e) = v_sand(t_e)");
  scalar("m_add_max_kg", mt.m_add_max_kg, "kg", "m_add(t_e) = m_grid");
  scalar("m_grid_kg", mt.m_grid_kg, "kg", "rho_d * grid area * t_z");
  scalar("grid_area_mm2", mt.grid_area_mm2, "mm^2", "cols * rows * step^2 * s^2");
  scalar("conservation_error", mt.conservation_error, "1",
         "|p_pounder + p_gran - p_max| / p_max at t_e (0 by design)");
  scalar("momentum_ratio", mt.m_add_max_kg * mt.v_te_m_s / mt.p_max_Ns, "1",
         "p_gran(t_e) / p_max (Eq. 11 with v_sand,max = v_p(t_e))");
  out.SetAttribute("momentum", "cell_area_mm2", mt.cell_area_mm2);
  out.SetAttribute("momentum", "relative_penetration_mm", mt.relative_penetration_mm);
  out.SetAttribute("momentum", "grid_definition",
                   "grid_cols x grid_rows subsets of the DIC grid, centred on the pounder axis, "
                   "the first grid_rows rows below the surface; each subset stands for a step x "
                   "step cell; the soil velocity is uniform there (rigid core)");
}

// truth.h5, series/: fine series at the DAQ rate from 2 ms before impact to the end of the record.
void WriteSeriesTruth(const ImpactScene& scene, const ImpactScene::SensorRecord& rec,
                      H5Writer& out) {
  std::vector<double> st, sz, sv, svs, sw, spp, spg, sm, sa;
  for (std::size_t i = 0; i < rec.time_s.size(); ++i) {
    const double ti = rec.time_s[i] - rec.impact_daq_time_s;
    if (ti < -0.002) continue;
    const PounderState ps = scene.Pounder(ti);
    st.push_back(ti);
    sz.push_back(ps.z_m);
    sv.push_back(ps.v_m_s);
    svs.push_back(scene.CoreVelocity(ti));
    sw.push_back(scene.CoreDisplacement(ti));
    spp.push_back(scene.PounderMomentum(ti));
    spg.push_back(scene.GranularMomentum(ti));
    sm.push_back(ti > 0 ? scene.AddedMassEq3(ti) : std::nan(""));
    sa.push_back(rec.accel_true_g[i]);
  }
  out.Write("series/t_s", st, "s", "time since impact (DAQ samples from 2 ms before impact)");
  out.Write("series/z_m", sz, "m", "pounder depth");
  out.Write("series/v_m_s", sv, "m/s", "pounder velocity");
  out.Write("series/v_sand_m_s", svs, "m/s", "grid soil velocity");
  out.Write("series/w_sand_m", sw, "m", "grid soil displacement");
  out.Write("series/p_pounder_Ns", spp, "N s", "m_p v_p");
  out.Write("series/p_gran_Ns", spg, "N s", "m_grid v_sand");
  out.Write("series/m_add_kg", sm, "kg", "Eq. 3 added mass");
  out.Write("series/accel_true_g", sa, "g", "noise-free accelerometer reading (sensor up)");
}

// truth.h5, the attributes of sensor/ (timing), model/ (parameters and summary) and camera/.
void WriteSetupTruth(const ImpactScene& scene, const ImpactScene::SensorRecord& rec,
                     H5Writer& out) {
  const ImpactSceneSpec& s = scene.spec();
  const ImpactSummary& sum = scene.model_run().summary;
  // Sensor timing.
  out.CreateGroup("sensor");
  out.SetAttribute("sensor", "frame0_daq_time_s", rec.frame0_daq_time_s);
  out.SetAttribute("sensor", "impact_daq_time_s", rec.impact_daq_time_s);
  out.SetAttribute("sensor", "release_daq_time_s", rec.release_daq_time_s);
  out.SetAttribute("sensor", "offset_g", s.sensor.offset_g);
  out.SetAttribute("sensor", "noise_g", s.sensor.noise_g);
  out.SetAttribute("sensor", "rate_hz", s.sensor.rate_hz);
  out.SetAttribute("sensor", "exposure_s", s.sensor.exposure_s);

  // Model.
  const ImpactModelParameters& p = scene.model_parameters();
  out.CreateGroup("model");
  out.SetAttribute("model", "pounder_mass_kg", p.pounder_mass_kg);
  out.SetAttribute("model", "impact_velocity_m_s", p.impact_velocity_m_s);
  out.SetAttribute("model", "width_m", p.width_m);
  out.SetAttribute("model", "depth_m", p.depth_m);
  out.SetAttribute("model", "added_mass_kg", sum.added_mass_max_kg);
  out.SetAttribute("model", "added_mass_mode", ToString(s.added_mass));
  out.SetAttribute("model", "K", p.friction_K);
  out.SetAttribute("model", "n", p.damping_exponent_n);
  out.SetAttribute("model", "u", p.damping_factor_u);
  out.SetAttribute("model", "T_s", p.sigmoid_delay_T_s);
  out.SetAttribute("model", "b_per_s", p.sigmoid_rate_b_per_s);
  out.SetAttribute("model", "density_kg_m3", p.density_kg_m3);
  out.SetAttribute("model", "g_m_s2", p.gravity_m_s2);
  out.SetAttribute("model", "t_end_s", sum.t_end_s);
  out.SetAttribute("model", "crater_depth_m", sum.crater_depth_m);
  out.SetAttribute("model", "relative_penetration", sum.relative_penetration);
  out.SetAttribute("model", "peak_deceleration_g", sum.peak_deceleration_g);
  out.SetAttribute("model", "t_peak_s", sum.t_peak_s);
  out.SetAttribute("model", "plateau_deceleration_g", sum.plateau_deceleration_g);
  out.SetAttribute("model", "momentum_ratio", sum.momentum_ratio);
  out.SetAttribute("model", "solver", sum.solver);

  // Camera.
  const SynthCamera& cam = scene.camera();
  out.CreateGroup("camera");
  out.SetAttribute("camera", "lens", ToString(s.lens));
  out.SetAttribute("camera", "width", cam.width);
  out.SetAttribute("camera", "height", cam.height);
  out.SetAttribute("camera", "fx", cam.fx);
  out.SetAttribute("camera", "fy", cam.fy);
  out.SetAttribute("camera", "cx", cam.cx);
  out.SetAttribute("camera", "cy", cam.cy);
  const char* dist_names[5] = {"k1", "k2", "p1", "p2", "k3"};
  for (int i = 0; i < 5; ++i) out.SetAttribute("camera", dist_names[i], cam.dist[i]);
  out.SetAttribute("camera", "mm_per_px", s.mm_per_px);
  out.SetAttribute("camera", "sx_mm_per_px", scene.sx_mm_per_px());
  out.SetAttribute("camera", "sy_mm_per_px", scene.sy_mm_per_px());
  out.SetAttribute("camera", "distance_mm", s.mm_per_px * std::sqrt(cam.fx * cam.fy));
  out.SetAttribute("camera", "pounder_axis_x_px", scene.axis_px());
  out.SetAttribute("camera", "surface_y_px", scene.surface_px());
  out.SetAttribute("camera", "fps", s.fps);
}

// truth.h5, base_sensors/ (only with base sensors): the wave model's parameters, each sensor's
// position, travel time and stress ratio, and the figures the tool measures computed from the
// noise-free records (docs/synth.md).
void WriteBaseSensorTruth(const ImpactScene& scene, const ImpactScene::SensorRecord& rec,
                          H5Writer& out) {
  const ImpactSceneSpec& s = scene.spec();
  const SceneBaseSensorOptions& b = s.base_sensors;
  if (b.columns.empty()) return;
  const double area_m2 = s.width_m * s.depth_m, c = s.soil.wave_speed_m_s;
  // The pounder's noise-free peak deceleration after the impact (the record's samples).
  double peak_decel_g = 0, pounder_peak_t = kNaN;
  for (std::size_t i = 0; i < rec.time_s.size(); ++i) {
    if (rec.time_s[i] >= rec.impact_daq_time_s && rec.accel_true_g[i] - 1 > peak_decel_g) {
      peak_decel_g = rec.accel_true_g[i] - 1;
      pounder_peak_t = rec.time_s[i] - rec.impact_daq_time_s;
    }
  }
  const double pounder_stress = s.pounder_mass_kg * s.g_m_s2 * peak_decel_g / area_m2;
  std::vector<double> distance, delay, ratio, peak_t, peak_stress, measured_ratio;
  for (std::size_t k = 0; k < b.columns.size(); ++k) {
    const double r = std::hypot(b.offset_mm[k], b.depth_mm[k]);
    distance.push_back(r);
    delay.push_back(1e-3 * r / c);
    ratio.push_back(b.stress_ratio * std::pow(b.depth_mm[k] / r, b.spreading_exponent));
    const std::vector<double>& f = rec.base_force_true_n[k];
    const auto it = std::max_element(f.begin(), f.end());
    peak_t.push_back(rec.time_s[static_cast<std::size_t>(it - f.begin())] - rec.impact_daq_time_s);
    peak_stress.push_back(*it / (1e-6 * b.area_mm2[k]));
    measured_ratio.push_back(peak_stress.back() / pounder_stress);
    out.Write("base_sensors/force_true_N/" + b.columns[k], f, "N",
              "noise-free dynamic base force (no offset); time axis: sensor.csv time_s");
  }
  out.Write("base_sensors/offset_mm", b.offset_mm, "mm", "horizontal offset from the pounder axis");
  out.Write("base_sensors/depth_mm", b.depth_mm, "mm", "depth below the undisturbed surface");
  out.Write("base_sensors/area_mm2", b.area_mm2, "mm^2", "sensing area");
  out.Write("base_sensors/distance_mm", distance, "mm", "straight distance from the impact point");
  out.Write("base_sensors/travel_time_s", delay, "s", "distance / wave speed: the pulse's delay");
  out.Write("base_sensors/stress_ratio_model", ratio, "1",
            "stress_ratio (depth / distance)^spreading_exponent");
  out.Write("base_sensors/peak_s", peak_t, "s",
            "peak of the noise-free base force after the impact (a sample time)");
  out.Write("base_sensors/peak_stress_Pa", peak_stress, "Pa", "noise-free peak force / area");
  out.Write("base_sensors/stress_ratio", measured_ratio, "1",
            "noise-free peak stress / the pounder's noise-free peak stress m_p a_peak / (D t_z) "
            "(the tool's definition, on the record's samples)");
  out.SetAttribute("base_sensors", "wave_speed_m_s", c);
  out.SetAttribute("base_sensors", "stress_ratio", b.stress_ratio);
  out.SetAttribute("base_sensors", "spreading_exponent", b.spreading_exponent);
  out.SetAttribute("base_sensors", "offset_n", b.offset_n);
  out.SetAttribute("base_sensors", "noise_n", b.noise_n);
  out.SetAttribute("base_sensors", "pounder_peak_stress_Pa", pounder_stress);
  out.SetAttribute("base_sensors", "pounder_peak_s", pounder_peak_t);
  out.SetAttribute("base_sensors", "columns", fmt::format("{}", fmt::join(b.columns, ",")));
  out.SetAttribute("base_sensors", "model",
                   "F_k(t) = ratio_k A_k m_p g max(0, decel_g(t - r_k / c)) / (D t_z), ratio_k = "
                   "stress_ratio (depth_k / r_k)^spreading_exponent, r_k from the impact point; "
                   "plus offset_n and noise_n");
}

void WriteTruth(const ImpactScene& scene, const ImpactScene::SensorRecord& rec,
                const std::string& path, const std::string& spec_yaml) {
  H5Writer out(path);
  out.WriteProvenance(spec_yaml);
  out.SetAttribute("/", "generator", "impactdic synth");
  out.SetAttribute("/", "conventions",
                   "t = 0 at contact; depths and velocities down positive; pixels are ideal "
                   "(undistorted) pixels of the first frame, x right, y down; panel mm origin at "
                   "the pounder axis on the undisturbed surface");
  const std::vector<double> t = WriteFrameTruth(scene, out);
  WriteSoilTruth(scene, t, out);
  WriteMomentumTruth(scene, t, out);
  WriteSeriesTruth(scene, rec, out);
  WriteSetupTruth(scene, rec, out);
  WriteBaseSensorTruth(scene, rec, out);
  out.Commit();
}

}  // namespace

namespace synth_internal {

SceneFiles WriteSceneFiles(
    const ImpactScene& base, int frames, const std::function<cv::Mat(int)>& render_frame,
    const std::string& progress_label, const ImpactScene::SensorRecord& record,
    const std::function<void(const std::string&, const std::string&)>& write_truth,
    const std::string& out_dir) {
  const ImpactSceneSpec& s = base.spec();
  const fs::path dir(out_dir);
  SceneFiles files;
  std::error_code ec;
  MakeFolders((dir / "frames").string(), ec);
  if (ec)
    throw Error(ErrorKind::kIo, "-o", OutputPathForMessages(out_dir),
                "a folder that can be created (" + ec.message() + ")");
  // Stale outputs of an earlier run would look complete: remove them first.
  for (const char* name : {"scene.yaml", "truth.h5", "sensor.csv", "spec.yaml"})
    fs::remove(dir / name, ec);
  for (const auto& entry : fs::directory_iterator(dir / "frames", ec)) {
    if (entry.path().extension() == ".png") fs::remove(entry.path(), ec);
  }

  WallTimer render_timer;
  {
    ProgressBar bar(progress_label, static_cast<std::size_t>(frames));
    for (int k = 0; k < frames; ++k) {
      WriteImage((dir / "frames" / fmt::format("frame_{:04d}.png", k)).string(), render_frame(k));
      bar.Advance();
    }
  }
  files.render_seconds = render_timer.ElapsedSeconds();

  // Calibration images through the same lens, the panel view at the scene's scale.
  if (s.render_calibration) {
    CalibrationSetOptions copt;
    copt.views = s.calibration_views;
    copt.seed = s.seed * 31 + 7;
    copt.panel_distance_mm = s.mm_per_px * std::sqrt(base.camera().fx * base.camera().fy);
    copt.render.bits = s.bits;
    files.calibration_dir = (dir / "calibration").string();
    RenderCalibrationSet(base.camera(), CheckerboardSpec{}, copt, files.calibration_dir);
  }
  files.calibration_yaml = !s.calibration_yaml.empty() ? s.calibration_yaml
                           : s.render_calibration      ? "calibration/camera.yaml"
                                                       : "";

  files.sensor_csv = (dir / "sensor.csv").string();
  std::vector<std::string> names = {"time_s", "accel_g", "exposure"};
  std::vector<std::vector<double>> columns = {record.time_s, record.accel_g, record.exposure};
  for (std::size_t k = 0; k < record.base_force_n.size(); ++k) {
    names.push_back(s.base_sensors.columns[k]);
    columns.push_back(record.base_force_n[k]);
  }
  WriteCsv(files.sensor_csv, names, columns, 10);
  const std::string spec_yaml = ImpactSceneSpecToYaml(s);
  files.spec_yaml = (dir / "spec.yaml").string();
  WriteTextFileAtomic(files.spec_yaml, spec_yaml);
  files.truth_h5 = (dir / "truth.h5").string();
  write_truth(files.truth_h5, spec_yaml);
  files.scene_yaml = (dir / "scene.yaml").string();
  WriteTextFileAtomic(files.scene_yaml, ImpactSceneYaml(base, files.calibration_yaml));
  return files;
}

}  // namespace synth_internal

ImpactSceneReport WriteImpactScene(const ImpactScene& scene, const std::string& out_dir) {
  WallTimer total;
  const ImpactScene::SensorRecord rec = scene.MakeSensorRecord();
  const synth_internal::SceneFiles files = synth_internal::WriteSceneFiles(
      scene, scene.frame_count(), [&](int k) { return scene.RenderFrame(k); }, "rendering frames",
      rec,
      [&](const std::string& path, const std::string& spec_yaml) {
        WriteTruth(scene, rec, path, spec_yaml);
      },
      out_dir);
  ImpactSceneReport report;
  report.out_dir = out_dir;
  report.frames = scene.frame_count();
  report.render_seconds = files.render_seconds;
  report.calibration_dir = files.calibration_dir;
  report.calibration_yaml = files.calibration_yaml;
  report.sensor_csv = files.sensor_csv;
  report.spec_yaml = files.spec_yaml;
  report.truth_h5 = files.truth_h5;
  report.scene_yaml = files.scene_yaml;

  report.t_e_s = scene.momentum().t_e_s;
  report.p_max_Ns = scene.momentum().p_max_Ns;
  report.m_grid_kg = scene.momentum().m_grid_kg;
  report.crater_depth_m = scene.model_run().summary.crater_depth_m;
  report.total_seconds = total.ElapsedSeconds();
  return report;
}

}  // namespace impactdic
