// `impactdic correlate` as a library function: the frames and correlate stages of the one stage
// graph (pipeline/pipeline.h, docs/architecture.md; the same stage functions as `run`), their
// /dic table written to a .csv or .h5 file (dic/dic_io.h WriteDicResultsFile). The command builds
// the scene from its flags (pipeline/scene_flags.h) and calls it:
//
//   Scene scene;
//   scene.inputs.frames = "frames/*.png";   // or inputs.frame_files: the reference, then the rest
//   scene.dic.options.icgn.max_iterations = 20;
//   PipelineSummary s = CorrelateScene(scene, "dic.h5");
//
// Everything that needs no decoding is checked before any work: the inputs listed (each image of
// inputs.frame_files once), the output's name and folder.
#ifndef IMPACTDIC_PIPELINE_CORRELATE_SCENE_H_
#define IMPACTDIC_PIPELINE_CORRELATE_SCENE_H_

#include <memory>
#include <string>

#include "impactdic/dic/correlator.h"
#include "impactdic/io/dic_results.h"
#include "impactdic/io/frame_source.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/scene.h"

namespace impactdic {

// Runs the frames and correlate stages of `scene` (whatever its `stages` list), after the
// calibrate stage when inputs.calibration is given (the frames undistorted, as in `run`; no
// sensor record is read), and writes `output` (.csv, .h5 or .hdf5) atomically. The rows are
// numbered from the reference (/dic/frame 0.., no first_frame attribute; /dic/frame_number the
// source's own numbers). A correlation with no valid subset is PartialResultsError naming
// `correlate --min-zncc`, nothing written, unless allow_partial (a warning). Returns the stages
// run, the warnings and the output.
PipelineSummary CorrelateScene(const Scene& scene, const std::string& output,
                               bool allow_partial = false);

// The same correlation kept in memory (the Python module's `correlate`): the table exactly as
// CorrelateScene's output file holds it, the correlation's summary and the run's. `frames`, when
// given, are the frames in place of the scene's inputs (frames in memory: io
// MakeMemoryFrameSource), preprocessed and selected by the scene's keys as files are; null: the
// scene's inputs.frames or inputs.frame_files. Messages name the scene keys (dic.min_zncc), not
// `correlate`'s flags, and the inputs as `names` say (the Python module: its arguments). Nothing
// usable is PartialResultsError unless allow_partial.
struct SceneCorrelation {
  DicResultsTable table;
  DicSummary dic;
  PipelineSummary summary;
};
// How messages name the inputs: the reference image, the deformed images, a sequence.
struct CorrelationInputNames {
  std::string reference = "inputs.frame_files[0]";
  std::string deformed = "inputs.frame_files";
  std::string frames = "inputs.frames";
};
SceneCorrelation CorrelateSceneInMemory(const Scene& scene, std::unique_ptr<FrameSource> frames,
                                        bool allow_partial = false,
                                        const CorrelationInputNames& names = {});

}  // namespace impactdic

#endif  // IMPACTDIC_PIPELINE_CORRELATE_SCENE_H_
