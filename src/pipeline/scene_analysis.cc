#include "impactdic/pipeline/scene_analysis.h"

#include <fmt/format.h>

#include <cstdint>
#include <string>

#include "impactdic/core/error.h"
#include "impactdic/core/timer.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/json.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/run_data.h"
#include "impactdic/sensor/sensor.h"
#include "outputs/writers.h"
#include "stages/scene_inputs.h"
#include "stages/stage.h"

namespace impactdic {
namespace {

// What the analysis needs of the scene, checked before any work: the sensor record, the stages
// it is about (sensor, kinematics, momentum) listed, and a scale (inputs.mm_per_px, else the
// calibration's plane scale, which the calibrate stage reads).
void CheckSceneForAnalysis(const Scene& scene) {
  if (scene.inputs.sensor.empty()) {
    throw Error(ErrorKind::kInvalidValue, "inputs.sensor", "empty",
                "the DAQ CSV (the momentum analysis needs the pounder velocity)")
        .WithFile(scene.path);
  }
  for (const char* stage : {"sensor", "kinematics", "momentum"}) {
    if (scene.HasStage(stage)) continue;
    std::string listed;
    for (const std::string& s : scene.stages) listed += (listed.empty() ? "" : ", ") + s;
    throw Error(ErrorKind::kInvalidValue, "stages", "[" + listed + "]",
                "sensor, kinematics and momentum listed (`analyze` runs them on the correlation "
                "results)")
        .WithFile(scene.path);
  }
  if (scene.inputs.calibration.empty() || !scene.HasStage("calibrate"))
    stages::RequireScale(scene, scene.inputs.mm_per_px);
}

}  // namespace

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
                                     bool allow_partial, const std::string& output_path) {
  CheckSceneForAnalysis(scene);
  CheckResultsAreOfScene(scene, results_path, "results file");
  WallTimer total;
  SceneAnalysisRun run;
  run.summary.scene_name = scene.name;
  run.data.mm_per_px = scene.inputs.mm_per_px;
  PipelineOptions options;
  options.allow_partial = allow_partial;
  stages::StageContext context{scene, options, run.data, run.summary};
  stages::RunAnalysisStages(context, results_path);
  if (!run.summary.failures.empty() && !allow_partial) {
    throw PartialResultsError(fmt::format("{}\nNothing was written ({} is as it was)",
                                          stages::FailedStagesText(run.summary), results_path),
                              "writes it, with the figures that could not be measured as NaN");
  }
  run.results_path = output_path.empty() ? results_path : output_path;
  H5Writer out(run.results_path, H5Writer::Mode::kUpdate, results_path);
  out.Remove("/summary");
  out.SetAttribute("/", "scene_name", scene.name);
  outputs::WriteAnalysisResults(out, run.data);
  out.Commit();
  run.summary.outputs.push_back(run.results_path);
  run.summary.seconds = total.ElapsedSeconds();
  return run;
}

JsonObject SceneAnalysisRun::ToJson() const {
  const SensorSummary& s = data.sensor->summary;
  JsonObject j = data.momentum->summary.ToJson();
  j.Add("impact_time_s", s.impact_time_s)
      .Add("impact_velocity_m_s", s.impact_velocity_m_s)
      .Add("final_penetration_m", s.final_penetration_m)
      .Add("results", results_path)
      .Add("usable", summary.IsUsable())
      // The analysis' key figures as `run`'s summary.json has them (measured and modelled).
      .Add("summary", summary.ToJson());
  return j;
}

std::string SceneAnalysisRun::FullReport(const std::string& scene_path) const {
  std::string text = "scene " + scene_path + " -> " + results_path + "\n" +
                     data.sensor->summary.FullReport() + data.momentum->summary.FullReport();
  if (data.model) text += "model: " + data.model->summary.BriefReport() + "\n";
  return text;
}

JsonObject SensorReportJson(const SensorSummary& s, const SensorOptions& o) {
  JsonObject j;
  j.Add("impact_time_s", s.impact_time_s)
      .Add("impact_velocity_m_s", s.impact_velocity_m_s)
      .Add("final_penetration_m", s.final_penetration_m)
      .Add("peak_deceleration_g", s.peak_deceleration_g)
      .Add("t_peak_s", s.t_peak_s)
      .Add("sample_rate_hz", s.sample_rate_hz)
      .Add("warnings", s.warnings)
      .Add("peak_time_daq_s", s.peak_time_s)
      .Add("stop_time_s", s.stop_time_s)
      .Add("stopped", s.stopped)
      .Add("release_time_s", s.release_time_s)
      .Add("offset_g", s.offset_g)
      .Add("noise_g", s.noise_g)
      .Add("cutoff_hz", s.cutoff_hz)
      .Add("integrate_from", ToString(o.integrate_from))
      .Add("offset_reference", ToString(o.offset_reference))
      .Add("samples", static_cast<std::int64_t>(s.samples))
      .Add("seconds", s.seconds);
  return j;
}

}  // namespace impactdic
