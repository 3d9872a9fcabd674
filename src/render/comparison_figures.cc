#include "impactdic/render/comparison_figures.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <map>
#include <utility>

#include "impactdic/core/error.h"
#include "impactdic/io/output_generation.h"

namespace impactdic {
namespace {

// Okabe & Ito colours (as the per-scene figures) without black, which the fit line uses.
constexpr const char* kGroupColors[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7",
                                        "#E69F00", "#56B4E9", "#F0E442"};
// Filled circle, square, triangle, diamond, downward triangle, then open ones.
constexpr int kGroupPointTypes[] = {7, 5, 9, 13, 11, 6, 4, 8, 12, 10};
constexpr const char* kFitColor = "#000000";
constexpr const char* kIdentityColor = "#808080";

bool Finite(const ComparisonPoint& p) {
  return std::isfinite(p.predicted) && std::isfinite(p.observed);
}

std::string Format(const char* format, double value) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, value);
  return buf;
}

// "y = 0.95 x + 1.2", "y = 1.1 x - 0.3".
std::string LineEquation(double slope, double intercept) {
  return "y = " + Format("%.3g", slope) + " x " + (intercept < 0 ? "- " : "+ ") +
         Format("%.3g", std::abs(intercept));
}

// The distinct finite widths, ascending, and the decimals (2..6) that tell them all apart in
// "D = %.*f m".
struct WidthGroups {
  std::vector<double> widths;
  int decimals = 2;
  bool any_unknown = false;
};

WidthGroups GroupWidths(const std::vector<ComparisonPoint>& points) {
  WidthGroups g;
  for (const auto& p : points) {
    if (!Finite(p)) continue;
    if (std::isfinite(p.width_m)) {
      g.widths.push_back(p.width_m);
    } else {
      g.any_unknown = true;
    }
  }
  std::sort(g.widths.begin(), g.widths.end());
  g.widths.erase(std::unique(g.widths.begin(), g.widths.end()), g.widths.end());
  for (g.decimals = 2; g.decimals < 6; ++g.decimals) {
    bool distinct = true;
    for (std::size_t i = 1; i < g.widths.size() && distinct; ++i) {
      char a[64], b[64];
      std::snprintf(a, sizeof a, "%.*f", g.decimals, g.widths[i - 1]);
      std::snprintf(b, sizeof b, "%.*f", g.decimals, g.widths[i]);
      distinct = std::string(a) != b;
    }
    if (distinct) break;
  }
  return g;
}

std::string WidthLabel(double width_m, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "D = %.*f m", decimals, width_m);
  return buf;
}

// The range covered by the finite points on both axes; false if there is none.
bool CommonRange(const std::vector<ComparisonPoint>& points, double* lo, double* hi) {
  *lo = HUGE_VAL;
  *hi = -HUGE_VAL;
  for (const auto& p : points) {
    if (!Finite(p)) continue;
    *lo = std::min({*lo, p.predicted, p.observed});
    *hi = std::max({*hi, p.predicted, p.observed});
  }
  return *lo <= *hi;
}

PlotSeries Line(double x0, double x1, double slope, double intercept, const std::string& label,
                const char* color, SeriesStyle style) {
  PlotSeries s;
  s.x = {x0, x1};
  s.y = {slope * x0 + intercept, slope * x1 + intercept};
  s.label = label;
  s.color = color;
  s.style = style;
  s.line_width = 2.0;
  return s;
}

std::string FitLabel(const ComparisonFit& fit) {
  return "fit: " + LineEquation(fit.slope, fit.intercept) +
         ", R^2 = " + Format("%.3f", fit.r_squared) + ", n = " + std::to_string(fit.n);
}

}  // namespace

ComparisonFit FitComparison(const std::vector<ComparisonPoint>& points) {
  ComparisonFit fit;
  double sum_x = 0, sum_y = 0;
  for (const auto& p : points) {
    if (!Finite(p)) {
      ++fit.skipped;
      continue;
    }
    ++fit.n;
    sum_x += p.predicted;
    sum_y += p.observed;
  }
  if (fit.n == 0) return fit;
  // Centred sums (two passes) for accuracy when the values are large and close together.
  const double mean_x = sum_x / fit.n, mean_y = sum_y / fit.n;
  double sxx = 0, sxy = 0, syy = 0, sum_r2 = 0, max_r = 0;
  int relative_n = 0;
  for (const auto& p : points) {
    if (!Finite(p)) continue;
    const double dx = p.predicted - mean_x, dy = p.observed - mean_y;
    sxx += dx * dx;
    sxy += dx * dy;
    syy += dy * dy;
    if (p.predicted != 0.0) {  // the relative deviation needs a prediction to divide by
      const double r = p.observed / p.predicted - 1.0;
      sum_r2 += r * r;
      max_r = std::max(max_r, std::abs(r));
      ++relative_n;
    }
  }
  if (relative_n > 0) {
    fit.rms_relative_deviation = std::sqrt(sum_r2 / relative_n);
    fit.max_relative_deviation = max_r;
  }
  if (fit.n < 2 || !(sxx > 0)) return fit;  // no line through one point or one x value
  fit.slope = sxy / sxx;
  fit.intercept = mean_y - fit.slope * mean_x;
  // R^2 = 1 - SS_res / SS_tot; for a least-squares line SS_res = syy - sxy^2 / sxx. Undefined
  // (NaN) when all observed values are equal.
  if (syy > 0) fit.r_squared = std::clamp(sxy * sxy / (sxx * syy), 0.0, 1.0);
  return fit;
}

Plot MakeComparisonPlot(const ComparisonFigureData& data) {
  Plot plot;
  plot.title = data.title;
  const ComparisonFit fit = FitComparison(data.points);
  if (fit.skipped > 0) {  // say so on the figure: those tests are not drawn
    plot.title += (plot.title.empty() ? "" : " ") + std::string("(") + std::to_string(fit.skipped) +
                  " of " + std::to_string(fit.n + fit.skipped) +
                  " tests without a value, not drawn)";
  }
  plot.x_label = data.x_label;
  plot.y_label = data.y_label;
  plot.legend = LegendPosition::kTopLeft;
  double lo = 0, hi = 0;
  if (!CommonRange(data.points, &lo, &hi)) return plot;  // nothing to draw
  if (data.identity_line) {
    // Equal ranges on both axes, so that the 1:1 line is the diagonal, with 5 % margins.
    const double pad = hi > lo ? 0.05 * (hi - lo) : std::max(0.05 * std::abs(hi), 1e-12);
    lo -= pad;
    hi += pad;
    plot.x_min = plot.y_min = lo;
    plot.x_max = plot.y_max = hi;
    plot.series.push_back(Line(lo, hi, 1.0, 0.0, "1:1", kIdentityColor, SeriesStyle::kDashed));
  } else {  // The fitted line over the x values (gnuplot scales each axis).
    lo = HUGE_VAL;
    hi = -HUGE_VAL;
    for (const auto& p : data.points) {
      if (!Finite(p)) continue;
      lo = std::min(lo, p.predicted);
      hi = std::max(hi, p.predicted);
    }
  }
  if (std::isfinite(fit.slope) && std::isfinite(fit.intercept)) {
    plot.series.push_back(
        Line(lo, hi, fit.slope, fit.intercept, FitLabel(fit), kFitColor, SeriesStyle::kLines));
  }

  const WidthGroups groups = GroupWidths(data.points);
  std::map<double, PlotSeries> by_width;  // NaN width (unknown) is drawn last, in its own series
  PlotSeries unknown;
  for (const auto& p : data.points) {
    if (!Finite(p)) continue;
    PlotSeries& s = std::isfinite(p.width_m) ? by_width[p.width_m] : unknown;
    s.x.push_back(p.predicted);
    s.y.push_back(p.observed);
  }
  std::size_t k = 0;
  auto add = [&](PlotSeries s, const std::string& label) {
    s.label = label;
    s.style = SeriesStyle::kPoints;
    s.color = kGroupColors[k % std::size(kGroupColors)];
    s.point_type = kGroupPointTypes[k % std::size(kGroupPointTypes)];
    s.point_size = 1.8;
    ++k;
    plot.series.push_back(std::move(s));
  };
  for (auto& [width, s] : by_width) add(std::move(s), WidthLabel(width, groups.decimals));
  if (!unknown.x.empty()) add(std::move(unknown), "D unknown");
  return plot;
}

PlotSummary PlotComparison(const ComparisonFigureData& data, const std::string& png_path,
                           const PlotOptions& options) {
  const ComparisonFit fit = FitComparison(data.points);
  if (fit.n == 0) {
    throw Error(ErrorKind::kInvalidValue, "comparison figure '" + data.title + "'",
                std::to_string(data.points.size()) +
                    " tests, none with finite predicted and observed values",
                "at least one test with both values")
        .WithFile(OutputPathForMessages(png_path));
  }
  return RenderPlot(MakeComparisonPlot(data), png_path, options);
}

}  // namespace impactdic
