#include "impactdic/momentum/scene_analysis.h"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>

#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/io/dic_results.h"
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

CorrelationSeries CorrelationSeriesFromTable(const DicResultsTable& t) {
  CorrelationSeries s;
  s.frames = t.rows;
  s.subsets = t.subsets;
  s.x_px = t.x_px;
  s.y_px = t.y_px;
  s.u_px = t.u_px;
  s.v_px = t.v_px;
  if (!t.status.empty()) {
    s.valid.resize(t.status.size());
    for (std::size_t k = 0; k < t.status.size(); ++k) s.valid[k] = t.IsValid(k) ? 1 : 0;
  }
  s.sigma_u_px = t.sigma_u_px;
  s.sigma_v_px = t.sigma_v_px;
  s.Check();
  return s;
}

CorrelationSeries ReadCorrelationSeries(const std::string& h5_path, long* first_frame) {
  if (!std::filesystem::exists(h5_path)) {
    throw Error(ErrorKind::kFileNotFound, "", "",
                "the correlation results (run `impactdic correlate` or `impactdic run` first)")
        .WithFile(h5_path);
  }
  const DicResultsTable table = ReadDicResults(H5Reader(h5_path), h5_path);
  if (first_frame) *first_frame = table.first_frame;
  return CorrelationSeriesFromTable(table);
}

double MeasuredPeakDeceleration(const SensorResult& sensor, double peak_stage_s) {
  const double t_i = sensor.summary.impact_time_s;
  const std::size_t k =
      PeakDecelerationSample(sensor.time_s, sensor.accel_g, t_i, /*from_s=*/0.0, peak_stage_s);
  return k < sensor.accel_g.size() ? sensor.accel_g[k] - 1 : std::nan("");
}

double MeasuredPlateauDeceleration(const SensorResult& sensor, double t1_after_impact_s, double g) {
  const SensorSummary& s = sensor.summary;
  if (!std::isfinite(s.impact_time_s) || !std::isfinite(s.stop_time_s)) return std::nan("");
  const double t1 = s.impact_time_s + t1_after_impact_s;
  if (!(s.stop_time_s > t1)) return std::nan("");
  const std::vector<double> v =
      SampleSeries(sensor.time_s, sensor.velocity_m_s, {t1, s.stop_time_s}, "sensor velocity");
  return (v[0] - v[1]) / (s.stop_time_s - t1) / g;
}

SceneAnalysisRun AnalyzeSceneResults(const Scene& scene, const std::string& results_path,
                                     double mm_per_px, bool allow_partial) {
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
  const MomentumSummary& m = run.analysis.momentum.summary;
  if (!m.IsUsable() && !allow_partial) {
    throw Error(ErrorKind::kNumerical,
                fmt::format("scene {}: the momentum stage produced nothing usable: t_e is not "
                            "measurable: {}\nNothing was written ({} is as it was); `impactdic "
                            "analyze --allow-partial` writes it, with the figures that could not "
                            "be measured as NaN",
                            scene.name, m.t_end_problem, results_path));
  }
  H5Writer out(results_path, H5Writer::Mode::kUpdate);
  WriteAnalysis(out, run.analysis, run.sensor);
  out.SetAttribute("kinematics", "mm_per_px", mm_per_px);
  out.Commit();
  return run;
}

}  // namespace impactdic
