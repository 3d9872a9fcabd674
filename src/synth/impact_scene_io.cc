// Synthetic impact scene: the spec YAML, the emitted scene file, and writing a scene to disk
// (frames, sensor CSV, calibration images, truth HDF5). Layout documented in docs/synth.md.
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <set>
#include <sstream>

#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/core/progress.h"
#include "impactdic/core/timer.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/csv.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/image_io.h"
#include "impactdic/io/input_file.h"
#include "impactdic/io/output_generation.h"
#include "impactdic/io/yaml.h"
#include "impactdic/synth/impact_scene.h"
#include "scene_files.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

constexpr const char* kSpecFileWhat = "a synthetic scene spec (YAML)";

// Reads one map of the spec, remembering which keys were asked for so unknown keys are errors.
class SpecSection {
 public:
  SpecSection(YAML::Node node, std::string prefix, std::string file)
      : node_(std::move(node)), prefix_(std::move(prefix)), file_(std::move(file)) {
    if (node_.IsDefined() && !node_.IsNull() && !node_.IsMap())
      Fail(node_, prefix_.empty() ? "(top level)" : prefix_, "a map of keys");
  }

  std::string PathOf(const std::string& key) const {
    return prefix_.empty() ? key : prefix_ + "." + key;
  }
  YAML::Node Get(const std::string& key) {
    known_.insert(key);
    if (!node_.IsDefined() || node_.IsNull()) return YAML::Node();
    return node_[key];
  }
  SpecSection Sub(const std::string& key) { return SpecSection(Get(key), PathOf(key), file_); }

  void Number(const std::string& key, double* value) {
    YAML::Node n = Get(key);
    if (!n.IsDefined() || n.IsNull()) return;
    double v = 0;
    if (!n.IsScalar() || !YAML::convert<double>::decode(n, v) || !std::isfinite(v))
      Fail(n, PathOf(key), "a number");
    *value = v;
  }
  void Integer(const std::string& key, int* value) {
    YAML::Node n = Get(key);
    if (!n.IsDefined() || n.IsNull()) return;
    int v = 0;
    if (!n.IsScalar() || !YAML::convert<int>::decode(n, v)) Fail(n, PathOf(key), "an integer");
    *value = v;
  }
  void Unsigned(const std::string& key, std::uint64_t* value) {
    YAML::Node n = Get(key);
    if (!n.IsDefined() || n.IsNull()) return;
    unsigned long long v = 0;
    if (!n.IsScalar() || !YAML::convert<unsigned long long>::decode(n, v))
      Fail(n, PathOf(key), "a non-negative integer");
    *value = v;
  }
  void Bool(const std::string& key, bool* value) {
    YAML::Node n = Get(key);
    if (!n.IsDefined() || n.IsNull()) return;
    bool v = false;
    if (!n.IsScalar() || !YAML::convert<bool>::decode(n, v)) Fail(n, PathOf(key), "true or false");
    *value = v;
  }
  void String(const std::string& key, std::string* value) {
    YAML::Node n = Get(key);
    if (!n.IsDefined() || n.IsNull()) return;
    if (!n.IsScalar()) Fail(n, PathOf(key), "a text value");
    *value = n.Scalar();
  }
  // Throws for keys nobody asked for.
  void Finish() const {
    if (!node_.IsDefined() || !node_.IsMap()) return;
    for (const auto& entry : node_) {
      const std::string key = entry.first.Scalar();
      if (known_.count(key)) continue;
      std::string list;
      for (const auto& k : known_) list += (list.empty() ? "" : ", ") + k;
      throw Error(ErrorKind::kInvalidValue, PathOf(key), "an unknown key", "one of " + list)
          .WithFile(file_, entry.first.Mark().line + 1);
    }
  }
  [[noreturn]] void Fail(const YAML::Node& n, const std::string& where,
                         const std::string& expected) const {
    std::string found = "nothing";
    if (n.IsScalar())
      found = "'" + n.Scalar() + "'";
    else if (n.IsSequence())
      found = "a list";
    else if (n.IsMap())
      found = "a map";
    throw Error(ErrorKind::kInvalidValue, where, found, expected)
        .WithFile(file_, n.Mark().line >= 0 ? n.Mark().line + 1 : 0);
  }

 private:
  YAML::Node node_;
  std::string prefix_, file_;
  std::set<std::string> known_;
};

std::string Num(double v) { return fmt::format("{}", v); }

}  // namespace

ImpactSceneSpec ParseImpactSceneSpec(const std::string& yaml_text, const std::string& path) {
  const YAML::Node root = LoadYaml(yaml_text, path, kSpecFileWhat);
  SpecSection top(root, "", path);
  ImpactSceneSpec spec;
  {
    std::string preset;
    top.String("preset", &preset);
    if (!preset.empty()) {
      try {
        spec = ImpactScenePreset(preset);
      } catch (Error& e) {
        throw e.WithFile(path);
      }
    }
  }
  top.String("name", &spec.name);
  top.Unsigned("seed", &spec.seed);

  SpecSection t = top.Sub("test");
  t.Number("mass_kg", &spec.pounder_mass_kg);
  t.Number("drop_height_m", &spec.drop_height_m);
  t.Number("impact_velocity_m_s", &spec.impact_velocity_m_s);
  t.Number("width_m", &spec.width_m);
  t.Number("depth_m", &spec.depth_m);
  t.Number("density_kg_m3", &spec.density_kg_m3);
  t.Number("bed_height_m", &spec.bed_height_m);
  t.Number("g_m_s2", &spec.g_m_s2);
  t.Finish();

  SpecSection m = top.Sub("model");
  {
    YAML::Node n = m.Get("added_mass");
    if (n.IsDefined() && !n.IsNull()) {
      double v = 0;
      if (n.IsScalar() && n.Scalar() == "grid") {
        spec.added_mass = SceneAddedMass::kGrid;
      } else if (n.IsScalar() && n.Scalar() == "eq4") {
        spec.added_mass = SceneAddedMass::kEq4;
      } else if (n.IsScalar() && YAML::convert<double>::decode(n, v) && std::isfinite(v) &&
                 v >= 0) {
        spec.added_mass = SceneAddedMass::kGiven;
        spec.added_mass_kg = v;
      } else {
        m.Fail(n, "model.added_mass", "grid, eq4 or an added mass >= 0 [kg]");
      }
    }
  }
  m.Number("K", &spec.K);
  m.Number("n", &spec.n);
  m.Number("u", &spec.u);
  m.Number("T_s", &spec.T_s);
  m.Number("b_per_s", &spec.b_per_s);
  m.Finish();

  SpecSection c = top.Sub("camera");
  {
    std::string lens;
    c.String("lens", &lens);
    if (!lens.empty()) {
      try {
        spec.lens = SceneLensFromString(lens, "camera.lens");
      } catch (Error& e) {
        throw e.WithFile(path);
      }
    }
  }
  c.Integer("width", &spec.width);
  c.Integer("height", &spec.height);
  c.Number("mm_per_px", &spec.mm_per_px);
  c.Number("fps", &spec.fps);
  c.Number("surface_fraction", &spec.surface_fraction);
  c.Finish();

  SpecSection f = top.Sub("frames");
  f.Integer("before_impact", &spec.frames_before_impact);
  f.Integer("count", &spec.frames);
  f.Number("impact_phase", &spec.impact_phase);
  f.Integer("bits", &spec.bits);
  f.Number("noise_sigma", &spec.noise_sigma);
  f.Integer("supersampling", &spec.supersampling);
  f.Number("background_level", &spec.background_level);
  f.Number("pounder_level", &spec.pounder_level);
  f.Finish();

  SpecSection sp = top.Sub("speckle");
  sp.Number("blob_radius_px", &spec.speckle.blob_radius_px);
  sp.Number("density", &spec.speckle.density);
  sp.Number("contrast", &spec.speckle.contrast);
  sp.Number("background", &spec.speckle.background);
  sp.Unsigned("seed", &spec.speckle.seed);
  sp.Finish();

  SpecSection so = top.Sub("soil");
  so.Number("core_depth_mm", &spec.soil.core_depth_mm);
  so.Number("cone_depth_mm", &spec.soil.cone_depth_mm);
  so.Number("decay_length_mm", &spec.soil.decay_length_mm);
  so.Number("wave_speed_m_s", &spec.soil.wave_speed_m_s);
  so.Number("wave_amplitude_mm", &spec.soil.wave_amplitude_mm);
  so.Number("wave_decay_length_mm", &spec.soil.wave_decay_length_mm);
  so.Number("wave_rise_time_s", &spec.soil.wave_rise_time_s);
  so.Finish();

  SpecSection se = top.Sub("sensor");
  se.Number("rate_hz", &spec.sensor.rate_hz);
  se.Number("offset_g", &spec.sensor.offset_g);
  se.Number("noise_g", &spec.sensor.noise_g);
  se.Number("exposure_s", &spec.sensor.exposure_s);
  se.Number("pre_release_s", &spec.sensor.pre_release_s);
  se.Number("tail_s", &spec.sensor.tail_s);
  se.Finish();

  SpecSection d = top.Sub("dic");
  d.Integer("subset_size", &spec.subset_size);
  d.Integer("step", &spec.step);
  d.Finish();

  SpecSection mo = top.Sub("momentum");
  mo.Integer("grid_cols", &spec.grid_cols);
  mo.Integer("grid_rows", &spec.grid_rows);
  mo.Finish();

  SpecSection ca = top.Sub("calibration");
  ca.Bool("render", &spec.render_calibration);
  ca.Integer("views", &spec.calibration_views);
  ca.String("scene_yaml", &spec.calibration_yaml);
  ca.Finish();
  top.Finish();

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
  o << "preprocess:\n  gaussian:\n    enabled: false\n  clahe:\n    enabled: false\n";
  o << fmt::format("dic:\n  subset_size: {}\n  step: {}\n  roi: [{}, {}, {}, {}]\n", s.subset_size,
                   s.step, grid.roi[0], grid.roi[1], grid.roi[2], grid.roi[3]);
  o << "  interpolation: bicubic\n  shape: affine\n  reference_update: auto\n"
       "  min_zncc: 0.8\n  max_iterations: 30\n  convergence_px: 0.001\n  search_radius_px: 12\n";
  o << "sensor:\n  time_column: time_s\n  accel_column: accel_g\n  accel_unit: g\n"
       "  exposure_column: exposure\n  cutoff_hz: 1500\n  integrate_from: release\n"
    << fmt::format("  quiet_window_s: {}\n",
                   std::min(0.005, 0.8 * s.sensor.pre_release_s > 0 ? 0.8 * s.sensor.pre_release_s
                                                                    : 0.005));
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

void WriteTruth(const ImpactScene& scene, const ImpactScene::SensorRecord& rec,
                const std::string& path, const std::string& spec_yaml) {
  const ImpactSceneSpec& s = scene.spec();
  const SceneMomentumTruth& mt = scene.momentum();
  const SceneDicGrid& grid = scene.dic_grid();
  const ImpactSummary& sum = scene.model_run().summary;
  const int F = scene.frame_count();
  const auto Fz = static_cast<std::size_t>(F);
  H5Writer out(path);
  out.WriteProvenance(spec_yaml);
  out.SetAttribute("/", "generator", "impactdic synth");
  out.SetAttribute("/", "conventions",
                   "t = 0 at contact; depths and velocities down positive; pixels are ideal "
                   "(undistorted) pixels of the first frame, x right, y down; panel mm origin at "
                   "the pounder axis on the undisturbed surface");

  // Frames.
  std::vector<double> t(Fz), daq(Fz), z(Fz), v(Fz), bottom(Fz), W(Fz), vs(Fz), pp(Fz), pg(Fz),
      ptot(Fz), madd(Fz);
  for (int k = 0; k < F; ++k) {
    t[k] = scene.FrameTime(k);
    daq[k] = scene.DaqTime(t[k]);
    const PounderState ps = scene.Pounder(t[k]);
    z[k] = ps.z_m;
    v[k] = ps.v_m_s;
    bottom[k] = scene.surface_px() + ps.z_m * 1000 / scene.sy_mm_per_px();
    W[k] = scene.CoreDisplacement(t[k]);
    vs[k] = scene.CoreVelocity(t[k]);
    pp[k] = scene.PounderMomentum(t[k]);
    pg[k] = scene.GranularMomentum(t[k]);
    ptot[k] = pp[k] + pg[k];
    madd[k] = t[k] > 0 ? scene.AddedMassEq3(t[k]) : std::nan("");
  }
  out.Write("frames/time_s", t, "s", "frame time since impact (rising exposure edge)");
  out.Write("frames/daq_time_s", daq, "s", "frame time on the DAQ clock of sensor.csv");
  out.Write("pounder/z_m", z, "m", "pounder bottom below the undisturbed surface, down positive");
  out.Write("pounder/v_m_s", v, "m/s", "pounder velocity, down positive");
  out.Write("pounder/bottom_y_px", bottom, "px", "pounder bottom row (ideal px)");
  out.Write("pounder/crater_depth_m", std::vector<double>{sum.crater_depth_m}, "m",
            "final penetration (model)");
  out.Write("pounder/t_end_s", std::vector<double>{sum.t_end_s}, "s", "time the pounder stops");

  // Soil at the DIC grid.
  const auto n = grid.centres_px.size();
  const Dims gdims{static_cast<std::size_t>(grid.rows), static_cast<std::size_t>(grid.cols)};
  const Dims fdims{Fz, gdims[0], gdims[1]};
  std::vector<double> gx(n), gy(n), u_px(Fz * n), v_px(Fz * n), vel_x(Fz * n), vel_y(Fz * n);
  std::vector<std::int32_t> occluded(Fz * n);
  const int half = s.subset_size / 2;
  for (std::size_t i = 0; i < n; ++i) {
    gx[i] = grid.centres_px[i].x;
    gy[i] = grid.centres_px[i].y;
  }
  for (int k = 0; k < F; ++k) {
    for (std::size_t i = 0; i < n; ++i) {
      const cv::Point2d m = scene.PanelFromIdeal(grid.centres_px[i]);
      const cv::Vec2d d = scene.SoilDisplacementMm(m.x, m.y, t[k]);
      const cv::Vec2d vel = scene.SoilVelocityMmS(m.x, m.y, t[k]);
      const std::size_t j = static_cast<std::size_t>(k) * n + i;
      u_px[j] = d[0] / scene.sx_mm_per_px();
      v_px[j] = d[1] / scene.sy_mm_per_px();
      vel_x[j] = vel[0];
      vel_y[j] = vel[1];
      occluded[j] = scene.PounderCovers(gx[i] + u_px[j], gy[i] + v_px[j], half, t[k]) ? 1 : 0;
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

  // Momentum over the default grid.
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

  // Fine series at the DAQ rate from impact to the end of the record.
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
  fs::create_directories(dir / "frames", ec);
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
  WriteCsv(files.sensor_csv, {"time_s", "accel_g", "exposure"},
           {record.time_s, record.accel_g, record.exposure}, 10);
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
