// Off-screen drawing of a DIC velocity field over its camera frame (no display needed): the frame
// in grey, the velocity magnitude of the subsets as a viridis colour map interpolated smoothly over
// the grid area (semi-transparent), arrows with a reference arrow, a colour bar with tick labels
// and units, the time since impact in ms and a scale bar in mm. Used for the snapshot figure at
// the end of the peak stage and for every frame of the animation (animation.h).
//
//   VelocityFieldSequence seq;        // plain data, filled by the pipeline or from results.h5
//   seq.frames = grey_frames;         // one CV_8U/CV_16U/CV_32F image per analysed frame
//   seq.time_ms = t_ms;               // time since impact of each frame
//   seq.num_subsets = n;
//   seq.x_px = x; seq.y_px = y;       // n (fixed) or frames*n (Lagrangian) subset centres
//   seq.vx_mm_s = vx; seq.vy_mm_s = vy;  // frames*n, NaN = invalid subset
//   seq.mm_per_px = 0.2;
//   VelocityFieldRenderer renderer(seq, VelocityOverlayOptions{});
//   cv::Mat bgr = renderer.RenderFrame(10);
//
// Interpolation: normalised convolution with a Gaussian applicability (Knutsson & Westin 1993,
// "Normalized and differential convolution", CVPR, doi:10.1109/CVPR.1993.341081), which handles
// invalid (NaN) subsets, Lagrangian (moving) subset positions and irregular grids alike.
// Colour map: viridis (van der Walt & Smith 2015, matplotlib), perceptually uniform and readable
// in greyscale; taken from OpenCV's COLORMAP_VIRIDIS table.
#ifndef IMPACTDIC_RENDER_VELOCITY_FIELD_H_
#define IMPACTDIC_RENDER_VELOCITY_FIELD_H_

#include <cstddef>
#include <functional>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "impactdic/core/numeric.h"
#include "impactdic/render/field_sequence.h"

namespace impactdic {

// The frames, times, subset positions and scale (FieldSequence) with the velocity of every subset.
struct VelocityFieldSequence : FieldSequence {
  // Velocity per frame and subset [mm/s], row-major [frame][subset]; NaN = invalid subset.
  std::vector<double> vx_mm_s;
  std::vector<double> vy_mm_s;
  // Direction of vy: true = along image rows (down, the image convention), false = up.
  bool vy_positive_down = true;

  // Consistency of all sizes and types (camera frames required); Error kInvalidValue naming the
  // field.
  void Check() const;
};

enum class VelocityDisplayUnit {
  kAuto,  // m/s when the colour-scale top is >= 1000 mm/s, else mm/s
  kMmPerS,
  kMPerS,
};
const char* ToString(VelocityDisplayUnit unit);  // "auto", "mm/s", "m/s"
VelocityDisplayUnit VelocityDisplayUnitFromString(const std::string& text);

struct VelocityOverlayOptions {
  double opacity = 0.7;  // alpha of the colour map over the frame, kOverlayOpacityRange
  // Top of the colour scale [mm/s]; NaN = the 99th percentile of all valid speeds of the
  // sequence (one scale for every frame, so colours are comparable over time).
  double max_speed_mm_s = kNaN;
  VelocityDisplayUnit unit = VelocityDisplayUnit::kAuto;
  bool arrows = true;
  // Minimum distance between drawn arrows in display pixels: denser grids are thinned.
  double arrow_spacing_display_px = 36.0;
  static constexpr ValueRange kArrowSpacingRange{4, 500, "px"};
  // Frames are scaled for display so that their width lies in [min_width_px, max_width_px].
  int min_width_px = 960;   // kDisplayWidthRange
  int max_width_px = 1920;  // kDisplayWidthRange, >= min_width_px
  // Display contrast for 16-bit and float frames: these percentiles of the first frame map to
  // black and white, [0, 100], low < high.
  double contrast_low_percentile = 0.5;
  double contrast_high_percentile = 99.5;

  void Check() const;  // Error kInvalidValue naming the field
};

// Renders frames of one sequence; the sequence must outlive the renderer. The colour scale, the
// display size and the grey contrast are fixed at construction (same for all frames).
class VelocityFieldRenderer {
 public:
  VelocityFieldRenderer(const VelocityFieldSequence& sequence,
                        const VelocityOverlayOptions& options);

  // A BGR 8-bit image of size canvas_size() (the header band with `title` is added on top when
  // the title is not empty, so titled images are taller).
  cv::Mat RenderFrame(std::size_t frame, const std::string& title = "") const;

  cv::Size canvas_size() const { return canvas_size_; }  // untitled frames; width, height even
  double color_max_mm_s() const { return color_max_mm_s_; }
  const std::string& unit_label() const { return unit_label_; }  // "mm/s" or "m/s"
  double grid_spacing_px() const { return spacing_px_; }         // estimated subset spacing
  double reference_speed_mm_s() const { return reference_speed_mm_s_; }
  std::size_t valid_speed_count() const { return valid_speeds_; }  // over the whole sequence

 private:
  // The constructor's steps, in order.
  void SetColourScale();      // colour_max, unit, reference arrow speed (whole sequence)
  void SetLayout();           // display scale and size, text scale, colour-bar panel, canvas
  void ChooseArrowSubsets();  // one arrow per cell of k x k grid spacings
  cv::Mat DisplayGrey(std::size_t frame) const;
  void DrawField(std::size_t frame, cv::Mat* canvas) const;
  void DrawArrows(std::size_t frame, cv::Mat* canvas) const;
  void DrawDecorations(std::size_t frame, cv::Mat* canvas) const;

  const VelocityFieldSequence& seq_;
  cv::Mat frame0_;  // The sequence's frame 0: size, grey contrast.
  VelocityOverlayOptions options_;
  double scale_ = 1.0;  // display px per image px
  cv::Size display_size_, canvas_size_;
  int panel_width_ = 0;
  double text_scale_ = 1.0;
  double grey_low_ = 0.0, grey_high_ = 255.0;
  double color_max_mm_s_ = 1.0;
  double unit_factor_ = 1.0;  // display unit per mm/s
  std::string unit_label_ = "mm/s";
  double spacing_px_ = 20.0;
  double reference_speed_mm_s_ = 1.0;
  double arrow_px_per_mm_s_ = 0.0;          // display px of arrow length per mm/s
  std::vector<std::size_t> arrow_subsets_;  // subsets that carry an arrow
  std::size_t valid_speeds_ = 0;
  cv::Mat lut_;  // 256 x 1 BGR viridis
};

// The 256-entry viridis colour table as a 256x1 CV_8UC3 BGR image.
cv::Mat ViridisLut();

// 1-2-5 "nice" tick step for a span divided into about `target_ticks` intervals.
double NiceStep(double span, int target_ticks);

// Writes the titled velocity-field image of `frame` as a PNG (atomically); returns its size.
cv::Size RenderVelocitySnapshot(const VelocityFieldSequence& sequence, std::size_t frame,
                                const std::string& png_path,
                                const VelocityOverlayOptions& options = {},
                                const std::string& title = "");

}  // namespace impactdic

#endif  // IMPACTDIC_RENDER_VELOCITY_FIELD_H_
