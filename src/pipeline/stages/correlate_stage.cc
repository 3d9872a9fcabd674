// correlate: subset DIC of the analysed frames (dic CorrelateFrames), as the rows of the
// results layout (dic MakeDicResultsTable). No valid subset in any frame is a failure.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <utility>
#include <vector>

#include "impactdic/core/threads.h"
#include "impactdic/dic/correlate_frames.h"
#include "impactdic/dic/correlator.h"
#include "impactdic/dic/dic_io.h"
#include "impactdic/dic/options.h"
#include "impactdic/io/dic_results.h"
#include "impactdic/pipeline/frame_stream.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/run_data.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/preprocess/preprocess.h"
#include "impactdic/strain/strain.h"
#include "scene_inputs.h"
#include "stage.h"

namespace impactdic::stages {
namespace {

class CorrelateStage : public Stage {
 public:
  const char* name() const override { return "correlate"; }

  std::string SkipReason(const StageContext& c) const override {
    std::string listed = NotListed(c.scene, name());
    if (!listed.empty()) return listed;
    return c.data.frames ? "" : "no frames";
  }

  std::string Run(StageContext& c) const override {
    const Scene& scene = c.scene;
    SceneRunData& d = c.data;
    DicOptions options = MakeDicOptions(scene.dic);
    // dic.keep_warp_gradient, or strain.gradient warp (which reads /dic/*_warp).
    options.keep_warp_gradient =
        options.keep_warp_gradient ||
        (scene.strain.enabled && scene.strain.gradient == StrainGradient::kWarp);
    const bool given = c.options.threads >= 0;  // Else the scene's dic.threads.
    const ThreadLimit limit(given ? c.options.threads : scene.dic.threads,
                            given ? "threads" : "dic.threads");
    options.grid.mask = SceneMask(scene, d.frames->frame_size());
    DicResult dic = CorrelateFrames(*d.frames, options);
    for (const auto& w : d.frames->warnings()) c.summary.warnings.push_back("frames: " + w);
    d.preprocess_note = d.frames->PreprocessNote();
    d.dic_summary = dic.summary;
    // Moved: the correlator's rows are released as the table fills (one copy in memory).
    d.dic = MakeDicResultsTable(std::move(dic), options, d.first_frame);
    d.dic->text_attributes["preprocess"] = d.preprocess_note;
    if (const PreprocessSummary* pre = d.frames->preprocess_summary())
      PrefilterAttributes(pre->gaussian, &d.dic->text_attributes, &d.dic->number_attributes);
    const DicSummary& summary = d.dic_summary;
    SceneFigures& fig = c.summary.figures;
    fig.dic_valid_fraction = summary.valid_fraction;
    fig.dic_subsets_per_s = summary.SubsetsPerSecond();
    if (!summary.IsUsable()) {
      c.summary.warnings.push_back(fmt::format(
          "correlation: only {:.1f} % of the subsets are valid", 100 * summary.valid_fraction));
    }
    if (summary.Discontinuous() > 0) {
      c.summary.warnings.push_back(fmt::format(
          "correlation: {} subset results flagged as straddling a discontinuity (status "
          "discontinuous, NaN; dic.continuity_check)",
          summary.Discontinuous()));
    }
    if (summary.Outliers() > 0) {
      c.summary.warnings.push_back(fmt::format(
          "correlation: {} subset results flagged as outliers by the normalized median test "
          "(status outlier, NaN; dic.outlier_check)",
          summary.Outliers()));
    }
    const std::string problem =
        summary.NothingUsable(KeyName(c, "dic.min_zncc"), scene.dic.options.icgn.min_zncc);
    if (!problem.empty()) c.summary.failures.push_back({"correlate", problem});
    return summary.BriefReport();
  }
};

}  // namespace

std::unique_ptr<Stage> MakeCorrelateStage() { return std::make_unique<CorrelateStage>(); }

}  // namespace impactdic::stages
