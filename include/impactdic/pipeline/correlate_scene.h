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

#include <string>

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

}  // namespace impactdic

#endif  // IMPACTDIC_PIPELINE_CORRELATE_SCENE_H_
