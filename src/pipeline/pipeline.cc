#include "impactdic/pipeline/pipeline.h"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <optional>
#include <system_error>
#include <utility>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/interrupt.h"
#include "impactdic/core/threads.h"
#include "impactdic/io/output_generation.h"
#include "impactdic/pipeline/run_data.h"
#include "route.h"
#include "stages/stage.h"

namespace impactdic {
namespace fs = std::filesystem;

PartialResultsError::PartialResultsError(std::string problem, std::string remedy)
    : Error(ErrorKind::kNumerical, fmt::format("{}; the option `{}` {}", problem, kOption, remedy)),
      problem_(std::move(problem)),
      remedy_(std::move(remedy)) {}

namespace {

// The writers of a run: the built-in ones, then the caller's.
OutputWriters RunOutputWriters(const PipelineOptions& options) {
  OutputWriters writers = BuiltInOutputWriters();
  writers.insert(writers.end(), options.extra_output_writers.begin(),
                 options.extra_output_writers.end());
  return writers;
}

// A run's outputs are one generation of its output folder (io/output_generation.h): written into
// a staging folder beside it and swapped in when all are complete. Opened, and the writers
// checked, before any stage runs: a folder that cannot be written fails the run at once.
void OpenOutputs(const Scene& scene, const PipelineOptions& options, const std::string& folder,
                 const OutputWriters& writers, std::optional<OutputGeneration>* generation) {
  if (!scene.HasStage("outputs")) return;
  OutputGenerationOptions o;
  o.command = "impactdic run";
  // Figures drawn by `render -o` into a folder of their own, or nested in the run's folder.
  o.replaces_kinds = {"render"};
  o.nested_kinds = {"render"};
  o.force = options.force;
  for (const auto& writer : writers)
    for (const std::string& name : writer->FileNames()) o.own_names.push_back(name);
  generation->emplace(folder, o);
  for (const auto& writer : writers) writer->CheckBeforeRun(scene);
}

// The stage graph (docs/architecture.md) as the route of `run` (route.h): each stage reads what
// the ones before it left in SceneRunData; the outputs stage writes one generation of the output
// folder once every analysis stage has run and none has failed (unless allow_partial).
PipelineSummary RunStages(const Scene& scene, const PipelineOptions& options) {
  const std::string folder =
      options.output_folder.empty() ? scene.outputs.folder : options.output_folder;
  const OutputWriters writers = RunOutputWriters(options);
  std::optional<OutputGeneration> generation;  // Removed again unless committed at the end.
  OpenOutputs(scene, options, folder, writers, &generation);
  Route route;
  route.output_folder = folder;
  route.run_stages = [](stages::StageContext& c) {
    stages::RunAnalysisStages(c, /*results_file=*/"");
  };
  route.nothing_written =
      fmt::format("No output was written (outputs of an earlier run in {} are kept)",
                  OutputPathForMessages(folder));
  route.partial_remedy =
      "writes them, with the figures that could not be measured as null and the reasons in "
      "summary.json";
  route.write = [&](stages::StageContext& c) {
    stages::RunStage(*stages::MakeOutputsStage(writers, generation ? &*generation : nullptr), c);
  };
  SceneRunData data;
  return RunRoute(scene, options, route, &data);
}

}  // namespace

void CheckSceneStages(const Scene& scene) {
  if (scene.HasStage("correlate") && !scene.HasStage("frames")) {
    std::string listed;
    for (const std::string& s : scene.stages) listed += (listed.empty() ? "" : ", ") + s;
    throw Error(ErrorKind::kInvalidValue, "stages", "[" + listed + "]",
                "frames listed with correlate (the correlation reads the images the frames "
                "stage reads and preprocesses)")
        .WithFile(scene.path);
  }
}

void CheckOutputFolderHoldsNoInput(const Scene& scene, const std::string& folder,
                                   const std::string& option) {
  CheckOutputFolderName(folder, option);
  std::error_code ec;
  const fs::path out = fs::weakly_canonical(fs::absolute(folder, ec), ec);
  if (ec || out.empty()) return;  // The generation names what is wrong with the folder.
  // A glob's folder is the input (its files may be written later); a video or a folder is itself.
  std::string frames = scene.inputs.frames;
  if (frames.find_first_of("*?[") != std::string::npos)
    frames = fs::path(frames).parent_path().string();
  for (const std::string& input : {scene.path, frames, scene.inputs.calibration,
                                   scene.inputs.sensor, scene.inputs.truth, scene.dic.mask}) {
    if (input.empty()) continue;
    const fs::path in = fs::weakly_canonical(fs::absolute(input, ec), ec);
    if (!IsSameOrInside(in.string(), out.string())) continue;
    throw Error(
        ErrorKind::kInvalidValue, option,
        OutputPathForMessages(folder) + ", which holds the input " + input,
        "an output folder apart from the inputs (what was written there before is replaced)")
        .WithFile(scene.path);
  }
}

void PipelineOptions::Check() const {
  CheckValue(threads == -1 || IsValidThreadCount(threads), "threads", std::to_string(threads),
             std::string("-1 (the scene's dic.threads) or ") + kThreadCountExpected);
}

PipelineSummary RunScene(const Scene& scene, const PipelineOptions& options) {
  options.Check();
  CheckSceneStages(scene);
  CheckSceneOutputs(scene);  // The scene file's were checked when read; a flag's are not.
  const std::string folder =
      options.output_folder.empty() ? scene.outputs.folder : options.output_folder;
  CheckOutputFolderHoldsNoInput(scene, folder,
                                options.output_folder.empty() ? "outputs.folder" : "-o");
  // The highest folder of the output path that does not exist yet (the run may create it and
  // its children).
  std::error_code ec;
  fs::path created;
  for (fs::path p = fs::absolute(folder, ec).lexically_normal(); !p.empty() && !fs::exists(p, ec);
       p = p.parent_path()) {
    created = p;
    if (p == p.parent_path()) break;
  }
  try {
    return RunStages(scene, options);
  } catch (...) {
    // A failed run leaves no empty folders behind (files already complete stay).
    if (!created.empty() && fs::is_directory(created, ec)) {
      bool has_files = false;
      for (auto it = fs::recursive_directory_iterator(created, ec);
           !ec && it != fs::recursive_directory_iterator(); it.increment(ec))
        has_files = has_files || !it->is_directory();
      if (!has_files && !ec) fs::remove_all(created, ec);
    }
    throw;
  }
}

}  // namespace impactdic
