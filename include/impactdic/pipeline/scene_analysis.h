// `impactdic analyze SCENE.yaml`: the sensor, kinematics and momentum stages of one scene from its
// correlation results (HDF5; read by momentum/scene_analysis.h), written back into the same file.
//
//   Scene scene = LoadScene("scene.yaml");
//   SceneAnalysisRun run = AnalyzeSceneResults(scene, "results/results.h5", /*mm_per_px=*/0.1);
#ifndef IMPACTDIC_PIPELINE_SCENE_ANALYSIS_H_
#define IMPACTDIC_PIPELINE_SCENE_ANALYSIS_H_

#include <string>

#include "impactdic/momentum/momentum.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/sensor/sensor.h"

namespace impactdic {

struct SceneAnalysisRun {
  SensorResult sensor;
  SceneAnalysis analysis;
  std::string results_path;
};

// Leaves the uncertain samples of the scene's correlation series out of its kinematics and
// momentum (momentum.max_sigma_px if set, else momentum.max_sigma_ratio) and returns the warning
// saying how many (empty when neither applies, or the ratio rule left nothing out). The one rule
// of `run` and `analyze`.
std::string ExcludeUncertainSamplesOfScene(const Scene& scene, CorrelationSeries* series);

// Reads the correlation results, analyses the sensor record, computes kinematics and momentum
// and writes /sensor, /kinematics and /momentum into results_path (update in place, atomically),
// or, with output_path, into a copy of it written there (results_path unchanged). The file
// written has the root attribute scene_name of the scene and no /summary group (a run's key
// figures, which this analysis replaces). A results file of another scene (its scene_name) is
// refused before any work: Error kInvalidValue naming both scene names.
// As `impactdic run`: when the momentum analysis produced nothing usable (t_e not measurable),
// PartialResultsError (pipeline/pipeline.h; kind kNumerical) with the reason and nothing written,
// unless allow_partial (then written, with NaN figures; the caller reports the run as partial).
SceneAnalysisRun AnalyzeSceneResults(const Scene& scene, const std::string& results_path,
                                     double mm_per_px, bool allow_partial = false,
                                     const std::string& output_path = "");

// Error kInvalidValue naming `option` unless the results file holds no scene name (correlate -o)
// or the scene's: "R holds the results of scene 'A'; expected results of scene 'B' (S)".
void CheckResultsAreOfScene(const Scene& scene, const std::string& results_path,
                            const std::string& option);

}  // namespace impactdic

#endif  // IMPACTDIC_PIPELINE_SCENE_ANALYSIS_H_
