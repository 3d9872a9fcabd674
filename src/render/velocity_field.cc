#include "impactdic/render/velocity_field.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>
#include <unordered_map>
#include <utility>

#include "field_draw.h"
#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/io/image_io.h"

namespace impactdic {
using render_internal::BlendField;
using render_internal::ColourBar;
using render_internal::ColourBarWidth;
using render_internal::DisplayLayout;
using render_internal::DrawColourBar;
using render_internal::DrawNote;
using render_internal::DrawScaleBar;
using render_internal::DrawTimeStamp;
using render_internal::EstimateGridSpacing;
using render_internal::Fmt;
using render_internal::GreyContrast;
using render_internal::kBlack;
using render_internal::kFont;
using render_internal::kPanelColor;
using render_internal::kWhite;
using render_internal::LayoutDisplay;
using render_internal::NiceFloor;
using render_internal::Percentile;
using render_internal::RoundUp8;
using render_internal::RoundUpToTick;
using render_internal::ShadeRect;
using render_internal::TextPad;
using render_internal::TextThickness;
using render_internal::TickLabel;
using render_internal::WithTitle;

const char* ToString(VelocityDisplayUnit unit) {
  switch (unit) {
    case VelocityDisplayUnit::kAuto: return "auto";
    case VelocityDisplayUnit::kMmPerS: return "mm/s";
    case VelocityDisplayUnit::kMPerS: return "m/s";
  }
  return "?";
}

VelocityDisplayUnit VelocityDisplayUnitFromString(const std::string& text) {
  for (auto u :
       {VelocityDisplayUnit::kAuto, VelocityDisplayUnit::kMmPerS, VelocityDisplayUnit::kMPerS}) {
    if (text == ToString(u)) return u;
  }
  throw Error(ErrorKind::kInvalidValue, "velocity unit", text, "one of auto, mm/s, m/s");
}

void VelocityFieldSequence::Check() const {
  CheckCommon("VelocityFieldSequence", /*require_images=*/true);
  const std::size_t n = num_subsets, f = num_frames();
  CheckValue(vx_mm_s.size() == f * n && vy_mm_s.size() == f * n,
             "VelocityFieldSequence.vx_mm_s/vy_mm_s",
             std::to_string(vx_mm_s.size()) + "/" + std::to_string(vy_mm_s.size()) + " values",
             std::to_string(f * n) + " = frames x subsets");
}

void VelocityOverlayOptions::Check() const {
  CheckRange(opacity, kOverlayOpacityRange, "VelocityOverlayOptions.opacity", "an opacity");
  CheckValue(std::isnan(max_speed_mm_s) || (max_speed_mm_s > 0 && std::isfinite(max_speed_mm_s)),
             "VelocityOverlayOptions.max_speed_mm_s", Fmt("%g", max_speed_mm_s),
             "> 0, or NaN for automatic");
  CheckRange(arrow_spacing_display_px, kArrowSpacingRange,
             "VelocityOverlayOptions.arrow_spacing_display_px", "an arrow spacing");
  render_internal::CheckDisplayOptions("VelocityOverlayOptions", min_width_px, max_width_px,
                                       contrast_low_percentile, contrast_high_percentile);
}

cv::Mat ViridisLut() {
  static const cv::Mat lut = [] {
    cv::Mat ramp(256, 1, CV_8UC1);
    for (int i = 0; i < 256; ++i) ramp.at<unsigned char>(i) = static_cast<unsigned char>(i);
    cv::Mat colored;
    cv::applyColorMap(ramp, colored, cv::COLORMAP_VIRIDIS);
    return colored;
  }();
  return lut;
}

double NiceStep(double span, int target_ticks) {
  if (!(span > 0) || !std::isfinite(span) || target_ticks < 1) return 1.0;
  const double raw = span / target_ticks;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double r = raw / mag;
  const double nice = r < 1.5 ? 1 : r < 3 ? 2 : r < 7 ? 5 : 10;
  return nice * mag;
}

VelocityFieldRenderer::VelocityFieldRenderer(const VelocityFieldSequence& sequence,
                                             const VelocityOverlayOptions& options)
    : seq_(sequence), options_(options), lut_(ViridisLut()) {
  seq_.Check();
  options_.Check();
  frame0_ = seq_.Frame(0);
  spacing_px_ = EstimateGridSpacing(seq_, frame0_.size());
  SetColourScale();
  SetLayout();
  ChooseArrowSubsets();
  const auto contrast =
      GreyContrast(frame0_, options_.contrast_low_percentile, options_.contrast_high_percentile);
  grey_low_ = contrast.first;
  grey_high_ = contrast.second;
}

void VelocityFieldRenderer::SetColourScale() {
  const std::size_t n = seq_.num_subsets, f = seq_.num_frames();
  // Colour scale: one for the whole sequence.
  std::vector<float> speeds;
  speeds.reserve(f * n);
  for (std::size_t i = 0; i < f * n; ++i) {
    const double v = std::hypot(seq_.vx_mm_s[i], seq_.vy_mm_s[i]);
    if (std::isfinite(v)) speeds.push_back(static_cast<float>(v));
  }
  valid_speeds_ = speeds.size();
  double top = options_.max_speed_mm_s;
  if (std::isnan(top)) top = Percentile(std::move(speeds), 99.0);  // One array of f x n speeds.
  if (!(top > 0) || !std::isfinite(top)) {
    LogDebug("velocity field: no positive speed; colour scale 0..1 mm/s");
    top = 1.0;
  }
  // Round the top up to a multiple of a nice tick step, so the bar ends on a labelled tick.
  color_max_mm_s_ = RoundUpToTick(top, 5);
  const bool metres = options_.unit == VelocityDisplayUnit::kMPerS ||
                      (options_.unit == VelocityDisplayUnit::kAuto && color_max_mm_s_ >= 1000.0);
  unit_factor_ = metres ? 1e-3 : 1.0;
  unit_label_ = metres ? "m/s" : "mm/s";
  reference_speed_mm_s_ = NiceFloor(0.8 * color_max_mm_s_ * unit_factor_) / unit_factor_;
}

namespace {

// The colour bar of a renderer's speeds (display units).
ColourBar SpeedBar(double top_display, const std::string& unit_label, const cv::Mat& lut) {
  ColourBar bar;
  bar.lut = lut;
  bar.high = top_display;
  bar.step = NiceStep(top_display, 5);
  bar.title = "|v|";
  bar.unit = "[" + unit_label + "]";
  return bar;
}

}  // namespace

void VelocityFieldRenderer::SetLayout() {
  const DisplayLayout layout =
      LayoutDisplay(frame0_.size(), options_.min_width_px, options_.max_width_px);
  scale_ = layout.scale;
  display_size_ = layout.size;
  text_scale_ = layout.text_scale;
  // Panel width from the widest tick label or unit title.
  panel_width_ =
      ColourBarWidth(SpeedBar(color_max_mm_s_ * unit_factor_, unit_label_, lut_), text_scale_);
  canvas_size_ =
      cv::Size(RoundUp8(display_size_.width + panel_width_), RoundUp8(display_size_.height));
  panel_width_ = canvas_size_.width - display_size_.width;
}

void VelocityFieldRenderer::ChooseArrowSubsets() {
  const std::size_t n = seq_.num_subsets;
  // Arrows: every k-th subset along each grid direction, k chosen so that arrows are at least
  // arrow_spacing_display_px apart; cells of k x k grid spacings anchored at the grid's corner so
  // that a regular grid is thinned regularly. The selection uses frame 0, so the same subsets
  // carry arrows in every frame. The colour-scale top gets an arrow one cell long.
  const double g = spacing_px_ * scale_;
  const double k = std::max(1.0, std::ceil(options_.arrow_spacing_display_px / g - 1e-9));
  const double cell = k * g;
  arrow_px_per_mm_s_ = cell / color_max_mm_s_;
  double min_x = HUGE_VAL, min_y = HUGE_VAL;
  for (std::size_t s = 0; s < n; ++s) {
    if (std::isfinite(seq_.x(0, s)) && std::isfinite(seq_.y(0, s))) {
      min_x = std::min(min_x, seq_.x(0, s) * scale_);
      min_y = std::min(min_y, seq_.y(0, s) * scale_);
    }
  }
  const double ox = min_x - 0.5 * g, oy = min_y - 0.5 * g;
  std::unordered_map<long long, std::pair<std::size_t, double>> chosen;
  for (std::size_t s = 0; s < n; ++s) {
    const double xd = seq_.x(0, s) * scale_, yd = seq_.y(0, s) * scale_;
    if (!std::isfinite(xd) || !std::isfinite(yd)) continue;
    const long long cx = static_cast<long long>(std::floor((xd - ox) / cell));
    const long long cy = static_cast<long long>(std::floor((yd - oy) / cell));
    const double d = std::hypot(xd - (ox + (cx + 0.5) * cell), yd - (oy + (cy + 0.5) * cell));
    const long long key = cy * 1000003LL + cx;
    auto it = chosen.find(key);
    if (it == chosen.end() || d < it->second.second - 1e-9) chosen[key] = {s, d};
  }
  for (const auto& entry : chosen) arrow_subsets_.push_back(entry.second.first);
  std::sort(arrow_subsets_.begin(), arrow_subsets_.end());  // deterministic drawing order
}

cv::Mat VelocityFieldRenderer::DisplayGrey(std::size_t frame) const {
  const cv::Mat src = frame == 0 ? frame0_ : seq_.Frame(frame);
  if (seq_.frames.empty()) CheckFieldFrame(src, frame0_, frame, "VelocityFieldSequence");
  return render_internal::DisplayGrey(src, {grey_low_, grey_high_},
                                      {frame0_.size(), scale_, display_size_, text_scale_});
}

void VelocityFieldRenderer::DrawField(std::size_t frame, cv::Mat* display) const {
  const std::size_t n = seq_.num_subsets;
  std::vector<double> speed(n);
  for (std::size_t s = 0; s < n; ++s)
    speed[s] = std::hypot(seq_.vx_mm_s[frame * n + s], seq_.vy_mm_s[frame * n + s]);
  BlendField(seq_, frame, speed, spacing_px_, {frame0_.size(), scale_, display_size_, text_scale_},
             lut_, 0.0, color_max_mm_s_, options_.opacity, display);
}

void VelocityFieldRenderer::DrawArrows(std::size_t frame, cv::Mat* display) const {
  const std::size_t n = seq_.num_subsets;
  const int thick = std::max(1, int(std::lround(text_scale_ * 1.6)));
  const double sign = seq_.vy_positive_down ? 1.0 : -1.0;
  for (std::size_t s : arrow_subsets_) {
    const double vx = seq_.vx_mm_s[frame * n + s], vy = sign * seq_.vy_mm_s[frame * n + s];
    const double len = std::hypot(vx, vy) * arrow_px_per_mm_s_;
    const cv::Point2d p0(seq_.x(frame, s) * scale_, seq_.y(frame, s) * scale_);
    // NaN velocity or position: no arrow (the comparisons are false for NaN).
    if (!(len >= 2.0) || !std::isfinite(p0.x) || !std::isfinite(p0.y)) continue;
    if (std::abs(p0.x) > 1e6 || std::abs(p0.y) > 1e6 || len > 1e6) continue;
    const cv::Point2d p1 = p0 + cv::Point2d(vx, vy) * arrow_px_per_mm_s_;
    const double tip = std::min(0.4, 9.0 * text_scale_ / 0.7 / len);
    constexpr int kShift = 4;  // sub-pixel endpoints
    const cv::Point q0(int(std::lround(p0.x * 16)), int(std::lround(p0.y * 16)));
    const cv::Point q1(int(std::lround(p1.x * 16)), int(std::lround(p1.y * 16)));
    cv::arrowedLine(*display, q0, q1, kBlack, thick + 2, cv::LINE_AA, kShift, tip);
    cv::arrowedLine(*display, q0, q1, kWhite, thick, cv::LINE_AA, kShift, tip);
  }
}

void VelocityFieldRenderer::DrawDecorations(std::size_t frame, cv::Mat* canvas) const {
  const double ts = text_scale_;
  const int thick = TextThickness(ts), pad = TextPad(ts);
  int baseline = 0;
  cv::Mat display = (*canvas)(cv::Rect(0, 0, display_size_.width, display_size_.height));
  DrawTimeStamp(seq_.time_ms[frame], frame, ts, &display);
  // "no valid subsets" note, top right, when this frame has none.
  const std::size_t n = seq_.num_subsets;
  bool any = false;
  for (std::size_t s = 0; s < n && !any; ++s) {
    any = std::isfinite(std::hypot(seq_.vx_mm_s[frame * n + s], seq_.vy_mm_s[frame * n + s]));
  }
  if (!any) DrawNote("no valid subsets", ts, &display);
  DrawScaleBar(seq_.mm_per_px, {frame0_.size(), scale_, display_size_, text_scale_}, &display);
  // Reference arrow, bottom right.
  if (options_.arrows) {
    const double ref_display = reference_speed_mm_s_ * unit_factor_;
    const std::string text = TickLabel(ref_display, NiceFloor(ref_display)) + " " + unit_label_;
    const cv::Size sz = cv::getTextSize(text, kFont, ts, thick, &baseline);
    const int len = int(std::lround(reference_speed_mm_s_ * arrow_px_per_mm_s_));
    const int box_w = std::max(len, sz.width) + 2 * pad;
    const int box_h = sz.height + 4 * pad;
    const int x0 = display.cols - box_w - pad / 2, y0 = display.rows - box_h - pad / 2;
    ShadeRect(&display, cv::Rect(x0, y0, box_w, box_h), kBlack, 0.55);
    cv::putText(display, text, cv::Point(x0 + (box_w - sz.width) / 2, y0 + pad + sz.height), kFont,
                ts, kWhite, thick, cv::LINE_AA);
    const int ay = y0 + 2 * pad + sz.height + pad / 2;
    const int ax = x0 + (box_w - len) / 2;
    const int athick = std::max(1, int(std::lround(ts * 1.6)));
    const double tip = std::min(0.4, 9.0 * ts / 0.7 / std::max(len, 1));
    cv::arrowedLine(display, {ax, ay}, {ax + len, ay}, kWhite, athick, cv::LINE_AA, 0, tip);
  }

  // Colour bar panel on the right.
  cv::Mat panel = (*canvas)(cv::Rect(display_size_.width, 0, panel_width_, canvas_size_.height));
  DrawColourBar(SpeedBar(color_max_mm_s_ * unit_factor_, unit_label_, lut_), ts,
                display_size_.height, &panel);
}

cv::Mat VelocityFieldRenderer::RenderFrame(std::size_t frame, const std::string& title) const {
  CheckValue(frame < seq_.num_frames(), "velocity field frame", std::to_string(frame),
             "< " + std::to_string(seq_.num_frames()));
  cv::Mat canvas(canvas_size_, CV_8UC3, kPanelColor);
  cv::Mat display = canvas(cv::Rect(0, 0, display_size_.width, display_size_.height));
  DisplayGrey(frame).copyTo(display);
  DrawField(frame, &display);
  if (options_.arrows) DrawArrows(frame, &display);
  DrawDecorations(frame, &canvas);
  return title.empty() ? canvas : WithTitle(canvas, title, text_scale_);
}

cv::Size RenderVelocitySnapshot(const VelocityFieldSequence& sequence, std::size_t frame,
                                const std::string& png_path, const VelocityOverlayOptions& options,
                                const std::string& title) {
  VelocityFieldRenderer renderer(sequence, options);
  const cv::Mat image = renderer.RenderFrame(frame, title);
  WriteImage(png_path, image);
  return image.size();
}

}  // namespace impactdic
