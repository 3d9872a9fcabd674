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
    std::string codec = ToString(AnimationOptions{}.codec);  // Defaults: the render library's.
    RenderResultsOptions options;
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
  cmd->add_option("--codec", args->codec,
                  "video codec: auto (H.264 MP4, else MJPG AVI), h264 (or fail), mjpg")
      ->capture_default_str();
  cmd->add_option("--fps", args->options.animation_options.fps,
                  "playback frame rate of the animation, in " + AnimationOptions::kFpsRange.Text())
      ->capture_default_str();
  cmd->callback([args, output] {
    // RenderResults checks the options before any work, named as flags here.
    if (output->count() > 0) CheckOutputFolderName(args->options.output_dir, "-o");
    RenderResultsOptions& options = args->options;
    std::cout << WithFlagNames({{"video codec", "--codec"},
                                {"AnimationOptions.fps", "--fps"},
                                {"png_frames", "--png-frames"},
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
