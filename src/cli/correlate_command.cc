// impactdic correlate: subset DIC of an image sequence, a video or a camera file: the flags, then
// the library's CorrelateFiles (pipeline/correlate_files.h).
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <cstddef>
#include <exception>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "commands.h"
#include "impactdic/core/error.h"
#include "impactdic/dic/options.h"
#include "impactdic/io/image_io.h"
#include "impactdic/pipeline/correlate_files.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/pipeline/scene_flags.h"
#include "impactdic/preprocess/preprocess.h"

namespace impactdic::cli {
namespace {

// The flags that are not scene keys, and --subset and --gaussian (their own messages); the DIC
// options are the scene's dic.* and preprocess.* keys (AddSceneKeyFlags; defaults: DicOptions).
struct CorrelateArgs {
  std::string reference;
  std::vector<std::string> deformed;
  std::string frames;
  std::optional<int> subset;
  std::string roi;
  std::string mode = ToString(DicOptions{}.mode);
  std::string gaussian = ToString(GaussianBlurOptions{}.mode);  // GaussianFromString.
  // The analysed frames, in the source's own numbering (FrameSource::FrameNumber); given when
  // first_given / last_given.
  long long first = 0, last = 0;
  bool first_given = false, last_given = false, gaussian_given = false;
  std::string output;
  bool allow_partial = false;  // Write the results even when no subset is valid (as `run`).
  bool warp_gradient = DicOptions{}.keep_warp_gradient;  // DicOptions::keep_warp_gradient.
  SceneKeyValues keys;        // --dic.*, --preprocess.* and their aliases.
  Scene scene;                // The keys, set by ApplySceneKeyFlags.
  bool update_given = false;  // dic.reference_update was on the command line.
};

// The command-line flags of the library fields named in errors.
const FlagNames kCorrelateFlags = {{"interpolation", "--interp"},
                                   {"shape function", "--shape"},
                                   {"dic.grid.subset_size", "--subset"},
                                   {"dic.grid.step", "--step"},
                                   {"dic.grid.roi", "--roi"},
                                   {"dic.grid.mask", "--mask"},
                                   {"dic.init.search_radius_px", "--search-radius"},
                                   {"dic.icgn.min_zncc", "--min-zncc"},
                                   {"dic.icgn.max_uncertainty_px", "--max-uncertainty"},
                                   {"dic.continuity.min_misfit", "--continuity-min-misfit"},
                                   {"dic.outliers.threshold", "--outlier-threshold"},
                                   {"dic.outliers.noise_px", "--outlier-noise"},
                                   {"dic.outliers.sigma_factor", "--outlier-sigma-factor"},
                                   {"frames video", "--frames"}};

cv::Rect ParseRoi(const std::string& text) {
  std::vector<int> v;
  std::stringstream ss(text);
  std::string item;
  bool ok = true;
  while (std::getline(ss, item, ',')) {
    try {
      std::size_t used = 0;
      v.push_back(std::stoi(item, &used));
      ok = ok && used == item.size();
    } catch (const std::exception&) {
      ok = false;
    }
  }
  CheckValue(ok && v.size() == 4, "--roi", text, "X0,Y0,X1,Y1 (four integers, pixels)");
  CheckValue(v[0] >= 0 && v[1] >= 0 && v[2] > v[0] && v[3] > v[1], "--roi", text,
             "0 <= X0 < X1 and 0 <= Y0 < Y1");
  return cv::Rect(cv::Point(v[0], v[1]), cv::Point(v[2], v[3]));
}

void Run(const CorrelateArgs& a) {
  // Validate every option before any work.
  const bool pair = !a.reference.empty() || !a.deformed.empty();
  if (pair == !a.frames.empty()) {
    throw Error(ErrorKind::kInvalidValue, "input",
                pair ? "both --reference/--deformed and --frames" : "none",
                "either --reference REF --deformed DEF [DEF ...] or --frames GLOB");
  }
  if (pair) {
    CheckValue(!a.reference.empty(), "--reference", "missing", "the reference image");
    CheckValue(!a.deformed.empty(), "--deformed", "missing", "at least one deformed image");
  }
  DicOptions options = a.scene.dic.options;  // The dic.* keys given.
  if (a.subset) options.grid.subset_size = *a.subset;
  if (!a.roi.empty()) options.grid.roi = ParseRoi(a.roi);
  if (!a.scene.dic.mask.empty()) options.grid.mask = ReadGreyImage(a.scene.dic.mask) != 0;
  options.mode = SequenceModeFromString(a.mode, "--mode");
  if (options.mode == SequenceMode::kPairs && a.update_given && options.update.policy != "fixed") {
    throw Error(ErrorKind::kInvalidValue, "--reference-update",
                options.update.policy + " with --mode pairs",
                "no --reference-update (or fixed): pairs never update the reference");
  }
  PreprocessOptions preprocess = a.scene.preprocess;  // The preprocess.* keys given.
  if (a.gaussian_given) preprocess.gaussian = GaussianFromString(a.gaussian, "--gaussian");
  preprocess.roi = options.grid.roi;
  options.keep_warp_gradient = a.warp_gradient;
  WithFlagNames(kCorrelateFlags, [&] { options.Check(); });
  CorrelateFilesRequest r{a.reference,
                          a.deformed,
                          a.frames,
                          std::nullopt,
                          std::nullopt,
                          a.scene.dic.first_frame,
                          a.scene.dic.last_frame,
                          options,
                          preprocess,
                          a.scene.dic.mask,
                          a.scene.dic.threads,
                          a.output,
                          a.allow_partial};
  if (a.first_given) r.first = a.first;
  if (a.last_given) r.last = a.last;
  WithFlagNames(kCorrelateFlags, [&] {
    try {
      CorrelateFiles(r);
    } catch (const PartialResultsError& e) {
      RethrowWithPartialFlag(e, "correlate");
    }
  });
}

}  // namespace

void RegisterCorrelateCommand(CLI::App& app) {
  auto args = std::make_shared<CorrelateArgs>();
  auto* cmd = app.add_subcommand(
      "correlate", "correlate: subset DIC (IC-GN, B-spline, reference updating) of a sequence");
  cmd->add_option("--reference", args->reference, "Reference image (first frame)");
  cmd->add_option("--deformed", args->deformed, "Deformed image(s), in order");
  cmd->add_option("--mode", args->mode,
                  "sequence | pairs: sequence = the deformed images are "
                  "frames of one recording, each predicted from the previous ones, reference "
                  "updated by --reference-update; pairs = independent images, each correlated "
                  "against the reference alone (--reference-update does not apply)")
      ->capture_default_str();
  AddSceneKeyOption(cmd, "inputs.frames", &args->frames,
                    "Folder or glob of frames (sorted; the first is the reference), a video "
                    "file (.mp4, .avi, .mov, .mkv: its frames, numbered from 0), or a camera file "
                    "(Phantom .cine; Photron .mraw with its .cih/.cihx, or the .cih/.cihx: the "
                    "camera's frame numbers, negative before the trigger, and time stamps)");
  cmd->add_option("--first", args->first,
                  "First analysed frame (the reference), by the frames' own numbers: the number "
                  "in the file names of a numbered image sequence (else the 0-based position), "
                  "the 0-based frame index of a video, the camera's frame number of a camera "
                  "file (may be negative). Default: the first frame (or --dic.first_frame)");
  cmd->add_option("--last", args->last,
                  "Last analysed frame, numbered as --first. Default: the last frame");
  AddSceneKeyOption(cmd, "dic.subset_size", &args->subset,
                    "Subset size [px], odd, in " + kSubsetSizeRange.Text(),
                    std::to_string(DicOptions{}.grid.subset_size));
  AddSceneKeyOption(cmd, "dic.roi", &args->roi,
                    "Region of interest X0,Y0,X1,Y1 [px] (default: image)");
  cmd->add_option("--gaussian", args->gaussian,
                  fmt::format("auto | none | on | SIGMA[,KERNEL]: Gaussian pre-filter of every "
                              "image, the reference included (short for the "
                              "--preprocess.gaussian.* flags): auto = when the reference's "
                              "near-Nyquist bias figure is above {} px; on = sigma {} px; KERNEL "
                              "odd, default {}. Reduces the sub-pixel bias of sharp or aliased "
                              "speckle (docs/dic.md, \"Sub-pixel bias\")",
                              GaussianBlurOptions{}.auto_threshold_px,
                              GaussianBlurOptions{}.sigma_px, GaussianBlurOptions{}.kernel_size))
      ->capture_default_str();
  cmd->add_flag("--warp-gradient", args->warp_gradient,
                "Keep the displacement gradient of each subset's warp since the reference "
                "(composed across reference updates): /dic/dudx_warp, dudy_warp, dvdx_warp, "
                "dvdy_warp in .h5, the last four columns of .csv (docs/dic.md, \"Warp gradient\")");
  cmd->add_option("-o,--output", args->output, "Output file (.csv or .h5)");
  cmd->add_flag(kAllowPartialFlag, args->allow_partial,
                "Write the output (exit 0) even when no subset is valid in any deformed image; "
                "without it such a correlation fails (exit 1) and writes nothing, as `run` does");
  AddSceneKeyFlags(cmd, {"dic", "preprocess"}, &args->keys);
  cmd->callback([args, cmd] {
    const auto given = [cmd](const char* name) { return cmd->count(name) > 0; };
    args->update_given = given("--reference-update") || given("--dic.reference_update");
    args->first_given = given("--first");
    args->last_given = given("--last");
    args->gaussian_given = given("--gaussian");
    ApplySceneKeyFlags(*cmd, args->keys, &args->scene);
    Run(*args);
  });
}

}  // namespace impactdic::cli
