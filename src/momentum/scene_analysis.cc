#include "impactdic/momentum/scene_analysis.h"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>

#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/io/hdf5_store.h"

namespace impactdic {

SensorOptions SensorOptionsFromScene(const Scene& scene) {
  SensorOptions o;
  o.columns.time = scene.sensor.time_column;
  o.columns.accel = scene.sensor.accel_column;
  o.columns.accel_unit = AccelUnitFromString(scene.sensor.accel_unit);
  o.columns.exposure = scene.sensor.exposure_column;
  o.g_m_s2 = scene.test.g_m_s2;
  o.cutoff_hz = scene.sensor.cutoff_hz;
  o.quiet_window_s = scene.sensor.quiet_window_s;
  o.integrate_from = IntegrationStartFromString(scene.sensor.integrate_from);
  if (o.integrate_from == IntegrationStart::kImpact)
    o.impact_velocity_m_s = scene.test.ImpactVelocity();
  o.Check();
  return o;
}

MomentumOptions MomentumOptionsFromScene(const Scene& scene, double mm_per_px) {
  MomentumOptions m;
  m.pounder_mass_kg = scene.test.mass_kg;
  m.pounder_width_m = scene.test.width_m;
  m.depth_m = scene.test.depth_m;
  m.density_kg_m3 = scene.test.density_kg_m3;
  m.grid_cols = scene.momentum.grid_cols;
  m.grid_rows = scene.momentum.grid_rows;
  m.rect_mm = scene.momentum.rect_mm;
  if (scene.momentum.min_valid_fraction) m.min_valid_fraction = *scene.momentum.min_valid_fraction;
  if (scene.momentum.pounder_center_x_px && scene.momentum.surface_y_px) {
    const double cx_mm = *scene.momentum.pounder_center_x_px * mm_per_px;
    m.footprint.x_left_mm = cx_mm - 500 * scene.test.width_m;
    m.footprint.x_right_mm = cx_mm + 500 * scene.test.width_m;
    m.footprint.bottom_y_mm = *scene.momentum.surface_y_px * mm_per_px;
  } else if (!m.rect_mm) {
    throw Error(ErrorKind::kInvalidValue, "momentum.pounder_center_x_px / surface_y_px", "missing",
                "the pounder's position in the first frame (px), or momentum.rect_mm")
        .WithFile(scene.path);
  }
  m.Check();
  return m;
}

CorrelationSeries ReadCorrelationSeries(const std::string& h5_path, long* first_frame) {
  if (!std::filesystem::exists(h5_path)) {
    throw Error(ErrorKind::kFileNotFound, "", "",
                "the correlation results (run `impactdic correlate` or `impactdic run` first)")
        .WithFile(h5_path);
  }
  H5Reader in(h5_path);
  Dims du, dv, dx, dy;
  CorrelationSeries s;
  s.u_px = in.ReadDouble("dic/u_px", &du);
  s.v_px = in.ReadDouble("dic/v_px", &dv);
  s.x_px = in.ReadDouble("dic/x_px", &dx);
  s.y_px = in.ReadDouble("dic/y_px", &dy);
  if (du.size() < 2 || du != dv) {
    throw Error(ErrorKind::kFileFormat, "/dic/u_px, /dic/v_px",
                fmt::format("{}-D / {}-D datasets of different or too few dimensions", du.size(),
                            dv.size()),
                "equal [frames x subsets] (or [frames x rows x cols]) datasets")
        .WithFile(h5_path);
  }
  s.frames = du[0];
  s.subsets = s.u_px.size() / s.frames;
  if (s.x_px.size() < s.subsets || s.y_px.size() != s.x_px.size() ||
      s.x_px.size() % s.subsets != 0) {
    throw Error(ErrorKind::kFileFormat, "/dic/x_px, /dic/y_px",
                fmt::format("{} / {} entries", s.x_px.size(), s.y_px.size()),
                fmt::format("one position per subset ({}), or one per frame and subset", s.subsets))
        .WithFile(h5_path);
  }
  s.x_px.resize(s.subsets);
  s.y_px.resize(s.subsets);
  if (in.Exists("dic/status")) {
    Dims ds;
    const std::vector<std::int32_t> status = in.ReadInt("dic/status", &ds);
    if (status.size() != s.u_px.size()) {
      throw Error(ErrorKind::kFileFormat, "/dic/status", fmt::format("{} entries", status.size()),
                  fmt::format("one per frame and subset ({})", s.u_px.size()))
          .WithFile(h5_path);
    }
    s.valid.resize(status.size());
    for (std::size_t i = 0; i < status.size(); ++i) s.valid[i] = status[i] == 0 ? 1 : 0;
  }
  if (in.Exists("dic/sigma_u_px") && in.Exists("dic/sigma_v_px")) {
    s.sigma_u_px = in.ReadFloat("dic/sigma_u_px");
    s.sigma_v_px = in.ReadFloat("dic/sigma_v_px");
    if (s.sigma_u_px.size() != s.u_px.size() || s.sigma_v_px.size() != s.u_px.size()) {
      throw Error(ErrorKind::kFileFormat, "/dic/sigma_u_px, /dic/sigma_v_px",
                  fmt::format("{} / {} entries", s.sigma_u_px.size(), s.sigma_v_px.size()),
                  fmt::format("one per frame and subset ({})", s.u_px.size()))
          .WithFile(h5_path);
    }
  }
  // The dic stage writes one row per DEFORMED image (/dic/frame: 1-based image index, the
  // reference image being 0). Prepend the reference row (zero displacement) so row k is frame k.
  if (in.Exists("dic/frame")) {
    const std::vector<std::int32_t> index = in.ReadInt("dic/frame");
    for (std::size_t k = 0; k < index.size(); ++k) {
      if (index.size() != s.frames || index[k] != index[0] + static_cast<std::int32_t>(k)) {
        throw Error(ErrorKind::kFileFormat, "/dic/frame",
                    fmt::format("{} indices starting {}, not consecutive or not one per row",
                                index.size(), index.empty() ? -1 : index[0]),
                    "consecutive image indices, one per row of /dic/u_px")
            .WithFile(h5_path);
      }
    }
    if (!index.empty() && index[0] == 1) {
      const std::size_t n = s.subsets;
      s.u_px.insert(s.u_px.begin(), n, 0.0);
      s.v_px.insert(s.v_px.begin(), n, 0.0);
      if (!s.valid.empty()) s.valid.insert(s.valid.begin(), n, std::uint8_t{1});
      if (!s.sigma_u_px.empty()) {
        s.sigma_u_px.insert(s.sigma_u_px.begin(), n, 0.0f);
        s.sigma_v_px.insert(s.sigma_v_px.begin(), n, 0.0f);
      }
      ++s.frames;
    } else if (!index.empty() && index[0] != 0) {
      throw Error(ErrorKind::kFileFormat, "/dic/frame", fmt::format("first index {}", index[0]),
                  "0 (reference row included) or 1 (first deformed image)")
          .WithFile(h5_path);
    }
  }
  if (first_frame) {
    *first_frame = in.HasAttribute("dic", "first_frame")
                       ? std::lround(in.ReadNumberAttribute("dic", "first_frame"))
                       : -1;
  }
  s.Check();
  return s;
}

SceneAnalysisRun AnalyzeSceneResults(const Scene& scene, const std::string& results_path,
                                     double mm_per_px) {
  CheckValue(std::isfinite(mm_per_px) && mm_per_px > 0, "inputs.mm_per_px",
             fmt::format("{}", mm_per_px), "> 0 mm/px (or a calibration with a plane scale)");
  if (scene.inputs.sensor.empty()) {
    throw Error(ErrorKind::kInvalidValue, "inputs.sensor", "empty",
                "the DAQ CSV (the momentum analysis needs the pounder velocity)")
        .WithFile(scene.path);
  }
  const SensorOptions sopt = SensorOptionsFromScene(scene);
  const MomentumOptions mopt = MomentumOptionsFromScene(scene, mm_per_px);
  long first = -1;
  CorrelationSeries dic = ReadCorrelationSeries(results_path, &first);
  if (scene.momentum.max_sigma_px) {
    std::size_t excluded = 0;
    try {
      excluded =
          ExcludeUncertainSamples(*scene.momentum.max_sigma_px, "momentum.max_sigma_px", &dic);
    } catch (Error& e) {
      e.WithFile(results_path);
      throw;
    }
    LogWarning(
        "kinematics: {} of {} subset samples left out (sigma_u or sigma_v > "
        "momentum.max_sigma_px = {} px)",
        excluded, dic.frames * dic.subsets, *scene.momentum.max_sigma_px);
  }
  if (first < 0) first = scene.dic.first_frame;
  SceneAnalysisRun run;
  run.results_path = results_path;
  run.sensor = AnalyzeSensorCsv(scene.inputs.sensor, sopt);
  PanelMapping mapping;
  mapping.mm_per_px = mm_per_px;
  try {
    run.analysis =
        AnalyzeCorrelation(dic, mapping, scene.inputs.fps, scene.sensor.frame_time_offset_s,
                           run.sensor, mopt, static_cast<std::size_t>(first));
  } catch (Error& e) {
    // Name the file to fix: the DAQ record when its exposure channel times the frames, else the
    // scene's settings (fps, frame_time_offset_s, the grid).
    if (e.file().empty()) {
      const bool timing = e.where() == "exposure channel" || e.where() == "frame times";
      e.WithFile(timing && !run.sensor.exposure.empty() ? scene.inputs.sensor : scene.path);
    }
    throw;
  }
  H5Writer out(results_path, H5Writer::Mode::kUpdate);
  WriteAnalysis(out, run.analysis, run.sensor);
  out.SetAttribute("kinematics", "mm_per_px", mm_per_px);
  out.Commit();
  return run;
}

}  // namespace impactdic
