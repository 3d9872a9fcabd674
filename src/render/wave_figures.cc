#include "impactdic/render/wave_figures.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/numeric.h"
#include "impactdic/sensor/sensor.h"

namespace impactdic {
namespace {

// Okabe & Ito colours (the palette of render/gnuplot.cc), one per base channel.
constexpr const char* kChannelColours[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00"};
constexpr const char* kBlack = "#000000";
constexpr const char* kGrey = "#505050";

const char* ChannelColour(std::size_t i) { return kChannelColours[i % std::size(kChannelColours)]; }

// The front's speed and 95 % interval, "c = 80.1 m/s [78.8, 80.4]" (upper end "inf" when
// unbounded).
std::string SpeedText(double c, const std::array<double, 2>& ci) {
  return fmt::format("c = {:.1f} m/s [{:.1f}, {}]", c, ci[0],
                     std::isfinite(ci[1]) ? fmt::format("{:.1f}", ci[1]) : std::string("inf"));
}

PlotSeries Points(std::vector<double> x, std::vector<double> y, std::string label,
                  const char* colour, int point_type, double size = 1.6) {
  PlotSeries s;
  s.x = std::move(x);
  s.y = std::move(y);
  s.label = std::move(label);
  s.color = colour;
  s.style = SeriesStyle::kPoints;
  s.point_type = point_type;
  s.point_size = size;
  return s;
}

PlotSeries Line(std::vector<double> x, std::vector<double> y, std::string label, const char* colour,
                SeriesStyle style = SeriesStyle::kLines) {
  PlotSeries s;
  s.x = std::move(x);
  s.y = std::move(y);
  s.label = std::move(label);
  s.color = colour;
  s.style = style;
  return s;
}

}  // namespace

Plot MakeSpaceTimePlot(const WaveResult& wave) {
  const SpaceTime& st = wave.front.space_time;
  const std::size_t frames = st.time_s.size(), rows = st.rows();
  CheckValue(
      frames > 0 && rows > 0 && st.velocity_mm_s.size() == frames * rows &&
          st.pounder_base_mm.size() == frames,
      "space-time data (/wave/front/space_time)",
      fmt::format("{} frames, {} rows, {} velocities", frames, rows, st.velocity_mm_s.size()),
      "frames x centre-line rows of velocities (the front computed)");
  Plot plot;
  plot.title = "Space-time diagram of the centre line";
  plot.x_label = "time since impact t [ms]";
  plot.y_label = "depth below the undisturbed surface [mm]";
  plot.reverse_y = true;
  plot.legend = LegendPosition::kBelow;
  std::vector<double> t_ms(frames);
  for (std::size_t f = 0; f < frames; ++f) t_ms[f] = 1e3 * st.time_s[f];
  PlotCells& cells = plot.cells;
  cells.label = "downward velocity [m/s]";
  const double dt = MedianStep(UniqueSorted(t_ms, 0));
  const double dz = MedianStep(UniqueSorted(st.depth_mm, 0));
  cells.half_width = std::isfinite(dt) && dt > 0 ? dt / 2 : 0.5;
  cells.half_height = std::isfinite(dz) && dz > 0 ? dz / 2 : 0.5;
  for (std::size_t f = 0; f < frames; ++f) {
    for (std::size_t r = 0; r < rows; ++r) {
      cells.x.push_back(t_ms[f]);
      cells.y.push_back(st.depth_mm[r]);
      cells.value.push_back(1e-3 * st.velocity_mm_s[f * rows + r]);
    }
  }
  plot.series.push_back(Line(t_ms, st.pounder_base_mm, "pounder's base", kBlack));
  // The deepest point drawn: the field's bottom, or the base sensors.
  double bottom = *std::max_element(st.depth_mm.begin(), st.depth_mm.end());
  for (const WaveChannel& c : wave.channels)
    if (std::isfinite(c.depth_mm)) bottom = std::max(bottom, c.depth_mm);
  const WaveFront& front = wave.front;
  if (std::isfinite(front.speed_m_s) && std::isfinite(front.intercept_s)) {
    // depth [mm] = c [m/s = mm/ms] (t - t0) [ms], from the surface to the bottom.
    const double t0 = 1e3 * front.intercept_s;
    plot.series.push_back(Line({t0, t0 + bottom / front.speed_m_s}, {0, bottom},
                               "front " + SpeedText(front.speed_m_s, front.speed_ci_m_s), kBlack,
                               SeriesStyle::kDashed));
  }
  for (std::size_t i = 0; i < wave.channels.size(); ++i) {  // One legend entry per sensor.
    const WaveChannel& c = wave.channels[i];
    const bool onset = std::isfinite(c.onset_s);
    if (onset)
      plot.series.push_back(
          Points({1e3 * c.onset_s}, {c.depth_mm}, c.column + " onset, peak", ChannelColour(i), 9));
    if (std::isfinite(c.peak_s))
      plot.series.push_back(Points({1e3 * c.peak_s}, {c.depth_mm}, onset ? "" : c.column + " peak",
                                   ChannelColour(i), 7));
  }
  plot.y_max = 1.04 * bottom;  // The sensors' markers clear of the axis.
  plot.x_min = t_ms.front() - cells.half_width;
  plot.x_max = t_ms.back() + cells.half_width;
  return plot;
}

PlotSummary PlotSpaceTime(const WaveResult& wave, const std::string& png_path,
                          const PlotOptions& options) {
  return RenderPlot(MakeSpaceTimePlot(wave), png_path, options);
}

Plot MakeBaseForcePlot(const std::vector<double>& t_s, const std::vector<BaseForceRecord>& records,
                       const WaveResult& wave) {
  Plot plot;
  plot.title = "Base force records";
  plot.x_label = "time since impact t [ms]";
  plot.y_label = "dynamic base force [N]";
  plot.legend = LegendPosition::kBelow;
  std::vector<double> t_ms(t_s.size());
  for (std::size_t k = 0; k < t_s.size(); ++k) t_ms[k] = 1e3 * t_s[k];
  // The window: the impact to past the latest return time (or peak), a quarter of it before.
  double end_ms = 0;
  for (const WaveChannel& c : wave.channels) {
    for (double t : {c.return_time_s + 3 * c.return_time_sigma_s, 2 * c.peak_s})
      if (std::isfinite(t)) end_ms = std::max(end_ms, 1.25e3 * t);
  }
  if (end_ms > 0 && !t_ms.empty()) {
    plot.x_min = std::max(t_ms.front(), -0.25 * end_ms);
    plot.x_max = std::min(t_ms.back(), end_ms);
  }
  for (std::size_t i = 0; i < records.size(); ++i) {
    const BaseForceRecord& r = records[i];
    CheckValue(r.force_n.size() == t_s.size(), "base force record " + r.column,
               fmt::format("{} values for {} times", r.force_n.size(), t_s.size()),
               "one value per time");
    plot.series.push_back(Line(t_ms, r.force_n, r.column, ChannelColour(i)));
    const auto channel = std::find_if(wave.channels.begin(), wave.channels.end(),
                                      [&](const WaveChannel& c) { return c.column == r.column; });
    if (channel == wave.channels.end()) continue;
    for (const auto& [t, name, type] :
         {std::tuple{channel->onset_s, "onset", 9}, std::tuple{channel->peak_s, "peak", 7}}) {
      if (!std::isfinite(t)) continue;
      plot.series.push_back(Points({1e3 * t}, {InterpolateSeries(t_s, r.force_n, t)},
                                   fmt::format("{} {} {:.2f} ms", r.column, name, 1e3 * t),
                                   ChannelColour(i), type));
    }
    // Sensors at one depth predict nearly the same return: one label for returns within 1 ms.
    const double t_return = 1e3 * channel->return_time_s;
    if (!std::isfinite(t_return)) continue;
    const bool near_another =
        std::any_of(plot.markers.begin(), plot.markers.end(),
                    [&](const PlotMarker& m) { return std::abs(m.value - t_return) < 1; });
    plot.markers.push_back({.orientation = MarkerOrientation::kVertical,
                            .value = t_return,
                            .label = near_another ? "" : fmt::format("return {:.1f} ms", t_return),
                            .color = ChannelColour(i)});
  }
  // The impact is t = 0 (the axis); the pounder's peak deceleration starts the peak travel time.
  if (std::isfinite(wave.pounder_peak_s))
    plot.markers.push_back({.orientation = MarkerOrientation::kVertical,
                            .value = 1e3 * wave.pounder_peak_s,
                            .label = "pounder peak",
                            .color = kBlack});
  return plot;
}

PlotSummary PlotBaseForce(const std::vector<double>& t_s,
                          const std::vector<BaseForceRecord>& records, const WaveResult& wave,
                          const std::string& png_path, const PlotOptions& options) {
  return RenderPlot(MakeBaseForcePlot(t_s, records, wave), png_path, options);
}

Plot MakeDepthProfilePlot(const WaveFront& front) {
  Plot plot;
  plot.title = "Vertical displacement along the centre line";
  plot.x_label = "depth below the pounder's base z [mm]";
  plot.y_label = "downward displacement u [mm]";
  plot.log_y = true;
  plot.legend = LegendPosition::kBelow;
  bool any = false;
  const std::pair<const DepthDecayFit*, const char*> rows[] = {{&front.displacement_te, "t_e"},
                                                               {&front.displacement_end, "end"}};
  for (std::size_t i = 0; i < 2; ++i) {
    const DepthDecayFit& d = *rows[i].first;
    if (d.profile_depth_mm.empty()) continue;
    any = true;
    const char* colour = ChannelColour(i);
    std::vector<double> z_fit, u_fit, z_out, u_out;
    double z_max = 0;
    for (std::size_t k = 0; k < d.profile_depth_mm.size(); ++k) {
      const double z = d.profile_depth_mm[k], u = d.profile_value[k];
      if (!std::isfinite(z) || !std::isfinite(u)) continue;
      z_max = std::max(z_max, z);
      (d.profile_in_fit[k] != 0 ? z_fit : z_out).push_back(z);
      (d.profile_in_fit[k] != 0 ? u_fit : u_out).push_back(u);
    }
    const std::string at = fmt::format("{} ({:.2f} ms)", rows[i].second, 1e3 * d.time_s);
    plot.series.push_back(Points(z_fit, u_fit, at + ", in the fit", colour, 7, 1.2));
    if (!z_out.empty())
      plot.series.push_back(Points(z_out, u_out, at + ", below the noise", colour, 6, 1.2));
    if (std::isfinite(d.decay_length_mm)) {
      std::vector<double> z, u;
      for (int k = 0; k <= 50; ++k) {
        z.push_back(z_max * k / 50.0);
        u.push_back(d.surface_value * std::exp(-z.back() / d.decay_length_mm));
      }
      const std::array<double, 2>& ci = d.decay_length_ci_mm;
      plot.series.push_back(Line(
          z, u,
          fmt::format("fit {}: lambda = {:.1f} mm [{:.1f}, {}]", rows[i].second, d.decay_length_mm,
                      ci[0], std::isfinite(ci[1]) ? fmt::format("{:.1f}", ci[1]) : "inf"),
          colour, SeriesStyle::kDashed));
    }
  }
  CheckValue(any, "displacement-depth profile (/wave/front/displacement/profile_*)", "none",
             "the centre line's profile at t_e or at the last frame");
  const DepthDecayFit& te = front.displacement_te;
  if (std::isfinite(te.depth_of_influence_mm) && std::isfinite(front.pounder_base_depth_mm))
    plot.markers.push_back(
        {.orientation = MarkerOrientation::kVertical,
         .value = te.depth_of_influence_mm - front.pounder_base_depth_mm,
         .label = fmt::format("influence depth {:.0f} mm", te.depth_of_influence_mm),
         .color = kGrey});
  return plot;
}

PlotSummary PlotDepthProfile(const WaveFront& front, const std::string& png_path,
                             const PlotOptions& options) {
  return RenderPlot(MakeDepthProfilePlot(front), png_path, options);
}

}  // namespace impactdic
