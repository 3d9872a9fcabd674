// Re-rendering the figures and the animation of a results file (`impactdic render RESULTS.h5`).
// Reads what exists (names in results_layout.h, documented in docs/render.md) and skips, with a log
// line and an entry in the summary, every output whose data is absent.
//
//   RenderResultsOptions options;
//   options.output_dir = "run1/figures";
//   RenderResultsSummary s = RenderResults("run1/results.h5", options);
//   std::cout << s.FullReport();
#ifndef IMPACTDIC_RENDER_RENDER_RESULTS_H_
#define IMPACTDIC_RENDER_RENDER_RESULTS_H_

#include <cstddef>
#include <functional>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "impactdic/io/hdf5_store.h"
#include "impactdic/render/animation.h"
#include "impactdic/render/gnuplot.h"
#include "impactdic/render/strain_field.h"
#include "impactdic/render/velocity_field.h"

namespace impactdic {

struct RenderResultsOptions {
  std::string output_dir;  // folder for the outputs (created if missing); empty = the file's folder
  bool figures = true;     // the gnuplot figures
  // The field snapshots: the velocity field at the end of the peak stage and, when the file has
  // /strain, the strain maps at t_e and at the last analysed frame.
  bool snapshot = true;
  bool animation = true;  // the velocity animation, and the strain animation when /strain exists
  // Also every animation frame as PNG (output_dir/velocity_frames, strain_frames); only with
  // `animation` (Check).
  bool png_frames = false;
  // true: the outputs are one new generation of output_dir (io/output_generation.h): drawn into a
  // staging folder and swapped in together, keeping the folder's other entries (results.h5,
  // summaries) and replacing every earlier figure and animation; output_dir must be new, empty or
  // written by impactdic, and hold no results.h5 other than the one rendered. false: straight into
  // output_dir (for a caller that stages the folder itself, as `impactdic run` does).
  bool new_generation = true;
  // Also replace an output folder another kind of command wrote (a campaign, a synth scene:
  // io/output_generation.h); files impactdic did not write are never replaced.
  bool force = false;
  // Into the folder of its results file, when that stores only a preview of the frames (fewer
  // rows than /time, or downsampled: outputs.frames: preview) and no frame_loader is given, the
  // velocity snapshot and the animation are drawn under their preview names
  // (results_layout.h kPreviewSnapshotPng, kPreviewAnimationName ...): the run's own, drawn from
  // every analysed frame at full size, are kept.
  // The camera frame of each row of /time (e.g. `impactdic run` re-reading its frames from their
  // source, one at a time) instead of /frames/images, which may be a preview or absent.
  std::function<cv::Mat(std::size_t)> frame_loader;
  PlotOptions plot;
  AnimationOptions animation_options;       // png_frames_dir is set from png_frames
  VelocityOverlayOptions snapshot_overlay;  // the velocity-field figure at t_e
  StrainOverlayOptions strain_overlay;      // the strain maps and animation

  void Check() const;
};

struct RenderResultsSummary {
  std::vector<std::string> written;  // output files
  std::vector<std::string> skipped;  // "<output>: <reason>"
  bool has_animation = false;
  AnimationSummary animation;
  bool has_strain_animation = false;
  AnimationSummary strain_animation;
  double wall_s = 0.0;

  std::string BriefReport() const;  // one line
  std::string FullReport() const;   // one line per output
};

// The velocity-field data of a results file, or an Error kFileFormat naming the missing or
// inconsistent dataset. `require_frames` = false allows files without /frames/images (then
// `frames` is empty and the sequence cannot be rendered); `read_frames` = false does not read
// them. A preview (/frames/row present) gives the sequence of the stored rows only, each frame
// scaled back to the full frame size (attributes of /frames).
VelocityFieldSequence ReadVelocityFieldSequence(const H5Reader& reader, bool require_frames = true,
                                                bool read_frames = true);

// The strain field data of a results file (/strain/eps_v, gamma_max, shear_band if present, with
// /time and the /dic grid), or an Error kFileFormat naming the missing or inconsistent dataset.
// The camera frames as in ReadVelocityFieldSequence when stored and `read_frames` (a preview
// keeps the stored rows only); without them the sequence has none (a plain background of the
// size in the attributes of /frames, else of the grid).
StrainFieldSequence ReadStrainFieldSequence(const H5Reader& reader, bool read_frames = true);

// Renders everything the file has data for. Errors: kFileNotFound / kFileFormat for a missing or
// unreadable file, kFileFormat when the file has none of the data any output needs (naming what
// was looked for) or inconsistent shapes, kIo for an output folder that cannot be written,
// kInvalidValue for one holding files impactdic did not write or another results.h5. On an error
// the output folder is as it was.
RenderResultsSummary RenderResults(const std::string& results_path,
                                   const RenderResultsOptions& options = {});

// The same from an open reader (a file held in memory: H5Writer::CommitToMemory); `results_path`
// names it in messages and its folder is the default output folder.
RenderResultsSummary RenderResults(const H5Reader& reader, const std::string& results_path,
                                   const RenderResultsOptions& options);

}  // namespace impactdic

#endif  // IMPACTDIC_RENDER_RENDER_RESULTS_H_
