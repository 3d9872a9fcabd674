#include "impactdic/render/velocity_field.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>
#include <unordered_map>
#include <utility>

#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/io/image_io.h"

namespace impactdic {
namespace {

constexpr int kFont = cv::FONT_HERSHEY_DUPLEX;
const cv::Scalar kPanelColor(32, 32, 32);
const cv::Scalar kWhite(255, 255, 255);
const cv::Scalar kBlack(0, 0, 0);

std::string Fmt(const char* format, double value) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, value);
  return buf;
}

// Largest 1, 2 or 5 times a power of ten that is <= value (value > 0).
double NiceFloor(double value) {
  if (!(value > 0) || !std::isfinite(value)) return 1.0;
  const double mag = std::pow(10.0, std::floor(std::log10(value)));
  const double r = value / mag;
  const double nice = r >= 5 ? 5 : r >= 2 ? 2 : 1;
  return nice * mag;
}

// Tick label with as many decimals as the step needs.
std::string TickLabel(double value, double step) {
  const int decimals = std::max(0, static_cast<int>(-std::floor(std::log10(step) + 1e-9)));
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, value);
  return buf;
}

int RoundUpEven(int v) { return v + (v & 1); }
int RoundUp8(int v) { return (v + 7) / 8 * 8; }

// Blends a filled rectangle of `color` with opacity `alpha` into img (clipped).
void ShadeRect(cv::Mat* img, cv::Rect rect, const cv::Scalar& color, double alpha) {
  rect &= cv::Rect(0, 0, img->cols, img->rows);
  if (rect.area() <= 0) return;
  cv::Mat roi = (*img)(rect);
  cv::Mat fill(roi.size(), roi.type(), color);
  cv::addWeighted(fill, alpha, roi, 1.0 - alpha, 0.0, roi);
}

double Percentile(std::vector<float> values, double percent) {
  if (values.empty()) return 0.0;
  const std::size_t k =
      std::min(values.size() - 1,
               static_cast<std::size_t>(std::lround(percent / 100.0 * (values.size() - 1))));
  std::nth_element(values.begin(), values.begin() + k, values.end());
  return values[k];
}

}  // namespace

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

namespace {

void CheckFrame(const cv::Mat& m, const cv::Mat& first, std::size_t i) {
  CheckValue(!m.empty() && m.dims == 2, "VelocityFieldSequence.frames[" + std::to_string(i) + "]",
             "an empty image", "a 2-D grey image");
  CheckValue(m.type() == CV_8UC1 || m.type() == CV_16UC1 || m.type() == CV_32FC1,
             "VelocityFieldSequence.frames[" + std::to_string(i) + "]",
             "OpenCV type " + std::to_string(m.type()), "CV_8UC1, CV_16UC1 or CV_32FC1");
  CheckValue(m.size() == first.size() && m.type() == first.type(),
             "VelocityFieldSequence.frames[" + std::to_string(i) + "]",
             std::to_string(m.cols) + "x" + std::to_string(m.rows), "the size and type of frame 0");
}

}  // namespace

cv::Mat VelocityFieldSequence::Frame(std::size_t i) const {
  if (!frames.empty() || !load_frame) return frames.at(i);
  cv::Mat m = load_frame(i);
  CheckFrame(m, m, i);
  return m;
}

void VelocityFieldSequence::Check() const {
  const std::size_t n = num_subsets, f = num_frames();
  CheckValue(f > 0, "VelocityFieldSequence.frames", "no frames", "at least one frame");
  if (frames.empty()) CheckFrame(Frame(0), Frame(0), 0);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const cv::Mat& m = frames[i];
    CheckValue(!m.empty() && m.dims == 2, "VelocityFieldSequence.frames[" + std::to_string(i) + "]",
               "an empty image", "a 2-D grey image");
    CheckValue(m.type() == CV_8UC1 || m.type() == CV_16UC1 || m.type() == CV_32FC1,
               "VelocityFieldSequence.frames[" + std::to_string(i) + "]",
               "OpenCV type " + std::to_string(m.type()), "CV_8UC1, CV_16UC1 or CV_32FC1");
    CheckValue(m.size() == frames[0].size() && m.type() == frames[0].type(),
               "VelocityFieldSequence.frames[" + std::to_string(i) + "]",
               std::to_string(m.cols) + "x" + std::to_string(m.rows),
               "the size and type of frame 0");
  }
  CheckValue(time_ms.size() == f, "VelocityFieldSequence.time_ms",
             std::to_string(time_ms.size()) + " values", std::to_string(f) + " (one per frame)");
  CheckValue(x_px.size() == y_px.size() && (x_px.size() == n || x_px.size() == f * n),
             "VelocityFieldSequence.x_px/y_px",
             std::to_string(x_px.size()) + "/" + std::to_string(y_px.size()) + " values",
             std::to_string(n) + " (fixed) or " + std::to_string(f * n) + " (per frame)");
  CheckValue(vx_mm_s.size() == f * n && vy_mm_s.size() == f * n,
             "VelocityFieldSequence.vx_mm_s/vy_mm_s",
             std::to_string(vx_mm_s.size()) + "/" + std::to_string(vy_mm_s.size()) + " values",
             std::to_string(f * n) + " = frames x subsets");
}

void VelocityOverlayOptions::Check() const {
  CheckValue(opacity >= 0 && opacity <= 1, "VelocityOverlayOptions.opacity", Fmt("%g", opacity),
             "0..1");
  CheckValue(std::isnan(max_speed_mm_s) || (max_speed_mm_s > 0 && std::isfinite(max_speed_mm_s)),
             "VelocityOverlayOptions.max_speed_mm_s", Fmt("%g", max_speed_mm_s),
             "> 0, or NaN for automatic");
  CheckValue(arrow_spacing_display_px >= 4 && arrow_spacing_display_px <= 500,
             "VelocityOverlayOptions.arrow_spacing_display_px", Fmt("%g", arrow_spacing_display_px),
             "4..500");
  CheckValue(min_width_px >= 160 && min_width_px <= 8000, "VelocityOverlayOptions.min_width_px",
             std::to_string(min_width_px), "160..8000");
  CheckValue(max_width_px >= min_width_px && max_width_px <= 8000,
             "VelocityOverlayOptions.max_width_px", std::to_string(max_width_px),
             "min_width_px..8000");
  CheckValue(contrast_low_percentile >= 0 && contrast_high_percentile <= 100 &&
                 contrast_low_percentile < contrast_high_percentile,
             "VelocityOverlayOptions.contrast_low_percentile/contrast_high_percentile",
             Fmt("%g", contrast_low_percentile) + "/" + Fmt("%g", contrast_high_percentile),
             "0 <= low < high <= 100");
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

std::size_t FrameNearestTime(const VelocityFieldSequence& sequence, double t_ms) {
  std::size_t best = 0;
  double best_d = HUGE_VAL;
  for (std::size_t i = 0; i < sequence.time_ms.size(); ++i) {
    const double d = std::abs(sequence.time_ms[i] - t_ms);
    if (std::isfinite(d) && d < best_d) {
      best_d = d;
      best = i;
    }
  }
  return best;
}

VelocityFieldRenderer::VelocityFieldRenderer(const VelocityFieldSequence& sequence,
                                             const VelocityOverlayOptions& options)
    : seq_(sequence), options_(options), lut_(ViridisLut()) {
  seq_.Check();
  options_.Check();
  frame0_ = seq_.Frame(0);
  EstimateGridSpacing();
  SetColourScale();
  SetLayout();
  ChooseArrowSubsets();
  SetGreyContrast();
}

void VelocityFieldRenderer::EstimateGridSpacing() {
  const cv::Size image = frame0_.size();
  const std::size_t n = seq_.num_subsets;
  // Grid spacing: median nearest-neighbour distance of (up to 256) subsets of frame 0.
  std::vector<cv::Point2d> pts;
  for (std::size_t s = 0; s < n; ++s) {
    const double x = seq_.x(0, s), y = seq_.y(0, s);
    if (std::isfinite(x) && std::isfinite(y)) pts.emplace_back(x, y);
  }
  std::vector<double> nn;
  const std::size_t stride = std::max<std::size_t>(1, pts.size() / 256);
  for (std::size_t i = 0; i < pts.size(); i += stride) {
    double best = HUGE_VAL;
    for (std::size_t j = 0; j < pts.size(); ++j) {
      if (j == i) continue;
      const double d = std::hypot(pts[i].x - pts[j].x, pts[i].y - pts[j].y);
      if (d > 1e-6) best = std::min(best, d);
    }
    if (std::isfinite(best)) nn.push_back(best);
  }
  if (!nn.empty()) {
    std::nth_element(nn.begin(), nn.begin() + nn.size() / 2, nn.end());
    spacing_px_ = nn[nn.size() / 2];
  } else {
    spacing_px_ = std::max(8.0, std::min(image.width, image.height) / 12.0);
  }
  spacing_px_ = std::clamp(spacing_px_, 2.0, 0.5 * std::max(image.width, image.height));
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
  const double step = NiceStep(top, 5);
  color_max_mm_s_ = std::ceil(top / step - 1e-9) * step;
  const bool metres = options_.unit == VelocityDisplayUnit::kMPerS ||
                      (options_.unit == VelocityDisplayUnit::kAuto && color_max_mm_s_ >= 1000.0);
  unit_factor_ = metres ? 1e-3 : 1.0;
  unit_label_ = metres ? "m/s" : "mm/s";
  reference_speed_mm_s_ = NiceFloor(0.8 * color_max_mm_s_ * unit_factor_) / unit_factor_;
}

void VelocityFieldRenderer::SetLayout() {
  const cv::Size image = frame0_.size();
  // Display size.
  scale_ = 1.0;
  if (image.width < options_.min_width_px) scale_ = double(options_.min_width_px) / image.width;
  if (image.width > options_.max_width_px) scale_ = double(options_.max_width_px) / image.width;
  display_size_ = cv::Size(std::max(2, int(std::lround(image.width * scale_))),
                           std::max(2, int(std::lround(image.height * scale_))));
  text_scale_ = std::clamp(display_size_.height / 720.0 * 0.7, 0.45, 1.5);

  // Panel width from the widest tick label or unit title.
  const int thick = std::max(1, int(std::lround(text_scale_ * 1.4)));
  int widest = 0, baseline = 0;
  const double tick_step = NiceStep(color_max_mm_s_ * unit_factor_, 5);
  for (double v = 0; v <= color_max_mm_s_ * unit_factor_ * (1 + 1e-9); v += tick_step) {
    widest = std::max(
        widest,
        cv::getTextSize(TickLabel(v, tick_step), kFont, text_scale_, thick, &baseline).width);
  }
  const int title_w =
      cv::getTextSize("[" + unit_label_ + "]", kFont, text_scale_, thick, &baseline).width;
  const int bar_w = int(std::lround(28 * text_scale_ / 0.7));
  panel_width_ = std::max(title_w + int(30 * text_scale_), bar_w + widest + int(60 * text_scale_));
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

void VelocityFieldRenderer::SetGreyContrast() {
  // Grey contrast for 16-bit and float frames, from frame 0.
  if (frame0_.type() != CV_8UC1) {
    cv::Mat as_float;
    frame0_.convertTo(as_float, CV_32F);
    std::vector<float> sample;
    const std::size_t total = as_float.total();
    const std::size_t sample_stride = std::max<std::size_t>(1, total / 200000);
    const float* p = as_float.ptr<float>();  // convertTo output is continuous
    for (std::size_t i = 0; i < total; i += sample_stride) {
      if (std::isfinite(p[i])) sample.push_back(p[i]);
    }
    grey_low_ = Percentile(sample, options_.contrast_low_percentile);
    grey_high_ = Percentile(sample, options_.contrast_high_percentile);
    if (!(grey_high_ > grey_low_)) grey_high_ = grey_low_ + 1.0;
  }
}

cv::Mat VelocityFieldRenderer::DisplayGrey(std::size_t frame) const {
  cv::Mat grey8;
  const cv::Mat src = frame == 0 ? frame0_ : seq_.Frame(frame);
  if (seq_.frames.empty()) CheckFrame(src, frame0_, frame);  // A loaded frame.
  if (src.type() == CV_8UC1) {
    grey8 = src;
  } else {
    const double alpha = 255.0 / (grey_high_ - grey_low_);
    src.convertTo(grey8, CV_8U, alpha, -grey_low_ * alpha);  // saturating
  }
  cv::Mat resized;
  cv::resize(grey8, resized, display_size_, 0, 0, scale_ < 1 ? cv::INTER_AREA : cv::INTER_LINEAR);
  cv::Mat bgr;
  cv::cvtColor(resized, bgr, cv::COLOR_GRAY2BGR);
  return bgr;
}

void VelocityFieldRenderer::DrawField(std::size_t frame, cv::Mat* display) const {
  const cv::Size image = frame0_.size();
  const std::size_t n = seq_.num_subsets;
  // Work grid of cells of about a quarter subset spacing.
  const double cell = std::max(1.0, spacing_px_ / 4.0);
  const int gw = std::max(1, int(std::ceil(image.width / cell)));
  const int gh = std::max(1, int(std::ceil(image.height / cell)));
  cv::Mat num(gh, gw, CV_32F, cv::Scalar(0)), den(gh, gw, CV_32F, cv::Scalar(0));
  cv::Mat far_from_data(gh, gw, CV_8U, cv::Scalar(255));
  int valid = 0;
  for (std::size_t s = 0; s < n; ++s) {
    const double speed = std::hypot(seq_.vx_mm_s[frame * n + s], seq_.vy_mm_s[frame * n + s]);
    const double gx = seq_.x(frame, s) / cell - 0.5, gy = seq_.y(frame, s) / cell - 0.5;
    if (!std::isfinite(speed) || !std::isfinite(gx) || !std::isfinite(gy)) continue;
    if (gx < -1 || gy < -1 || gx > gw || gy > gh) continue;
    ++valid;
    // Bilinear splat of value and weight.
    const int x0 = int(std::floor(gx)), y0 = int(std::floor(gy));
    const double fx = gx - x0, fy = gy - y0;
    for (int dy = 0; dy <= 1; ++dy) {
      for (int dx = 0; dx <= 1; ++dx) {
        const int xx = x0 + dx, yy = y0 + dy;
        if (xx < 0 || yy < 0 || xx >= gw || yy >= gh) continue;
        const float w = float((dx ? fx : 1 - fx) * (dy ? fy : 1 - fy));
        num.at<float>(yy, xx) += w * float(speed);
        den.at<float>(yy, xx) += w;
      }
    }
    const int cx = std::clamp(int(std::lround(gx)), 0, gw - 1);
    const int cy = std::clamp(int(std::lround(gy)), 0, gh - 1);
    far_from_data.at<unsigned char>(cy, cx) = 0;
  }
  if (valid == 0) return;
  // Normalised convolution with a Gaussian of half a grid spacing.
  const double sigma = 0.5 * spacing_px_ / cell;
  cv::GaussianBlur(num, num, cv::Size(), sigma, sigma, cv::BORDER_CONSTANT);
  cv::GaussianBlur(den, den, cv::Size(), sigma, sigma, cv::BORDER_CONSTANT);
  cv::Mat dist;
  cv::distanceTransform(far_from_data, dist, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  cv::Mat value(gh, gw, CV_32F), alpha(gh, gw, CV_32F);
  const float full = float(0.6 * spacing_px_ / cell), zero = float(0.9 * spacing_px_ / cell);
  for (int y = 0; y < gh; ++y) {
    for (int x = 0; x < gw; ++x) {
      const float d = den.at<float>(y, x);
      value.at<float>(y, x) = d > 1e-12f ? num.at<float>(y, x) / d : 0.f;
      const float r = dist.at<float>(y, x);
      const float a = d > 1e-12f ? std::clamp((zero - r) / (zero - full), 0.f, 1.f) : 0.f;
      alpha.at<float>(y, x) = a * float(options_.opacity);
    }
  }
  // To display resolution: cell (i, j) covers image pixels [j*cell, (j+1)*cell).
  cv::Mat value_d, alpha_d;
  const cv::Size covered(int(std::lround(gw * cell * scale_)),
                         int(std::lround(gh * cell * scale_)));
  cv::resize(value, value_d, covered, 0, 0, cv::INTER_LINEAR);
  cv::resize(alpha, alpha_d, covered, 0, 0, cv::INTER_LINEAR);
  const float to_index = float(255.0 / color_max_mm_s_);
  const int rows = std::min(display->rows, covered.height);
  const int cols = std::min(display->cols, covered.width);
  for (int y = 0; y < rows; ++y) {
    cv::Vec3b* out = display->ptr<cv::Vec3b>(y);
    const float* v = value_d.ptr<float>(y);
    const float* a = alpha_d.ptr<float>(y);
    for (int x = 0; x < cols; ++x) {
      if (a[x] <= 0.f) continue;
      const int idx = std::clamp(static_cast<int>(std::lroundf(v[x] * to_index)), 0, 255);
      const cv::Vec3b c = lut_.at<cv::Vec3b>(idx);
      for (int k = 0; k < 3; ++k) {
        out[x][k] = cv::saturate_cast<unsigned char>(out[x][k] * (1.f - a[x]) + c[k] * a[x]);
      }
    }
  }
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
  const int thick = std::max(1, int(std::lround(ts * 1.4)));
  const int pad = int(std::lround(10 * ts / 0.7));
  int baseline = 0;
  cv::Mat display = (*canvas)(cv::Rect(0, 0, display_size_.width, display_size_.height));

  // Time stamp, top left.
  {
    const double t = seq_.time_ms[frame];
    const std::string text = std::isfinite(t)
                                 ? "t = " + Fmt(std::abs(t) >= 100 ? "%.1f" : "%.2f", t) + " ms"
                                 : "frame " + std::to_string(frame);
    const cv::Size sz = cv::getTextSize(text, kFont, ts * 1.15, thick, &baseline);
    ShadeRect(&display, cv::Rect(pad / 2, pad / 2, sz.width + 2 * pad, sz.height + 2 * pad), kBlack,
              0.55);
    cv::putText(display, text, cv::Point(pad / 2 + pad, pad / 2 + pad + sz.height), kFont,
                ts * 1.15, kWhite, thick, cv::LINE_AA);
  }
  // "no valid subsets" note, top right, when this frame has none.
  {
    const std::size_t n = seq_.num_subsets;
    bool any = false;
    for (std::size_t s = 0; s < n && !any; ++s) {
      any = std::isfinite(std::hypot(seq_.vx_mm_s[frame * n + s], seq_.vy_mm_s[frame * n + s]));
    }
    if (!any) {
      const std::string text = "no valid subsets";
      const cv::Size sz = cv::getTextSize(text, kFont, ts, thick, &baseline);
      const int x = display.cols - sz.width - 2 * pad - pad / 2;
      ShadeRect(&display, cv::Rect(x, pad / 2, sz.width + 2 * pad, sz.height + 2 * pad), kBlack,
                0.55);
      cv::putText(display, text, cv::Point(x + pad, pad / 2 + pad + sz.height), kFont, ts,
                  cv::Scalar(80, 180, 255), thick, cv::LINE_AA);
    }
  }
  // Scale bar, bottom left.
  if (seq_.mm_per_px > 0 && std::isfinite(seq_.mm_per_px)) {
    const double target_mm = 0.18 * display_size_.width / scale_ * seq_.mm_per_px;
    const double mm = NiceFloor(target_mm);
    const int len = int(std::lround(mm / seq_.mm_per_px * scale_));
    const std::string text = (mm >= 1 ? Fmt("%.0f", mm) : Fmt("%g", mm)) + " mm";
    const cv::Size sz = cv::getTextSize(text, kFont, ts, thick, &baseline);
    const int bar_h = std::max(4, int(std::lround(7 * ts / 0.7)));
    const int box_w = std::max(len, sz.width) + 2 * pad;
    const int box_h = sz.height + bar_h + 3 * pad;
    const int x0 = pad / 2, y0 = display.rows - box_h - pad / 2;
    ShadeRect(&display, cv::Rect(x0, y0, box_w, box_h), kBlack, 0.55);
    const int bar_x = x0 + (box_w - len) / 2, bar_y = y0 + 2 * pad + sz.height;
    cv::rectangle(display, cv::Rect(bar_x, bar_y, len, bar_h), kWhite, cv::FILLED);
    cv::putText(display, text, cv::Point(x0 + (box_w - sz.width) / 2, y0 + pad + sz.height), kFont,
                ts, kWhite, thick, cv::LINE_AA);
  }
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
  panel.setTo(kPanelColor);
  const double top_display = color_max_mm_s_ * unit_factor_;
  const std::string title1 = "|v|";
  const std::string title2 = "[" + unit_label_ + "]";
  const cv::Size t1 = cv::getTextSize(title1, kFont, ts * 1.1, thick, &baseline);
  const cv::Size t2 = cv::getTextSize(title2, kFont, ts, thick, &baseline);
  const int bar_w = int(std::lround(28 * ts / 0.7));
  const int bar_x = int(std::lround(22 * ts / 0.7));
  cv::putText(panel, title1, cv::Point(bar_x, pad + t1.height), kFont, ts * 1.1, kWhite, thick,
              cv::LINE_AA);
  cv::putText(panel, title2, cv::Point(bar_x, 2 * pad + t1.height + t2.height), kFont, ts, kWhite,
              thick, cv::LINE_AA);
  const int bar_top = 4 * pad + t1.height + t2.height;
  const int bar_bottom = display_size_.height - 3 * pad;
  if (bar_bottom - bar_top < 10) return;
  const int bar_h = bar_bottom - bar_top;
  for (int y = 0; y <= bar_h; ++y) {
    const int idx = std::clamp(int(std::lround(255.0 * (bar_h - y) / bar_h)), 0, 255);
    const cv::Vec3b c = lut_.at<cv::Vec3b>(idx);
    cv::line(panel, {bar_x, bar_top + y}, {bar_x + bar_w, bar_top + y},
             cv::Scalar(c[0], c[1], c[2]));
  }
  cv::rectangle(panel, cv::Rect(bar_x, bar_top, bar_w + 1, bar_h + 1), cv::Scalar(200, 200, 200),
                1);
  const double step = NiceStep(top_display, 5);
  const int tick_len = std::max(4, int(std::lround(8 * ts / 0.7)));
  for (int k = 0;; ++k) {
    const double v = k * step;
    if (v > top_display * (1 + 1e-9)) break;
    const int y = bar_bottom - int(std::lround(v / top_display * bar_h));
    cv::line(panel, {bar_x + bar_w, y}, {bar_x + bar_w + tick_len, y}, kWhite, thick, cv::LINE_AA);
    const std::string label = TickLabel(v, step);
    const cv::Size sz = cv::getTextSize(label, kFont, ts, thick, &baseline);
    cv::putText(panel, label, cv::Point(bar_x + bar_w + tick_len + pad / 2, y + sz.height / 2),
                kFont, ts, kWhite, thick, cv::LINE_AA);
  }
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
  if (title.empty()) return canvas;
  // Header band with the title.
  const int thick = std::max(1, int(std::lround(text_scale_ * 1.4)));
  int baseline = 0;
  const cv::Size sz = cv::getTextSize(title, kFont, text_scale_ * 1.2, thick, &baseline);
  const int band = RoundUpEven(int(sz.height * 2.4));
  cv::Mat titled(canvas.rows + band, canvas.cols, CV_8UC3, kPanelColor);
  canvas.copyTo(titled(cv::Rect(0, band, canvas.cols, canvas.rows)));
  cv::putText(titled, title,
              cv::Point(std::max(4, (titled.cols - sz.width) / 2), band / 2 + sz.height / 2), kFont,
              text_scale_ * 1.2, kWhite, thick, cv::LINE_AA);
  return titled;
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
