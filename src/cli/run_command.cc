// impactdic run SCENE.yaml [-o OUTDIR] [--png-frames] [--threads N] [--allow-partial] [--force]:
// the whole pipeline on one scene (pipeline/pipeline.h). A stage that produced nothing usable makes
// the run fail (exit 1, no output written) unless --allow-partial.
#include <CLI/CLI.hpp>
#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "commands.h"
#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/core/threads.h"
#include "impactdic/io/json.h"
#include "impactdic/io/output_generation.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/scene.h"

namespace impactdic::cli {

void RegisterRunCommand(CLI::App& app) {
  struct Args {
    std::string scene, output;
    bool png_frames = false;
    std::optional<int> threads;  // Unset: the scene's dic.threads.
    bool allow_partial = false;
    bool force = false;
    std::string format = "text";
    SceneKeyValues keys;  // --dic.*, --sensor.*, --outputs.* ...: override the scene file.
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "run",
      "Run the stages a scene needs (calibration -> sensor -> frames -> correlate -> "
      "kinematics -> momentum -> model -> strain (only with the scene's strain.enabled: "
      "docs/strain.md) -> outputs; the sensor comes first because its impact time decides the "
      "first frame to correlate)");
  cmd->add_option("scene", args->scene, "Scene file (YAML)")->required();
  // -o, --png-frames and --threads are short for scene keys (one name each when given).
  auto* output = cmd->add_option("-o,--output", args->output,
                                 "Output folder (default: the scene's outputs.folder)");
  SetsKeys(output, {"outputs.folder"});
  SetsKeys(
      cmd->add_flag("--png-frames", args->png_frames, "Also write the animation frames as PNG"),
      {"outputs.png_frames"});
  SetsKeys(cmd->add_option("--threads", args->threads,
                           std::string("Correlation threads: ") + kThreadCountExpected +
                               " (default: the scene's dic.threads)"),
           {"dic.threads"});
  cmd->add_flag(kAllowPartialFlag, args->allow_partial,
                "Write the outputs (exit 0) even when a stage produced nothing usable (no valid "
                "subset, no measurable t_e, a model solve that did not stop): the figures that "
                "depend on it are null, the reasons in summary.json's failures and warnings");
  cmd->add_flag("--force", args->force,
                "Replace an output folder another command wrote (a synth scene, a campaign) or "
                "that holds other commands' outputs; files impactdic did not write are never "
                "replaced");
  cmd->add_option("--format", args->format, "Summary on stdout: text or json");
  AddSceneKeyFlags(
      cmd, {"test", "preprocess", "dic", "sensor", "momentum", "model", "strain", "outputs"},
      &args->keys);
  cmd->footer(
      "A --SECTION.KEY flag overrides that key of the scene file (-o is short for "
      "--outputs.folder, --threads for --dic.threads, --png-frames for --outputs.png_frames true: "
      "give one name of each); the inputs.* paths come from the scene file.");
  cmd->callback([args, cmd, output] {
    if (output->count() > 0) CheckOutputFolderName(args->output, "-o");
    if (args->threads) CheckThreadCount(*args->threads, "--threads");
    CheckFormat(args->format);
    Scene scene = LoadScene(args->scene);
    ApplySceneKeyFlags(*cmd, args->keys, &scene);
    MakeSensorOptions(scene);  // The flags' values checked together, as the scene file's.
    PipelineOptions options;
    options.output_folder = args->output;
    options.png_frames = args->png_frames;
    options.threads = args->threads.value_or(-1);
    options.allow_partial = args->allow_partial;
    options.force = args->force;
    PipelineSummary summary;
    try {
      summary = RunScene(scene, options);
    } catch (const PartialResultsError& e) {
      RethrowWithPartialFlag(e, "run");
    }
    if (!summary.IsUsable())
      LogWarning("run: partial results (--allow-partial): {}", summary.FailureText());
    std::cout << (args->format == "json" ? summary.ToJson().Dump() + "\n" : summary.FullReport());
  });
}

}  // namespace impactdic::cli
