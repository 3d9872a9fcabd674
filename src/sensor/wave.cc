#include "impactdic/sensor/wave.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <string>
#include <vector>

#include "impactdic/core/error.h"

namespace impactdic {
namespace {

std::size_t FirstAtOrAfter(const std::vector<double>& t, double tq) {
  return static_cast<std::size_t>(std::lower_bound(t.begin(), t.end(), tq) - t.begin());
}

// Standard deviation of x over [begin, end) (0 for fewer than 2 samples).
double StdDevOver(const std::vector<double>& x, std::size_t begin, std::size_t end) {
  if (end <= begin + 1) return 0;
  double mean = 0;
  for (std::size_t i = begin; i < end; ++i) mean += x[i];
  mean /= static_cast<double>(end - begin);
  double ss = 0;
  for (std::size_t i = begin; i < end; ++i) ss += (x[i] - mean) * (x[i] - mean);
  return std::sqrt(ss / static_cast<double>(end - begin - 1));
}

// The reflection check of a return time (wave.h): the filtered deceleration's local maxima in the
// window around it.
ReflectionCheck CheckReflection(const SensorResult& sensor, const WaveResult& w,
                                double return_time_s, double return_sigma_s) {
  ReflectionCheck r;
  if (!std::isfinite(return_time_s)) {
    r.note = "no return time (no plausible wave speed)";
    return r;
  }
  const double half = std::max(kReflectionMinHalfWindowS, 3 * return_sigma_s);
  r.window_s = {return_time_s - half, return_time_s + half};
  const std::vector<double>& t = sensor.time_s;
  const double t0 = sensor.summary.impact_time_s;
  if (!(t0 + r.window_s[1] <= t.back())) {
    r.note = fmt::format("the record ends {:.4g} ms after the impact, before the window's end",
                         1e3 * (t.back() - t0));
    return r;
  }
  const std::size_t a = FirstAtOrAfter(t, t0 + r.window_s[0]);
  std::size_t b = FirstAtOrAfter(t, t0 + r.window_s[1]);
  b = std::min(b, t.size() - 1);
  std::vector<double> decel(sensor.accel_g.size());
  for (std::size_t i = 0; i < decel.size(); ++i) decel[i] = sensor.accel_g[i] - 1;
  r.checked = true;
  r.prominence_g = LargestProminence(decel, a, b);
  r.threshold_g = kReflectionSigma * w.noise_g;
  r.local_maximum = r.prominence_g > r.threshold_g;
  return r;
}

// The speed r / travel with its uncertainty, or NaN with the reason in `problems`.
void Speed(double distance_m, double travel_s, double sigma_t_s, const std::string& which,
           const std::string& column, double* speed, double* sigma, WaveChannel* c) {
  if (!std::isfinite(travel_s)) return;
  if (!(travel_s > 0)) {
    c->problems.push_back(fmt::format(
        "{} travel time {:.4g} ms is not positive: the sensor's {} comes before the pounder's; "
        "check the column ({}) and its position (sensor.base_depths_mm, sensor.base_offsets_mm)",
        which, 1e3 * travel_s, which, column));
    return;
  }
  const double c_m_s = distance_m / travel_s;
  if (!kWaveSpeedRange.Contains(c_m_s)) {
    c->problems.push_back(fmt::format(
        "{} wave speed {:.4g} m/s (distance {:.4g} mm over {:.4g} ms) is outside {} (soils' "
        "compression waves): check the position (sensor.base_depths_mm, sensor.base_offsets_mm) "
        "and the column ({})",
        which, c_m_s, 1e3 * distance_m, 1e3 * travel_s, kWaveSpeedRange.Text(), column));
    return;
  }
  *speed = c_m_s;
  *sigma = c_m_s * sigma_t_s / travel_s;
}

WaveChannel AnalyzeChannel(const SensorResult& sensor, const SensorOptions& options, std::size_t k,
                           const WaveResult& w) {
  const BaseForceChannel& b = sensor.base[k];
  const SensorSummary& s = sensor.summary;
  WaveChannel c;
  c.column = b.column;
  c.unit = ToString(b.unit);
  c.offset_mm = options.base.offset_mm[k];
  c.depth_mm = options.base.depth_mm[k];
  c.area_mm2 = options.base.area_mm2[k];
  c.distance_mm = std::hypot(c.offset_mm, c.depth_mm);
  if (!b.problem.empty()) {
    c.problems.push_back(b.problem);
    return c;
  }
  c.onset_s = b.onset_time_s - s.impact_time_s;
  c.peak_s = b.peak_time_s - s.impact_time_s;
  c.travel_onset_s = c.onset_s;
  c.travel_peak_s = b.peak_time_s - s.peak_time_s;
  const double r_m = 1e-3 * c.distance_mm;
  Speed(r_m, c.travel_peak_s, w.travel_time_sigma_s, "peak", c.column, &c.speed_peak_m_s,
        &c.speed_peak_sigma_m_s, &c);
  Speed(r_m, c.travel_onset_s, w.travel_time_sigma_s, "onset", c.column, &c.speed_onset_m_s,
        &c.speed_onset_sigma_m_s, &c);
  if (std::isfinite(c.speed_peak_m_s)) {
    const double depth_m = 1e-3 * c.depth_mm;
    c.return_time_s = 2 * depth_m / c.speed_peak_m_s;
    c.return_time_sigma_s =
        2 * depth_m * c.speed_peak_sigma_m_s / (c.speed_peak_m_s * c.speed_peak_m_s);
  }
  c.peak_force_n = b.peak_force_n;
  const double stress = b.peak_force_n / (1e-6 * c.area_mm2);
  const double ratio = stress / w.pounder_peak_stress_pa;
  if (!std::isfinite(ratio)) {
    c.peak_stress_pa = stress;
    c.problems.push_back("no stress ratio: the pounder's peak deceleration is not known");
  } else if (ratio < 1) {
    c.peak_stress_pa = stress;
    c.stress_ratio = ratio;
  } else {
    c.problems.push_back(fmt::format(
        "peak stress {:.4g} kPa ({:.4g} N over {:.4g} mm^2) is {:.3g} times the pounder's "
        "{:.4g} kPa: the bed cannot raise the stress; check the unit (sensor.base_units: {} "
        "given; kN for a record in N multiplies it by 1000) and the area (sensor.base_areas_mm2)",
        1e-3 * stress, b.peak_force_n, c.area_mm2, ratio, 1e-3 * w.pounder_peak_stress_pa, c.unit));
  }
  c.reflection = CheckReflection(sensor, w, c.return_time_s, c.return_time_sigma_s);
  return c;
}

}  // namespace

double LargestProminence(const std::vector<double>& y, std::size_t a, std::size_t b) {
  if (b < a + 2) return 0;
  const std::size_t n = b - a + 1;
  std::vector<double> left_min(n), right_min(n);
  left_min[0] = y[a];
  for (std::size_t i = 1; i < n; ++i) left_min[i] = std::min(left_min[i - 1], y[a + i]);
  right_min[n - 1] = y[b];
  for (std::size_t i = n - 1; i-- > 0;) right_min[i] = std::min(right_min[i + 1], y[a + i]);
  double best = 0;
  for (std::size_t i = 1; i + 1 < n; ++i) {
    const double v = y[a + i];
    if (v > y[a + i - 1] && v >= y[a + i + 1])
      best = std::max(best, v - std::max(left_min[i], right_min[i]));
  }
  return best;
}

void WaveOptions::Check() const {
  CheckRange(pounder_mass_kg, kPounderMassRange, "test.mass_kg", "a pounder mass");
  CheckRange(pounder_width_m, kPounderSizeRange, "test.width_m", "a pounder width D");
  CheckRange(pounder_depth_m, kPounderSizeRange, "test.depth_m", "an out-of-plane depth t_z");
  CheckValue(std::isfinite(g_m_s2) && g_m_s2 > 0, "test.g_m_s2", fmt::format("{}", g_m_s2), "> 0");
}

const WaveChannel* WaveResult::CentreChannel() const {
  const WaveChannel* best = nullptr;
  for (const WaveChannel& c : channels)
    if (best == nullptr || std::abs(c.offset_mm) < std::abs(best->offset_mm)) best = &c;
  return best;
}

std::vector<std::string> WaveResult::Warnings() const {
  std::vector<std::string> out;
  for (const WaveChannel& c : channels)
    for (const std::string& p : c.problems) out.push_back(c.column + ": " + p);
  return out;
}

WaveResult AnalyzeWave(const SensorResult& sensor, const SensorOptions& options,
                       const WaveOptions& wave) {
  wave.Check();
  CheckValue(sensor.base.size() == options.columns.base_force.size(), "wave analysis",
             fmt::format("{} processed base channels", sensor.base.size()),
             fmt::format("the {} of sensor.base_columns", options.columns.base_force.size()));
  const SensorSummary& s = sensor.summary;
  const std::vector<double>& t = sensor.time_s;
  WaveResult w;
  w.pounder_peak_stress_pa = wave.pounder_mass_kg * wave.g_m_s2 * s.peak_deceleration_g /
                             (wave.pounder_width_m * wave.pounder_depth_m);
  w.pounder_peak_s = s.peak_time_s - s.impact_time_s;
  w.sample_interval_s = 1 / s.sample_rate_hz;
  w.filter_time_constant_s = 1 / (2 * std::numbers::pi * s.cutoff_hz);
  w.travel_time_sigma_s = std::sqrt(2 * w.sample_interval_s * w.sample_interval_s / 12 +
                                    w.filter_time_constant_s * w.filter_time_constant_s);
  const std::size_t r1 = FirstAtOrAfter(t, s.impact_time_s - options.quiet_guard_s);
  const std::size_t r0 =
      FirstAtOrAfter(t, s.impact_time_s - options.quiet_guard_s - options.quiet_window_s);
  w.noise_g = StdDevOver(sensor.accel_g, r0, r1);
  for (std::size_t k = 0; k < sensor.base.size(); ++k)
    w.channels.push_back(AnalyzeChannel(sensor, options, k, w));
  return w;
}

}  // namespace impactdic
