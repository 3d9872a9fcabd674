// The drawing shared by the field renderers (velocity_field.cc, strain_field.cc): display layout,
// grey background, a subset field interpolated and coloured over it, time stamp, scale bar,
// colour bar. Internal to render.
#ifndef IMPACTDIC_SRC_RENDER_FIELD_DRAW_H_
#define IMPACTDIC_SRC_RENDER_FIELD_DRAW_H_

#include <cstddef>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <utility>
#include <vector>

#include "impactdic/render/field_sequence.h"

namespace impactdic::render_internal {

inline constexpr int kFont = cv::FONT_HERSHEY_DUPLEX;
inline const cv::Scalar kPanelColor(32, 32, 32);
inline const cv::Scalar kWhite(255, 255, 255);
inline const cv::Scalar kBlack(0, 0, 0);

std::string Fmt(const char* format, double value);
// Largest 1, 2 or 5 times a power of ten that is <= value (value > 0).
double NiceFloor(double value);
// Tick label with as many decimals as the step needs.
std::string TickLabel(double value, double step);
inline int RoundUpEven(int v) { return v + (v & 1); }
inline int RoundUp8(int v) { return (v + 7) / 8 * 8; }
// Line thickness and padding of text drawn at `text_scale`.
inline int TextThickness(double text_scale) {
  return std::max(1, static_cast<int>(std::lround(text_scale * 1.4)));
}
inline int TextPad(double text_scale) {
  return static_cast<int>(std::lround(10 * text_scale / 0.7));
}
// Blends a filled rectangle of `color` with opacity `alpha` into img (clipped).
void ShadeRect(cv::Mat* img, cv::Rect rect, const cv::Scalar& color, double alpha);
// The value at `percent` [0, 100] of `values` (nearest rank); 0 for none.
double Percentile(std::vector<float> values, double percent);
// `top` (> 0) rounded up to a multiple of NiceStep(top, target_ticks) (velocity_field.h), so a
// colour bar ends on a labelled tick; *step (optional) receives that step.
double RoundUpToTick(double top, int target_ticks, double* step = nullptr);

// The display options every field renderer has: Error kInvalidValue naming
// `type_name`.min_width_px (160..8000), .max_width_px (min_width_px..8000),
// .contrast_low_percentile/contrast_high_percentile (0 <= low < high <= 100).
void CheckDisplayOptions(const std::string& type_name, int min_width_px, int max_width_px,
                         double contrast_low_percentile, double contrast_high_percentile);

// Display scale of a frame: enlarged to min_width_px or shrunk to max_width_px, and the text size
// that goes with it.
struct DisplayLayout {
  cv::Size image;      // frame size [px]
  double scale = 1.0;  // display px per image px
  cv::Size size;       // display size
  double text_scale = 1.0;
};
DisplayLayout LayoutDisplay(cv::Size image, int min_width_px, int max_width_px);

// Median nearest-neighbour distance of (up to 256) subsets of frame 0 [px], clamped to
// [2, half the larger image side]; a twelfth of the smaller side when there are too few subsets.
double EstimateGridSpacing(const FieldSequence& seq, cv::Size image);

// Display contrast (low, high) of a 16-bit or float frame: its percentiles; (0, 255) for 8-bit.
std::pair<double, double> GreyContrast(const cv::Mat& frame, double low_percentile,
                                       double high_percentile);
// The grey frame as BGR at display size, stretched between `contrast` for 16-bit and float.
cv::Mat DisplayGrey(const cv::Mat& frame, std::pair<double, double> contrast,
                    const DisplayLayout& layout);

// A scalar subset field over `display` (BGR, the frame at layout.scale): per-subset values of
// `frame` (NaN = invalid) interpolated by normalised convolution with a Gaussian of half a grid
// spacing, fading out 0.6..0.9 grid spacings from the nearest valid subset, coloured by `lut`
// (256 x 1 BGR) from `low` (entry 0) to `high` (entry 255, clipped beyond) with opacity `opacity`.
void BlendField(const FieldSequence& seq, std::size_t frame, const std::vector<double>& values,
                double spacing_px, const DisplayLayout& layout, const cv::Mat& lut, double low,
                double high, double opacity, cv::Mat* display);

// Time since impact (or "frame i" for NaN), top left.
void DrawTimeStamp(double t_ms, std::size_t frame, double text_scale, cv::Mat* display);
// `text` in orange, top right (e.g. "no valid subsets").
void DrawNote(const std::string& text, double text_scale, cv::Mat* display);
// A scale bar of a 1-2-5 number of mm, bottom left; nothing without a positive scale.
void DrawScaleBar(double mm_per_px, const DisplayLayout& layout, cv::Mat* display);

// A vertical colour bar for values low..high (display units) with 1-2-5 ticks, under a title of
// two lines, and optional notes under the bar; ColourBarWidth is the panel width it needs.
struct ColourBar {
  cv::Mat lut;  // 256 x 1 BGR, entry 0 at `low`
  double low = 0.0, high = 1.0;
  double step = 0.2;        // between ticks, which are at the multiples of step in [low, high]
  std::string title, unit;  // e.g. "|v|", "[mm/s]"
  std::vector<std::string> notes;  // lines under the bar
};
int ColourBarWidth(const ColourBar& bar, double text_scale);
// Into `panel` (its full height; the bar ends 3 paddings above display_height).
void DrawColourBar(const ColourBar& bar, double text_scale, int display_height, cv::Mat* panel);

// `canvas` under a header band holding `title` (centred).
cv::Mat WithTitle(const cv::Mat& canvas, const std::string& title, double text_scale);

}  // namespace impactdic::render_internal

#endif  // IMPACTDIC_SRC_RENDER_FIELD_DRAW_H_
