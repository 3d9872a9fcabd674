#include "impactdic/pipeline/scene_analysis.h"

#include <fmt/format.h>

#include <cmath>
#include <cstddef>
#include <optional>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/kinematics/kinematics.h"
#include "impactdic/momentum/scene_analysis.h"
#include "impactdic/pipeline/pipeline.h"

namespace impactdic {

std::string ExcludeUncertainSamplesOfScene(const Scene& scene, CorrelationSeries* series) {
  if (scene.momentum.max_sigma_px) {
    return ExcludeUncertainSamplesWithWarning(*scene.momentum.max_sigma_px, "momentum.max_sigma_px",
                                              series);
  }
  if (!std::isfinite(scene.momentum.max_sigma_ratio) || series->sigma_u_px.empty()) return "";
  return ExcludeSamplesAboveMedianSigmaWithWarning(scene.momentum.max_sigma_ratio,
                                                   "momentum.max_sigma_ratio", series);
}

void CheckResultsAreOfScene(const Scene& scene, const std::string& results_path,
                            const std::string& option) {
  const H5Reader in(results_path);
  if (!in.HasAttribute("/", "scene_name")) return;
  const std::string name = in.ReadStringAttribute("/", "scene_name");
  if (name == scene.name) return;
  throw Error(ErrorKind::kInvalidValue, option,
              fmt::format("{}, which holds the results of scene '{}'", results_path, name),
              fmt::format("the results of scene '{}' ({}); analysing another scene's results "
                          "would mix two tests",
                          scene.name, scene.path));
}

SceneAnalysisRun AnalyzeSceneResults(const Scene& scene, const std::string& results_path,
                                     double mm_per_px, bool allow_partial,
                                     const std::string& output_path) {
  CheckValue(std::isfinite(mm_per_px) && mm_per_px > 0, "inputs.mm_per_px",
             fmt::format("{}", mm_per_px), "> 0 mm/px (or a calibration with a plane scale)");
  if (scene.inputs.sensor.empty()) {
    throw Error(ErrorKind::kInvalidValue, "inputs.sensor", "empty",
                "the DAQ CSV (the momentum analysis needs the pounder velocity)")
        .WithFile(scene.path);
  }
  CheckResultsAreOfScene(scene, results_path, "results file");
  const SensorOptions sopt = MakeSensorOptions(scene);
  const MomentumOptions mopt = MakeMomentumOptions(scene, mm_per_px);
  long first = -1;
  CorrelationSeries dic = ReadCorrelationSeries(results_path, &first);
  try {
    const std::string warning = ExcludeUncertainSamplesOfScene(scene, &dic);
    if (!warning.empty()) LogWarning("{}", warning);
  } catch (Error& e) {
    e.WithFile(results_path);
    throw;
  }
  if (first < 0) first = scene.dic.first_frame;
  SceneAnalysisRun run;
  run.results_path = results_path;
  run.sensor = AnalyzeSensorCsv(scene.inputs.sensor, sopt);
  RequireExposureChannel(run.sensor, sopt.columns.exposure);
  PanelMapping mapping;
  mapping.mm_per_px = mm_per_px;
  try {
    run.analysis = AnalyzeCorrelation(dic, mapping, SceneFrameClock(scene), run.sensor, mopt,
                                      static_cast<std::size_t>(first));
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
    throw PartialResultsError(
        fmt::format("scene {}: the momentum stage produced nothing usable: t_e is not "
                    "measurable: {}\nNothing was written ({} is as it was)",
                    scene.name, m.t_end_problem, results_path),
        "writes it, with the figures that could not be measured as NaN");
  }
  H5Writer out(output_path.empty() ? results_path : output_path, H5Writer::Mode::kUpdate,
               results_path);
  out.Remove("/summary");
  out.SetAttribute("/", "scene_name", scene.name);
  WriteAnalysis(out, run.analysis, run.sensor);
  out.SetAttribute("kinematics", "mm_per_px", mm_per_px);
  out.Commit();
  return run;
}

}  // namespace impactdic
