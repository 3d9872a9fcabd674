// The stages of a scene's run as units (private to the pipeline module). A stage reads its inputs
// from SceneRunData (what the stages before it left), adds its outputs there and its figures,
// warnings and failures to the summary, and returns a one-line note; SkipReason says why it does
// not run. RunStages (pipeline.cc) runs them in order; docs/architecture.md draws the graph.
#ifndef IMPACTDIC_SRC_PIPELINE_STAGES_STAGE_H_
#define IMPACTDIC_SRC_PIPELINE_STAGES_STAGE_H_

#include <memory>
#include <string>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/io/output_generation.h"
#include "impactdic/pipeline/output_writer.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/run_data.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/sensor/frame_timeline.h"

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
// Instead of frames and correlate (`impactdic analyze SCENE`): the /dic group of results_file,
// the frame range it covers and the frames' DAQ times; the figure dic_valid_fraction from its
// attribute. Always runs.
std::unique_ptr<Stage> MakeLoadDicStage(const std::string& results_file);
std::unique_ptr<Stage> MakeKinematicsStage();
// Also the measured peak deceleration over the peak stage (impact .. t_e).
std::unique_ptr<Stage> MakeMomentumStage();
std::unique_ptr<Stage> MakeModelStage();
// After the model (t_e from momentum, the crater depths from the model and the sensor).
std::unique_ptr<Stage> MakeStrainStage();
// The outputs: every writer into the staging folder of the run's output generation, committed
// when all are complete.
std::unique_ptr<Stage> MakeOutputsStage(const OutputWriters& writers, OutputGeneration* generation);

// The correlation of the stage graph: frames, then correlate (`run`, and `impactdic correlate`
// alone: pipeline/correlate_scene.h).
void RunCorrelationStages(StageContext& context);

// The one stage graph up to the outputs (docs/architecture.md), of `run` and `analyze`:
// calibrate, sensor, the correlation results (frames and correlate when results_file is empty,
// else load_dic of results_file), kinematics, momentum, model, strain.
void RunAnalysisStages(StageContext& context, const std::string& results_file);

// "scene NAME: N stage(s) produced nothing usable:" and a line "  stage: reason" per failure.
std::string FailedStagesText(const PipelineSummary& summary);

// Names the file to fix in an error of the frames' timing or the momentum analysis that names
// none: the DAQ record when its exposure channel times the frames ("exposure channel", "frame
// times"), else the scene file (fps, frame_time_offset_s, the momentum grid).
void NameFileToFix(const StageContext& context, Error& error);

// The timeline of the source frames first_index.. numbered `numbers` (sensor MakeFrameTimeline)
// on the scene's camera clock (SceneFrameClock: a camera file's rate and time stamps, else
// inputs.fps) and, after the sensor stage, on the DAQ clock: how the frames and load_dic stages
// both time frames. Errors name the file to fix: the scene for inputs.fps, else the DAQ record.
FrameTimeline TimeSceneFrames(const StageContext& context, int first_index,
                              std::vector<long long> numbers);

// The name of scene key `key` in messages: the key, or the flag of the command whose flags made
// the scene (PipelineOptions::flags_of).
std::string KeyName(const StageContext& context, const std::string& key);

// "not among the scene's stages" unless the scene lists `name` ("").
std::string NotListed(const Scene& scene, const char* name);

}  // namespace impactdic::stages

#endif  // IMPACTDIC_SRC_PIPELINE_STAGES_STAGE_H_
