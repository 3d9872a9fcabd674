// `impactdic analyze SCENE.yaml`: the scene's analysis from the correlation results of a results
// file, through the one stage graph of `impactdic run` (pipeline/pipeline.h, docs/architecture.md)
// with a load_dic stage (the file's /dic group) in place of the frames and correlate stages:
// calibrate, sensor, load_dic, kinematics, momentum, model, strain (as the scene lists them), then
// written back into the file. The same stages on the same /dic give the same analysis as the run.
//
//   Scene scene = LoadScene("scene.yaml");
//   SceneAnalysisRun run = AnalyzeSceneResults(scene, "results/results.h5");
#ifndef IMPACTDIC_PIPELINE_SCENE_ANALYSIS_H_
#define IMPACTDIC_PIPELINE_SCENE_ANALYSIS_H_

#include <string>

#include "impactdic/io/json.h"
#include "impactdic/pipeline/given_keys.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/run_data.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/sensor/sensor.h"

namespace impactdic {

struct SceneAnalysisRun {
  PipelineSummary summary;   // The stages, the key figures, warnings and failures.
  SceneRunData data;         // What the stages produced (sensor, dic, kinematics, momentum, ...).
  std::string results_path;  // The file written.

  // `impactdic analyze SCENE`'s reports: MomentumSummary::ToJson's keys, then impact_time_s,
  // impact_velocity_m_s, final_penetration_m, results, usable and summary (PipelineSummary's
  // JSON, as run's summary.json); the text: "scene PATH -> RESULTS", the sensor's and the
  // momentum's full reports and the model's brief one.
  JsonObject ToJson() const;
  std::string FullReport(const std::string& scene_path) const;
};

// `impactdic analyze --sensor`'s JSON report: impact_time_s, impact_velocity_m_s,
// final_penetration_m, peak_deceleration_g, t_peak_s, sample_rate_hz, warnings first, in this
// order (the contract's keys), then the record's other figures and the options' integrate_from
// and offset_reference.
JsonObject SensorReportJson(const SensorSummary& s, const SensorOptions& o);

// Runs the analysis stages on the /dic group of results_path and writes the groups of the stages
// that ran (/sensor, /kinematics, /momentum, /model, /strain: results_file_writer's, as results.h5)
// into results_path (update in place, atomically), or, with output_path, into a copy of it
// written there (results_path unchanged). The file written has the root attribute scene_name of
// the scene and no /summary group (a run's key figures; this analysis' are in the returned
// summary). Before any work: the results file must be of this scene (CheckResultsAreOfScene),
// the scene must give a sensor record and list sensor, kinematics and momentum, and have a scale
// (inputs.mm_per_px or a calibration). As `impactdic run`: when a stage produced nothing usable
// (t_e not measurable, a model solve that did not reach v = 0), PartialResultsError
// (pipeline/pipeline.h; kind kNumerical) naming each and why with nothing written, unless
// allow_partial (then written, with NaN figures; the caller reports the run as partial).
SceneAnalysisRun AnalyzeSceneResults(const Scene& scene, const std::string& results_path,
                                     bool allow_partial = false,
                                     const std::string& output_path = "");

// What `impactdic analyze` was asked. Its two forms are scenes: SCENE.yaml (AnalyzeCommandScene
// loads it), or the accelerometer record alone (--sensor CSV: the library's defaults, the
// acceleration column chosen from the file, inputs.sensor the CSV); the flags given set the
// scene's keys (scene_flags.h) and are named in `given`.
struct AnalyzeRequest {
  Scene scene;
  GivenKeys given;      // The keys the command line set: errors name the flag typed.
  std::string results;  // --results (SCENE form; empty: <outputs.folder>/results.h5).
  std::string output;   // --output: the HDF5 file to write (empty: SCENE form updates `results`).
  bool allow_partial = false;  // --allow-partial (SCENE form).
};

// The scene of exactly one of `scene_path` (LoadScene) and `sensor_csv` (the record alone, see
// AnalyzeRequest); Error naming "SCENE / --sensor" when both or neither are given.
Scene AnalyzeCommandScene(const std::string& scene_path, const std::string& sensor_csv);

// `impactdic analyze SCENE.yaml`: checks the paths before any work (--results an HDF5 file of this
// scene, --output none of the inputs and of this scene if it exists, neither inside a folder of
// outputs written together: CheckNotInAGeneration) and the sensor keys given, then
// AnalyzeSceneResults(scene, results, allow_partial, output).
SceneAnalysisRun AnalyzeSceneResults(const AnalyzeRequest& request);

// The accelerometer record alone (`impactdic analyze --sensor CSV`).
struct SensorRecordAnalysis {
  std::string csv;
  SensorOptions options;  // As used: integrate_from, offset_reference, ...
  SensorResult result;

  JsonObject ToJson() const;       // SensorReportJson.
  std::string FullReport() const;  // "sensor record CSV", the integration start and the offset
                                   // reference, then SensorSummary::FullReport.
};

// Runs the sensor stage's analysis on request.scene.inputs.sensor and writes /sensor into
// request.output if given (its other groups kept). Before reading the record: only keys of the
// record (sensor.*, test.impact_velocity_m_s; not sensor.frame_time_offset_s nor the base force
// channels' sensor.base_*, whose wave figures need the scene's pounder) given, nor
// --results or --allow-partial; exactly one of sensor.integrate_from release and
// test.impact_velocity_m_s (integrate from the release, or from the impact at that velocity);
// SensorOptions::Check; the output's location (an HDF5 file, not the record, not inside a
// generation). Errors name the flag given (request.given), else the key's flag of `analyze`.
SensorRecordAnalysis AnalyzeSensorRecord(const AnalyzeRequest& request);

// Error kInvalidValue naming `option` unless the results file holds no scene name (correlate -o)
// or the scene's: "R holds the results of scene 'A'; expected results of scene 'B' (S)".
void CheckResultsAreOfScene(const Scene& scene, const std::string& results_path,
                            const std::string& option);

}  // namespace impactdic

#endif  // IMPACTDIC_PIPELINE_SCENE_ANALYSIS_H_
