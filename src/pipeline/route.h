// One driver for every command that runs a scene's stages (private to the pipeline module):
// `run`, `analyze SCENE`, `analyze --sensor` and `correlate` each describe their route (which
// stages, what is written), and RunRoute builds the stage context, runs them, applies the one
// failure rule (a stage that produced nothing usable fails the route, nothing written, unless
// allow_partial) and writes the outputs. A rule added here holds for every route.
#ifndef IMPACTDIC_SRC_PIPELINE_ROUTE_H_
#define IMPACTDIC_SRC_PIPELINE_ROUTE_H_

#include <functional>
#include <string>

#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/run_data.h"
#include "impactdic/pipeline/scene.h"
#include "stages/stage.h"

namespace impactdic {

struct Route {
  // The stages of the route, in the stage graph's order (stages/stage.h: RunAnalysisStages,
  // RunCorrelationStages, ...).
  std::function<void(stages::StageContext&)> run_stages;
  // The failure message's last sentence: what was not written ("Nothing was written (X is as it
  // was)"), and what allow_partial writes instead (PartialResultsError's remedy).
  std::string nothing_written;
  std::string partial_remedy;
  // Writes the route's outputs (adding them to the summary's outputs) after the failure rule.
  std::function<void(stages::StageContext&)> write;
  // The folder the outputs go to, for the summary (run); "" for a route writing one file.
  std::string output_folder;
};

// Runs `route` on `scene` into `data` (its mm_per_px starts as the scene's inputs.mm_per_px):
// the summary with its stages, figures, failures, outputs and seconds (up to the outputs while
// they are written, all of it on return). Throws PartialResultsError when a stage failed and
// options.allow_partial is false, before anything is written.
PipelineSummary RunRoute(const Scene& scene, const PipelineOptions& options, const Route& route,
                         SceneRunData* data);

}  // namespace impactdic

#endif  // IMPACTDIC_SRC_PIPELINE_ROUTE_H_
