// Synthetic impact scene: model, truth fields and exact rendering (see impact_scene.h and
// docs/synth.md).
#include "impactdic/synth/impact_scene.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <functional>

#include "impactdic/core/error.h"
#include "impactdic/core/numeric.h"
#include "impactdic/core/range.h"
#include "lens_render.h"
#include "random.h"

namespace impactdic {
namespace {

using synth_detail::Rng;
using synth_detail::SplitMix64;

// C2 smooth step: 0 for x <= 0, 1 for x >= 1, x^3 (10 - 15 x + 6 x^2) between; and derivative.
double SmoothStep(double x) {
  if (x <= 0) return 0;
  if (x >= 1) return 1;
  return x * x * x * (10 - 15 * x + 6 * x * x);
}
double SmoothStepDerivative(double x) {
  if (x <= 0 || x >= 1) return 0;
  return 30 * x * x * (1 - x) * (1 - x);
}

}  // namespace

const char* ToString(SceneLens lens) { return kSceneLensNames.Name(lens); }

SceneLens SceneLensFromString(const std::string& text, const std::string& where) {
  return kSceneLensNames.Parse(text, where);
}

const char* ToString(SceneAddedMass mode) {
  switch (mode) {
    case SceneAddedMass::kGrid: return "grid";
    case SceneAddedMass::kEq4: return "eq4";
    case SceneAddedMass::kGiven: return "given";
  }
  return "?";
}

void SceneSoilOptions::Check() const {
  auto num = [](double v) { return fmt::format("{}", v); };
  CheckValue(core_depth_mm >= 0 && std::isfinite(core_depth_mm), "soil.core_depth_mm",
             num(core_depth_mm), "a depth >= 0 [mm] (0 = auto)");
  CheckValue(cone_depth_mm >= 0 && std::isfinite(cone_depth_mm), "soil.cone_depth_mm",
             num(cone_depth_mm), "a depth >= 0 [mm] (0 = D/2)");
  CheckValue(decay_length_mm >= 0 && std::isfinite(decay_length_mm), "soil.decay_length_mm",
             num(decay_length_mm), "a length >= 0 [mm] (0 = D)");
  CheckValue(wave_speed_m_s > 0 && std::isfinite(wave_speed_m_s), "soil.wave_speed_m_s",
             num(wave_speed_m_s), "a speed > 0 [m/s]");
  CheckValue(wave_amplitude_mm >= 0 && std::isfinite(wave_amplitude_mm), "soil.wave_amplitude_mm",
             num(wave_amplitude_mm), "an amplitude >= 0 [mm]");
  CheckValue(wave_decay_length_mm > 0 && std::isfinite(wave_decay_length_mm),
             "soil.wave_decay_length_mm", num(wave_decay_length_mm), "a length > 0 [mm]");
  CheckValue(wave_rise_time_s > 0 && std::isfinite(wave_rise_time_s), "soil.wave_rise_time_s",
             num(wave_rise_time_s), "a time > 0 [s]");
}

void SceneSensorOptions::Check() const {
  auto num = [](double v) { return fmt::format("{}", v); };
  CheckValue(rate_hz >= 1000 && rate_hz <= 1e6, "sensor.rate_hz", num(rate_hz),
             "a sampling rate in [1000, 1e6] Hz");
  CheckValue(std::isfinite(offset_g), "sensor.offset_g", num(offset_g), "a finite offset [g]");
  CheckValue(noise_g >= 0 && std::isfinite(noise_g), "sensor.noise_g", num(noise_g),
             "a noise level >= 0 [g rms]");
  CheckValue(exposure_s > 0 && std::isfinite(exposure_s), "sensor.exposure_s", num(exposure_s),
             "an exposure > 0 [s], shorter than the frame interval");
  CheckValue(pre_release_s >= 0 && std::isfinite(pre_release_s), "sensor.pre_release_s",
             num(pre_release_s), "a duration >= 0 [s]");
  CheckValue(tail_s > 0 && std::isfinite(tail_s), "sensor.tail_s", num(tail_s),
             "a duration > 0 [s]");
}

void SceneBaseSensorOptions::Check() const {
  auto num = [](double v) { return fmt::format("{}", v); };
  const std::size_t n = columns.size();
  for (const auto& c : columns)
    CheckValue(!c.empty(), "base_sensors.columns", "an empty name", "column names");
  for (const auto& [size, key] : {std::pair{offset_mm.size(), "base_sensors.offsets_mm"},
                                  std::pair{depth_mm.size(), "base_sensors.depths_mm"},
                                  std::pair{area_mm2.size(), "base_sensors.areas_mm2"}}) {
    CheckValue(size == n, key, fmt::format("{} values for {} columns", size, n),
               "one value per column of base_sensors.columns");
  }
  for (double x : offset_mm)
    CheckValue(std::isfinite(x), "base_sensors.offsets_mm", num(x), "finite offsets [mm]");
  for (double d : depth_mm)
    CheckValue(d > 0 && std::isfinite(d), "base_sensors.depths_mm", num(d), "depths > 0 [mm]");
  for (double a : area_mm2)
    CheckValue(a > 0 && std::isfinite(a), "base_sensors.areas_mm2", num(a), "areas > 0 [mm^2]");
  CheckValue(stress_ratio > 0 && stress_ratio <= 1, "base_sensors.stress_ratio", num(stress_ratio),
             "a ratio in (0, 1]");
  CheckValue(spreading_exponent >= 0 && std::isfinite(spreading_exponent),
             "base_sensors.spreading_exponent", num(spreading_exponent), "an exponent >= 0");
  CheckValue(std::isfinite(offset_n), "base_sensors.offset_n", num(offset_n), "a finite force [N]");
  CheckValue(noise_n >= 0 && std::isfinite(noise_n), "base_sensors.noise_n", num(noise_n),
             "a noise level >= 0 [N rms]");
}

double ImpactSceneSpec::ImpactVelocity() const {
  return std::isnan(impact_velocity_m_s) ? std::sqrt(2 * g_m_s2 * drop_height_m)
                                         : impact_velocity_m_s;
}

void ImpactSceneSpec::Check() const {
  auto num = [](double v) { return fmt::format("{}", v); };
  auto pos = [&](double v, const char* where, const char* what) {
    CheckValue(v > 0 && std::isfinite(v), where, num(v), what);
  };
  // The ranges of a drop test, shared with scene files and `impactdic model` (core/range.h).
  CheckRange(pounder_mass_kg, kPounderMassRange, "test.mass_kg", "a pounder mass");
  if (std::isnan(impact_velocity_m_s)) {
    pos(drop_height_m, "test.drop_height_m",
        "a drop height > 0 [m] (or give test.impact_velocity_m_s)");
    CheckRange(drop_height_m, kDropHeightRange, "test.drop_height_m", "a drop height");
  } else {
    CheckRange(impact_velocity_m_s, kImpactVelocityRange, "test.impact_velocity_m_s",
               "an impact velocity");
  }
  CheckRange(width_m, kPounderSizeRange, "test.width_m", "a pounder width D");
  CheckRange(depth_m, kPounderSizeRange, "test.depth_m", "an out-of-plane depth t_z");
  CheckRange(density_kg_m3, kSoilDensityRange, "test.density_kg_m3", "a dry density");
  CheckRange(bed_height_m, kBedHeightRange, "test.bed_height_m", "a bed height");
  pos(g_m_s2, "test.g_m_s2", "a gravitational acceleration > 0 [m/s^2]");
  CheckRange(g_m_s2, kGravityRange, "test.g_m_s2", "a gravitational acceleration");
  if (added_mass == SceneAddedMass::kGiven)
    CheckValue(added_mass_kg >= 0 && std::isfinite(added_mass_kg), "model.added_mass",
               num(added_mass_kg), "grid, eq4 or an added mass >= 0 [kg]");
  CheckValue(K >= 0 && std::isfinite(K), "model.K", num(K), "a friction coefficient K >= 0");
  CheckValue(n >= 0 && n < 1, "model.n", num(n), "a damping exponent n in [0, 1)");
  CheckValue(u >= 1 && std::isfinite(u), "model.u", num(u), "a damping factor u >= 1");
  CheckValue(T_s >= 0 && std::isfinite(T_s), "model.T_s", num(T_s), "a time offset T >= 0 [s]");
  CheckValue(b_per_s > 0 && b_per_s <= 1e7, "model.b_per_s", num(b_per_s),
             "a sigmoid steepness b in (0, 1e7] [1/s]");
  CheckValue(width >= 64 && width <= 8192, "camera.width", std::to_string(width),
             "an image width in [64, 8192] px");
  CheckValue(height >= 48 && height <= 8192, "camera.height", std::to_string(height),
             "an image height in [48, 8192] px");
  CheckRange(mm_per_px, kMmPerPxRange, "camera.mm_per_px", "a panel scale");
  CheckValue(fps >= 100 && fps <= 1e6, "camera.fps", num(fps), "a frame rate in [100, 1e6] 1/s");
  CheckValue(surface_fraction >= 0.05 && surface_fraction <= 0.8, "camera.surface_fraction",
             num(surface_fraction), "a fraction of the image height in [0.05, 0.8]");
  CheckValue(frames_before_impact >= 1 && frames_before_impact <= 100, "frames.before_impact",
             std::to_string(frames_before_impact), "a frame count in [1, 100]");
  CheckValue(frames == 0 || (frames >= frames_before_impact + 2 && frames <= 100000),
             "frames.count", std::to_string(frames),
             fmt::format("0 (auto) or a frame count in [before_impact + 2 = {}, 100000]",
                         frames_before_impact + 2));
  CheckValue(impact_phase > 0 && impact_phase <= 1, "frames.impact_phase", num(impact_phase),
             "a fraction of the frame interval in (0, 1]");
  CheckValue(bits == 8 || bits == 16, "frames.bits", std::to_string(bits), "8 or 16");
  CheckValue(noise_sigma >= 0 && std::isfinite(noise_sigma), "frames.noise_sigma", num(noise_sigma),
             "a noise level >= 0 [grey levels]");
  CheckValue(supersampling >= 1 && supersampling <= 8, "frames.supersampling",
             std::to_string(supersampling), "samples per pixel side in [1, 8]");
  CheckValue(background_level >= 0 && background_level <= 1, "frames.background_level",
             num(background_level), "a grey level in [0, 1]");
  CheckValue(pounder_level >= 0 && pounder_level <= 1, "frames.pounder_level", num(pounder_level),
             "a grey level in [0, 1]");
  try {
    speckle.Check();
  } catch (const Error& e) {
    throw Error(ErrorKind::kInvalidValue, std::string("speckle: ") + e.what());
  }
  soil.Check();
  sensor.Check();
  base_sensors.Check();
  CheckValue(sensor.exposure_s < 1 / fps, "sensor.exposure_s", num(sensor.exposure_s),
             fmt::format("an exposure shorter than the frame interval 1/fps = {} s", 1 / fps));
  CheckValue(subset_size >= 5 && subset_size % 2 == 1, "dic.subset_size",
             std::to_string(subset_size), "an odd subset size >= 5 [px]");
  CheckValue(step >= 1, "dic.step", std::to_string(step), "a grid step >= 1 [px]");
  CheckValue(grid_cols >= 1 && grid_cols <= 100, "momentum.grid_cols", std::to_string(grid_cols),
             "a subset count in [1, 100]");
  CheckValue(grid_rows >= 1 && grid_rows <= 100, "momentum.grid_rows", std::to_string(grid_rows),
             "a subset count in [1, 100]");
  CheckValue(calibration_views >= 4 && calibration_views <= 100, "calibration.views",
             std::to_string(calibration_views), "a view count in [4, 100]");
}

ImpactSceneSpec ImpactScenePreset(const std::string& name) {
  ImpactSceneSpec spec;
  if (name == "small") return spec;
  if (name == "full") {
    spec.width = 1920;
    spec.height = 1440;
    spec.mm_per_px = 0.42;
    // 23.5 mm cells like the small preset's: the 6 x 2 grid spans 141 x 47 mm under the
    // footprint, m_grid = M = 1.97 kg (a smaller step makes the added mass, and the peak, tiny).
    spec.subset_size = 41;
    spec.step = 56;
    spec.speckle.blob_radius_px = 3.0;
    return spec;
  }
  if (name == "tiny") {
    spec.width = 160;
    spec.height = 120;
    spec.mm_per_px = 5.0;
    spec.lens = SceneLens::kIdeal;
    spec.subset_size = 11;
    spec.step = 5;
    spec.frames = 8;
    spec.frames_before_impact = 1;
    spec.speckle.blob_radius_px = 1.5;
    spec.render_calibration = false;
    return spec;
  }
  throw Error(ErrorKind::kInvalidValue, "preset", "'" + name + "'", "small, full or tiny");
}

// ---------------------------------------------------------------------------------------------

ImpactScene::ImpactScene(const ImpactSceneSpec& spec) : spec_(spec) {
  spec_.Check();
  SetUpCamera();
  // Where the pounder hits: the grid's middle column(s) straddle the axis, so with integer subset
  // centres the axis sits on an integer or half-integer column.
  const int cols = spec_.grid_cols, rows = spec_.grid_rows, step = spec_.step;
  axis_px_ = std::floor(spec_.width / 2.0) + (((cols - 1) * step) % 2 ? 0.5 : 0.0);
  surface_px_ = std::round(spec_.surface_fraction * spec_.height) - 0.5;
  // Momentum grid mass.
  momentum_.cols = cols;
  momentum_.rows = rows;
  momentum_.cell_area_mm2 = step * step * sx_ * sy_;
  momentum_.grid_area_mm2 = cols * rows * momentum_.cell_area_mm2;
  momentum_.m_grid_kg = spec_.density_kg_m3 * momentum_.grid_area_mm2 * 1e-6 * spec_.depth_m;
  RunImpactModel();
  FindPeakMomentum();
  FindMomentumTruthAtTe();
  LayOutGrids();
  SetUpCoreGeometry();
  // Frames.
  if (spec_.frames > 0) {
    frame_count_ = spec_.frames;
  } else {
    const double t_first = FrameTime(spec_.frames_before_impact);
    frame_count_ = spec_.frames_before_impact +
                   static_cast<int>(std::ceil((run_.summary.t_end_s - t_first) * spec_.fps)) + 1 +
                   3;
  }
  // Speckle: the margin covers the largest material displacement into view.
  const double max_disp_px = CoreDisplacement(1e9) * 1000 / std::min(sx_, sy_) +
                             spec_.soil.wave_amplitude_mm / std::min(sx_, sy_);
  pattern_ = std::make_shared<SpecklePattern>(spec_.speckle, spec_.width, spec_.height,
                                              64 + std::ceil(max_disp_px));
  MapPixelCorners();
  // DAQ clock: starts pre_release before the release, shifted so frame 0 falls on a sample.
  const double nominal = release_time_s() - spec_.sensor.pre_release_s;
  const double t0 = FrameTime(0);
  const double samples = std::ceil((t0 - nominal) * spec_.sensor.rate_hz - 1e-9);
  daq_origin_s_ = t0 - samples / spec_.sensor.rate_hz;
}

// The camera: the sample lens scaled to the image size, or an ideal pinhole; the object-side
// scale sx_, sy_ [mm/px] at the panel.
void ImpactScene::SetUpCamera() {
  const double w = spec_.width, h = spec_.height;
  if (spec_.lens == SceneLens::kSample) {
    const SynthCamera base = SampleCamera();
    const double kx = w / base.width, ky = h / base.height;
    camera_ = base;
    camera_.fx = base.fx * kx;
    camera_.fy = base.fy * ky;
    camera_.cx = (base.cx + 0.5) * kx - 0.5;
    camera_.cy = (base.cy + 0.5) * ky - 0.5;
  } else {
    camera_.fx = camera_.fy = 820.0 * w / 640.0;
    camera_.cx = (w - 1) / 2;
    camera_.cy = (h - 1) / 2;
    camera_.dist = {0, 0, 0, 0, 0};
  }
  camera_.width = spec_.width;
  camera_.height = spec_.height;
  camera_.Check();
  const double distance_mm = spec_.mm_per_px * std::sqrt(camera_.fx * camera_.fy);
  sx_ = distance_mm / camera_.fx;
  sy_ = distance_mm / camera_.fy;
}

// The impact model (Eq. 9) of the spec, solved at rtol 1e-10; the added mass from the spec's
// choice (the momentum grid's mass, Eq. 4 or given).
void ImpactScene::RunImpactModel() {
  v0_ = spec_.ImpactVelocity();
  ImpactModelParameters& p = model_params_;
  p.pounder_mass_kg = spec_.pounder_mass_kg;
  p.impact_velocity_m_s = v0_;
  p.width_m = spec_.width_m;
  p.depth_m = spec_.depth_m;
  p.density_kg_m3 = spec_.density_kg_m3;
  p.gravity_m_s2 = spec_.g_m_s2;
  p.bed_height_m = spec_.bed_height_m;
  p.friction_K = spec_.K;
  p.damping_exponent_n = spec_.n;
  p.damping_factor_u = spec_.u;
  p.sigmoid_delay_T_s = spec_.T_s;
  p.sigmoid_rate_b_per_s = spec_.b_per_s;
  switch (spec_.added_mass) {
    case SceneAddedMass::kGrid: p.added_mass_kg = momentum_.m_grid_kg; break;
    case SceneAddedMass::kEq4: p.added_mass_kg = kNaN; break;
    case SceneAddedMass::kGiven: p.added_mass_kg = spec_.added_mass_kg; break;
  }
  p.Check();
  ImpactSolverOptions solver;
  solver.rtol = 1e-10;
  run_ = SimulateImpact(p, solver);
  if (!run_.summary.stopped)
    throw Error(ErrorKind::kNumerical,
                fmt::format("the impact model did not stop the pounder ({}): {}",
                            run_.summary.stop_reason, run_.summary.BriefReport()));
}

// p_max: the maximum of m_p v_p(t) over t >= 0 (at t = 0 unless gravity still wins there),
// sampled then refined by golden-section search.
void ImpactScene::FindPeakMomentum() {
  const double mp = spec_.pounder_mass_kg, t_end = run_.summary.t_end_s;
  const int n = 4000;
  const double span = std::min(t_end, 2 * spec_.T_s + 20 / spec_.b_per_s);
  int best = 0;
  double best_v = run_.solution.StateAt(0).v_m_s;
  for (int i = 1; i <= n; ++i) {
    const double v = run_.solution.StateAt(span * i / n).v_m_s;
    if (v > best_v) best_v = v, best = i;
  }
  double lo = span * std::max(0, best - 1) / n, hi = span * std::min(n, best + 1) / n;
  if (best > 0) {
    momentum_.t_pmax_s =
        GoldenSectionMaximize([&](double t) { return run_.solution.StateAt(t).v_m_s; }, lo, hi,
                              {.max_iterations = 80, .relative_tolerance = 1e-15});
    best_v = std::max(best_v, run_.solution.StateAt(momentum_.t_pmax_s).v_m_s);
  } else {
    momentum_.t_pmax_s = 0;
  }
  momentum_.p_max_Ns = mp * best_v;
}

// t_e: the first root of (m_p + m_grid) v_p(t) - p_max after t_pmax (bisection), and the truth
// there: added mass, core displacement, relative penetration, momentum conservation.
void ImpactScene::FindMomentumTruthAtTe() {
  const double mp = spec_.pounder_mass_kg, t_end = run_.summary.t_end_s;
  const double mg = momentum_.m_grid_kg, pmax = momentum_.p_max_Ns;
  auto g = [&](double t) { return (mp + mg) * run_.solution.StateAt(t).v_m_s - pmax; };
  const int n = 4000;
  double lo = momentum_.t_pmax_s, hi = t_end;
  for (int i = 1; i <= n; ++i) {
    const double t = momentum_.t_pmax_s + (t_end - momentum_.t_pmax_s) * i / n;
    if (g(t) <= 0) {
      hi = t;
      break;
    }
    lo = t;
  }
  for (int it = 0; it < 200 && hi - lo > 1e-16; ++it) {
    const double mid = 0.5 * (lo + hi);
    if (g(mid) > 0)
      lo = mid;
    else
      hi = mid;
  }
  momentum_.t_e_s = 0.5 * (lo + hi);
  const ImpactState s = run_.solution.StateAt(momentum_.t_e_s);
  momentum_.v_te_m_s = s.v_m_s;
  momentum_.m_add_max_kg = pmax / s.v_m_s - mp;
  z_te_m_ = s.z_m;
  W_te_m_ = (pmax * momentum_.t_e_s - mp * s.z_m) / mg;
  momentum_.relative_penetration_mm = (z_te_m_ - W_te_m_) * 1000;
  momentum_.conservation_error =
      std::abs(mp * s.v_m_s + mg * CoreVelocity(momentum_.t_e_s) - pmax) / pmax;
}

// DIC grid: subset centres at roi.x + half + i step; the ROI starts below the surface by more
// than the pounder's penetration relative to the core, so the grid is never covered above it.
// The momentum grid: cols x rows subsets centred on the axis, at the top of the DIC grid.
void ImpactScene::LayOutGrids() {
  const int cols = spec_.grid_cols, rows = spec_.grid_rows, step = spec_.step;
  const int half = spec_.subset_size / 2, margin = 8;
  const double D_mm = spec_.width_m * 1000;
  const double first_col = axis_px_ - 0.5 * (cols - 1) * step;  // integer by construction
  int c0 = static_cast<int>(std::lround(first_col));
  while (c0 - step - half >= margin) c0 -= step;
  int c1 = c0;
  while (c1 + step + half <= spec_.width - 1 - margin) c1 += step;
  const int y0 =
      static_cast<int>(std::ceil(surface_px_ + momentum_.relative_penetration_mm / sy_ + 2.0));
  int r1 = y0 + half;
  CheckValue(r1 + half <= spec_.height - 1 - margin, "camera.surface_fraction",
             fmt::format("{}", spec_.surface_fraction),
             "room for at least one subset row below the surface");
  while (r1 + step + half <= spec_.height - 1 - margin) r1 += step;
  dic_grid_.roi = {c0 - half, y0, c1 + half + 1, r1 + half + 1};
  dic_grid_.cols = (c1 - c0) / step + 1;
  dic_grid_.rows = (r1 - (y0 + half)) / step + 1;
  for (int r = 0; r < dic_grid_.rows; ++r)
    for (int c = 0; c < dic_grid_.cols; ++c)
      dic_grid_.centres_px.emplace_back(c0 + c * step, y0 + half + r * step);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c)
      momentum_.centres_px.emplace_back(first_col + c * step, y0 + half + r * step);
  CheckValue(rows <= dic_grid_.rows, "momentum.grid_rows", std::to_string(rows),
             fmt::format("at most the {} subset rows that fit below the surface", dic_grid_.rows));
  const double half_width_mm = 0.5 * (cols - 1) * step * sx_;
  CheckValue(half_width_mm <= D_mm / 2, "momentum.grid_cols", std::to_string(cols),
             fmt::format("a grid whose subset centres lie under the {} mm wide footprint "
                         "({} cols x dic.step {} px x {:.4g} mm/px is {:.4g} mm wide)",
                         D_mm, cols, step, sx_, 2 * half_width_mm));
}

// Core geometry: the rigid core must contain the default grid's subset centres with room to
// spare (one step) so the grid mean is exact wherever the pipeline lays its 6 x 2 subsets.
void ImpactScene::SetUpCoreGeometry() {
  const int half = spec_.subset_size / 2, step = spec_.step;
  const double D_mm = spec_.width_m * 1000;
  const double grid_bottom_px = momentum_.centres_px.back().y + half + step;
  const double needed_mm = (grid_bottom_px - surface_px_) * sy_;
  if (spec_.soil.core_depth_mm > 0) {
    CheckValue(spec_.soil.core_depth_mm >= needed_mm, "soil.core_depth_mm",
               fmt::format("{}", spec_.soil.core_depth_mm),
               fmt::format("a core depth >= {:.4g} mm (the momentum grid plus one step), or 0",
                           needed_mm));
    core_depth_mm_ = spec_.soil.core_depth_mm;
  } else {
    core_depth_mm_ = std::max(0.3 * D_mm, needed_mm);
  }
  cone_depth_mm_ = spec_.soil.cone_depth_mm > 0 ? spec_.soil.cone_depth_mm : D_mm / 2;
  decay_mm_ = spec_.soil.decay_length_mm > 0 ? spec_.soil.decay_length_mm : 1.5 * D_mm;
}

// Ideal positions of the pixel corners (distorted pixel (c - 0.5, r - 0.5)).
void ImpactScene::MapPixelCorners() {
  corner_map_.assign(static_cast<std::size_t>(spec_.width + 1) * (spec_.height + 1), {});
  tbb::parallel_for(0, spec_.height + 1, [&](int r) {
    for (int c = 0; c <= spec_.width; ++c) {
      cv::Point2d n;
      if (!camera_.Undistort({c - 0.5, r - 0.5}, &n))
        throw Error(ErrorKind::kNumerical, "camera", "distortion",
                    "an invertible distortion over the image");
      corner_map_[static_cast<std::size_t>(r) * (spec_.width + 1) + c] = camera_.Pinhole(n);
    }
  });
}

cv::Point2d ImpactScene::PanelFromIdeal(cv::Point2d q) const {
  return {(q.x - axis_px_) * sx_, (q.y - surface_px_) * sy_};
}
cv::Point2d ImpactScene::IdealFromPanel(cv::Point2d m) const {
  return {axis_px_ + m.x / sx_, surface_px_ + m.y / sy_};
}

double ImpactScene::FrameTime(int k) const {
  return (k - spec_.frames_before_impact + spec_.impact_phase) / spec_.fps;
}

PounderState ImpactScene::Pounder(double t) const {
  const double g = spec_.g_m_s2;
  const double t_rel = release_time_s();
  if (t < t_rel) return {-v0_ * v0_ / (2 * g), 0.0};
  if (t < 0) return {v0_ * t + 0.5 * g * t * t, v0_ + g * t};
  if (t >= run_.summary.t_end_s) return {run_.summary.crater_depth_m, 0.0};
  const ImpactState s = run_.solution.StateAt(t);
  return {s.z_m, s.v_m_s};
}

double ImpactScene::CoreDisplacement(double t) const {
  if (t <= 0) return 0;
  if (t <= momentum_.t_e_s) {
    return (momentum_.p_max_Ns * t - spec_.pounder_mass_kg * Pounder(t).z_m) / momentum_.m_grid_kg;
  }
  return W_te_m_ + Pounder(t).z_m - z_te_m_;
}

double ImpactScene::CoreVelocity(double t) const {
  if (t <= 0) return 0;
  if (t <= momentum_.t_e_s)
    return (momentum_.p_max_Ns - spec_.pounder_mass_kg * Pounder(t).v_m_s) / momentum_.m_grid_kg;
  return Pounder(t).v_m_s;
}

double ImpactScene::PounderMomentum(double t) const {
  return spec_.pounder_mass_kg * Pounder(t).v_m_s;
}
double ImpactScene::GranularMomentum(double t) const {
  return momentum_.m_grid_kg * CoreVelocity(t);
}
double ImpactScene::AddedMassEq3(double t) const {
  const double v = Pounder(t).v_m_s;
  return v > 0 ? momentum_.p_max_Ns / v - spec_.pounder_mass_kg : kNaN;
}

// Euclidean distance from (X, Y) to the convex core C (footprint strip |X| <= a above Y_u, then
// a triangle down to the apex), with its gradient (zero inside).
double ImpactScene::DistanceToCore(double X, double Y, cv::Vec2d* gradient) const {
  const double a = spec_.width_m * 500, Yu = core_depth_mm_, hc = cone_depth_mm_;
  const double sgn = X < 0 ? -1.0 : 1.0, px = std::abs(X);
  bool inside = false;
  if (Y <= Yu) {
    inside = px <= a;
  } else if (Y <= Yu + hc) {
    inside = px <= a * (1 - (Y - Yu) / hc);
  }
  if (inside) {
    *gradient = {0, 0};
    return 0;
  }
  // Nearest point on the vertical ray (a, y <= Yu) and on the slanted edge (a, Yu) - (0, Yu + hc).
  const double q1x = a, q1y = std::min(Y, Yu);
  const double ex = -a, ey = hc;
  const double s = std::clamp(((px - a) * ex + (Y - Yu) * ey) / (ex * ex + ey * ey), 0.0, 1.0);
  const double q2x = a + s * ex, q2y = Yu + s * ey;
  const double d1 = std::hypot(px - q1x, Y - q1y), d2 = std::hypot(px - q2x, Y - q2y);
  const double qx = d1 <= d2 ? q1x : q2x, qy = d1 <= d2 ? q1y : q2y, d = std::min(d1, d2);
  if (d <= 0) {
    *gradient = {0, 0};
    return 0;
  }
  *gradient = {sgn * (px - qx) / d, (Y - qy) / d};
  return d;
}

cv::Vec2d ImpactScene::SoilDisplacementMm(double X, double Y, double t) const {
  return EvalSoil(X, Y, SoilTime{t, CoreDisplacement(t) * 1000, 0}, nullptr, nullptr);
}

cv::Vec4d ImpactScene::SoilGradient(double X, double Y, double t) const {
  cv::Vec4d g;
  EvalSoil(X, Y, SoilTime{t, CoreDisplacement(t) * 1000, 0}, &g, nullptr);
  return g;
}

cv::Vec2d ImpactScene::SoilVelocityMmS(double X, double Y, double t) const {
  cv::Vec2d v;
  EvalSoil(X, Y, SoilTime{t, CoreDisplacement(t) * 1000, CoreVelocity(t) * 1000}, nullptr, &v);
  return v;
}

// u = (0, W f) + (1 - f) A(r) S(xi) e_r, xi = (t - r / c) / tau (see the header).
cv::Vec2d ImpactScene::EvalSoil(double X, double Y, const SoilTime& ft, cv::Vec4d* grad,
                                cv::Vec2d* vel) const {
  const SceneSoilOptions& so = spec_.soil;
  const double L = decay_mm_;
  cv::Vec2d gd;
  const double d = DistanceToCore(X, Y, &gd);
  const double f = std::exp(-(d / L) * (d / L));
  const double dfdd = -2 * d / (L * L) * f;
  const double fX = dfdd * gd[0], fY = dfdd * gd[1];
  cv::Vec2d u(0, ft.W_mm * f);
  cv::Vec4d g(0, 0, ft.W_mm * fX, ft.W_mm * fY);
  cv::Vec2d v(0, ft.Wdot_mm_s * f);
  if (so.wave_amplitude_mm > 0 && f < 1) {
    const double r = std::hypot(X, Y);
    if (r > 0) {
      const double c_mm_s = so.wave_speed_m_s * 1000, tau = so.wave_rise_time_s;
      const double xi = (ft.t_s - r / c_mm_s) / tau;
      const double S = SmoothStep(xi);
      const double A = so.wave_amplitude_mm * std::exp(-r / so.wave_decay_length_mm);
      const double ex = X / r, ey = Y / r;
      const double G = (1 - f) * A * S;
      u[0] += G * ex;
      u[1] += G * ey;
      if (grad) {
        const double Sp = SmoothStepDerivative(xi);
        // dG/dr along e_r (A' = -A / lambda, dxi/dr = -1 / (c tau)), plus the (1 - f) factor.
        const double dGdr = (1 - f) * (-A / so.wave_decay_length_mm * S - A * Sp / (c_mm_s * tau));
        const double GX = -fX * A * S + dGdr * ex, GY = -fY * A * S + dGdr * ey;
        // d(G e_i)/dx_j = dG/dx_j e_i + G (delta_ij - e_i e_j) / r
        g[0] += GX * ex + G * (1 - ex * ex) / r;
        g[1] += GY * ex + G * (-ex * ey) / r;
        g[2] += GX * ey + G * (-ex * ey) / r;
        g[3] += GY * ey + G * (1 - ey * ey) / r;
      }
      if (vel) {
        const double Gdot = (1 - f) * A * SmoothStepDerivative(xi) / tau;
        v[0] += Gdot * ex;
        v[1] += Gdot * ey;
      }
    }
  }
  if (grad) *grad = g;
  if (vel) *vel = v;
  return u;
}

DisplacementField ImpactScene::SoilFieldPx(double t) const {
  const SoilTime ft{t, CoreDisplacement(t) * 1000, 0};
  const ImpactScene* self = this;
  DisplacementField field;
  field.u = [self, ft](double Xp, double Yp) {
    const cv::Point2d m = self->PanelFromIdeal({Xp, Yp});
    const cv::Vec2d u = self->EvalSoil(m.x, m.y, ft, nullptr, nullptr);
    return cv::Vec2d(u[0] / self->sx_, u[1] / self->sy_);
  };
  field.gradient = [self, ft](double Xp, double Yp) {
    const cv::Point2d m = self->PanelFromIdeal({Xp, Yp});
    cv::Vec4d g;
    self->EvalSoil(m.x, m.y, ft, &g, nullptr);
    const double sx = self->sx_, sy = self->sy_;
    return cv::Vec4d(g[0], g[1] * sy / sx, g[2] * sx / sy, g[3]);
  };
  return field;
}

bool ImpactScene::PounderCovers(double cx, double cy, double half, double t) const {
  const double z_px = surface_px_ + Pounder(t).z_m * 1000 / sy_;
  const double a_px = spec_.width_m * 500 / sx_;
  return cy - half - 0.5 <= z_px && std::abs(cx - axis_px_) - half - 0.5 <= a_px;
}

namespace {

struct PounderDrawing {
  double z_mm;      // Bottom of the block (depth, down positive).
  double a_mm;      // Half width.
  double block_mm;  // Block height.
  double shaft_mm;  // Shaft half width.
  double rim_mm;    // Lighter bevel band along the block's sides and bottom.
  double level;
  // Returns the pounder's grey level at panel point (x, y), or a negative number if not there.
  double At(double x, double y) const {
    const double ax = std::abs(x);
    if (y > z_mm) return -1;
    if (y >= z_mm - block_mm) {
      if (ax > a_mm) return -1;
      const bool rim = ax >= a_mm - rim_mm || y >= z_mm - rim_mm;
      return rim ? level + 0.12 : level;
    }
    if (ax <= shaft_mm) return level + 0.06;
    return -1;
  }
};

}  // namespace

cv::Mat ImpactScene::RenderAt(double t_s, std::uint64_t noise_seed, bool with_noise) const {
  return RenderWithField(SoilFieldPx(t_s), Pounder(t_s).z_m, noise_seed, with_noise);
}

// For each pixel: ss x ss samples inside its undistorted quadrilateral; a sample shows the
// pounder if it covers it, else the material point x = X + u(X) (Newton) decides: above the
// undisturbed surface the background, below it the analytic speckle.
cv::Mat ImpactScene::RenderWithField(const DisplacementField& field, double pounder_z_m,
                                     std::uint64_t noise_seed, bool with_noise) const {
  PounderDrawing pounder{pounder_z_m * 1000,
                         spec_.width_m * 500,
                         0.4 * spec_.width_m * 1000,
                         0.15 * spec_.width_m * 1000,
                         std::max(1.5 * std::max(sx_, sy_), 0.02 * spec_.width_m * 1000),
                         spec_.pounder_level};
  return synth_detail::RenderThroughLens(
      spec_, corner_map_, noise_seed, with_noise, [&](const cv::Point2d& q) {
        const cv::Point2d m = PanelFromIdeal(q);
        const double pl = pounder.At(m.x, m.y);
        if (pl >= 0) return pl;
        double X, Y;
        InvertField(field, q.x, q.y, &X, &Y);
        return (Y - surface_px_) < 0 ? spec_.background_level : pattern_->Intensity(X, Y);
      });
}

cv::Mat ImpactScene::RenderFrame(int k, bool with_noise) const {
  CheckValue(k >= 0 && k < frame_count_, "frame index", std::to_string(k),
             fmt::format("in [0, {})", frame_count_));
  return RenderAt(FrameTime(k), spec_.seed * 7919 + 1000003ull * static_cast<std::uint64_t>(k),
                  with_noise);
}

ImpactScene::SensorRecord ImpactScene::MakeSensorRecord() const {
  SensorRecord rec;
  const SceneSensorOptions& so = spec_.sensor;
  const double dt = 1 / so.rate_hz, g = spec_.g_m_s2;
  const double t_last = FrameTime(frame_count_ - 1);
  const auto n = static_cast<std::size_t>(std::ceil((DaqTime(t_last) + so.tail_s) / dt)) + 1;
  rec.frame0_daq_time_s = DaqTime(FrameTime(0));
  rec.impact_daq_time_s = DaqTime(0);
  rec.release_daq_time_s = DaqTime(release_time_s());
  // Velocities at the half-sample points: the reading is the cell average of 1 - a_down / g.
  std::vector<double> v_half(n + 1);
  tbb::parallel_for(std::size_t{0}, n + 1, [&](std::size_t i) {
    v_half[i] = Pounder(daq_origin_s_ + (static_cast<double>(i) - 0.5) * dt).v_m_s;
  });
  Rng noise(SplitMix64(spec_.seed) ^ 0x5EB50Bull);
  rec.time_s.resize(n);
  rec.accel_g.resize(n);
  rec.accel_true_g.resize(n);
  rec.exposure.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double daq = static_cast<double>(i) * dt;
    const double t = daq_origin_s_ + daq;
    rec.time_s[i] = daq;
    rec.accel_true_g[i] = 1 - (v_half[i + 1] - v_half[i]) / (g * dt);
    rec.accel_g[i] = rec.accel_true_g[i] + so.offset_g + so.noise_g * noise.Normal();
    const double k = std::floor((t - FrameTime(0)) * spec_.fps + 1e-9);
    double e = 0;
    if (k >= 0 && k < frame_count_) {
      const double since = t - FrameTime(static_cast<int>(k));
      e = (since > -1e-12 && since < so.exposure_s) ? 1.0 : 0.0;
    }
    rec.exposure[i] = e;
  }
  AddBaseForce(&rec);
  return rec;
}

void ImpactScene::AddBaseForce(SensorRecord* rec) const {
  const SceneBaseSensorOptions& b = spec_.base_sensors;
  const std::size_t n = rec->time_s.size();
  const double dt = 1 / spec_.sensor.rate_hz, g = spec_.g_m_s2;
  const double area_m2 = spec_.width_m * spec_.depth_m;
  for (std::size_t k = 0; k < b.columns.size(); ++k) {
    const double r_mm = std::hypot(b.offset_mm[k], b.depth_mm[k]);
    const double delay_s = 1e-3 * r_mm / spec_.soil.wave_speed_m_s;
    const double ratio = b.stress_ratio * std::pow(b.depth_mm[k] / r_mm, b.spreading_exponent);
    const double scale = ratio * 1e-6 * b.area_mm2[k] * spec_.pounder_mass_kg * g / area_m2;
    std::vector<double> truth(n, 0.0), written(n);
    tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
      // The accelerometer's cell average (MakeSensorRecord) at the delayed time.
      const double t = daq_origin_s_ + static_cast<double>(i) * dt - delay_s;
      if (t + 0.5 * dt <= 0) return;  // Before the contact (truth[i] stays 0).
      const double reading_g =
          1 - (Pounder(t + 0.5 * dt).v_m_s - Pounder(t - 0.5 * dt).v_m_s) / (g * dt);
      truth[i] = scale * std::max(0.0, reading_g);
    });
    Rng noise(SplitMix64(spec_.seed + 17 * (k + 1)) ^ 0xBA5E5E45ull);
    for (std::size_t i = 0; i < n; ++i)
      written[i] = truth[i] + b.offset_n + b.noise_n * noise.Normal();
    rec->base_force_true_n.push_back(std::move(truth));
    rec->base_force_n.push_back(std::move(written));
  }
}

}  // namespace impactdic
