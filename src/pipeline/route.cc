#include "route.h"

#include <fmt/format.h>

#include "impactdic/core/timer.h"

namespace impactdic {

PipelineSummary RunRoute(const Scene& scene, const PipelineOptions& options, const Route& route,
                         SceneRunData* data) {
  WallTimer total;
  PipelineSummary summary;
  summary.scene_name = scene.name;
  summary.output_folder = route.output_folder;
  data->mm_per_px = scene.inputs.mm_per_px;
  stages::StageContext context{scene, options, *data, summary};
  route.run_stages(context);
  if (!summary.failures.empty() && !options.allow_partial) {
    throw PartialResultsError(
        fmt::format("{}\n{}", stages::FailedStagesText(summary), route.nothing_written),
        route.partial_remedy);
  }
  summary.seconds = total.ElapsedSeconds();  // timing.json: up to the outputs.
  route.write(context);
  summary.seconds = total.ElapsedSeconds();
  return summary;
}

}  // namespace impactdic
