// kinematics: subset motion on the panel (mm, mm/s) from the correlation rows, without the samples
// whose sigma is above momentum.max_sigma_px or momentum.max_sigma_ratio x the frame's median.
#include <algorithm>
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/io/dic_results.h"
#include "impactdic/kinematics/kinematics.h"
#include "impactdic/momentum/scene_analysis.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/run_data.h"
#include "impactdic/pipeline/scene.h"
#include "scene_inputs.h"
#include "stage.h"

namespace impactdic::stages {
namespace {

class KinematicsStage : public Stage {
 public:
  const char* name() const override { return "kinematics"; }

  std::string SkipReason(const StageContext& c) const override {
    if (!c.data.dic) return "no correlation results";
    return NotListed(c.scene, name());
  }

  std::string Run(StageContext& c) const override {
    SceneRunData& d = c.data;
    RequireScale(c.scene, d.mm_per_px);
    PanelMapping mapping;
    mapping.mm_per_px = d.mm_per_px;
    KinematicsOptions k;
    k.fps = d.timeline.fps;  // A camera file's own rate, else inputs.fps.
    {
      // The series the kinematics use, borrowing the rows of /dic (no copy): without the
      // uncertain samples (ExcludeUncertainSamplesOfScene marks them invalid and says how many;
      // /dic keeps them).
      BorrowedCorrelationSeries series(&*d.dic);
      try {
        const std::string warning = ExcludeUncertainSamplesOfScene(c.scene, &series.series());
        if (!warning.empty()) {
          LogWarning("{}", warning);
          c.summary.warnings.push_back(warning);
        }
      } catch (Error& e) {  // e.g. no sigmas in a results file: name it.
        if (e.file().empty() && !d.dic_file.empty()) e.WithFile(d.dic_file);
        throw;
      }
      d.kinematics = ComputeKinematics(series.series(), mapping, k);
    }
    return d.kinematics->summary.BriefReport();
  }
};

}  // namespace

std::unique_ptr<Stage> MakeKinematicsStage() { return std::make_unique<KinematicsStage>(); }

}  // namespace impactdic::stages
