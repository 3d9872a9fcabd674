// The whole pipeline on one scene (docs/architecture.md, "The stage graph"; the stage graph and the
// data between the stages in docs/architecture.md): calibrate -> sensor -> frames -> correlate ->
// kinematics
// -> momentum -> model -> strain -> outputs, skipping what the scene does not need and saying so
// (strain only with strain.enabled). Each
// stage is a unit in src/pipeline/stages/, the data between them is SceneRunData
// (pipeline/run_data.h), the outputs are OutputWriters (pipeline/output_writer.h).
// `impactdic run SCENE.yaml` is a thin layer over RunScene().
//
//   Scene scene = LoadScene("sample_frames/scene.yaml");
//   PipelineOptions options;
//   options.output_folder = "results/sample";
//   PipelineSummary s = RunScene(scene, options);
//   std::cout << s.FullReport();
//
// A stage that ran but produced nothing usable (no valid subset in any frame, no measurable t_e, a
// model solve that did not reach v = 0) is a FAILURE (PipelineSummary::failures): the figures
// that depend on it are NaN (null in summary.json) with the reasons in `warnings`, and RunScene
// throws PartialResultsError (an Error of kind kNumerical) naming each failed stage and why before
// writing any output -- as for any failed run, nothing new is written and a previous run's outputs
// stay -- unless options.allow_partial (`impactdic run --allow-partial`): then the outputs are
// written and summary.json says "usable": false with the failures.
//
// Outputs (folder: options.output_folder, else the scene's outputs.folder), one generation
// (io/output_generation.h): written into a staging folder beside it and swapped in only when all
// are complete, so the folder never holds files of two runs; a failed or interrupted run leaves the
// previous outputs as they were. The folder must be new, empty or one impactdic wrote. Files:
//   results.h5      everything (layout: docs/results.md, names in io/results_layout.h)
//   summary.json    key figures (measured and modelled), summary.csv the same as one CSV row
//   timing.json     wall times of the run and its stages, the correlation's subsets per second
//   strain.csv      the strain series (strain.enabled and outputs.csv; docs/strain.md)
//   momentum.png, deceleration.png, added_mass.png, velocity_field_te.png, velocity.mp4 (or .avi)
#ifndef IMPACTDIC_PIPELINE_PIPELINE_H_
#define IMPACTDIC_PIPELINE_PIPELINE_H_

#include <algorithm>
#include <optional>
#include <string>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/numeric.h"
#include "impactdic/dic/options.h"
#include "impactdic/io/json.h"
#include "impactdic/pipeline/output_writer.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/preprocess/preprocess.h"
#include "impactdic/sensor/wave.h"

namespace impactdic {

struct PipelineOptions {
  std::string output_folder;  // Empty: the scene's outputs.folder. Created (replaced) at the end.
  bool png_frames = false;  // Also write the animation frames as PNG (or scene outputs.png_frames).
  int threads = -1;         // Correlation threads; -1: the scene's dic.threads (0 = all cores).
  // Write the outputs and return even when a stage produced nothing usable (file comment);
  // false: such a run throws PartialResultsError before writing anything.
  bool allow_partial = false;
  // Also replace an output folder another kind of command wrote (a synth scene, a campaign) or
  // holding other commands' outputs (io/output_generation.h); files impactdic did not write are
  // never replaced.
  bool force = false;
  // The command whose flags made the scene ("correlate"), "" for a scene file: messages about a
  // key then name the command's flag for it (SceneFlagShortName), not the key.
  std::string flags_of;
  // Writers run after the built-in ones (results.h5, figures, summary.json, summary.csv) when the
  // scene has the outputs stage (pipeline/output_writer.h).
  OutputWriters extra_output_writers;
  void Check() const;
};

// What happened to one stage.
struct StageReport {
  std::string name;
  bool ran = false;
  std::string note;  // What it did, or why it was skipped.
  double seconds = 0;
};

// The key figures of a scene (summary.json / summary.csv). NaN: not available.
struct SceneFigures {
  double impact_velocity_m_s = kNaN;  // From the sensor (else the scene's v0).
  double p_max_kg_m_s = kNaN;
  double t_end_peak_s = kNaN;                 // After impact.
  double momentum_conservation_error = kNaN;  // |p_tot(t_e) - p_max| / p_max
  double added_mass_max_kg = kNaN;            // Measured, Eq. 3 at t_e.
  double added_mass_eq4_kg = kNaN;            // Eq. 4 prediction.
  double sigmoid_M_kg = kNaN, sigmoid_b_per_s = kNaN, sigmoid_T_s = kNaN;
  double momentum_ratio_measured = kNaN;  // Eq. 11
  double momentum_ratio_model = kNaN;
  double v_sand_max_m_s = kNaN;
  double peak_deceleration_measured_g = kNaN;  // Largest of the peak stage (impact..t_e).
  double peak_deceleration_model_g = kNaN;
  double plateau_deceleration_measured_g = kNaN;  // Mean over [t1, t_stop], t1 = T + 4/b.
  double plateau_deceleration_model_g = kNaN;
  double crater_depth_measured_m = kNaN;  // Sensor: penetration where v returns to 0.
  double crater_depth_model_m = kNaN;
  double t_end_model_s = kNaN;
  double dic_valid_fraction = kNaN;
  double dic_subsets_per_s = kNaN;  // A wall-time rate: in timing.json and summary.csv only.
  // With base force channels (docs/wave.md): the base sensor nearest the pounder's centre line
  // (smallest horizontal offset) gives the wave speed from the peak travel time and the stress
  // ratio (the attenuation); the DIC front's speed and the displacement's decay length along the
  // centre line at t_e. NaN without base channels or when not determined.
  double wave_speed_peak_m_s = kNaN;
  double wave_stress_ratio = kNaN;
  double wave_front_speed_m_s = kNaN;
  double wave_decay_length_te_mm = kNaN;

  // summary.json's figures: every one of CsvNames() but the wall-time rate dic_subsets_per_s, so
  // that two runs of one scene give the same bytes.
  JsonObject ToJson() const;
  // Column names and values of summary.csv, in the same order.
  std::vector<std::string> CsvNames() const;
  std::vector<double> CsvValues() const;
};

// The strain stage's key figures (summary.json "strain", summary.csv's strain_* columns; only
// when the stage ran): the compacted zone (eps_v > strain.compaction_threshold) at t_e and at the
// last analysed frame, its depth measured from `depth_from`, next to the crater depths. NaN: not
// available (te_note says why for the t_e figures).
struct StrainFigures {
  double compacted_area_te_mm2 = kNaN, compacted_depth_te_mm = kNaN;
  double compacted_area_end_mm2 = kNaN, compacted_depth_end_mm = kNaN;
  double crater_depth_model_mm = kNaN, crater_depth_measured_mm = kNaN;
  std::string te_note;     // Why the t_e figures are NaN ("" when t_e is known).
  std::string depth_from;  // "momentum.surface_y_px" or "grid top row".
  std::string gradient;    // "fit" or "warp".
  JsonObject ToJson() const;
  // summary.csv's extra columns (strain_compacted_area_te_mm2, ...) and values, in one order.
  std::vector<std::string> CsvNames() const;
  std::vector<double> CsvValues() const;
};

// summary.json's "wave": the pounder's peak stress and time, the travel-time uncertainty and its
// parts, and per channel (an object under "channels" keyed by its column) the WaveChannel's
// figures (null when not available) with its "problems" (docs/wave.md).
JsonObject WaveJson(const WaveResult& wave);

// A run (RunScene) or an analysis (AnalyzeSceneResults) in which a stage produced nothing usable,
// with partial output not allowed: Error(kNumerical) reading "PROBLEM; the option `allow_partial`
// REMEDY". problem() says what failed and what was kept, remedy() what the option would write. The
// option is named by its library name (PipelineOptions::allow_partial, the allow_partial argument
// of AnalyzeSceneResults); a front end names its own spelling of it with the same two texts.
class PartialResultsError : public Error {
 public:
  static constexpr const char* kOption = "allow_partial";

  PartialResultsError(std::string problem, std::string remedy);
  const std::string& problem() const { return problem_; }
  const std::string& remedy() const { return remedy_; }

 private:
  std::string problem_, remedy_;
};

// A stage that ran but produced nothing usable, and why.
struct StageFailure {
  std::string stage;
  std::string reason;
};

struct PipelineSummary {
  std::string scene_name;
  std::string output_folder;
  std::vector<StageReport> stages;
  SceneFigures figures;
  std::optional<StrainFigures> strain;  // When the strain stage ran.
  std::optional<WaveResult> wave;       // When the scene has base force channels.
  // The momentum figures' standard uncertainties (momentum UncertaintyJson), when the momentum
  // stage ran.
  std::optional<JsonObject> uncertainty;
  std::vector<StageFailure> failures;  // Empty: every stage that ran produced what it is for.
  std::vector<std::string> outputs;    // Files written.
  std::vector<std::string> warnings;
  double seconds = 0;
  bool IsUsable() const { return failures.empty(); }
  // "stage: reason; stage: reason" (empty when usable).
  std::string FailureText() const;
  std::string BriefReport() const;
  std::string FullReport() const;
  // summary.json: the figures' keys (SceneFigures::ToJson), "uncertainty" (momentum
  // UncertaintyJson, when the momentum stage ran), "strain" (StrainFigures::ToJson, when
  // the strain stage ran), "wave" (WaveJson, with base force channels), then "usable", "failures"
  // (stage -> reason) and "warnings". Nothing that varies between runs of one scene (no time, rate,
  // path or version).
  JsonObject ToJson() const;
  // timing.json: "seconds" (the run up to its outputs), "stages" (name -> seconds, the stages that
  // ran) and "dic_subsets_per_s" (null without a correlation).
  JsonObject TimingJson() const;
};

// The output folder must not hold an input: a run replaces the files it wrote there before
// (results.h5, summary.*, figures, video) and a campaign its whole folder, so a scene, frame,
// sensor or calibration file in it could be overwritten, removed or taken for an output. Error
// kInvalidValue naming `option`, the folder and the input. RunScene checks it; so does
// RunCampaign for its folder.
void CheckOutputFolderHoldsNoInput(const Scene& scene, const std::string& folder,
                                   const std::string& option);

// The scene's `stages` list is consistent: `correlate` needs `frames` (the images it correlates).
// Error kInvalidValue naming `stages` otherwise. RunScene checks it before any work.
void CheckSceneStages(const Scene& scene);

// Runs the scene. Throws Error for bad input (missing or truncated frames, sensor record not
// covering the frames, unwritable output folder, ...) and for stages that produced nothing usable
// (unless options.allow_partial; file comment) before anything that looks complete is written.
PipelineSummary RunScene(const Scene& scene, const PipelineOptions& options);

// The correlation options of a scene's `dic` section: SceneDic::options (keys not in the scene
// keep the dic library's defaults) with the region of interest (roi, roi_polygon) applied. Error
// naming the key if invalid (dic.reference_update other than the default or fixed with dic.mode
// pairs).
DicOptions MakeDicOptions(const SceneDic& dic);

// The preprocessing of a scene's frames: PreprocessOptions of the preprocess.* keys, measured and
// undistorted over the correlation's region of interest (MakeDicOptions' grid.roi).
PreprocessOptions MakePreprocessOptions(const Scene& scene);

}  // namespace impactdic

#endif  // IMPACTDIC_PIPELINE_PIPELINE_H_
