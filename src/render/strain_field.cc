#include "impactdic/render/strain_field.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "field_draw.h"
#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/io/image_io.h"
#include "impactdic/render/velocity_field.h"

namespace impactdic {
namespace R = render_internal;
namespace {

const cv::Scalar kPlainBackground(128, 128, 128);
constexpr const char* kTypeName = "StrainFieldSequence";

// The finite values of a field (absolute values when `absolute`) as floats, for a percentile.
std::vector<float> FiniteValues(const std::vector<double>& field, bool absolute) {
  std::vector<float> values;
  values.reserve(field.size());
  for (double v : field) {
    if (std::isfinite(v)) values.push_back(static_cast<float>(absolute ? std::abs(v) : v));
  }
  return values;
}

// A colour limit [dimensionless]: `given`, else the percentile of `field`; a small positive value
// when the field has none; rounded up to a tick of its bar in percent (*step in strain units).
double ColourLimit(double given, const std::vector<double>& field, bool absolute, double percentile,
                   int ticks, const char* name, double* step) {
  double limit = given;
  if (std::isnan(limit)) limit = R::Percentile(FiniteValues(field, absolute), percentile);
  if (!(limit > 0) || !std::isfinite(limit)) {
    LogDebug("strain field: no positive {}; colour limit 0.1 %", name);
    limit = 1e-3;
  }
  double step_percent = 0.0;
  const double top_percent = R::RoundUpToTick(100.0 * limit, ticks, &step_percent);
  *step = step_percent / 100.0;
  return top_percent / 100.0;
}

}  // namespace

void StrainFieldSequence::Check() const {
  CheckCommon(kTypeName, /*require_images=*/false);
  const std::size_t fn = num_frames() * num_subsets;
  CheckValue(eps_v.size() == fn && gamma_max.size() == fn,
             std::string(kTypeName) + ".eps_v/gamma_max",
             std::to_string(eps_v.size()) + "/" + std::to_string(gamma_max.size()) + " values",
             std::to_string(fn) + " = frames x subsets");
  CheckValue(shear_band.empty() || shear_band.size() == fn, std::string(kTypeName) + ".shear_band",
             std::to_string(shear_band.size()) + " values",
             "none or " + std::to_string(fn) + " = frames x subsets");
  CheckValue(
      plain_size.width >= 0 && plain_size.height >= 0, std::string(kTypeName) + ".plain_size",
      std::to_string(plain_size.width) + "x" + std::to_string(plain_size.height), "a size >= 0");
}

void StrainOverlayOptions::Check() const {
  CheckRange(opacity, kOverlayOpacityRange, "StrainOverlayOptions.opacity", "an opacity");
  for (const auto& [value, name] :
       {std::pair{eps_v_limit, "StrainOverlayOptions.eps_v_limit"},
        std::pair{gamma_max_limit, "StrainOverlayOptions.gamma_max_limit"}}) {
    CheckValue(std::isnan(value) || (value > 0 && std::isfinite(value)), name, R::Fmt("%g", value),
               "> 0, or NaN for automatic");
  }
  CheckRange(percentile, kPercentileRange, "StrainOverlayOptions.percentile", "a percentile");
  R::CheckDisplayOptions("StrainOverlayOptions", min_width_px, max_width_px,
                         contrast_low_percentile, contrast_high_percentile);
}

cv::Mat CoolWarmLut() {
  static const cv::Mat lut = [] {
    // Moreland's cool-warm map at 0, 1/4, 1/2, 3/4, 1 (RGB).
    constexpr std::array<std::array<double, 3>, 5> kRgb = {
        {{59, 76, 192}, {141, 176, 254}, {221, 221, 221}, {244, 154, 123}, {180, 4, 38}}};
    cv::Mat table(256, 1, CV_8UC3);
    for (int i = 0; i < 256; ++i) {
      const double t = i / 255.0 * 4.0;
      const int k = std::min(3, static_cast<int>(t));
      const double f = t - k;
      cv::Vec3b& c = table.at<cv::Vec3b>(i);
      for (int ch = 0; ch < 3; ++ch) {
        const double v = kRgb[k][ch] * (1 - f) + kRgb[k + 1][ch] * f;
        c[2 - ch] = cv::saturate_cast<unsigned char>(v);  // BGR
      }
    }
    return table;
  }();
  return lut;
}

StrainFieldRenderer::StrainFieldRenderer(const StrainFieldSequence& sequence,
                                         const StrainOverlayOptions& options)
    : seq_(sequence), options_(options) {
  seq_.Check();
  options_.Check();
  if (seq_.has_images()) {
    frame0_ = seq_.Frame(0);
    image_size_ = frame0_.size();
    const auto contrast = R::GreyContrast(frame0_, options_.contrast_low_percentile,
                                          options_.contrast_high_percentile);
    grey_low_ = contrast.first;
    grey_high_ = contrast.second;
  } else if (seq_.plain_size.area() > 0) {
    image_size_ = seq_.plain_size;
  } else {
    // The extent of the subsets with the margin left of the smallest on the far side too.
    double min_x = HUGE_VAL, min_y = HUGE_VAL, max_x = 0, max_y = 0;
    for (std::size_t i = 0; i < seq_.x_px.size(); ++i) {
      if (!std::isfinite(seq_.x_px[i]) || !std::isfinite(seq_.y_px[i])) continue;
      min_x = std::min(min_x, seq_.x_px[i]), max_x = std::max(max_x, seq_.x_px[i]);
      min_y = std::min(min_y, seq_.y_px[i]), max_y = std::max(max_y, seq_.y_px[i]);
    }
    if (!std::isfinite(min_x)) min_x = min_y = 0, max_x = max_y = 64;
    image_size_ = cv::Size(static_cast<int>(std::ceil(max_x + std::max(min_x, 1.0))),
                           static_cast<int>(std::ceil(max_y + std::max(min_y, 1.0))));
  }
  spacing_px_ = R::EstimateGridSpacing(seq_, image_size_);
  eps_v_limit_ = ColourLimit(options_.eps_v_limit, seq_.eps_v, /*absolute=*/true,
                             options_.percentile, 3, "|eps_v|", &eps_v_step_);
  gamma_max_limit_ = ColourLimit(options_.gamma_max_limit, seq_.gamma_max, /*absolute=*/false,
                                 options_.percentile, 5, "gamma_max", &gamma_max_step_);
  has_shear_band_ = options_.shear_bands && !seq_.shear_band.empty();
  const R::DisplayLayout layout =
      R::LayoutDisplay(image_size_, options_.min_width_px, options_.max_width_px);
  scale_ = layout.scale;
  display_size_ = layout.size;
  text_scale_ = layout.text_scale;
  bar_width_ = 0;
  for (int panel = 0; panel < 2; ++panel) {
    R::ColourBar bar;
    // The bar's text only (no colours) sets the width.
    bar.low = panel == 0 ? -100 * eps_v_limit_ : 0.0;
    bar.high = 100 * (panel == 0 ? eps_v_limit_ : gamma_max_limit_);
    bar.step = 100 * (panel == 0 ? eps_v_step_ : gamma_max_step_);
    bar.unit = "[%]";
    bar.notes = {"99th pct", "compression +", "o shear band"};
    bar_width_ = std::max(bar_width_, R::ColourBarWidth(bar, text_scale_));
  }
  canvas_size_ = cv::Size(R::RoundUp8(2 * (display_size_.width + bar_width_)),
                          R::RoundUp8(display_size_.height));
}

cv::Point2d StrainFieldRenderer::CanvasPoint(int panel, std::size_t frame,
                                             std::size_t subset) const {
  const double x0 = panel == 0 ? 0.0 : display_size_.width + bar_width_;
  return {x0 + seq_.x(frame, subset) * scale_, seq_.y(frame, subset) * scale_};
}

cv::Rect StrainFieldRenderer::ColourBarRect(int panel) const {
  const int x0 = panel == 0 ? display_size_.width : 2 * display_size_.width + bar_width_;
  const int width = panel == 0 ? bar_width_ : canvas_size_.width - x0;
  return {x0, 0, width, canvas_size_.height};
}

cv::Mat StrainFieldRenderer::Background(std::size_t frame) const {
  if (!seq_.has_images()) return cv::Mat(display_size_, CV_8UC3, kPlainBackground);
  const cv::Mat src = frame == 0 ? frame0_ : seq_.Frame(frame);
  if (seq_.frames.empty()) CheckFieldFrame(src, frame0_, frame, kTypeName);
  return R::DisplayGrey(src, {grey_low_, grey_high_},
                        {image_size_, scale_, display_size_, text_scale_});
}

void StrainFieldRenderer::DrawPanel(int panel, std::size_t frame, cv::Mat* canvas) const {
  const std::size_t n = seq_.num_subsets;
  const std::vector<double>& field = panel == 0 ? seq_.eps_v : seq_.gamma_max;
  const std::vector<double> values(field.begin() + frame * n, field.begin() + (frame + 1) * n);
  const R::DisplayLayout layout{image_size_, scale_, display_size_, text_scale_};
  const int x0 = panel == 0 ? 0 : display_size_.width + bar_width_;
  cv::Mat display = (*canvas)(cv::Rect(x0, 0, display_size_.width, display_size_.height));
  Background(frame).copyTo(display);
  R::ColourBar bar;
  bar.unit = "[%]";
  bar.notes = {std::isnan(panel == 0 ? options_.eps_v_limit : options_.gamma_max_limit)
                   ? R::Fmt("%g", options_.percentile) + "th pct"
                   : std::string("fixed")};
  if (panel == 0) {
    bar.lut = CoolWarmLut();
    bar.low = -100 * eps_v_limit_;
    bar.high = 100 * eps_v_limit_;
    bar.step = 100 * eps_v_step_;
    bar.title = "eps_v";
    bar.notes.emplace_back("compression +");
  } else {
    bar.lut = ViridisLut();
    bar.high = 100 * gamma_max_limit_;
    bar.step = 100 * gamma_max_step_;
    bar.title = "gamma_max";
    if (has_shear_band_) bar.notes.emplace_back("o shear band");
  }
  R::BlendField(seq_, frame, values, spacing_px_, layout, bar.lut, bar.low / 100, bar.high / 100,
                options_.opacity, &display);
  if (panel == 1 && has_shear_band_) {
    const int radius = std::max(2, static_cast<int>(std::lround(0.15 * spacing_px_ * scale_)));
    for (std::size_t s = 0; s < n; ++s) {
      const double band = seq_.shear_band[frame * n + s];
      const cv::Point2d p(seq_.x(frame, s) * scale_, seq_.y(frame, s) * scale_);
      if (!(band != 0 && std::isfinite(band)) || !std::isfinite(p.x) || !std::isfinite(p.y))
        continue;
      const cv::Point c(static_cast<int>(std::lround(p.x)), static_cast<int>(std::lround(p.y)));
      cv::circle(display, c, radius + 1, R::kBlack, cv::FILLED, cv::LINE_AA);
      cv::circle(display, c, radius, R::kWhite, cv::FILLED, cv::LINE_AA);
    }
  }
  if (std::none_of(values.begin(), values.end(), [](double v) { return std::isfinite(v); }))
    R::DrawNote("no valid subsets", text_scale_, &display);
  if (panel == 0) {
    R::DrawTimeStamp(seq_.time_ms[frame], frame, text_scale_, &display);
    R::DrawScaleBar(seq_.mm_per_px, layout, &display);
  }
  cv::Mat bar_panel = (*canvas)(ColourBarRect(panel));
  R::DrawColourBar(bar, text_scale_, display_size_.height, &bar_panel);
}

cv::Mat StrainFieldRenderer::RenderFrame(std::size_t frame, const std::string& title) const {
  CheckValue(frame < seq_.num_frames(), "strain field frame", std::to_string(frame),
             "< " + std::to_string(seq_.num_frames()));
  cv::Mat canvas(canvas_size_, CV_8UC3, R::kPanelColor);
  DrawPanel(0, frame, &canvas);
  DrawPanel(1, frame, &canvas);
  return title.empty() ? canvas : R::WithTitle(canvas, title, text_scale_);
}

cv::Size RenderStrainSnapshot(const StrainFieldSequence& sequence, std::size_t frame,
                              const std::string& png_path, const StrainOverlayOptions& options,
                              const std::string& title) {
  const StrainFieldRenderer renderer(sequence, options);
  const cv::Mat image = renderer.RenderFrame(frame, title);
  WriteImage(png_path, image);
  return image.size();
}

}  // namespace impactdic
