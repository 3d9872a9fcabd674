#include "stage.h"

#include <vector>

#include "impactdic/core/log.h"
#include "impactdic/core/timer.h"

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

std::string NotListed(const Scene& scene, const char* name) {
  return scene.HasStage(name) ? "" : "not among the scene's stages";
}

}  // namespace impactdic::stages
