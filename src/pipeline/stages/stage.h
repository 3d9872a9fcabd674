// The stages of a scene's run as units (private to the pipeline module). A stage reads its inputs
// from SceneRunData (what the stages before it left), adds its outputs there and its figures,
// warnings and failures to the summary, and returns a one-line note; SkipReason says why it does
// not run. RunStages (pipeline.cc) runs them in order; docs/architecture.md draws the graph.
#ifndef IMPACTDIC_SRC_PIPELINE_STAGES_STAGE_H_
#define IMPACTDIC_SRC_PIPELINE_STAGES_STAGE_H_

#include <memory>
#include <string>

#include "impactdic/io/output_generation.h"
#include "impactdic/pipeline/output_writer.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/run_data.h"
#include "impactdic/pipeline/scene.h"

namespace impactdic::stages {

struct StageContext {
  const Scene& scene;
  const PipelineOptions& options;
  SceneRunData& data;
  PipelineSummary& summary;
};

class Stage {
 public:
  virtual ~Stage() = default;
  virtual const char* name() const = 0;  // As in the scene's `stages` list.
  // Why it does not run ("" = it runs): not among the scene's stages, an input not given, nothing
  // from the stage it needs.
  virtual std::string SkipReason(const StageContext& context) const = 0;
  // Runs it; returns what it did (one line). Throws Error for bad input.
  virtual std::string Run(StageContext& context) const = 0;
};

// Runs the stage or records why not (PipelineSummary::stages, with its time; logged).
void RunStage(const Stage& stage, StageContext& context);

// The analysis stages in the order they run (the sensor before the frames: its impact time
// decides the first frame to correlate).
std::unique_ptr<Stage> MakeCalibrateStage();
std::unique_ptr<Stage> MakeSensorStage();
std::unique_ptr<Stage> MakeFramesStage();
std::unique_ptr<Stage> MakeCorrelateStage();
std::unique_ptr<Stage> MakeKinematicsStage();
std::unique_ptr<Stage> MakeMomentumStage();
std::unique_ptr<Stage> MakeModelStage();
// After the model (t_e from momentum, the crater depths from the model and the sensor).
std::unique_ptr<Stage> MakeStrainStage();
// The outputs: every writer into the staging folder of the run's output generation, committed
// when all are complete.
std::unique_ptr<Stage> MakeOutputsStage(const OutputWriters& writers, OutputGeneration* generation);

// The measured peak deceleration of the peak stage (a figure of the sensor record, its window
// t_e from the momentum stage, else the scene model's T + 4/b); run between momentum and model.
void AddMeasuredPeakDeceleration(StageContext& context);

// "not among the scene's stages" unless the scene lists `name` ("").
std::string NotListed(const Scene& scene, const char* name);

}  // namespace impactdic::stages

#endif  // IMPACTDIC_SRC_PIPELINE_STAGES_STAGE_H_
