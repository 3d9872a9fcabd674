#include "stage.h"

#include <fmt/format.h>

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/core/timer.h"
#include "impactdic/pipeline/frame_stream.h"
#include "impactdic/pipeline/run_data.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/pipeline/scene_flags.h"
#include "impactdic/sensor/frame_timeline.h"
#include "impactdic/sensor/sensor.h"

namespace impactdic::stages {

void RunStage(const Stage& stage, StageContext& context) {
  std::vector<StageReport>& reports = context.summary.stages;
  const std::string why = stage.SkipReason(context);
  if (!why.empty()) {
    reports.push_back({stage.name(), false, why, 0});
    LogInfo("[{}] skipped: {}", stage.name(), why);
    return;
  }
  WallTimer timer;
  const std::string note = stage.Run(context);
  reports.push_back({stage.name(), true, note, timer.ElapsedSeconds()});
  LogInfo("[{}] {} ({:.2f} s)", stage.name(), note, timer.ElapsedSeconds());
}

void RunCorrelationStages(StageContext& context) {
  RunStage(*MakeFramesStage(), context);
  RunStage(*MakeCorrelateStage(), context);
}

void RunAnalysisStages(StageContext& context, const std::string& results_file) {
  RunStage(*MakeCalibrateStage(), context);
  RunStage(*MakeSensorStage(), context);
  if (results_file.empty()) {
    RunCorrelationStages(context);
  } else {
    RunStage(*MakeLoadDicStage(results_file), context);
  }
  for (const auto& make : {MakeKinematicsStage, MakeMomentumStage, MakeModelStage, MakeStrainStage})
    RunStage(*make(), context);
}

std::string FailedStagesText(const PipelineSummary& summary) {
  std::string text =
      fmt::format("{}{} stage(s) produced nothing usable:",
                  summary.scene_name.empty() ? "" : "scene " + summary.scene_name + ": ",
                  summary.failures.size());
  for (const StageFailure& f : summary.failures)
    text += fmt::format("\n  {}: {}", f.stage, f.reason);
  return text;
}

void NameFileToFix(const StageContext& context, Error& error) {
  if (!error.file().empty()) return;
  const bool timing = error.where() == "exposure channel" || error.where() == "frame times";
  const bool exposure = context.data.sensor && !context.data.sensor->exposure.empty();
  error.WithFile(timing && exposure ? context.scene.inputs.sensor : context.scene.path);
}

FrameTimeline TimeSceneFrames(const StageContext& context, int first_index,
                              std::vector<long long> numbers) {
  const Scene& scene = context.scene;
  const SceneRunData& d = context.data;
  try {
    if (d.sensor) RequireExposureChannel(*d.sensor, scene.sensor.options.columns.exposure);
    return MakeFrameTimeline(first_index, std::move(numbers), SceneFrameClock(scene),
                             d.sensor ? &*d.sensor : nullptr);
  } catch (Error& e) {  // e.g. a record that ends before the last frame: name the file.
    if (e.file().empty())
      e.WithFile(e.where() == "inputs.fps" || !d.sensor ? scene.path : scene.inputs.sensor);
    throw;
  }
}

std::string KeyName(const StageContext& context, const std::string& key) {
  const std::string& command = context.options.flags_of;
  return command.empty() ? key : SceneFlagShortName(command, key);
}

std::string NotListed(const Scene& scene, const char* name) {
  return scene.HasStage(name) ? "" : "not among the scene's stages";
}

}  // namespace impactdic::stages
