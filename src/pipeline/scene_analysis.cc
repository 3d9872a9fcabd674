#include "impactdic/pipeline/scene_analysis.h"

#include <fmt/format.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>

#include "impactdic/core/error.h"
#include "impactdic/core/strings.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/json.h"
#include "impactdic/io/output_generation.h"
#include "impactdic/pipeline/given_keys.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/run_data.h"
#include "impactdic/sensor/sensor.h"
#include "impactdic/sensor/sensor_results.h"
#include "outputs/writers.h"
#include "route.h"
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

// The sensor library's error fields that are not themselves a scene key.
const FieldKeys kSensorFieldKeys = {{"sensor.columns.time", "sensor.time_column"},
                                    {"accel_unit", "sensor.accel_unit"},
                                    {"offset_reference", "sensor.offset_reference"},
                                    {"sensor.impact_velocity_m_s", "test.impact_velocity_m_s"}};

// The keys of the accelerometer record alone: the others need frames or a scene's test (the base
// force channels' wave figures need the pounder's mass and area, test.*: sensor/wave.h).
bool IsSensorRecordKey(const std::string& key) {
  return key == "inputs.sensor" || key == "test.impact_velocity_m_s" ||
         (key.rfind("sensor.", 0) == 0 && key != "sensor.frame_time_offset_s" &&
          key.rfind("sensor.base_", 0) != 0);
}

// The options of AnalyzeSensorRecord, checked (see there).
SensorOptions SensorRecordOptions(const AnalyzeRequest& r) {
  const GivenKeys& given = r.given;
  const std::string sensor_flag = given.Name("inputs.sensor");
  for (const auto& [key, flag] : given.flags)
    CheckValue(IsSensorRecordKey(key), flag, "with " + sensor_flag,
               flag + " only with the SCENE.yaml form");
  CheckValue(r.results.empty(), "--results", "with " + sensor_flag,
             "--results only with the SCENE.yaml form");
  CheckValue(!r.allow_partial, "--allow-partial", "with " + sensor_flag,
             "--allow-partial only with the SCENE.yaml form");
  SensorOptions o = r.scene.sensor.options;
  const bool from_release =
      given.Has("sensor.integrate_from") && o.integrate_from == IntegrationStart::kRelease;
  const bool from_impact = given.Has("test.impact_velocity_m_s");
  CheckValue(from_release != from_impact,
             given.Name("sensor.integrate_from") + " / " + given.Name("test.impact_velocity_m_s"),
             from_release ? "both given" : "neither given",
             "exactly one: integrate from the release (v = 0) or from the impact with the given "
             "impact velocity [m/s]");
  if (from_impact) {
    o.integrate_from = IntegrationStart::kImpact;
    o.impact_velocity_m_s = r.scene.test.impact_velocity_m_s.value();
  }
  WithGivenNames(given, kSensorFieldKeys, /*name_defaults=*/true, [&] { o.Check(); });
  return o;
}

}  // namespace

Scene AnalyzeCommandScene(const std::string& scene_path, const std::string& sensor_csv) {
  if (scene_path.empty() == sensor_csv.empty()) {
    throw Error(ErrorKind::kInvalidValue, "SCENE / --sensor",
                scene_path.empty() ? "neither given" : "both given",
                "either a scene file (momentum analysis) or --sensor CSV (accelerometer only)");
  }
  if (!scene_path.empty()) return LoadScene(scene_path);
  Scene scene;
  scene.inputs.sensor = sensor_csv;
  scene.sensor.options.columns.accel.clear();  // Chosen from the file: accel_g, else accel_m_s2.
  return scene;
}

SensorRecordAnalysis AnalyzeSensorRecord(const AnalyzeRequest& request) {
  SensorRecordAnalysis a;
  a.csv = request.scene.inputs.sensor;
  a.options = SensorRecordOptions(request);
  if (!request.output.empty()) {
    CheckOutputLocation(request.output, {"--output", {".h5", ".hdf5"}, {a.csv}});
    CheckNotInAGeneration(request.output, "--output");
  }
  if (!std::filesystem::exists(a.csv)) {
    throw Error(ErrorKind::kFileNotFound, request.given.Name("inputs.sensor"), a.csv,
                "an existing DAQ CSV file")
        .WithFile(a.csv);
  }
  // The record alone through the one route: no stage of the graph needs a scene's test, so the
  // record is analysed with the checked options and only /sensor is written.
  Route route;
  route.run_stages = [&](stages::StageContext& c) {
    c.data.sensor = WithGivenNames(request.given, kSensorFieldKeys, /*name_defaults=*/true,
                                   [&] { return AnalyzeSensorCsv(a.csv, a.options); });
  };
  route.nothing_written = "Nothing was written";
  route.partial_remedy = "writes it";
  route.write = [&](stages::StageContext& c) {
    if (request.output.empty()) return;
    // Only /sensor is replaced: /dic, /frames, ... of an existing results file stay.
    H5Writer out(request.output, /*owned_groups=*/{results_layout::kSensorGroup});
    WriteSensorResults(out, *c.data.sensor);
    out.Commit();
    c.summary.outputs.push_back(request.output);
  };
  SceneRunData data;
  RunRoute(request.scene, PipelineOptions{}, route, &data);
  a.result = std::move(*data.sensor);
  return a;
}

JsonObject SensorRecordAnalysis::ToJson() const {
  return SensorReportJson(result.summary, options);
}

std::string SensorRecordAnalysis::FullReport() const {
  return "sensor record " + csv + "\nintegration from " + ToString(options.integrate_from) +
         ", offset from " + ToString(options.offset_reference) + "\n" + result.summary.FullReport();
}

SceneAnalysisRun AnalyzeSceneResults(const AnalyzeRequest& request) {
  const Scene& scene = request.scene;
  const std::string& output = request.output;
  CheckValue(request.results.empty() || EndsWith(request.results, ".h5") ||
                 EndsWith(request.results, ".hdf5"),
             "--results", request.results, "an HDF5 file (.h5, .hdf5)");
  // The flags' values checked together, as the scene file's.
  WithGivenNames(request.given, kSensorFieldKeys, /*name_defaults=*/false,
                 [&] { MakeSensorOptions(scene); });
  const std::string results =
      request.results.empty()
          ? (std::filesystem::path(scene.outputs.folder) / "results.h5").string()
          : request.results;
  const std::string results_option = request.results.empty() ? "outputs.folder" : "--results";
  CheckResultsAreOfScene(scene, results, results_option);
  if (output.empty()) {
    CheckNotInAGeneration(results, results_option);
  } else {
    CheckOutputLocation(output,
                        {"--output", {".h5", ".hdf5"}, {scene.path, scene.inputs.sensor, results}});
    CheckNotInAGeneration(output, "--output");
    // Replaced whole by the analysis: never another scene's file (nor one that is not HDF5).
    if (std::filesystem::exists(output)) CheckResultsAreOfScene(scene, output, "--output");
  }
  return AnalyzeSceneResults(scene, results, request.allow_partial, output);
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
                                     bool allow_partial, const std::string& output_path) {
  CheckSceneForAnalysis(scene);
  CheckResultsAreOfScene(scene, results_path, "results file");
  SceneAnalysisRun run;
  run.results_path = output_path.empty() ? results_path : output_path;
  PipelineOptions options;
  options.allow_partial = allow_partial;
  Route route;
  route.run_stages = [&results_path](stages::StageContext& c) {
    stages::RunAnalysisStages(c, results_path);
  };
  route.nothing_written = fmt::format("Nothing was written ({} is as it was)", results_path);
  route.partial_remedy = "writes it, with the figures that could not be measured as NaN";
  route.write = [&](stages::StageContext& c) {
    H5Writer out(run.results_path, H5Writer::Mode::kUpdate, results_path);
    out.Remove("/summary");
    out.SetAttribute("/", "scene_name", scene.name);
    outputs::WriteAnalysisResults(out, c.data);
    out.Commit();
    c.summary.outputs.push_back(run.results_path);
  };
  run.summary = RunRoute(scene, options, route, &run.data);
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
