// What every drawn subset field has in common (render/velocity_field.h, render/strain_field.h):
// the camera frames (optional for some fields), the time of each frame, the subset centres
// (fixed or per frame) and the panel scale. The field values themselves are in the derived
// sequences, row-major [frame][subset].
#ifndef IMPACTDIC_RENDER_FIELD_SEQUENCE_H_
#define IMPACTDIC_RENDER_FIELD_SEQUENCE_H_

#include <cstddef>
#include <functional>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "impactdic/core/numeric.h"
#include "impactdic/core/range.h"

namespace impactdic {

// How a field is drawn over its frames (VelocityOverlayOptions, StrainOverlayOptions): the colour
// map's opacity, the frame's width on screen and the percentiles of a 16-bit or float frame that
// map to black and white.
inline constexpr ValueRange kOverlayOpacityRange{0, 1, ""};
inline constexpr ValueRange kDisplayWidthRange{160, 8000, "px"};
inline constexpr ValueRange kContrastPercentileRange{0, 100, "%"};

struct FieldSequence {
  // One grey camera frame per analysed time step (CV_8UC1, CV_16UC1 or CV_32FC1; all the same
  // size and type). 16-bit and float frames are contrast-stretched for display.
  std::vector<cv::Mat> frames;
  // Instead of `frames` (left empty): frame_count frames handed over one at a time by
  // load_frame(i) (e.g. re-read from their source), so a long sequence is never held in memory;
  // each must have the size and type of frame 0.
  std::size_t frame_count = 0;
  std::function<cv::Mat(std::size_t)> load_frame;
  std::vector<double> time_ms;  // time since impact of each frame [ms]; NaN = unknown
  std::size_t num_subsets = 0;
  // Subset centres in image pixels (x right, y down): num_subsets values (the same positions in
  // every frame) or frames * num_subsets values, row-major [frame][subset] (Lagrangian positions).
  std::vector<double> x_px;
  std::vector<double> y_px;
  // Scale of the panel plane [mm/px], for the scale bar; NaN or <= 0 = no scale bar.
  double mm_per_px = kNaN;

  // Whether camera images are given (stored or loaded).
  bool has_images() const { return !frames.empty() || (load_frame && frame_count > 0); }
  // Frames of the sequence: the images' count, or (no images) one per time.
  std::size_t num_frames() const {
    return !frames.empty() ? frames.size() : load_frame ? frame_count : time_ms.size();
  }
  // Frame i (stored or loaded); Error kInvalidValue if a loaded frame differs from frame 0.
  cv::Mat Frame(std::size_t i) const;
  bool lagrangian() const { return x_px.size() != num_subsets; }
  double x(std::size_t frame, std::size_t subset) const {
    return lagrangian() ? x_px[frame * num_subsets + subset] : x_px[subset];
  }
  double y(std::size_t frame, std::size_t subset) const {
    return lagrangian() ? y_px[frame * num_subsets + subset] : y_px[subset];
  }
  // Consistency of the frames (when `require_images`, at least one), times and positions; Error
  // kInvalidValue naming the field as `type_name`.field.
  void CheckCommon(const std::string& type_name, bool require_images) const;
  // Keeps the given rows (frame indices) of the times, Lagrangian positions and of every
  // per-frame field in `per_frame` (row-major [frame][subset]); the frames are the caller's.
  void KeepRows(const std::vector<std::size_t>& rows,
                const std::vector<std::vector<double>*>& per_frame);
};

// A frame of a sequence: a 2-D grey image of the size and type of `first`; Error kInvalidValue
// naming type_name.frames[index].
void CheckFieldFrame(const cv::Mat& frame, const cv::Mat& first, std::size_t index,
                     const std::string& type_name);

// Index of the frame whose time is nearest to `t_ms` (frames with NaN time are ignored; 0 if none
// has a time).
std::size_t FrameNearestTime(const FieldSequence& sequence, double t_ms);

}  // namespace impactdic

#endif  // IMPACTDIC_RENDER_FIELD_SEQUENCE_H_
