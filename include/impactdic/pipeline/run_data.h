// The data that flows between the stages of a scene's run or analysis (pipeline/pipeline.h,
// pipeline/scene_analysis.h; the stage graph in docs/architecture.md). Each stage reads what the
// stages before it left here and adds its own outputs; an empty optional means the stage did not
// run (its reason is in PipelineSummary::stages). The output writers (pipeline/output_writer.h)
// read it all. The summary (PipelineSummary) is only written by the stages, never read: what a
// stage needs from another is here.
#ifndef IMPACTDIC_PIPELINE_RUN_DATA_H_
#define IMPACTDIC_PIPELINE_RUN_DATA_H_

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "impactdic/calib/calibration.h"
#include "impactdic/core/numeric.h"
#include "impactdic/dic/correlator.h"
#include "impactdic/io/dic_results.h"
#include "impactdic/kinematics/kinematics.h"
#include "impactdic/model/impact_model.h"
#include "impactdic/momentum/momentum.h"
#include "impactdic/pipeline/frame_stream.h"
#include "impactdic/sensor/frame_timeline.h"
#include "impactdic/sensor/sensor.h"
#include "impactdic/sensor/wave.h"
#include "impactdic/strain/strain_results.h"

namespace impactdic {

struct SceneRunData {
  // calibrate: the camera model, and the panel scale [mm/px] (inputs.mm_per_px, else the
  // calibration's plane scale; 0 = none).
  std::optional<CameraCalibration> calibration;
  double mm_per_px = 0;

  // sensor: the accelerometer record analysed (impact time and velocity, pounder motion).
  std::optional<SensorResult> sensor;
  // sensor, with base force channels (sensor.base_columns): the wave figures (sensor/wave.h).
  std::optional<WaveResult> wave;
  // sensor, then momentum: the measured peak deceleration of the peak stage [g] (momentum
  // MeasuredPeakDeceleration) and that stage's length after the impact [s]: the sensor stage sets
  // them over T + 4/b of the scene's model, the momentum stage over t_e when it measured t_e. NaN
  // without a sensor record.
  double peak_stage_s = kNaN;
  double peak_deceleration_measured_g = kNaN;

  // frames: the analysed frames first_frame..last_frame of the source's source_frames, read on
  // demand and preprocessed (pipeline/frame_stream.h: one frame in memory at a time; null = the
  // stage did not run), and their timeline (sensor/frame_timeline.h: each analysed frame's source
  // position, number, camera and DAQ times, the frame rate): the one record of when a frame was
  // taken, read by every later stage and writer. load_dic builds it from the rows of the results
  // file the same way (stages TimeSceneFrames).
  int source_frames = 0;
  int first_frame = 0, last_frame = -1;
  FrameTimeline timeline;
  std::shared_ptr<FrameStream> frames;
  // Before the frames stage: the frames to read instead of the scene's inputs (frames in memory;
  // pipeline CorrelateSceneInMemory), taken by the stage. Null: the scene's inputs.
  std::unique_ptr<FrameSource> given_frames;
  std::string preprocess_note;  // What the preprocessing did (one line).

  // correlate: the correlation's rows (io/dic_results.h; row 0 = frame first_frame) and summary.
  // load_dic (`analyze SCENE`, instead of frames and correlate): the rows read from dic_file, the
  // frame range and times as the frames stage sets them, no frames and an empty dic_summary.
  std::optional<DicResultsTable> dic;
  DicSummary dic_summary;
  std::string dic_file;  // The results file /dic was read from ("" = correlated in this run).

  // kinematics: subset motion on the panel from the analysed series (momentum.max_sigma_px
  // applied), dt = 1 / timeline.fps.
  std::optional<KinematicsResult> kinematics;

  // momentum: the momentum balance (needs kinematics and the sensor record).
  std::optional<MomentumResult> momentum;

  // model: the impact model's solve and its parameters (impact velocity: the sensor's measured
  // one, else the scene's v0).
  std::optional<ImpactRun> model;
  ImpactModelParameters model_parameters;

  // strain: the strain fields, density, compacted zone and shear bands (strain.enabled and the
  // correlation results; strain/strain_results.h); released with dic after results.h5.
  std::optional<StrainResult> strain;
};

}  // namespace impactdic

#endif  // IMPACTDIC_PIPELINE_RUN_DATA_H_
