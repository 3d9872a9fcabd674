// outputs: every output writer (pipeline/output_writer.h) into the staging folder of the run's
// output generation, swapped in when all are complete.
#include <fmt/format.h>

#include <memory>
#include <string>
#include <vector>

#include "impactdic/core/log.h"
#include "impactdic/io/output_generation.h"
#include "impactdic/io/results_layout.h"
#include "impactdic/pipeline/output_writer.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/run_data.h"
#include "stage.h"

namespace impactdic::stages {
namespace {

// The built-in writers after results.h5 read the results from it (render, summaries): the rows of
// /dic, the kinematics and the strain fields (O(subsets x frames), the run's largest data) are
// released once it is written, so that rendering a long recording does not hold them as well
// (strain.csv is written before results.h5 for this reason). Kept when the caller
// added writers of its own (PipelineOptions::extra_output_writers), which may read them.
void ReleaseRunResults(SceneRunData& d) {
  d.dic.reset();
  d.kinematics.reset();
  d.strain.reset();
}

class OutputsStage : public Stage {
 public:
  OutputsStage(const OutputWriters& writers, OutputGeneration* generation)
      : writers_(writers), generation_(generation) {}

  const char* name() const override { return "outputs"; }

  std::string SkipReason(const StageContext& c) const override {
    return NotListed(c.scene, name());
  }

  std::string Run(StageContext& c) const override {
    OutputContext out{c.scene, c.options, c.data, c.summary, generation_->staging_folder(), {}, {}};
    // Every writer decides on the whole run's data, before results.h5's writer releases the
    // rows it wrote (ReleaseRunResults).
    std::vector<std::string> skip_reasons;
    for (const auto& writer : writers_) skip_reasons.push_back(writer->SkipReason(c.scene, c.data));
    for (std::size_t i = 0; i < writers_.size(); ++i) {
      const auto& writer = writers_[i];
      const std::string& why = skip_reasons[i];
      if (why.empty()) {
        writer->Write(out);
      } else {
        LogInfo("[outputs] {} skipped: {}", writer->name(), why);
      }
      if (writer->name() == std::string(results_layout::kResultsFile) &&
          c.options.extra_output_writers.empty())
        ReleaseRunResults(c.data);
    }
    // All complete: swap the new generation in (the previous one stays until this succeeds).
    generation_->Commit();
    for (auto& o : c.summary.outputs) o = generation_->FinalPath(o);
    return fmt::format("{} files in {}", c.summary.outputs.size(),
                       OutputPathForMessages(c.summary.output_folder));
  }

 private:
  const OutputWriters& writers_;
  OutputGeneration* generation_;
};

}  // namespace

std::unique_ptr<Stage> MakeOutputsStage(const OutputWriters& writers,
                                        OutputGeneration* generation) {
  return std::make_unique<OutputsStage>(writers, generation);
}

}  // namespace impactdic::stages
