// impactdic render RESULTS.h5 [-o OUTDIR] [--png-frames] [--codec auto|h264|mjpg] [--fps F]
// [--force]
#include <CLI/CLI.hpp>
#include <iostream>
#include <memory>
#include <string>

#include "commands.h"
#include "impactdic/core/error.h"
#include "impactdic/io/output_generation.h"
#include "impactdic/render/animation.h"
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
    std::string output_dir;
    bool png_frames = false;
    bool no_animation = false;
    bool no_figures = false;
    bool force = false;
    std::string codec = ToString(AnimationOptions{}.codec);  // Defaults: the render library's.
    double fps = AnimationOptions{}.fps;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("RESULTS", args->results, "results.h5 written by `impactdic run`")->required();
  auto* output = cmd->add_option(
      "-o,--output", args->output_dir,
      "output folder (created if missing; default: the folder of RESULTS). The "
      "figures and animation replace the earlier ones together when all are drawn; "
      "the folder's other files (results.h5, summaries) stay; from a preview of the "
      "frames (outputs.frames: preview) into the run's folder, the snapshot and "
      "animation are named *_preview and the run's own stay");
  cmd->add_flag("--png-frames", args->png_frames,
                "also write every animation frame as PNG (OUTDIR/velocity_frames, strain_frames)");
  cmd->add_flag("--no-animation", args->no_animation, "skip the animations");
  cmd->add_flag("--no-figures", args->no_figures, "skip the gnuplot figures");
  cmd->add_flag("--force", args->force,
                "replace an output folder another command wrote (a campaign, a synth scene); "
                "files impactdic did not write are never replaced");
  cmd->add_option("--codec", args->codec,
                  "video codec: auto (H.264 MP4, else MJPG AVI), h264 (or fail), mjpg")
      ->capture_default_str();
  cmd->add_option("--fps", args->fps,
                  "playback frame rate of the animation, in " + AnimationOptions::kFpsRange.Text())
      ->capture_default_str();
  cmd->callback([args, output] {
    // Validate every option before any work (RenderResults checks the rest, named as flags).
    if (output->count() > 0) CheckOutputFolderName(args->output_dir, "-o");
    CheckValue(!args->no_animation || !args->png_frames, "--png-frames",
               "given with --no-animation", "--png-frames only together with the animation");
    RenderResultsOptions options;
    options.animation_options.fps = args->fps;
    options.output_dir = args->output_dir;
    options.png_frames = args->png_frames;
    options.animation = !args->no_animation;
    options.figures = !args->no_figures;
    options.force = args->force;
    std::cout << WithFlagNames({{"video codec", "--codec"},
                                {"AnimationOptions.fps", "--fps"},
                                {"results file", "RESULTS"}},
                               [&] {
                                 options.animation_options.codec =
                                     VideoCodecFromString(args->codec);
                                 return RenderResults(args->results, options);
                               })
                     .FullReport();
  });
}

}  // namespace impactdic::cli
