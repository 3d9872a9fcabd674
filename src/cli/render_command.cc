// impactdic render RESULTS.h5 [-o OUTDIR] [--png-frames] [--codec auto|h264|mjpg] [--fps F]
// [--force] [--outputs.plot.* ...]: the figures and animations again, drawn as the scene's
// outputs.plot, .video, .velocity_map and .strain_map keys say (given as flags).
#include <CLI/CLI.hpp>
#include <iostream>
#include <memory>
#include <string>

#include "commands.h"
#include "impactdic/io/output_generation.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/render/render_results.h"

namespace impactdic::cli {

void RegisterRenderCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "render",
      "Re-render the figures (PNG, gnuplot) and the velocity animation (MP4 H.264, else MJPG AVI) "
      "from a results file; when it has /strain, also the strain maps at t_e and at the last "
      "frame (strain_te.png, strain_end.png) and the strain animation (strain.mp4)");
  struct Args {
    std::string results;
    RenderResultsOptions options;  // Its output flags; the drawing from the scene keys below.
    SceneKeyValues keys;           // --outputs.plot.*, .video.*, .velocity_map.*, .strain_map.*
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("RESULTS", args->results, "results.h5 written by `impactdic run`")->required();
  auto* output = cmd->add_option(
      "-o,--output", args->options.output_dir,
      "output folder (created if missing; default: the folder of RESULTS). The "
      "figures and animation replace the earlier ones together when all are drawn; "
      "the folder's other files (results.h5, summaries) stay; from a preview of the "
      "frames (outputs.frames: preview) into the run's folder, the snapshot and "
      "animation are named *_preview and the run's own stay");
  cmd->add_flag("--png-frames", args->options.png_frames,
                "also write every animation frame as PNG (OUTDIR/velocity_frames, strain_frames)");
  cmd->add_flag("!--no-animation", args->options.animation, "skip the animations");
  cmd->add_flag("!--no-figures", args->options.figures, "skip the gnuplot figures");
  cmd->add_flag("--force", args->options.force,
                "replace an output folder another command wrote (a campaign, a synth scene); "
                "files impactdic did not write are never replaced");
  AddSceneKeyFlags(cmd,
                   {"outputs.plot", "outputs.video", "outputs.velocity_map", "outputs.strain_map"},
                   &args->keys);
  cmd->callback([args, cmd, output] {
    // RenderResults checks the options before any work, named as flags here.
    if (output->count() > 0) CheckOutputFolderName(args->options.output_dir, "-o");
    Scene scene;
    ApplySceneKeyFlags(*cmd, args->keys, &scene);
    RenderResultsOptions options = SceneRenderOptions(scene);
    const RenderResultsOptions& given = args->options;
    options.output_dir = given.output_dir;
    options.figures = given.figures;
    options.animation = given.animation;
    options.png_frames = given.png_frames;
    options.force = given.force;
    std::cout << WithFlagNames({{"png_frames", "--png-frames"}, {"results file", "RESULTS"}}, [&] {
                   return RenderResults(args->results, options);
                 }).FullReport();
  });
}

}  // namespace impactdic::cli
