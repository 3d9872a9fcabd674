#include "impactdic/pipeline/correlate_files.h"

#include <fmt/format.h>

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/core/threads.h"
#include "impactdic/core/timer.h"
#include "impactdic/dic/correlate_frames.h"
#include "impactdic/dic/correlator.h"
#include "impactdic/dic/dic_io.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/camera_file.h"
#include "impactdic/io/csv.h"
#include "impactdic/io/frame_source.h"
#include "impactdic/io/image_io.h"
#include "impactdic/pipeline/frame_stream.h"
#include "impactdic/pipeline/pipeline.h"

namespace impactdic {
namespace {

// The frames' source: the images listed (`paths`), a camera file or a video. A video needs two
// decodable frames (Error naming it); camera files say what they hold.
std::unique_ptr<FrameSource> OpenSource(const CorrelateFilesRequest& a, bool pair, bool camera,
                                        bool video, const std::vector<std::string>& paths) {
  if (camera) return MakeCameraFileSource(a.frames);
  if (!video) return MakeImageFileSource(paths, pair ? "" : a.frames);
  std::unique_ptr<FrameSource> source = MakeVideoSource(a.frames);
  if (source->frame_count() < 2) {
    throw Error(ErrorKind::kInvalidValue, "frames video",
                fmt::format("{} decodable frame(s)", source->frame_count()),
                "a video of at least two frames (the first is the reference)")
        .WithFile(a.frames);
  }
  return source;
}

// --first/--last: the analysed frames, by the source's frame numbers (Error naming the flag and
// the source's span when no frame has the number), else by index; at least two of them.
void SelectFrames(const CorrelateFilesRequest& a, FrameStream* frames) {
  const FrameSource& source = frames->source();
  const int count = source.frame_count();
  const std::string expected =
      fmt::format("a frame index below {} ({})", count, source.description());
  CheckValue(a.first_index < count, "--dic.first_frame", std::to_string(a.first_index), expected);
  CheckValue(a.last_index < count, "--dic.last_frame", std::to_string(a.last_index),
             expected + ", or -1");
  const int first = a.first ? FrameIndexOf(source, *a.first, "--first") : a.first_index;
  const int last = a.last              ? FrameIndexOf(source, *a.last, "--last")
                   : a.last_index >= 0 ? a.last_index
                                       : count - 1;
  if (last - first < 1) {
    throw Error(ErrorKind::kInvalidValue, "--first/--last",
                fmt::format("frames {}..{} of {} (one frame)", source.FrameNumber(first),
                            source.FrameNumber(last), source.description()),
                "at least two frames (the first is the reference)");
  }
  frames->SetRange(first, last);
}

// Each image once: the same file given twice (under any spelling of its path, a symbolic or a
// hard link) would be correlated twice and numbered alike. Error naming the option and both
// spellings. Files that cannot be examined are left to the image reader's message.
void CheckEachImageOnce(const std::vector<std::string>& paths) {
  const auto repeated = FirstRepeatedFile(paths);
  if (!repeated) return;
  const auto [earlier, i] = *repeated;
  const std::string& first = paths[earlier];
  const std::string found =
      "'" + paths[i] + "', " +
      (earlier == 0        ? "the --reference image" + (first == paths[i] ? "" : " '" + first + "'")
       : first == paths[i] ? std::string("given twice")
                           : "the same file as '" + first + "'");
  throw Error(ErrorKind::kInvalidValue, "--deformed", found,
              "each deformed image once, and none of them the reference");
}

// A correlation with no valid subset fails as `run`'s correlate stage does (DicSummary's one
// rule), naming the flag of its ZNCC threshold, unless --allow-partial; nothing is written.
void CheckSomethingUsable(const CorrelateFilesRequest& a, const DicResult& result,
                          const DicOptions& options) {
  const std::string problem = result.summary.NothingUsable("--min-zncc", options.icgn.min_zncc);
  if (problem.empty()) return;
  if (a.allow_partial) {
    LogWarning("correlate: partial results (--allow-partial): {}", problem);
    return;
  }
  throw PartialResultsError(
      fmt::format("correlate: {}\nNothing was written ({} is as it was)", problem, a.output),
      "writes it, every subset with its status");
}

}  // namespace

void CorrelateFiles(const CorrelateFilesRequest& a) {
  const bool pair = !a.reference.empty() || !a.deformed.empty();
  CheckValue(!a.output.empty(), "-o/--output", "missing", "an output file ending in .csv or .h5");
  // The inputs, listed (not decoded) before the output is checked.
  std::vector<std::string> paths;
  const bool camera = !pair && IsCameraFile(a.frames);
  const bool video = !pair && !camera && IsVideoFile(a.frames);  // As `run`'s inputs.frames.
  if (pair) {
    paths.push_back(a.reference);
    paths.insert(paths.end(), a.deformed.begin(), a.deformed.end());
    CheckEachImageOnce(paths);
  } else if (camera || video) {
    paths.push_back(a.frames);  // Opened and checked below.
  } else {
    paths = ListFrameSequence(a.frames);  // A gap in the numbering is an error, as in `run`.
    CheckValue(paths.size() >= 2, "--frames",
               a.frames + " (" + std::to_string(paths.size()) + " image)",
               "at least two images (the first is the reference)");
  }
  if (a.first && a.last && *a.first > *a.last) {
    throw Error(ErrorKind::kInvalidValue, "--first/--last",
                fmt::format("{} > {}", *a.first, *a.last), "--first <= --last");
  }
  std::vector<std::string> inputs = paths;
  inputs.push_back(a.mask);
  CheckOutputLocation(
      a.output,
      {"-o/--output", {".csv", ".h5", ".hdf5"}, inputs, {CsvHeaderLine(DicCsvColumns())}});
  const ThreadLimit threads(a.threads, "--threads");
  WallTimer wall;
  DicResult result;
  try {
    FrameStream frames(OpenSource(a, pair, camera, video, paths), a.preprocess,
                       /*calibration=*/nullptr);
    SelectFrames(a, &frames);
    result = CorrelateFrames(frames, a.options);
    const GaussianDecision& prefilter = frames.preprocess_summary()->gaussian;
    PrefilterAttributes(prefilter, &result.text_attributes, &result.number_attributes);
    if (prefilter.applied) {
      result.preprocess =
          fmt::format("gaussian: sigma {} px, kernel {}x{} (reference and deformed images)",
                      a.preprocess.gaussian.sigma_px, a.preprocess.gaussian.kernel_size,
                      a.preprocess.gaussian.kernel_size);
    }
  } catch (Error& e) {
    if (e.where() == "mask" && e.file().empty()) e.WithFile(a.mask);  // Its size is wrong.
    throw;
  }
  CheckSomethingUsable(a, result, a.options);
  WriteDicResult(a.output, &result, a.options);
  if (!result.preprocess.empty()) LogInfo("correlate: pre-filter {}", result.preprocess);
  const double seconds = wall.ElapsedSeconds();
  LogInfo("correlate: {}", result.summary.FullReport());
  LogInfo(
      "correlate: wrote {}; wall time {:.3f} s with reading the images and writing the "
      "results ({:.0f} POIs/s)",
      a.output, seconds,
      double(result.summary.subsets) * result.summary.frames / std::max(seconds, 1e-9));
  if (!result.summary.IsUsable()) {
    LogWarning("correlate: only {:.1f}% of the subset results are valid",
               100 * result.summary.valid_fraction);
  }
}

}  // namespace impactdic
