// `impactdic correlate` as a library function: subset DIC of images, a video or a camera file
// (the frames stage's FrameStream and the dic module's CorrelateFrames), written to .csv or .h5
// (dic/dic_io.h). The command parses its flags into the request (the DIC options are the scene's
// dic.* and preprocess.* keys, pipeline/scene_flags.h) and calls it:
//
//   CorrelateFilesRequest r;
//   r.frames = "frames/*.png";
//   r.options.icgn.max_iterations = 20;
//   r.output = "dic.h5";
//   CorrelateFiles(r);
//
// Everything is checked before any work: the inputs listed, the output's name and folder. Errors
// name the command's flags (--frames, --deformed, --first, --last, --dic.first_frame, ...).
#ifndef IMPACTDIC_PIPELINE_CORRELATE_FILES_H_
#define IMPACTDIC_PIPELINE_CORRELATE_FILES_H_

#include <optional>
#include <string>
#include <vector>

#include "impactdic/dic/options.h"
#include "impactdic/preprocess/preprocess.h"

namespace impactdic {

struct CorrelateFilesRequest {
  // The images: the reference and the deformed ones, or `frames` (a folder, glob, video or
  // camera file: inputs.frames of a scene).
  std::string reference;
  std::vector<std::string> deformed;
  std::string frames;
  // The analysed frames by the source's own numbers (FrameSource::FrameNumber); unset: by the
  // indices first_index and last_index (-1: the last), as dic.first_frame / dic.last_frame.
  std::optional<long long> first, last;
  int first_index = 0, last_index = -1;
  DicOptions options;            // Checked.
  PreprocessOptions preprocess;  // Checked; roi = options.grid.roi.
  std::string mask;              // The mask image options.grid.mask was read from (messages).
  int threads = 0;               // core/threads.h.
  std::string output;            // .csv, .h5 or .hdf5.
  // Write the results even when no subset is valid; otherwise PartialResultsError, nothing
  // written (as `run`).
  bool allow_partial = false;
};

void CorrelateFiles(const CorrelateFilesRequest& request);

}  // namespace impactdic

#endif  // IMPACTDIC_PIPELINE_CORRELATE_FILES_H_
