#include "impactdic/render/figures.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

#include "impactdic/core/error.h"
#include "impactdic/model/impact_model.h"

namespace impactdic {
namespace {

constexpr const char* kBlue = "#0072B2";
constexpr const char* kRed = "#D55E00";
constexpr const char* kGreen = "#009E73";
constexpr const char* kGrey = "#505050";

std::vector<double> ToMs(const std::vector<double>& t_s) {
  std::vector<double> t_ms(t_s.size());
  std::transform(t_s.begin(), t_s.end(), t_ms.begin(), [](double t) { return 1e3 * t; });
  return t_ms;
}

void CheckSameLength(const std::vector<double>& t, const std::vector<double>& y,
                     const std::string& name) {
  CheckValue(y.empty() || y.size() == t.size(), name,
             std::to_string(y.size()) + " values for " + std::to_string(t.size()) + " times",
             "one value per time (or none)");
}

void AddSeries(Plot* plot, const std::vector<double>& t_ms, const std::vector<double>& y,
               const std::string& label, const char* color,
               SeriesStyle style = SeriesStyle::kLines) {
  if (y.empty()) return;
  PlotSeries s;
  s.x = t_ms;
  s.y = y;
  s.label = label;
  s.color = color;
  s.style = style;
  plot->series.push_back(std::move(s));
}

// A +-1 u band around y (before its line, so the line is drawn over it); nothing without u.
void AddBand(Plot* plot, const std::vector<double>& t_ms, const std::vector<double>& y,
             const std::vector<double>& u, const std::string& label, const char* color) {
  if (u.empty() || y.empty()) return;
  CheckValue(u.size() == y.size(), "figure band", std::to_string(u.size()) + " uncertainties",
             "one per value");
  AddSeries(plot, t_ms, y, label, color, SeriesStyle::kBand);
  plot->series.back().y_u = u;
}

void AddTeMarker(Plot* plot, double t_e_s) {
  if (!std::isfinite(t_e_s)) return;
  plot->markers.push_back({.orientation = MarkerOrientation::kVertical,
                           .value = 1e3 * t_e_s,
                           .label = "t_e = " +
                                    [&] {
                                      char buf[32];
                                      std::snprintf(buf, sizeof buf, "%.2f ms", 1e3 * t_e_s);
                                      return std::string(buf);
                                    }(),
                           .color = kGrey});
}

}  // namespace

Plot MakeMomentumPlot(const MomentumFigureData& d) {
  CheckSameLength(d.t_s, d.p_pounder_Ns, "momentum figure p_pounder");
  CheckSameLength(d.t_s, d.p_gran_Ns, "momentum figure p_gran");
  CheckSameLength(d.t_s, d.p_total_Ns, "momentum figure p_total");
  Plot plot;
  plot.title = "Momentum of pounder and soil";
  plot.x_label = "time since impact t [ms]";
  plot.y_label = "momentum p [N s]";
  plot.enhanced_text = true;
  plot.legend = LegendPosition::kBelow;
  const auto t_ms = ToMs(d.t_s);
  // Unlabelled (the legend below has room for one row): the title says what they are.
  AddBand(&plot, t_ms, d.p_gran_Ns, d.p_gran_u_Ns, "", kGreen);
  AddBand(&plot, t_ms, d.p_total_Ns, d.p_total_u_Ns, "", kRed);
  if (!d.p_gran_u_Ns.empty() || !d.p_total_u_Ns.empty())
    plot.title += " (shaded: +-1 standard uncertainty)";
  AddSeries(&plot, t_ms, d.p_pounder_Ns, "pounder p_p = m_p v_p", kBlue);
  AddSeries(&plot, t_ms, d.p_gran_Ns, "granular p_{gran}", kGreen, SeriesStyle::kDashed);
  AddSeries(&plot, t_ms, d.p_total_Ns, "total p_p + p_{gran}", kRed);
  if (std::isfinite(d.p_max_Ns)) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "p_{max} = %.3g N s", d.p_max_Ns);
    plot.markers.push_back({.orientation = MarkerOrientation::kHorizontal,
                            .value = d.p_max_Ns,
                            .label = buf,
                            .color = "#000000"});
  }
  AddTeMarker(&plot, d.t_e_s);
  return plot;
}

PlotSummary PlotMomentum(const MomentumFigureData& data, const std::string& png_path,
                         const PlotOptions& options) {
  return RenderPlot(MakeMomentumPlot(data), png_path, options);
}

Plot MakeDecelerationPlot(const DecelerationFigureData& d) {
  CheckSameLength(d.measured_t_s, d.measured_decel_g, "deceleration figure measured_decel_g");
  CheckSameLength(d.model_t_s, d.model_decel_g, "deceleration figure model_decel_g");
  CheckValue(d.measured_decel_g.empty() || !d.measured_t_s.empty(), "deceleration figure",
             "values without times", "times for the measured series");
  Plot plot;
  plot.title = "Pounder deceleration: measured and modelled";
  plot.x_label = "time since impact t [ms]";
  plot.y_label = "deceleration -a_p [g]";
  plot.enhanced_text = true;
  AddSeries(&plot, ToMs(d.measured_t_s), d.measured_decel_g, "measured (accelerometer)", kBlue);
  AddSeries(&plot, ToMs(d.model_t_s), d.model_decel_g, "model (Eq. 9)", kRed);
  plot.markers.push_back({.orientation = MarkerOrientation::kHorizontal,
                          .value = 0.0,
                          .label = "",
                          .color = "#a0a0a0"});
  AddTeMarker(&plot, d.t_e_s);
  // The accelerometer record usually starts long before the impact: show the model's time span
  // (the impact) with 10 % margins when there is a model.
  double lo = HUGE_VAL, hi = -HUGE_VAL;
  for (double t : d.model_t_s) {
    if (std::isfinite(t)) lo = std::min(lo, t), hi = std::max(hi, t);
  }
  if (hi > lo) {
    const double margin = 0.1 * (hi - lo);
    plot.x_min = 1e3 * (lo - margin);
    plot.x_max = 1e3 * (hi + margin);
    // The model's deceleration grows without bound as v -> 0 at its stop (the v^-n term): scale
    // the y axis to the measured record in view and to the model before its last 10 %, so that
    // the end spike is clipped instead of flattening the peak and the plateau.
    double top = 0.0;
    for (std::size_t i = 0; i < d.measured_t_s.size(); ++i) {
      const double t = d.measured_t_s[i], a = d.measured_decel_g[i];
      if (t >= lo - margin && t <= hi + margin && std::isfinite(a)) top = std::max(top, a);
    }
    for (std::size_t i = 0; i < d.model_t_s.size(); ++i) {
      const double t = d.model_t_s[i], a = d.model_decel_g[i];
      if (t <= lo + 0.9 * (hi - lo) && std::isfinite(a)) top = std::max(top, a);
    }
    if (top > 0) plot.y_max = 1.15 * top;
  }
  return plot;
}

PlotSummary PlotDeceleration(const DecelerationFigureData& data, const std::string& png_path,
                             const PlotOptions& options) {
  return RenderPlot(MakeDecelerationPlot(data), png_path, options);
}

Plot MakeAddedMassPlot(const AddedMassFigureData& d) {
  CheckSameLength(d.t_s, d.m_add_kg, "added-mass figure m_add_kg");
  Plot plot;
  plot.title = "Added mass m_{add}(t)";
  plot.x_label = "time since impact t [ms]";
  plot.y_label = "added mass m_{add} [kg]";
  plot.enhanced_text = true;
  plot.legend = LegendPosition::kBottomRight;
  AddBand(&plot, ToMs(d.t_s), d.m_add_kg, d.m_add_u_kg, "m_{add} +-1 standard uncertainty", kBlue);
  AddSeries(&plot, ToMs(d.t_s), d.m_add_kg, "measured p_{max}/v_p - m_p (Eq. 3)", kBlue,
            SeriesStyle::kLinesPoints);
  if (!plot.series.empty()) plot.series.back().line_width = 1.5;
  if (std::isfinite(d.sigmoid_M_kg) && std::isfinite(d.sigmoid_b_per_s) &&
      std::isfinite(d.sigmoid_T_s)) {
    // The fit over the measured time span (or around T if there is none), 400 samples.
    double t0 = d.sigmoid_T_s - 6.0 / std::max(std::abs(d.sigmoid_b_per_s), 1e-12);
    double t1 = d.sigmoid_T_s + 6.0 / std::max(std::abs(d.sigmoid_b_per_s), 1e-12);
    bool have_data = false;
    double lo = HUGE_VAL, hi = -HUGE_VAL;
    for (double t : d.t_s) {
      if (!std::isfinite(t)) continue;
      lo = std::min(lo, t);
      hi = std::max(hi, t);
      have_data = true;
    }
    if (have_data && hi > lo) {
      t0 = lo;
      t1 = hi;
    }
    PlotSeries fit;
    fit.label = "sigmoid fit (Eq. 5)";
    fit.color = kRed;
    constexpr int kSamples = 400;
    for (int i = 0; i < kSamples; ++i) {
      const double t = t0 + (t1 - t0) * i / (kSamples - 1);
      fit.x.push_back(1e3 * t);
      fit.y.push_back(AddedMassAt(d.sigmoid_M_kg, d.sigmoid_b_per_s, d.sigmoid_T_s, t).m_add_kg);
    }
    char buf[128];
    std::snprintf(buf, sizeof buf, "fit: M = %.3g kg, b = %.4g 1/s, T = %.3g ms", d.sigmoid_M_kg,
                  d.sigmoid_b_per_s, 1e3 * d.sigmoid_T_s);
    fit.label = buf;
    plot.series.push_back(std::move(fit));
  }
  AddTeMarker(&plot, d.t_e_s);
  return plot;
}

PlotSummary PlotAddedMass(const AddedMassFigureData& data, const std::string& png_path,
                          const PlotOptions& options) {
  return RenderPlot(MakeAddedMassPlot(data), png_path, options);
}

Plot MakeXyPlot(const XyFigureData& d) {
  Plot plot;
  plot.title = d.title;
  plot.x_label = d.x_label;
  plot.y_label = d.y_label;
  plot.log_x = d.log_x;
  plot.log_y = d.log_y;
  plot.legend = d.legend;
  for (const auto& s : d.series) {
    PlotSeries p;
    p.x = s.x;
    p.y = s.y;
    p.label = s.label;
    p.style = s.style;
    plot.series.push_back(std::move(p));
  }
  return plot;
}

PlotSummary PlotXy(const XyFigureData& data, const std::string& png_path,
                   const PlotOptions& options) {
  return RenderPlot(MakeXyPlot(data), png_path, options);
}

}  // namespace impactdic
