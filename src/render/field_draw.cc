#include "field_draw.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "impactdic/core/error.h"
#include "impactdic/render/velocity_field.h"

namespace impactdic::render_internal {

std::string Fmt(const char* format, double value) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, value);
  return buf;
}

double NiceFloor(double value) {
  if (!(value > 0) || !std::isfinite(value)) return 1.0;
  const double mag = std::pow(10.0, std::floor(std::log10(value)));
  const double r = value / mag;
  const double nice = r >= 5 ? 5 : r >= 2 ? 2 : 1;
  return nice * mag;
}

std::string TickLabel(double value, double step) {
  const int decimals = std::max(0, static_cast<int>(-std::floor(std::log10(step) + 1e-9)));
  if (std::abs(value) < 1e-9 * step) value = 0.0;  // no "-0.0"
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, value);
  return buf;
}

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

double RoundUpToTick(double top, int target_ticks, double* step) {
  const double s = NiceStep(top, target_ticks);
  if (step) *step = s;
  return std::ceil(top / s - 1e-9) * s;
}

void CheckDisplayOptions(const std::string& type_name, int min_width_px, int max_width_px,
                         double contrast_low_percentile, double contrast_high_percentile) {
  CheckRange(min_width_px, kDisplayWidthRange, type_name + ".min_width_px", "a display width");
  CheckRange(max_width_px, kDisplayWidthRange, type_name + ".max_width_px", "a display width");
  CheckValue(max_width_px >= min_width_px, type_name + ".max_width_px",
             std::to_string(max_width_px),
             ">= min_width_px (" + std::to_string(min_width_px) + ")");
  CheckValue(contrast_low_percentile >= 0 && contrast_high_percentile <= 100 &&
                 contrast_low_percentile < contrast_high_percentile,
             type_name + ".contrast_low_percentile/contrast_high_percentile",
             Fmt("%g", contrast_low_percentile) + "/" + Fmt("%g", contrast_high_percentile),
             "0 <= low < high <= 100");
}

DisplayLayout LayoutDisplay(cv::Size image, int min_width_px, int max_width_px) {
  DisplayLayout l;
  l.image = image;
  if (image.width < min_width_px) l.scale = double(min_width_px) / image.width;
  if (image.width > max_width_px) l.scale = double(max_width_px) / image.width;
  l.size = cv::Size(std::max(2, int(std::lround(image.width * l.scale))),
                    std::max(2, int(std::lround(image.height * l.scale))));
  l.text_scale = std::clamp(l.size.height / 720.0 * 0.7, 0.45, 1.5);
  return l;
}

double EstimateGridSpacing(const FieldSequence& seq, cv::Size image) {
  std::vector<cv::Point2d> pts;
  for (std::size_t s = 0; s < seq.num_subsets; ++s) {
    const double x = seq.x(0, s), y = seq.y(0, s);
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
  double spacing = 0.0;
  if (!nn.empty()) {
    std::nth_element(nn.begin(), nn.begin() + nn.size() / 2, nn.end());
    spacing = nn[nn.size() / 2];
  } else {
    spacing = std::max(8.0, std::min(image.width, image.height) / 12.0);
  }
  return std::clamp(spacing, 2.0, 0.5 * std::max(image.width, image.height));
}

std::pair<double, double> GreyContrast(const cv::Mat& frame, double low_percentile,
                                       double high_percentile) {
  if (frame.type() == CV_8UC1) return {0.0, 255.0};
  cv::Mat as_float;
  frame.convertTo(as_float, CV_32F);
  std::vector<float> sample;
  const std::size_t total = as_float.total();
  const std::size_t sample_stride = std::max<std::size_t>(1, total / 200000);
  const float* p = as_float.ptr<float>();  // convertTo output is continuous
  for (std::size_t i = 0; i < total; i += sample_stride) {
    if (std::isfinite(p[i])) sample.push_back(p[i]);
  }
  const double low = Percentile(sample, low_percentile);
  double high = Percentile(sample, high_percentile);
  if (!(high > low)) high = low + 1.0;
  return {low, high};
}

cv::Mat DisplayGrey(const cv::Mat& frame, std::pair<double, double> contrast,
                    const DisplayLayout& layout) {
  cv::Mat grey8;
  if (frame.type() == CV_8UC1) {
    grey8 = frame;
  } else {
    const double alpha = 255.0 / (contrast.second - contrast.first);
    frame.convertTo(grey8, CV_8U, alpha, -contrast.first * alpha);  // saturating
  }
  cv::Mat resized;
  cv::resize(grey8, resized, layout.size, 0, 0,
             layout.scale < 1 ? cv::INTER_AREA : cv::INTER_LINEAR);
  cv::Mat bgr;
  cv::cvtColor(resized, bgr, cv::COLOR_GRAY2BGR);
  return bgr;
}

namespace {

// The field's value and opacity on a work grid of `cell` image px: normalised convolution of the
// valid subsets' values; opacity 1 up to 0.6 grid spacings from the nearest valid subset, 0 from
// 0.9 on. False when no subset is valid.
bool InterpolateField(const FieldSequence& seq, std::size_t frame,
                      const std::vector<double>& values, double spacing_px, cv::Size image,
                      double cell, cv::Mat* value, cv::Mat* alpha) {
  const int gw = std::max(1, int(std::ceil(image.width / cell)));
  const int gh = std::max(1, int(std::ceil(image.height / cell)));
  cv::Mat num(gh, gw, CV_32F, cv::Scalar(0)), den(gh, gw, CV_32F, cv::Scalar(0));
  cv::Mat far_from_data(gh, gw, CV_8U, cv::Scalar(255));
  int valid = 0;
  for (std::size_t s = 0; s < seq.num_subsets; ++s) {
    const double v = values[s];
    const double gx = seq.x(frame, s) / cell - 0.5, gy = seq.y(frame, s) / cell - 0.5;
    if (!std::isfinite(v) || !std::isfinite(gx) || !std::isfinite(gy)) continue;
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
        num.at<float>(yy, xx) += w * float(v);
        den.at<float>(yy, xx) += w;
      }
    }
    const int cx = std::clamp(int(std::lround(gx)), 0, gw - 1);
    const int cy = std::clamp(int(std::lround(gy)), 0, gh - 1);
    far_from_data.at<unsigned char>(cy, cx) = 0;
  }
  if (valid == 0) return false;
  // Normalised convolution with a Gaussian of half a grid spacing.
  const double sigma = 0.5 * spacing_px / cell;
  cv::GaussianBlur(num, num, cv::Size(), sigma, sigma, cv::BORDER_CONSTANT);
  cv::GaussianBlur(den, den, cv::Size(), sigma, sigma, cv::BORDER_CONSTANT);
  cv::Mat dist;
  cv::distanceTransform(far_from_data, dist, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  *value = cv::Mat(gh, gw, CV_32F);
  *alpha = cv::Mat(gh, gw, CV_32F);
  const float full = float(0.6 * spacing_px / cell), zero = float(0.9 * spacing_px / cell);
  for (int y = 0; y < gh; ++y) {
    for (int x = 0; x < gw; ++x) {
      const float d = den.at<float>(y, x);
      value->at<float>(y, x) = d > 1e-12f ? num.at<float>(y, x) / d : 0.f;
      const float r = dist.at<float>(y, x);
      alpha->at<float>(y, x) = d > 1e-12f ? std::clamp((zero - r) / (zero - full), 0.f, 1.f) : 0.f;
    }
  }
  return true;
}

}  // namespace

void BlendField(const FieldSequence& seq, std::size_t frame, const std::vector<double>& values,
                double spacing_px, const DisplayLayout& layout, const cv::Mat& lut, double low,
                double high, double opacity, cv::Mat* display) {
  // Work grid of cells of about a quarter subset spacing.
  const double cell = std::max(1.0, spacing_px / 4.0);
  cv::Mat value, alpha;
  if (!InterpolateField(seq, frame, values, spacing_px, layout.image, cell, &value, &alpha)) return;
  // To display resolution: cell (i, j) covers image pixels [j*cell, (j+1)*cell).
  cv::Mat value_d, alpha_d;
  const cv::Size covered(int(std::lround(value.cols * cell * layout.scale)),
                         int(std::lround(value.rows * cell * layout.scale)));
  cv::resize(value, value_d, covered, 0, 0, cv::INTER_LINEAR);
  cv::resize(alpha, alpha_d, covered, 0, 0, cv::INTER_LINEAR);
  const float to_index = float(255.0 / (high - low)), offset = float(low);
  const float max_alpha = float(opacity);
  const int rows = std::min(display->rows, covered.height);
  const int cols = std::min(display->cols, covered.width);
  for (int y = 0; y < rows; ++y) {
    cv::Vec3b* out = display->ptr<cv::Vec3b>(y);
    const float* v = value_d.ptr<float>(y);
    const float* a0 = alpha_d.ptr<float>(y);
    for (int x = 0; x < cols; ++x) {
      const float a = a0[x] * max_alpha;
      if (a <= 0.f) continue;
      const int idx =
          std::clamp(static_cast<int>(std::lroundf((v[x] - offset) * to_index)), 0, 255);
      const cv::Vec3b& c = lut.at<cv::Vec3b>(idx);
      for (int k = 0; k < 3; ++k) {
        out[x][k] = cv::saturate_cast<unsigned char>(out[x][k] * (1.f - a) + c[k] * a);
      }
    }
  }
}

void DrawTimeStamp(double t_ms, std::size_t frame, double text_scale, cv::Mat* display) {
  const double ts = text_scale;
  const int thick = TextThickness(ts), pad = TextPad(ts);
  int baseline = 0;
  const std::string text = std::isfinite(t_ms)
                               ? "t = " + Fmt(std::abs(t_ms) >= 100 ? "%.1f" : "%.2f", t_ms) + " ms"
                               : "frame " + std::to_string(frame);
  const cv::Size sz = cv::getTextSize(text, kFont, ts * 1.15, thick, &baseline);
  ShadeRect(display, cv::Rect(pad / 2, pad / 2, sz.width + 2 * pad, sz.height + 2 * pad), kBlack,
            0.55);
  cv::putText(*display, text, cv::Point(pad / 2 + pad, pad / 2 + pad + sz.height), kFont, ts * 1.15,
              kWhite, thick, cv::LINE_AA);
}

void DrawNote(const std::string& text, double text_scale, cv::Mat* display) {
  const double ts = text_scale;
  const int thick = TextThickness(ts), pad = TextPad(ts);
  int baseline = 0;
  const cv::Size sz = cv::getTextSize(text, kFont, ts, thick, &baseline);
  const int x = display->cols - sz.width - 2 * pad - pad / 2;
  ShadeRect(display, cv::Rect(x, pad / 2, sz.width + 2 * pad, sz.height + 2 * pad), kBlack, 0.55);
  cv::putText(*display, text, cv::Point(x + pad, pad / 2 + pad + sz.height), kFont, ts,
              cv::Scalar(80, 180, 255), thick, cv::LINE_AA);
}

void DrawScaleBar(double mm_per_px, const DisplayLayout& layout, cv::Mat* display) {
  if (!(mm_per_px > 0 && std::isfinite(mm_per_px))) return;
  const double ts = layout.text_scale;
  const int thick = TextThickness(ts), pad = TextPad(ts);
  int baseline = 0;
  const double target_mm = 0.18 * layout.size.width / layout.scale * mm_per_px;
  const double mm = NiceFloor(target_mm);
  const int len = int(std::lround(mm / mm_per_px * layout.scale));
  const std::string text = (mm >= 1 ? Fmt("%.0f", mm) : Fmt("%g", mm)) + " mm";
  const cv::Size sz = cv::getTextSize(text, kFont, ts, thick, &baseline);
  const int bar_h = std::max(4, int(std::lround(7 * ts / 0.7)));
  const int box_w = std::max(len, sz.width) + 2 * pad;
  const int box_h = sz.height + bar_h + 3 * pad;
  const int x0 = pad / 2, y0 = display->rows - box_h - pad / 2;
  ShadeRect(display, cv::Rect(x0, y0, box_w, box_h), kBlack, 0.55);
  const int bar_x = x0 + (box_w - len) / 2, bar_y = y0 + 2 * pad + sz.height;
  cv::rectangle(*display, cv::Rect(bar_x, bar_y, len, bar_h), kWhite, cv::FILLED);
  cv::putText(*display, text, cv::Point(x0 + (box_w - sz.width) / 2, y0 + pad + sz.height), kFont,
              ts, kWhite, thick, cv::LINE_AA);
}

namespace {

// Tick values of a colour bar: the multiples of its step in [low, high].
std::vector<double> Ticks(const ColourBar& bar) {
  std::vector<double> ticks;
  const long long first = static_cast<long long>(std::ceil(bar.low / bar.step - 1e-9));
  const long long last = static_cast<long long>(std::floor(bar.high / bar.step + 1e-9));
  for (long long k = first; k <= last; ++k) ticks.push_back(static_cast<double>(k) * bar.step);
  return ticks;
}

}  // namespace

int ColourBarWidth(const ColourBar& bar, double text_scale) {
  const double ts = text_scale;
  const int thick = TextThickness(ts);
  int widest_tick = 0, widest_text = 0, baseline = 0;
  for (double v : Ticks(bar)) {
    widest_tick = std::max(
        widest_tick, cv::getTextSize(TickLabel(v, bar.step), kFont, ts, thick, &baseline).width);
  }
  widest_text = cv::getTextSize(bar.unit, kFont, ts, thick, &baseline).width;
  for (const auto& note : bar.notes) {
    widest_text = std::max(widest_text, cv::getTextSize(note, kFont, ts, thick, &baseline).width);
  }
  const int bar_w = int(std::lround(28 * ts / 0.7));
  return std::max(widest_text + int(30 * ts), bar_w + widest_tick + int(60 * ts));
}

void DrawColourBar(const ColourBar& bar, double text_scale, int display_height, cv::Mat* panel) {
  const double ts = text_scale;
  const int thick = TextThickness(ts), pad = TextPad(ts);
  int baseline = 0;
  panel->setTo(kPanelColor);
  const cv::Size t1 = cv::getTextSize(bar.title, kFont, ts * 1.1, thick, &baseline);
  const cv::Size t2 = cv::getTextSize(bar.unit, kFont, ts, thick, &baseline);
  const int bar_w = int(std::lround(28 * ts / 0.7));
  const int bar_x = int(std::lround(22 * ts / 0.7));
  cv::putText(*panel, bar.title, cv::Point(bar_x, pad + t1.height), kFont, ts * 1.1, kWhite, thick,
              cv::LINE_AA);
  cv::putText(*panel, bar.unit, cv::Point(bar_x, 2 * pad + t1.height + t2.height), kFont, ts,
              kWhite, thick, cv::LINE_AA);
  const int note_h = cv::getTextSize("Ag", kFont, ts, thick, &baseline).height + pad;
  const int bar_top = 4 * pad + t1.height + t2.height;
  const int bar_bottom = display_height - 3 * pad - static_cast<int>(bar.notes.size()) * note_h;
  if (bar_bottom - bar_top < 10) return;
  const int bar_h = bar_bottom - bar_top;
  for (int y = 0; y <= bar_h; ++y) {
    const int idx = std::clamp(int(std::lround(255.0 * (bar_h - y) / bar_h)), 0, 255);
    const cv::Vec3b& c = bar.lut.at<cv::Vec3b>(idx);
    cv::line(*panel, {bar_x, bar_top + y}, {bar_x + bar_w, bar_top + y},
             cv::Scalar(c[0], c[1], c[2]));
  }
  cv::rectangle(*panel, cv::Rect(bar_x, bar_top, bar_w + 1, bar_h + 1), cv::Scalar(200, 200, 200),
                1);
  const int tick_len = std::max(4, int(std::lround(8 * ts / 0.7)));
  for (double v : Ticks(bar)) {
    const int y = bar_bottom - int(std::lround((v - bar.low) / (bar.high - bar.low) * bar_h));
    cv::line(*panel, {bar_x + bar_w, y}, {bar_x + bar_w + tick_len, y}, kWhite, thick, cv::LINE_AA);
    const std::string label = TickLabel(v, bar.step);
    const cv::Size sz = cv::getTextSize(label, kFont, ts, thick, &baseline);
    cv::putText(*panel, label, cv::Point(bar_x + bar_w + tick_len + pad / 2, y + sz.height / 2),
                kFont, ts, kWhite, thick, cv::LINE_AA);
  }
  int y = bar_bottom + pad;
  for (const auto& note : bar.notes) {
    y += note_h;
    cv::putText(*panel, note, cv::Point(bar_x, y), kFont, ts, kWhite, thick, cv::LINE_AA);
  }
}

cv::Mat WithTitle(const cv::Mat& canvas, const std::string& title, double text_scale) {
  const int thick = TextThickness(text_scale);
  int baseline = 0;
  const cv::Size sz = cv::getTextSize(title, kFont, text_scale * 1.2, thick, &baseline);
  const int band = RoundUpEven(int(sz.height * 2.4));
  cv::Mat titled(canvas.rows + band, canvas.cols, CV_8UC3, kPanelColor);
  canvas.copyTo(titled(cv::Rect(0, band, canvas.cols, canvas.rows)));
  cv::putText(titled, title,
              cv::Point(std::max(4, (titled.cols - sz.width) / 2), band / 2 + sz.height / 2), kFont,
              text_scale * 1.2, kWhite, thick, cv::LINE_AA);
  return titled;
}

}  // namespace impactdic::render_internal
