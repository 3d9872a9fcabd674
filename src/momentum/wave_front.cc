#include "impactdic/momentum/wave_front.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/range.h"
#include "impactdic/momentum/fit.h"

namespace impactdic {
namespace {

// Subsets of one grid row share their reference y; a row is those within this of the shallowest.
constexpr double kRowToleranceMm = 1.0;

// Ordinary least squares y = a + b x with the standard error of b.
struct Line {
  double a = kNaN, b = kNaN, se_b = kNaN, rms = kNaN;
  std::size_t n = 0;
};

Line FitLine(const std::vector<double>& x, const std::vector<double>& y) {
  Line line;
  line.n = x.size();
  if (line.n < 3) return line;
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < line.n; ++i) {
    mx += x[i];
    my += y[i];
  }
  mx /= static_cast<double>(line.n);
  my /= static_cast<double>(line.n);
  double sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < line.n; ++i) {
    sxx += (x[i] - mx) * (x[i] - mx);
    sxy += (x[i] - mx) * (y[i] - my);
  }
  if (!(sxx > 0)) return line;
  line.b = sxy / sxx;
  line.a = my - line.b * mx;
  double sse = 0;
  for (std::size_t i = 0; i < line.n; ++i) {
    const double r = y[i] - line.a - line.b * x[i];
    sse += r * r;
  }
  line.rms = std::sqrt(sse / static_cast<double>(line.n));
  line.se_b = std::sqrt(sse / static_cast<double>(line.n - 2) / sxx);
  return line;
}

double HalfWidth(const Line& line, double confidence) {
  return StudentTQuantile(0.5 + confidence / 2, static_cast<double>(line.n - 2)) * line.se_b;
}

double StandardDeviation(const std::vector<double>& v) {
  if (v.size() < 2) return kNaN;
  double m = 0;
  for (double x : v) m += x;
  m /= static_cast<double>(v.size());
  double s = 0;
  for (double x : v) s += (x - m) * (x - m);
  return std::sqrt(s / static_cast<double>(v.size() - 1));
}

struct Frames {
  std::vector<double> t_s;         // After the impact.
  std::vector<std::size_t> noise;  // Frames whose velocity stencil is before the impact.
  std::size_t first_after = 0;     // The first frame not in `noise`.
};

// Why the front cannot be measured from these inputs ("" when it can): the pounder's position on
// the panel, and the frames on the sensor's clock.
std::string InputProblem(const KinematicsResult& k, const std::vector<double>& frame_daq_time_s,
                         const SensorResult& sensor, const WaveFrontOptions& o) {
  if (!std::isfinite(o.pounder_center_x_mm) || !std::isfinite(o.surface_y_mm) ||
      !(o.pounder_width_mm > 0))
    return "the pounder's position on the panel is not known (momentum.pounder_center_x_px and "
           "surface_y_px)";
  if (frame_daq_time_s.size() != k.frames || !std::isfinite(sensor.summary.impact_time_s))
    return "the frames are not on the sensor's clock or the impact was not found";
  return "";
}

// The frames' times after the impact and the noise frames (the header's definition).
Frames MakeFrames(const KinematicsResult& k, const std::vector<double>& frame_daq_time_s,
                  const SensorResult& sensor) {
  Frames fr;
  fr.t_s.reserve(frame_daq_time_s.size());
  for (double t : frame_daq_time_s) fr.t_s.push_back(t - sensor.summary.impact_time_s);
  for (std::size_t f = 0; f + 2 < k.frames && fr.t_s[f + 2] < 0; ++f) fr.noise.push_back(f);
  fr.first_after = fr.noise.size();
  return fr;
}

// The noise of `field` at subset s over the noise frames.
double Noise(const KinematicsResult& k, const std::vector<double>& field, const Frames& fr,
             std::size_t s) {
  std::vector<double> v;
  for (std::size_t f : fr.noise)
    if (std::isfinite(field[f * k.subsets + s])) v.push_back(field[f * k.subsets + s]);
  return v.size() >= static_cast<std::size_t>(kMinNoiseFrames) ? StandardDeviation(v) : kNaN;
}

// Arrival of subset s after the impact (NaN: none), the criterion of the header; *by_peak: the
// threshold is the fraction of the peak (not the noise's).
double Arrival(const KinematicsResult& k, const Frames& fr, std::size_t s, double noise_sd,
               const WaveFrontOptions& o, bool* by_peak) {
  double peak = -std::numeric_limits<double>::infinity();
  for (std::size_t f = fr.first_after; f < k.frames; ++f) {
    const double v = k.vel_y_mm_s[f * k.subsets + s];
    if (std::isfinite(v)) peak = std::max(peak, v);
  }
  *by_peak = o.peak_fraction * peak >= o.noise_factor * noise_sd;
  if (!(peak > o.noise_factor * noise_sd)) return kNaN;
  const double threshold = std::max(o.noise_factor * noise_sd, o.peak_fraction * peak);
  for (std::size_t f = fr.first_after; f < k.frames; ++f) {
    const double v = k.vel_y_mm_s[f * k.subsets + s];
    if (!(v > threshold)) continue;
    const double before = k.vel_y_mm_s[(f - 1) * k.subsets + s];  // f >= first_after >= 1.
    if (!std::isfinite(before) || before >= threshold) return fr.t_s[f];
    return fr.t_s[f - 1] + (threshold - before) / (v - before) * (fr.t_s[f] - fr.t_s[f - 1]);
  }
  return kNaN;
}

// `candidates`: the subsets whose arrival is the peak-fraction crossing (header).
void FitFrontSpeed(const std::vector<std::size_t>& candidates, const WaveFrontOptions& o,
                   WaveFront* w) {
  std::vector<std::size_t> use = candidates;
  const auto fit = [&](const std::vector<std::size_t>& ids) {
    std::vector<double> r, t;
    r.reserve(ids.size());
    t.reserve(ids.size());
    for (std::size_t s : ids) {
      r.push_back(w->distance_mm[s]);
      t.push_back(w->arrival_s[s]);
    }
    return FitLine(r, t);
  };
  Line line = fit(use);
  if (std::isfinite(line.b)) {  // One pass without the outliers of the first fit.
    std::vector<double> res;
    res.reserve(use.size());
    for (std::size_t s : use)
      res.push_back(std::abs(w->arrival_s[s] - line.a - line.b * w->distance_mm[s]));
    std::vector<double> sorted = res;
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(sorted.size() / 2),
                     sorted.end());
    const double sigma = 1.4826 * sorted[sorted.size() / 2];
    if (sigma > 0) {
      std::vector<std::size_t> kept;
      for (std::size_t i = 0; i < use.size(); ++i)
        if (res[i] <= kOutlierSigma * sigma) kept.push_back(use[i]);
      use = kept;
      line = fit(use);
    }
  }
  if (!std::isfinite(line.b)) {
    w->problem = fmt::format(
        "{} subsets below the surface and outside the pounder's footprint have an arrival at "
        "{} of their peak velocity (a peak above {} noise standard deviations / {}) at distinct "
        "distances; the fit needs 3",
        use.size(), o.peak_fraction, o.noise_factor, o.peak_fraction);
    return;
  }
  for (std::size_t s : use) w->in_fit[s] = 1;
  w->fit_subsets = use.size();
  w->intercept_s = line.a;
  w->rms_residual_s = line.rms;
  if (!(line.b > 0)) {
    w->problem = fmt::format(
        "the arrival does not increase with the distance (slope {:.3g} s/m over {} subsets): no "
        "front runs outward",
        1e3 * line.b, use.size());
    return;
  }
  const double h = HalfWidth(line, o.confidence);
  w->speed_m_s = 1e-3 / line.b;  // r [mm], t [s].
  w->speed_ci_m_s = {1e-3 / (line.b + h), line.b - h > 0 ? 1e-3 / (line.b - h) : kNaN};
}

DepthDecayFit FitDecay(const KinematicsResult& k, const std::vector<double>& field,
                       const std::vector<double>& noise, const std::vector<std::size_t>& centre,
                       std::size_t frame, double t_s, double base_y_mm, double base_depth_mm,
                       const WaveFrontOptions& o, bool displacement) {
  DepthDecayFit d;
  d.time_s = t_s;
  std::vector<double> z, lnu;
  d.profile_depth_mm.assign(centre.size(), kNaN);
  d.profile_value.assign(centre.size(), kNaN);
  d.profile_in_fit.assign(centre.size(), 0);
  for (std::size_t i = 0; i < centre.size(); ++i) {
    const std::size_t s = centre[i];
    const double u = field[frame * k.subsets + s];
    const double depth = k.y_mm[s] - base_y_mm;
    if (!(depth > 0)) continue;
    d.profile_depth_mm[i] = depth;
    d.profile_value[i] = u;
    if (std::isfinite(u) && std::isfinite(noise[s]) && u > o.noise_factor * noise[s] && u > 0) {
      d.profile_in_fit[i] = 1;
      z.push_back(depth);
      lnu.push_back(std::log(u));
    }
  }
  d.subsets = z.size();
  const Line line = FitLine(z, lnu);
  if (!std::isfinite(line.b)) {
    d.problem = fmt::format(
        "{} centre-line subsets below the pounder move downward by more than {} noise standard "
        "deviations at {:.3f} ms; the fit needs 3 at distinct depths",
        z.size(), o.noise_factor, 1e3 * t_s);
    return d;
  }
  if (!(line.b < 0)) {
    d.problem = fmt::format("no decay with depth at {:.3f} ms (slope of ln u {:.3g} 1/m)",
                            1e3 * t_s, 1e3 * line.b);
    return d;
  }
  const double h = HalfWidth(line, o.confidence);
  d.surface_value = std::exp(line.a);
  d.decay_length_mm = -1 / line.b;
  d.decay_length_ci_mm = {-1 / (line.b - h), line.b + h < 0 ? -1 / (line.b + h) : kNaN};
  if (displacement)
    d.depth_of_influence_mm = base_depth_mm + d.decay_length_mm * std::log(1 / kInfluenceFraction);
  return d;
}

// The centre line's rows (subsets at one reference depth, within a micrometre) and each row's
// mean downward velocity per frame; the pounder's base from the sensor's penetration.
SpaceTime CentreLineSpaceTime(const KinematicsResult& k, const std::vector<std::size_t>& centre,
                              const Frames& fr, const std::vector<double>& frame_daq_time_s,
                              const SensorResult& sensor, double surface_y_mm) {
  SpaceTime st;
  st.time_s = fr.t_s;
  std::vector<std::size_t> by_depth = centre;
  std::sort(by_depth.begin(), by_depth.end(),
            [&](std::size_t a, std::size_t b) { return k.y_mm[a] < k.y_mm[b]; });
  std::vector<std::vector<std::size_t>> rows;
  for (std::size_t s : by_depth) {
    if (rows.empty() || k.y_mm[s] - k.y_mm[rows.back().front()] > 1e-3) {
      rows.emplace_back();
      st.depth_mm.push_back(k.y_mm[s] - surface_y_mm);
    }
    rows.back().push_back(s);
  }
  st.velocity_mm_s.assign(k.frames * rows.size(), kNaN);
  for (std::size_t f = 0; f < k.frames; ++f) {
    for (std::size_t r = 0; r < rows.size(); ++r) {
      double sum = 0;
      std::size_t n = 0;
      for (std::size_t s : rows[r]) {
        const double v = k.vel_y_mm_s[f * k.subsets + s];
        if (std::isfinite(v)) sum += v, ++n;
      }
      if (n > 0) st.velocity_mm_s[f * rows.size() + r] = sum / static_cast<double>(n);
    }
    st.pounder_base_mm.push_back(std::max(
        0.0, 1e3 * InterpolateSeries(sensor.time_s, sensor.penetration_m, frame_daq_time_s[f])));
  }
  return st;
}

}  // namespace

void WaveFrontOptions::Check() const {
  CheckValue(noise_factor > 0 && std::isfinite(noise_factor), "WaveFrontOptions.noise_factor",
             fmt::format("{}", noise_factor), "> 0");
  CheckValue(peak_fraction > 0 && peak_fraction < 1, "WaveFrontOptions.peak_fraction",
             fmt::format("{}", peak_fraction), "in (0, 1)");
  CheckRange(confidence, kConfidenceRange, "WaveFrontOptions.confidence", "a confidence level");
}

WaveFront AnalyzeWaveFront(const KinematicsResult& k, const std::vector<double>& frame_daq_time_s,
                           const SensorResult& sensor, double t_end_peak_s,
                           const WaveFrontOptions& o) {
  o.Check();
  WaveFront w;
  w.noise_factor = o.noise_factor;
  w.peak_fraction = o.peak_fraction;
  w.crater_depth_mm = 1e3 * sensor.summary.final_penetration_m;
  const auto give_up = [&](const std::string& why) {
    w.problem = why;
    for (DepthDecayFit* d :
         {&w.displacement_te, &w.velocity_te, &w.displacement_end, &w.velocity_end})
      d->problem = why;
    return w;
  };
  if (const std::string why = InputProblem(k, frame_daq_time_s, sensor, o); !why.empty())
    return give_up(why);
  w.computed = true;
  const Frames fr = MakeFrames(k, frame_daq_time_s, sensor);
  w.distance_mm.assign(k.subsets, kNaN);
  w.arrival_s.assign(k.subsets, kNaN);
  w.in_fit.assign(k.subsets, 0);
  if (fr.noise.size() < static_cast<std::size_t>(kMinNoiseFrames) || fr.first_after == 0)
    return give_up(fmt::format(
        "{} frames before the impact have a velocity free of it; the noise needs {} (more "
        "frames before the impact: dic.first_frame_number)",
        fr.noise.size(), kMinNoiseFrames));

  const double cx = o.pounder_center_x_mm, sy = o.surface_y_mm, half = o.pounder_width_mm / 2;
  std::vector<double> noise_v(k.subsets), noise_u(k.subsets);
  std::vector<std::size_t> outside, centre;
  for (std::size_t s = 0; s < k.subsets; ++s) {
    const double dx = k.x_mm[s] - cx, dy = k.y_mm[s] - sy;
    w.distance_mm[s] = std::hypot(dx, dy);
    noise_v[s] = Noise(k, k.vel_y_mm_s, fr, s);
    noise_u[s] = Noise(k, k.disp_y_mm, fr, s);
    bool by_peak = false;
    if (std::isfinite(noise_v[s])) w.arrival_s[s] = Arrival(k, fr, s, noise_v[s], o, &by_peak);
    if (std::isfinite(w.arrival_s[s])) ++w.arrivals;
    if (dy > 0 && std::abs(dx) > half && std::isfinite(w.arrival_s[s]) && by_peak)
      outside.push_back(s);
    if (dy > 0 && std::abs(dx) <= half) centre.push_back(s);
  }
  w.centre_line_subsets = centre.size();
  w.centre_line = centre;
  w.space_time = CentreLineSpaceTime(k, centre, fr, frame_daq_time_s, sensor, sy);
  FitFrontSpeed(outside, o, &w);

  // The pounder's base at a frame: the surface + its penetration (sensor, DAQ clock).
  const auto fit_at = [&](std::size_t f, DepthDecayFit* u, DepthDecayFit* v) {
    const double base_depth = w.space_time.pounder_base_mm[f];
    *u = FitDecay(k, k.disp_y_mm, noise_u, centre, f, fr.t_s[f], sy + base_depth, base_depth, o,
                  /*displacement=*/true);
    *v = FitDecay(k, k.vel_y_mm_s, noise_v, centre, f, fr.t_s[f], sy + base_depth, base_depth, o,
                  /*displacement=*/false);
    return base_depth;
  };
  if (std::isfinite(t_end_peak_s)) {
    std::size_t best = 0;
    for (std::size_t f = 1; f < k.frames; ++f)
      if (std::abs(fr.t_s[f] - t_end_peak_s) < std::abs(fr.t_s[best] - t_end_peak_s)) best = f;
    w.pounder_base_depth_mm = fit_at(best, &w.displacement_te, &w.velocity_te);
  } else {
    w.displacement_te.problem = w.velocity_te.problem = "t_e was not measured (momentum)";
  }
  fit_at(k.frames - 1, &w.displacement_end, &w.velocity_end);
  return w;
}

void CheckDicReflections(const KinematicsResult& k, const std::vector<double>& frame_daq_time_s,
                         const SensorResult& sensor, const WaveFrontOptions& o,
                         std::vector<WaveChannel>* channels) {
  o.Check();
  const auto not_checked = [&](const std::string& why) {
    for (WaveChannel& c : *channels) c.dic_reflection = DicReflectionCheck{.note = why};
  };
  if (const std::string why = InputProblem(k, frame_daq_time_s, sensor, o); !why.empty())
    return not_checked(why);
  // The near-surface row: the shallowest subsets below the surface outside the footprint.
  const double half = o.pounder_width_mm / 2;
  double shallowest = std::numeric_limits<double>::infinity();
  for (std::size_t s = 0; s < k.subsets; ++s) {
    const double dy = k.y_mm[s] - o.surface_y_mm;
    if (dy > 0 && std::abs(k.x_mm[s] - o.pounder_center_x_mm) > half)
      shallowest = std::min(shallowest, dy);
  }
  std::vector<std::size_t> row;
  for (std::size_t s = 0; s < k.subsets; ++s) {
    const double dy = k.y_mm[s] - o.surface_y_mm;
    if (dy > 0 && dy <= shallowest + kRowToleranceMm &&
        std::abs(k.x_mm[s] - o.pounder_center_x_mm) > half)
      row.push_back(s);
  }
  if (row.empty()) return not_checked("no subset below the surface outside the pounder's columns");
  // The signal per frame: the mean over the row's measured subsets (NaN when under half are).
  std::vector<double> signal(k.frames, kNaN);
  for (std::size_t f = 0; f < k.frames; ++f) {
    double sum = 0;
    std::size_t n = 0;
    for (std::size_t s : row) {
      const double v = k.vel_y_mm_s[f * k.subsets + s];
      if (std::isfinite(v)) sum += v, ++n;
    }
    if (2 * n >= row.size() && n > 0) signal[f] = sum / static_cast<double>(n);
  }
  const Frames fr = MakeFrames(k, frame_daq_time_s, sensor);
  std::vector<double> quiet;
  for (std::size_t f : fr.noise)
    if (std::isfinite(signal[f])) quiet.push_back(signal[f]);
  const double noise =
      quiet.size() >= static_cast<std::size_t>(kMinNoiseFrames) ? StandardDeviation(quiet) : kNaN;
  for (WaveChannel& c : *channels) {
    DicReflectionCheck& r = c.dic_reflection;
    r = DicReflectionCheck{.subsets = row.size()};
    const std::array<double, 2>& window = c.reflection.window_s;
    if (!std::isfinite(window[0]) || !std::isfinite(window[1])) {
      r.note = "no return time (no plausible wave speed)";
      continue;
    }
    if (!std::isfinite(noise)) {
      r.note = fmt::format(
          "{} frames before the impact have a near-surface velocity free of it; the noise needs "
          "{}",
          quiet.size(), kMinNoiseFrames);
      continue;
    }
    if (!(fr.t_s.back() >= window[1])) {
      r.note = fmt::format("the frames end {:.4g} ms after the impact, before the window's end",
                           1e3 * fr.t_s.back());
      continue;
    }
    std::size_t a = 0, b = k.frames - 1;
    while (a + 1 < k.frames && fr.t_s[a + 1] <= window[0]) ++a;
    while (b > 0 && fr.t_s[b - 1] >= window[1]) --b;
    std::vector<double> up(signal), down(signal);
    for (std::size_t f = a; f <= b; ++f) {
      if (!std::isfinite(signal[f])) {
        r.note =
            fmt::format("the near-surface velocity is not measured at {:.4g} ms", 1e3 * fr.t_s[f]);
        break;
      }
      up[f] = -signal[f];
    }
    if (!r.note.empty()) continue;
    r.checked = true;
    r.prominence_mm_s = std::max(LargestProminence(down, a, b), LargestProminence(up, a, b));
    r.threshold_mm_s = kReflectionSigma * noise;
    r.local_maximum = r.prominence_mm_s > r.threshold_mm_s;
  }
}

}  // namespace impactdic
