// impactdic correlate: subset DIC of an image sequence, a video or a camera file (library:
// impactdic/dic/correlate_frames.h on a pipeline FrameStream; results: impactdic/dic/dic_io.h).
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstddef>
#include <exception>
#include <filesystem>
#include <functional>
#include <memory>
#include <opencv2/core.hpp>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "commands.h"
#include "impactdic/core/enum_names.h"
#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/core/range.h"
#include "impactdic/core/strings.h"
#include "impactdic/core/threads.h"
#include "impactdic/core/timer.h"
#include "impactdic/dic/bspline.h"
#include "impactdic/dic/correlate_frames.h"
#include "impactdic/dic/correlator.h"
#include "impactdic/dic/dic_io.h"
#include "impactdic/dic/options.h"
#include "impactdic/dic/reference_update.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/camera_file.h"
#include "impactdic/io/csv.h"
#include "impactdic/io/frame_source.h"
#include "impactdic/io/image_io.h"
#include "impactdic/pipeline/frame_stream.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/preprocess/preprocess.h"

namespace impactdic::cli {
namespace {

// Defaults: the dic library's DicOptions (one definition for `correlate`, scenes and the library).
struct CorrelateArgs {
  std::string reference;
  std::vector<std::string> deformed;
  std::string frames;
  int subset = DicOptions{}.grid.subset_size;
  int step = DicOptions{}.grid.step;
  std::string roi;
  std::string mask;
  std::string interp = ToString(DicOptions{}.icgn.interpolation);
  std::string shape = ToString(DicOptions{}.icgn.shape);
  std::string update = ReferenceUpdateText(DicOptions{}.update);
  bool update_given = false;  // --reference-update was on the command line.
  int threads = 0;
  int search_radius = DicOptions{}.init.search_radius_px;
  double min_zncc = DicOptions{}.icgn.min_zncc;
  std::string mode = ToString(DicOptions{}.mode);
  std::string max_uncertainty = MaxUncertaintyText(DicOptions{}.icgn.max_uncertainty_px);
  std::string gaussian = ToString(GaussianBlurOptions{}.mode);  // GaussianFromString.
  // The continuity post-check (DicOptions::continuity), checked with the flags' names
  // (ContinuityFromArgs).
  std::string continuity = DicOptions{}.continuity.enabled ? "on" : "off";
  std::string continuity_misfit = ContinuityLimitText(DicOptions{}.continuity.misfit_ratio);
  std::string continuity_second =
      ContinuityLimitText(DicOptions{}.continuity.max_second_difference_px);
  std::string continuity_jump =
      ContinuityLimitText(DicOptions{}.continuity.max_neighbour_difference_px);
  double continuity_min_misfit = DicOptions{}.continuity.min_misfit;
  // The normalized median test (DicOptions::outliers).
  std::string outlier_check = DicOptions{}.outliers.enabled ? "on" : "off";
  double outlier_threshold = DicOptions{}.outliers.threshold;
  double outlier_noise = DicOptions{}.outliers.noise_px;
  double outlier_sigma_factor = DicOptions{}.outliers.sigma_factor;
  std::string continuity_local = ContinuityLimitText(DicOptions{}.continuity.local_ratio);
  // The analysed frames, in the source's own numbering (FrameSource::FrameNumber); given when
  // first_given / last_given.
  long long first = 0, last = 0;
  bool first_given = false, last_given = false;
  std::string output;
  bool allow_partial = false;  // Write the results even when no subset is valid (as `run`).
  bool warp_gradient = DicOptions{}.keep_warp_gradient;  // DicOptions::keep_warp_gradient.
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

// The frames' source: the images listed (`paths`), a camera file or a video. A video needs two
// decodable frames (Error naming it); camera files say what they hold.
std::unique_ptr<FrameSource> OpenSource(const CorrelateArgs& a, bool pair, bool camera, bool video,
                                        const std::vector<std::string>& paths) {
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

// The one preprocessing route of `run` (preprocess Preprocessor) with --gaussian alone: decided
// from the reference (the first analysed frame) over the ROI, as `run` decides from its first
// frame (docs/dic.md, "Sub-pixel bias"); logged.
PreprocessOptions CorrelatePreprocess(const GaussianBlurOptions& gaussian, cv::Rect roi) {
  PreprocessOptions o;
  o.gaussian = gaussian;
  o.roi = roi;
  return o;
}

// --first/--last: the analysed frames, by the source's frame numbers (Error naming the flag and
// the source's span when no frame has the number); at least two of them.
void SelectFrames(const CorrelateArgs& a, FrameStream* frames) {
  const FrameSource& source = frames->source();
  const int first = a.first_given ? FrameIndexOf(source, a.first, "--first") : 0;
  const int last = a.last_given ? FrameIndexOf(source, a.last, "--last") : source.frame_count() - 1;
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
void CheckSomethingUsable(const CorrelateArgs& a, const DicResult& result,
                          const DicOptions& options) {
  const std::string problem = result.summary.NothingUsable("--min-zncc", options.icgn.min_zncc);
  if (problem.empty()) return;
  if (a.allow_partial) {
    LogWarning("correlate: partial results ({}): {}", kAllowPartialFlag, problem);
    return;
  }
  RethrowWithPartialFlag(
      PartialResultsError(
          fmt::format("correlate: {}\nNothing was written ({} is as it was)", problem, a.output),
          "writes it, every subset with its status"),
      "correlate");
}

ContinuityCheckOptions ContinuityFromArgs(const CorrelateArgs& a) {
  ContinuityCheckOptions c;
  c.enabled = OnOffFromString(a.continuity, "--continuity-check");
  c.misfit_ratio = ContinuityLimitOf(&ContinuityCheckOptions::misfit_ratio)
                       .FromString(a.continuity_misfit, "--continuity-misfit-ratio");
  c.max_second_difference_px =
      ContinuityLimitOf(&ContinuityCheckOptions::max_second_difference_px)
          .FromString(a.continuity_second, "--continuity-max-second-difference");
  c.max_neighbour_difference_px =
      ContinuityLimitOf(&ContinuityCheckOptions::max_neighbour_difference_px)
          .FromString(a.continuity_jump, "--continuity-max-neighbour-difference");
  c.min_misfit = a.continuity_min_misfit;
  c.local_ratio = ContinuityLimitOf(&ContinuityCheckOptions::local_ratio)
                      .FromString(a.continuity_local, "--continuity-local-ratio");
  return c;
}

OutlierCheckOptions OutliersFromArgs(const CorrelateArgs& a) {
  OutlierCheckOptions o;
  o.enabled = OnOffFromString(a.outlier_check, "--outlier-check");
  o.threshold = a.outlier_threshold;
  o.noise_px = a.outlier_noise;
  o.sigma_factor = a.outlier_sigma_factor;
  return o;
}

void AddOutlierFlags(CLI::App* cmd, CorrelateArgs* args) {
  cmd->add_option("--outlier-check", args->outlier_check,
                  "on | off: normalized median test of each frame; spurious vectors become "
                  "`outlier` (NaN) (docs/dic.md)")
      ->capture_default_str();
  cmd->add_option("--outlier-threshold", args->outlier_threshold,
                  "Flag |d - neighbours' median| / (their median residual + noise) above it, in " +
                      kOutlierThresholdRange.Text())
      ->capture_default_str();
  cmd->add_option("--outlier-noise", args->outlier_noise,
                  "The noise level of the normalized median test, in " + kOutlierNoiseRange.Text())
      ->capture_default_str();
  cmd->add_option("--outlier-sigma-factor", args->outlier_sigma_factor,
                  "...and |d - median| above this times the subset's own sigma, in " +
                      kOutlierSigmaFactorRange.Text())
      ->capture_default_str();
}

void AddContinuityFlags(CLI::App* cmd, CorrelateArgs* args) {
  cmd->add_option("--continuity-check", args->continuity,
                  "on | off: post-check of each frame; converged subsets straddling a body edge "
                  "or a shear band become `discontinuous` (NaN) (docs/dic.md)")
      ->capture_default_str();
  cmd->add_option("--continuity-misfit-ratio", args->continuity_misfit,
                  "Flag 1 - ZNCC above this times its 7x7 neighbourhood's median; " +
                      ContinuityLimitOf(&ContinuityCheckOptions::misfit_ratio).Expected())
      ->capture_default_str();
  cmd->add_option("--continuity-min-misfit", args->continuity_min_misfit,
                  "...and 1 - ZNCC above this as well, in " + kMinMisfitRange.Text())
      ->capture_default_str();
  cmd->add_option(
         "--continuity-max-second-difference", args->continuity_second,
         "Flag a second difference of u, v along a grid row/column above it; " +
             ContinuityLimitOf(&ContinuityCheckOptions::max_second_difference_px).Expected())
      ->capture_default_str();
  cmd->add_option(
         "--continuity-max-neighbour-difference", args->continuity_jump,
         "Flag a displacement differing from an adjacent subset's by more; " +
             ContinuityLimitOf(&ContinuityCheckOptions::max_neighbour_difference_px).Expected())
      ->capture_default_str();
  cmd->add_option("--continuity-local-ratio", args->continuity_local,
                  "...and above this times the 7x7 neighbourhood's median of the same; " +
                      ContinuityLimitOf(&ContinuityCheckOptions::local_ratio).Expected())
      ->capture_default_str();
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
  DicOptions options;
  CheckThreadCount(a.threads, "--threads");
  options.grid.subset_size = a.subset;
  options.grid.step = a.step;
  if (!a.roi.empty()) options.grid.roi = ParseRoi(a.roi);
  if (!a.mask.empty()) options.grid.mask = ReadGreyImage(a.mask) != 0;
  WithFlagNames(kCorrelateFlags, [&] {
    options.icgn.interpolation = InterpolationFromString(a.interp);
    options.icgn.shape = ShapeFunctionFromString(a.shape);
  });
  options.update.policy = a.update;
  try {
    ReferenceUpdatePolicyFromString(a.update, options.update);
  } catch (const Error&) {
    throw Error(ErrorKind::kInvalidValue, "--reference-update", a.update,
                ReferenceUpdatePolicyUsage());
  }
  options.init.search_radius_px = a.search_radius;
  options.icgn.min_zncc = a.min_zncc;
  options.mode = SequenceModeFromString(a.mode, "--mode");
  if (options.mode == SequenceMode::kPairs && a.update_given && a.update != "fixed") {
    throw Error(ErrorKind::kInvalidValue, "--reference-update", a.update + " with --mode pairs",
                "no --reference-update (or fixed): pairs never update the reference");
  }
  options.icgn.max_uncertainty_px =
      MaxUncertaintyFromString(a.max_uncertainty, "--max-uncertainty");
  const GaussianBlurOptions gaussian = GaussianFromString(a.gaussian, "--gaussian");
  options.continuity = ContinuityFromArgs(a);
  options.outliers = OutliersFromArgs(a);
  options.keep_warp_gradient = a.warp_gradient;
  WithFlagNames(kCorrelateFlags, [&] { options.Check(); });
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
  if (a.first_given && a.last_given && a.first > a.last) {
    throw Error(ErrorKind::kInvalidValue, "--first/--last", fmt::format("{} > {}", a.first, a.last),
                "--first <= --last");
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
    FrameStream frames(OpenSource(a, pair, camera, video, paths),
                       CorrelatePreprocess(gaussian, options.grid.roi), /*calibration=*/nullptr);
    SelectFrames(a, &frames);
    result = CorrelateFrames(frames, options);
    const GaussianDecision& prefilter = frames.preprocess_summary()->gaussian;
    PrefilterAttributes(prefilter, &result.text_attributes, &result.number_attributes);
    if (prefilter.applied) {
      result.preprocess =
          fmt::format("gaussian: sigma {} px, kernel {}x{} (reference and deformed images)",
                      gaussian.sigma_px, gaussian.kernel_size, gaussian.kernel_size);
    }
  } catch (Error& e) {
    if (e.where() == "mask" && e.file().empty()) e.WithFile(a.mask);  // Its size is wrong.
    RethrowWithFlagNames(e, kCorrelateFlags);
  }
  CheckSomethingUsable(a, result, options);
  WriteDicResult(a.output, &result, options);
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
  cmd->add_option("--frames", args->frames,
                  "Folder or glob of frames (sorted; the first is the reference), a video "
                  "file (.mp4, .avi, .mov, .mkv: its frames, numbered from 0), or a camera file "
                  "(Phantom .cine; Photron .mraw with its .cih/.cihx, or the .cih/.cihx: the "
                  "camera's frame numbers, negative before the trigger, and time stamps)");
  cmd->add_option("--first", args->first,
                  "First analysed frame (the reference), by the frames' own numbers: the number "
                  "in the file names of a numbered image sequence (else the 0-based position), "
                  "the 0-based frame index of a video, the camera's frame number of a camera "
                  "file (may be negative). Default: the first frame");
  cmd->add_option("--last", args->last,
                  "Last analysed frame, numbered as --first. Default: the last frame");
  cmd->add_option("--subset", args->subset, "Subset size [px], odd, in " + kSubsetSizeRange.Text())
      ->capture_default_str();
  cmd->add_option("--step", args->step, "Grid step [px]")->capture_default_str();
  cmd->add_option("--roi", args->roi, "Region of interest X0,Y0,X1,Y1 [px] (default: image)");
  cmd->add_option("--mask", args->mask,
                  "Mask image of the reference's size: subsets are correlated only where their "
                  "centre pixel is non-zero (status `masked` elsewhere)");
  cmd->add_option("--interp", args->interp, Join(kInterpolationNames.Names(), " | "))
      ->capture_default_str();
  cmd->add_option("--shape", args->shape, Join(kShapeFunctionNames.Names(), " | "))
      ->capture_default_str();
  cmd->add_option("--reference-update", args->update, ReferenceUpdatePolicyUsage())
      ->capture_default_str();
  cmd->add_option("--threads", args->threads,
                  std::string("Worker threads: ") + kThreadCountExpected)
      ->capture_default_str();
  cmd->add_option("--search-radius", args->search_radius,
                  "Integer search radius [px], in " + kSearchRadiusRange.Text())
      ->capture_default_str();
  cmd->add_option("--min-zncc", args->min_zncc,
                  "ZNCC below which a subset fails, in " + kMinZnccRange.Text())
      ->capture_default_str();
  cmd->add_option("--max-uncertainty", args->max_uncertainty,
                  "Estimated standard deviation [px] of u or v above which a "
                  "converged subset is `uncertain` (NaN); 0 or none: no limit, every "
                  "converged subset is reported with sigma_u_px, sigma_v_px")
      ->capture_default_str();
  cmd->add_option("--gaussian", args->gaussian,
                  fmt::format("auto | none | on | SIGMA[,KERNEL]: Gaussian pre-filter of every "
                              "image, the reference included (as the scene's "
                              "preprocess.gaussian.*): auto = when the reference's near-Nyquist "
                              "bias figure is above {} px; on = sigma {} px; KERNEL odd, default "
                              "{}. Reduces the sub-pixel bias of sharp or aliased speckle "
                              "(docs/dic.md, \"Sub-pixel bias\")",
                              GaussianBlurOptions{}.auto_threshold_px,
                              GaussianBlurOptions{}.sigma_px, GaussianBlurOptions{}.kernel_size))
      ->capture_default_str();
  AddContinuityFlags(cmd, args.get());
  AddOutlierFlags(cmd, args.get());
  cmd->add_flag("--warp-gradient", args->warp_gradient,
                "Keep the displacement gradient of each subset's warp since the reference "
                "(composed across reference updates): /dic/dudx_warp, dudy_warp, dvdx_warp, "
                "dvdy_warp in .h5, the last four columns of .csv (docs/dic.md, \"Warp gradient\")");
  cmd->add_option("-o,--output", args->output, "Output file (.csv or .h5)");
  cmd->add_flag(kAllowPartialFlag, args->allow_partial,
                "Write the output (exit 0) even when no subset is valid in any deformed image; "
                "without it such a correlation fails (exit 1) and writes nothing, as `run` does");
  cmd->callback([args, cmd] {
    args->update_given = cmd->count("--reference-update") > 0;
    args->first_given = cmd->count("--first") > 0;
    args->last_given = cmd->count("--last") > 0;
    Run(*args);
  });
}

}  // namespace impactdic::cli
