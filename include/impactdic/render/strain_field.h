// Off-screen drawing of the strain fields of a run (results_layout.h /strain, strain/strain.h):
// the volumetric strain eps_v (COMPRESSION positive) and the maximum shear strain gamma_max side
// by side, each over its camera frame (or a plain grey background when the run stored none),
// interpolated and faded like the velocity field (velocity_field.h), with a colour bar in percent
// stating the limits, the time since impact and a scale bar; shear-band ridge samples as dots on
// the gamma_max panel. Used for the strain maps at t_e and at the last frame and for every frame
// of the strain animation (render_results.h, animation.h).
//
//   StrainFieldSequence seq;           // frames optional; time_ms, positions as FieldSequence
//   seq.eps_v = eps_v; seq.gamma_max = gamma_max;   // frames * subsets, NaN = unknown
//   StrainFieldRenderer renderer(seq, StrainOverlayOptions{});
//   cv::Mat bgr = renderer.RenderFrame(10);
//
// Colour maps: eps_v diverging, centred on 0 (blue = dilation, red = compaction): Moreland's
// cool-warm map (K. Moreland 2009, "Diverging Color Maps for Scientific Visualization", ISVC,
// doi:10.1007/978-3-642-10520-3_9), piecewise linear through five of its colours; gamma_max
// sequential, viridis (velocity_field.h ViridisLut). One colour scale for the whole sequence, so
// every frame of the animation has the same limits.
#ifndef IMPACTDIC_RENDER_STRAIN_FIELD_H_
#define IMPACTDIC_RENDER_STRAIN_FIELD_H_

#include <cstddef>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "impactdic/core/numeric.h"
#include "impactdic/render/field_sequence.h"

namespace impactdic {

// The frames (optional: none = a plain background), times, subset positions and scale
// (FieldSequence) with the strain of every subset.
struct StrainFieldSequence : FieldSequence {
  // Per frame and subset, row-major [frame][subset], dimensionless, NaN = unknown: volumetric
  // strain eps_v = -(exx + eyy) (compression positive) and maximum shear strain
  // gamma_max = eps_1 - eps_2.
  std::vector<double> eps_v;
  std::vector<double> gamma_max;
  // Optional (empty or [frame][subset]): non-zero = a shear-band ridge sample.
  std::vector<double> shear_band;
  // Frame size [px] of the plain background when there are no images; 0 x 0 = from the subset
  // positions (their largest coordinate plus the margin left of the smallest).
  cv::Size plain_size;

  // Consistency of all sizes and types; Error kInvalidValue naming the field.
  void Check() const;
};

struct StrainOverlayOptions {
  double opacity = 0.85;  // alpha of the colour maps over the frame, kOverlayOpacityRange
  // Colour limits, dimensionless: eps_v in [-eps_v_limit, +eps_v_limit], gamma_max in
  // [0, gamma_max_limit]; NaN = the `percentile` of |eps_v| (of gamma_max) over every frame and
  // subset of the sequence. Either is rounded up to a tick of its colour bar (drawn in percent).
  double eps_v_limit = kNaN;
  double gamma_max_limit = kNaN;
  double percentile = 99.0;  // kPercentileRange
  static constexpr ValueRange kPercentileRange{50, 100, "%", /*min_open=*/true};
  bool shear_bands = true;  // dots at the shear-band ridge samples, when the sequence has them
  // Each panel's frame is scaled for display so that its width lies in [min_width_px,
  // max_width_px].
  int min_width_px = 480;  // kDisplayWidthRange
  int max_width_px = 960;  // kDisplayWidthRange, >= min_width_px
  // Display contrast for 16-bit and float frames: these percentiles of the first frame map to
  // black and white, [0, 100], low < high.
  double contrast_low_percentile = 0.5;
  double contrast_high_percentile = 99.5;

  void Check() const;  // Error kInvalidValue naming the field
};

// Renders frames of one sequence; the sequence must outlive the renderer. The colour limits, the
// display size and the grey contrast are fixed at construction (the same for all frames).
class StrainFieldRenderer {
 public:
  StrainFieldRenderer(const StrainFieldSequence& sequence, const StrainOverlayOptions& options);

  // A BGR 8-bit image of size canvas_size(): the eps_v panel and its colour bar, then the
  // gamma_max panel and its colour bar (a header band with `title` on top when not empty).
  cv::Mat RenderFrame(std::size_t frame, const std::string& title = "") const;

  cv::Size canvas_size() const { return canvas_size_; }  // untitled frames; width, height even
  double eps_v_limit() const { return eps_v_limit_; }    // colour limits, dimensionless
  double gamma_max_limit() const { return gamma_max_limit_; }
  // Where subset `subset` of `frame` is drawn in an untitled frame, in panel 0 (eps_v) or 1
  // (gamma_max) [canvas px].
  cv::Point2d CanvasPoint(int panel, std::size_t frame, std::size_t subset) const;
  // The canvas columns of panel `panel`'s colour bar.
  cv::Rect ColourBarRect(int panel) const;

 private:
  cv::Mat Background(std::size_t frame) const;
  void DrawPanel(int panel, std::size_t frame, cv::Mat* canvas) const;

  const StrainFieldSequence& seq_;
  StrainOverlayOptions options_;
  cv::Mat frame0_;  // frame 0 when the sequence has images
  cv::Size image_size_;
  double scale_ = 1.0;  // display px per image px
  cv::Size display_size_, canvas_size_;
  int bar_width_ = 0;
  double text_scale_ = 1.0;
  double grey_low_ = 0.0, grey_high_ = 255.0;
  double spacing_px_ = 20.0;
  double eps_v_limit_ = 1e-3, gamma_max_limit_ = 1e-3;
  double eps_v_step_ = 1e-4, gamma_max_step_ = 1e-4;  // tick steps, dimensionless
  bool has_shear_band_ = false;
};

// The 256-entry diverging (cool-warm) colour table as a 256x1 CV_8UC3 BGR image: entry 0 blue,
// 128 light grey, 255 red.
cv::Mat CoolWarmLut();

// Writes the titled strain image of `frame` as a PNG (atomically); returns its size.
cv::Size RenderStrainSnapshot(const StrainFieldSequence& sequence, std::size_t frame,
                              const std::string& png_path, const StrainOverlayOptions& options = {},
                              const std::string& title = "");

}  // namespace impactdic

#endif  // IMPACTDIC_RENDER_STRAIN_FIELD_H_
