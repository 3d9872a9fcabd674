#include "impactdic/pipeline/correlate_scene.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/core/timer.h"
#include "impactdic/dic/dic_io.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/camera_file.h"
#include "impactdic/io/csv.h"
#include "impactdic/io/image_io.h"
#include "impactdic/pipeline/run_data.h"
#include "impactdic/pipeline/scene_flags.h"
#include "route.h"
#include "stages/stage.h"

namespace impactdic {
namespace {

// How `correlate`'s flags name the inputs in messages.
const CorrelationInputNames kCorrelateFlags = {"--reference", "--deformed", "--frames"};

// Each image of inputs.frame_files once: the same file given twice (under any spelling of its
// path, a symbolic or a hard link) would be correlated twice and numbered alike. Error naming
// the deformed images' input and both spellings. Files that cannot be examined are left to the
// image reader's message.
void CheckEachImageOnce(const std::vector<std::string>& paths, const CorrelationInputNames& names) {
  const auto repeated = FirstRepeatedFile(paths);
  if (!repeated) return;
  const auto [earlier, i] = *repeated;
  const std::string& first = paths[earlier];
  const std::string found = "'" + paths[i] + "', " +
                            (earlier == 0 ? "the " + names.reference + " image" +
                                                (first == paths[i] ? "" : " '" + first + "'")
                             : first == paths[i] ? std::string("given twice")
                                                 : "the same file as '" + first + "'");
  throw Error(ErrorKind::kInvalidValue, names.deformed, found,
              "each deformed image once, and none of them the reference");
}

// The files the correlation reads, listed (not decoded): the images, or the video or camera
// file, and the mask. The output must be none of them. Errors name the inputs by `names`.
std::vector<std::string> ListInputs(const Scene& scene, const CorrelationInputNames& names) {
  std::vector<std::string> inputs = scene.inputs.frame_files;
  const std::string& frames = scene.inputs.frames;
  if (inputs.empty() == frames.empty()) {
    throw Error(ErrorKind::kInvalidValue, "input",
                frames.empty()
                    ? "none"
                    : "both " + names.reference + "/" + names.deformed + " and " + names.frames,
                "either " + names.reference + " REF " + names.deformed + " DEF [DEF ...] or " +
                    names.frames + " GLOB");
  }
  if (!inputs.empty()) {
    CheckValue(!inputs[0].empty(), names.reference, "missing", "the reference image");
    CheckValue(inputs.size() >= 2, names.deformed, "missing", "at least one deformed image");
    CheckEachImageOnce(inputs, names);
  } else if (IsCameraFile(frames) || IsVideoFile(frames)) {
    inputs.push_back(frames);
  } else {
    inputs = ListFrameSequence(frames);  // A gap in the numbering is an error, as in `run`.
  }
  inputs.push_back(scene.dic.mask);
  return inputs;
}

// The table as `correlate -o` has always written it: rows numbered from the reference (no
// first_frame attribute) and, instead of the run's preprocessing note with its timings, the
// Gaussian pre-filter applied (if any), so that the same results give the same bytes.
void AsCorrelateFile(const Scene& scene, const FrameStream& frames, DicResultsTable* t) {
  for (auto* column : {&t->frame, &t->reference_frame})
    for (auto& f : *column) f -= static_cast<std::int32_t>(t->first_frame);
  t->first_frame = -1;
  t->text_attributes.erase("preprocess");
  const GaussianBlurOptions& g = scene.preprocess.gaussian;
  if (frames.preprocess_summary()->gaussian.applied) {
    t->text_attributes["preprocess"] =
        fmt::format("gaussian: sigma {} px, kernel {}x{} (reference and deformed images)",
                    g.sigma_px, g.kernel_size, g.kernel_size);
    LogInfo("correlate: pre-filter {}", t->text_attributes["preprocess"]);
  }
}

// The scene with the stages of a correlation: calibrate (only for a calibration given: the frames
// are then undistorted when it has distortion, as in `run`), frames and correlate.
Scene CorrelationScene(const Scene& given) {
  Scene scene = given;
  scene.stages = {"frames", "correlate"};
  if (!scene.inputs.calibration.empty()) scene.stages.insert(scene.stages.begin(), "calibrate");
  return scene;
}

void RunCorrelationRoute(stages::StageContext& c) {
  if (c.scene.HasStage("calibrate")) stages::RunStage(*stages::MakeCalibrateStage(), c);
  stages::RunCorrelationStages(c);
}

}  // namespace

PipelineSummary CorrelateScene(const Scene& given, const std::string& output, bool allow_partial) {
  const Scene scene = CorrelationScene(given);
  CheckValue(!output.empty(), "-o/--output", "missing", "an output file ending in .csv or .h5");
  CheckOutputLocation(output, {"-o/--output",
                               {".csv", ".h5", ".hdf5"},
                               ListInputs(scene, kCorrelateFlags),
                               {CsvHeaderLine(DicCsvColumns())}});
  PipelineOptions options;  // threads -1: dic.threads.
  options.allow_partial = allow_partial;
  options.flags_of = "correlate";  // The scene is correlate's flags: messages name them.
  Route route;
  route.run_stages = RunCorrelationRoute;
  route.nothing_written = fmt::format("Nothing was written ({} is as it was)", output);
  route.partial_remedy = "writes it, every subset with its status";
  route.write = [&output](stages::StageContext& c) {
    for (const StageFailure& f : c.summary.failures)
      LogWarning("correlate: partial results (--allow-partial): {}", f.reason);
    AsCorrelateFile(c.scene, *c.data.frames, &*c.data.dic);
    WriteDicResultsFile(output, *c.data.dic);
    c.summary.outputs.push_back(output);
  };
  SceneRunData data;
  PipelineSummary summary = RunRoute(scene, options, route, &data);
  const DicSummary& dic = data.dic_summary;
  LogInfo("correlate: {}", dic.FullReport());
  LogInfo(
      "correlate: wrote {}; wall time {:.3f} s with reading the images and writing the "
      "results ({:.0f} POIs/s)",
      output, summary.seconds, double(dic.subsets) * dic.frames / std::max(summary.seconds, 1e-9));
  if (!dic.IsUsable()) {
    LogWarning("correlate: only {:.1f}% of the subset results are valid", 100 * dic.valid_fraction);
  }
  return summary;
}

SceneCorrelation CorrelateSceneInMemory(const Scene& given, std::unique_ptr<FrameSource> frames,
                                        bool allow_partial, const CorrelationInputNames& names) {
  const Scene scene = CorrelationScene(given);
  if (!frames) ListInputs(scene, names);  // The files named, each image once (as CorrelateScene).
  PipelineOptions options;                // threads -1: dic.threads.
  options.allow_partial = allow_partial;
  Route route;
  route.run_stages = RunCorrelationRoute;
  route.nothing_written = "No results were returned";
  route.partial_remedy = "returns them, every subset with its status";
  route.write = [](stages::StageContext& c) {
    AsCorrelateFile(c.scene, *c.data.frames, &*c.data.dic);
  };
  SceneRunData data;
  data.given_frames = std::move(frames);
  SceneCorrelation result;
  result.summary = RunRoute(scene, options, route, &data);
  result.table = std::move(*data.dic);
  result.dic = data.dic_summary;
  return result;
}

}  // namespace impactdic
