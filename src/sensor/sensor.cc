#include "impactdic/sensor/sensor.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/core/numeric.h"
#include "impactdic/core/strings.h"
#include "impactdic/core/timer.h"
#include "impactdic/io/csv.h"
#include "impactdic/sensor/filter.h"

namespace impactdic {
namespace {

double Mean(const std::vector<double>& x, std::size_t begin, std::size_t end) {
  double s = 0;
  for (std::size_t i = begin; i < end; ++i) s += x[i];
  return s / static_cast<double>(end - begin);
}

double StdDev(const std::vector<double>& x, std::size_t begin, std::size_t end) {
  const double m = Mean(x, begin, end);
  double s = 0;
  for (std::size_t i = begin; i < end; ++i) s += (x[i] - m) * (x[i] - m);
  return end - begin > 1 ? std::sqrt(s / static_cast<double>(end - begin - 1)) : 0.0;
}

std::size_t FirstIndexAtOrAfter(const std::vector<double>& t, double tq) {
  return static_cast<std::size_t>(std::lower_bound(t.begin(), t.end(), tq) - t.begin());
}

}  // namespace

double InterpolateSeries(const std::vector<double>& t, const std::vector<double>& y, double tq) {
  if (t.empty()) return kNaN;
  if (tq <= t.front()) return y.front();
  if (tq >= t.back()) return y.back();
  const auto it = std::upper_bound(t.begin(), t.end(), tq);
  const std::size_t k = static_cast<std::size_t>(it - t.begin());
  const double w = (tq - t[k - 1]) / (t[k] - t[k - 1]);
  return y[k - 1] + w * (y[k] - y[k - 1]);
}

const char* ToString(AccelUnit unit) { return kAccelUnitNames.Name(unit); }

AccelUnit AccelUnitFromString(const std::string& text) {
  return kAccelUnitNames.Parse(text, "accel_unit");
}

const char* ToString(OffsetReference reference) { return kOffsetReferenceNames.Name(reference); }

OffsetReference OffsetReferenceFromString(const std::string& text) {
  return kOffsetReferenceNames.Parse(text, "offset_reference");
}

const char* ToString(IntegrationStart start) { return kIntegrationStartNames.Name(start); }

IntegrationStart IntegrationStartFromString(const std::string& text) {
  return kIntegrationStartNames.Parse(text, "integrate_from");
}

const char* ToString(ForceUnit unit) { return kForceUnitNames.Name(unit); }

ForceUnit ForceUnitFromString(const std::string& text) {
  return kForceUnitNames.Parse(text, "sensor.base_units");
}

double NewtonsPer(ForceUnit unit) { return unit == ForceUnit::kKilonewton ? 1000.0 : 1.0; }

namespace {

// The base channels' lists (BaseForceOptions) against sensor.base_columns: each as long, every
// value in its range. Named by their scene keys.
void CheckBaseForce(const std::vector<std::string>& columns, const BaseForceOptions& base) {
  const std::size_t n = columns.size();
  for (const std::string& c : columns)
    CheckValue(!c.empty(), "sensor.base_columns", "an empty column name", "column names");
  const auto length = [n](std::size_t size, const char* key) {
    CheckValue(size == n, key, fmt::format("{} values for {} base columns", size, n),
               fmt::format("one value per column of sensor.base_columns ({})", n));
  };
  length(base.units.size(), "sensor.base_units");
  length(base.offset_mm.size(), "sensor.base_offsets_mm");
  length(base.depth_mm.size(), "sensor.base_depths_mm");
  length(base.area_mm2.size(), "sensor.base_areas_mm2");
  const auto in_range = [](const std::vector<double>& values, const ValueRange& range,
                           const char* key, const char* what) {
    for (std::size_t k = 0; k < values.size(); ++k)
      CheckValue(range.Contains(values[k]), fmt::format("{}[{}]", key, k),
                 fmt::format("{}", values[k]), ExpectedText(what, range));
  };
  in_range(base.offset_mm, kBaseOffsetRange, "sensor.base_offsets_mm", "a horizontal offset");
  in_range(base.depth_mm, kBaseDepthRange, "sensor.base_depths_mm", "a depth below the surface");
  in_range(base.area_mm2, kBaseAreaRange, "sensor.base_areas_mm2", "a sensing area");
}

}  // namespace

void SensorOptions::Check() const {
  CheckValue(!columns.time.empty(), "sensor.columns.time", "an empty name", "a column name");
  CheckValue(std::isfinite(g_m_s2) && g_m_s2 > 0, "sensor.g_m_s2", fmt::format("{}", g_m_s2),
             "> 0");
  CheckValue(std::isfinite(cutoff_hz) && kCutoffRange.Contains(cutoff_hz), "sensor.cutoff_hz",
             fmt::format("{}", cutoff_hz),
             ExpectedText("a cut-off frequency", kCutoffRange) + ", below the Nyquist frequency");
  CheckValue(kQuietWindowRange.Contains(quiet_window_s), "sensor.quiet_window_s",
             fmt::format("{}", quiet_window_s), ExpectedText("a window length", kQuietWindowRange));
  CheckValue(std::isfinite(quiet_guard_s) && kQuietGuardRange.Contains(quiet_guard_s),
             "sensor.quiet_guard_s", fmt::format("{}", quiet_guard_s), ">= 0 s");
  if (integrate_from == IntegrationStart::kImpact) {
    CheckValue(std::isfinite(impact_velocity_m_s) && impact_velocity_m_s > 0,
               "sensor.impact_velocity_m_s", fmt::format("{}", impact_velocity_m_s),
               "> 0 m/s when integrating from the impact");
  }
  CheckValue(std::isnan(release_time_s) || std::isfinite(release_time_s), "sensor.release_time_s",
             fmt::format("{}", release_time_s), "a finite time or NaN (unknown)");
  CheckValue(std::isnan(release_time_s) || integrate_from == IntegrationStart::kRelease,
             "sensor.release_time_s",
             fmt::format("{} s, integrating from the impact", release_time_s),
             "a release time only when integrating from the release (integrate_from release)");
  CheckValue(
      std::isfinite(impact_threshold_g) && kImpactThresholdRange.Contains(impact_threshold_g),
      "sensor.impact_threshold_g", fmt::format("{}", impact_threshold_g),
      ExpectedText("an impact threshold", kImpactThresholdRange));
  CheckValue(std::isfinite(noise_band_sigma) && kNoiseBandSigmaRange.Contains(noise_band_sigma),
             "sensor.noise_band_sigma", fmt::format("{}", noise_band_sigma), "> 0");
  CheckValue(std::isfinite(stop_velocity_m_s) && kStopVelocityRange.Contains(stop_velocity_m_s),
             "sensor.stop_velocity_m_s", fmt::format("{}", stop_velocity_m_s), ">= 0 m/s");
  CheckValue(
      std::isfinite(max_step_deviation) && max_step_deviation > 0 && max_step_deviation <= 0.5,
      "sensor.max_step_deviation", fmt::format("{}", max_step_deviation), "in (0, 0.5]");
  CheckValue(std::isnan(expected_impact_velocity_m_s) ||
                 (std::isfinite(expected_impact_velocity_m_s) && expected_impact_velocity_m_s > 0),
             "sensor.expected_impact_velocity_m_s", fmt::format("{}", expected_impact_velocity_m_s),
             "> 0 m/s or NaN (not checked)");
  CheckBaseForce(columns.base_force, base);
}

SensorRecord ReadSensorCsv(const std::string& path, const SensorColumns& columns, double g_m_s2,
                           double max_step_deviation) {
  CsvReadOptions csv;
  csv.required_columns = {columns.time};
  csv.increasing_column = columns.time;
  const CsvTable table = ReadCsv(path, csv);

  std::string names;
  for (const auto& n : table.names) names += (names.empty() ? "" : ", ") + n;
  std::string accel = columns.accel;
  if (accel.empty()) {
    for (const char* candidate : {"accel_g", "accel_m_s2"})
      if (table.Has(candidate)) {
        accel = candidate;
        break;
      }
    if (accel.empty()) {
      throw Error(ErrorKind::kFileFormat, "acceleration column", "none; columns are " + names,
                  "a column 'accel_g' or 'accel_m_s2' (or name it with the accel column option)")
          .WithFile(path);
    }
  }
  if (!table.Has(accel)) {
    throw Error(ErrorKind::kFileFormat, "column '" + accel + "'", "missing; columns are " + names,
                "the acceleration column named in the options")
        .WithFile(path);
  }
  AccelUnit unit = columns.accel_unit;
  if (unit == AccelUnit::kAuto) {
    const std::string l = ToLower(accel);
    if (EndsWith(l, "_g") || l == "g") {
      unit = AccelUnit::kG;
    } else if (EndsWith(l, "_m_s2") || EndsWith(l, "m/s^2") || EndsWith(l, "m/s2")) {
      unit = AccelUnit::kMetrePerSecond2;
    } else {
      throw Error(ErrorKind::kInvalidValue, "accel_unit",
                  "auto, but column '" + accel + "' does not name its unit",
                  "g or m/s^2 (or a column name ending _g or _m_s2)")
          .WithFile(path);
    }
  }

  SensorRecord r;
  r.path = path;
  r.column_names = table.names;
  r.time_s = table.Column(columns.time);
  r.accel_g = table.Column(accel);
  if (unit == AccelUnit::kMetrePerSecond2)
    for (double& a : r.accel_g) a /= g_m_s2;
  if (!columns.exposure.empty() && table.Has(columns.exposure))
    r.exposure = table.Column(columns.exposure);
  if (columns.force.empty()) {
    for (const auto& n : table.names)
      if (StartsWith(ToLower(n), "force")) r.force_names.push_back(n);
  } else {
    r.force_names = columns.force;
  }
  for (const auto& n : r.force_names) r.force.push_back(table.Column(n));
  for (const auto& n : columns.base_force) {
    if (!table.Has(n)) {
      throw Error(ErrorKind::kFileFormat, "base force column '" + n + "' (sensor.base_columns)",
                  "missing; columns are " + names, "a column named as in sensor.base_columns")
          .WithFile(path);
    }
    r.base_force.push_back(table.Column(n));
  }

  const std::size_t n = r.time_s.size();
  if (n < 32) {
    throw Error(ErrorKind::kFileFormat, "rows", fmt::format("{} samples", n), "at least 32 samples")
        .WithFile(path);
  }
  std::vector<double> dt(n - 1);
  for (std::size_t i = 1; i < n; ++i) dt[i - 1] = r.time_s[i] - r.time_s[i - 1];
  std::vector<double> sorted = dt;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2),
                   sorted.end());
  const double median = sorted[sorted.size() / 2];
  for (std::size_t i = 0; i < dt.size(); ++i) {
    if (std::abs(dt[i] - median) > max_step_deviation * median) {
      throw Error(ErrorKind::kFileFormat, "column '" + columns.time + "'",
                  fmt::format("a time step of {:.6g} s between t = {:.9g} s and t = {:.9g} s "
                              "(data rows {} and {}); the median step is {:.6g} s",
                              dt[i], r.time_s[i], r.time_s[i + 1], i + 1, i + 2, median),
                  fmt::format("uniform sampling (every step within {:.3g} % of the median): "
                              "gaps or jitter break the filter and the integration",
                              100 * max_step_deviation))
          .WithFile(path);
    }
  }
  r.sample_rate_hz = 1 / median;
  return r;
}

double DetectImpactOnset(const std::vector<double>& time_s, const std::vector<double>& raw_g,
                         const std::vector<double>& filtered_g, std::size_t search_from,
                         const OnsetOptions& options, std::size_t* index) {
  const std::size_t n = time_s.size();
  std::size_t ks = search_from;
  while (ks < n && !(filtered_g[ks] > options.threshold_g)) ++ks;
  if (ks >= n) {
    const auto it = std::max_element(filtered_g.begin(), filtered_g.end());
    throw Error(ErrorKind::kNumerical, "impact detection",
                fmt::format("the filtered reading never exceeds {} g (maximum {:.3g} g at "
                            "t = {:.6g} s)",
                            options.threshold_g, *it,
                            time_s[static_cast<std::size_t>(it - filtered_g.begin())]),
                "a record containing the impact (or lower impact_threshold_g)");
  }
  const double dt = (time_s.back() - time_s.front()) / static_cast<double>(n - 1);
  const auto w = static_cast<std::size_t>(std::lround(options.window_s / dt));
  const auto guard = static_cast<std::size_t>(std::lround(options.guard_s / dt));
  if (ks < guard + 8) {
    throw Error(ErrorKind::kInvalidValue, "impact detection",
                fmt::format("the impact at t = {:.6g} s is only {} samples after the record "
                            "starts",
                            time_s[ks], ks),
                "a free-fall part before the impact (quiet_guard_s + at least 8 samples)");
  }
  const std::size_t a1 = ks - guard;
  const std::size_t a0 = a1 > w ? a1 - w : 0;
  const double base = Mean(filtered_g, a0, a1);
  const double sigma = StdDev(filtered_g, a0, a1);
  const double band = std::max(options.noise_band_sigma * sigma, 0.01 * options.threshold_g);
  std::size_t k0 = ks;
  while (k0 > a1 && filtered_g[k0] > base + band) --k0;

  // Change-point fit on the raw reading: y = c (j < m), y = c + J + s (t_j - t_m) (j >= m).
  // The two parts decouple: c is the mean before m, (c + J, s) a straight-line fit after.
  const std::size_t span = std::max<std::size_t>(10, ks - k0);
  const std::size_t lo = k0 > span ? k0 - span : 0;
  const std::size_t hi = std::min(n - 1, ks + 3);
  const std::size_t m_first = std::max(lo + 3, k0 > 3 ? k0 - 3 : 0);
  const std::size_t m_last = std::min(ks + 1, hi - 1);
  double best_sse = std::numeric_limits<double>::infinity();
  std::size_t best_m = ks;
  double best_jump = 0, best_slope = 0;
  for (std::size_t m = m_first; m <= m_last; ++m) {
    const double c = Mean(raw_g, lo, m);
    double sse = 0;
    for (std::size_t j = lo; j < m; ++j) sse += (raw_g[j] - c) * (raw_g[j] - c);
    // Line fit over j = m..hi in x = t_j - t_m.
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    const double cnt = static_cast<double>(hi - m + 1);
    for (std::size_t j = m; j <= hi; ++j) {
      const double x = time_s[j] - time_s[m];
      sx += x;
      sy += raw_g[j];
      sxx += x * x;
      sxy += x * raw_g[j];
    }
    const double det = cnt * sxx - sx * sx;
    const double slope = det > 0 ? (cnt * sxy - sx * sy) / det : 0;
    const double intercept = (sy - slope * sx) / cnt;
    for (std::size_t j = m; j <= hi; ++j) {
      const double r = raw_g[j] - intercept - slope * (time_s[j] - time_s[m]);
      sse += r * r;
    }
    if (sse < best_sse) {
      best_sse = sse;
      best_m = m;
      best_jump = intercept - c;
      best_slope = slope;
    }
  }
  const double step = time_s[best_m] - time_s[best_m - 1];
  double back = 0.5 * step;
  if (best_slope > 0) back = std::clamp(best_jump / best_slope, 0.0, step);
  const double onset = time_s[best_m] - back;
  *index = back >= step ? best_m - 1 : best_m;
  return onset;
}

namespace {

// The sample rate of the record: given, else from its time span.
double SampleRate(const SensorRecord& record, const SensorOptions& options) {
  const std::size_t n = record.time_s.size();
  CheckValue(n >= 32 && record.accel_g.size() == n, "sensor record",
             fmt::format("{} times, {} readings", n, record.accel_g.size()),
             "at least 32 samples, one reading per time");
  const double fs = record.sample_rate_hz > 0 ? record.sample_rate_hz
                                              : static_cast<double>(n - 1) /
                                                    (record.time_s.back() - record.time_s.front());
  if (!(options.cutoff_hz < 0.5 * fs)) {
    throw Error(ErrorKind::kInvalidValue, "sensor.cutoff_hz",
                fmt::format("{} Hz", options.cutoff_hz),
                fmt::format("below the Nyquist frequency {} Hz of this record", 0.5 * fs));
  }
  return fs;
}

// The quiet part of the record before the impact.
struct FreeFall {
  std::size_t w = 0, guard = 0;   // Quiet window and guard [samples].
  std::size_t ff0 = 0, ff1 = 0;   // The free-fall window [ff0, ff1) before the impact.
  double first_mean = 0;          // Mean reading of the record's first window.
  double window_level = 0;        // Mean reading of the free-fall window (~0 g + offset).
  bool starts_at_rest = false;    // The first window reads ~1 g more than the free fall.
  std::size_t release_index = 0;  // First sample after the release; n if not in the record.
};

// Coarse impact on the uncorrected reading (the threshold is far above any plausible offset),
// the free-fall window before it and the release. The record starts at rest (reading ~1 g) when
// its first window reads ~1 g more than the free fall before the impact. Release: the reading
// steps from the rest level (1 g) to free fall (0 g); the zero-phase filter's kernel is
// symmetric, so a step's instant is where the filtered reading crosses the midpoint between the
// two levels (interpolated between samples).
FreeFall FindFreeFall(const SensorRecord& record, const std::vector<double>& filtered_raw,
                      const SensorOptions& options, double fs, SensorSummary* s) {
  const std::vector<double>& t = record.time_s;
  const std::size_t n = t.size();
  FreeFall ff;
  ff.w = static_cast<std::size_t>(std::lround(options.quiet_window_s * fs));
  ff.guard = static_cast<std::size_t>(std::lround(options.quiet_guard_s * fs));
  CheckValue(ff.w >= 8 && ff.w < n / 2, "sensor.quiet_window_s",
             fmt::format("{} s = {} samples", options.quiet_window_s, ff.w),
             fmt::format("at least 8 samples and less than half the record ({} samples)", n));
  std::size_t ks = 0;
  while (ks < n && !(filtered_raw[ks] > options.impact_threshold_g)) ++ks;
  if (ks >= n) {
    const auto it = std::max_element(filtered_raw.begin(), filtered_raw.end());
    throw Error(ErrorKind::kNumerical, "impact detection",
                fmt::format("the filtered reading never exceeds {} g (maximum {:.3g} g at "
                            "t = {:.6g} s)",
                            options.impact_threshold_g, *it,
                            t[static_cast<std::size_t>(it - filtered_raw.begin())]),
                "a record containing the impact (or a lower impact threshold)")
        .WithFile(record.path);
  }
  if (ks < ff.guard + ff.w) {
    throw Error(ErrorKind::kInvalidValue, "sensor.quiet_window_s",
                fmt::format("{} s of free fall needed before the impact at t = {:.6g} s, the "
                            "record has {:.6g} s",
                            options.quiet_window_s + options.quiet_guard_s, t[ks], t[ks] - t[0]),
                "a record with free fall before the impact, or a shorter quiet window")
        .WithFile(record.path);
  }
  ff.ff1 = ks - ff.guard;
  ff.ff0 = ff.ff1 - ff.w;
  ff.first_mean = Mean(record.accel_g, 0, ff.w);
  ff.window_level = Mean(record.accel_g, ff.ff0, ff.ff1);
  ff.starts_at_rest = std::abs(ff.first_mean - ff.window_level - 1) < 0.5;
  ff.release_index = n;
  if (ff.starts_at_rest) {
    const double mid = ff.window_level + 0.5 * (ff.first_mean - ff.window_level);
    std::size_t k = ff.w;
    while (k < ks && filtered_raw[k] > mid) ++k;
    if (k > 0 && k < ks) {
      const double f = (filtered_raw[k - 1] - mid) / (filtered_raw[k - 1] - filtered_raw[k]);
      s->release_time_s = t[k - 1] + std::clamp(f, 0.0, 1.0) * (t[k] - t[k - 1]);
      ff.release_index = k;
    }
  }
  return ff;
}

// The accelerometer offset by SensorOptions::offset_reference, its window, the noise level and
// the warnings about both.
void EstimateOffset(const SensorRecord& record, const FreeFall& ff, const SensorOptions& options,
                    SensorSummary* s) {
  const std::vector<double>& t = record.time_s;
  const std::size_t n = t.size();
  std::size_t off0 = ff.ff0, off1 = ff.ff1;
  switch (options.offset_reference) {
    case OffsetReference::kFreeFall:
      // The whole free fall (release + guard .. impact - guard) when the release is in the record:
      // the offset's statistical error shrinks with the square root of its length.
      if (ff.release_index < n && ff.release_index + ff.guard + ff.w < ff.ff1)
        off0 = ff.release_index + ff.guard;
      s->offset_g = Mean(record.accel_g, off0, off1);
      break;
    case OffsetReference::kFreeFallWindow: s->offset_g = ff.window_level; break;
    case OffsetReference::kRest:
      if (!ff.starts_at_rest) {
        throw Error(
            ErrorKind::kInvalidValue, "offset_reference = rest",
            fmt::format("a record whose first {} s read {:.3g} g, {:.3g} g above the free "
                        "fall before the impact",
                        options.quiet_window_s, ff.first_mean, ff.first_mean - ff.window_level),
            "a record starting with the pounder at rest (1 g above free fall), or the "
            "free-fall offset reference")
            .WithFile(record.path);
      }
      off0 = 0;
      off1 = ff.w;
      s->offset_g = ff.first_mean - 1;
      break;
    case OffsetReference::kNone:
      off0 = off1 = 0;
      s->offset_g = 0;
      break;
  }
  s->offset_window_s = {off1 > off0 ? t[off0] : kNaN, off1 > off0 ? t[off1 - 1] : kNaN};
  s->noise_g = StdDev(record.accel_g, ff.ff0, ff.ff1);
  if (std::abs(s->offset_g) > 0.2)
    s->warnings.push_back(fmt::format("large accelerometer offset {:.3g} g", s->offset_g));
  const double ff_level = ff.window_level - s->offset_g;
  if (std::abs(ff_level) > 0.1 + 5 * s->noise_g) {
    s->warnings.push_back(fmt::format(
        "the window before the impact reads {:.3g} g after offset correction, not 0 g (free fall)",
        ff_level));
  }
}

// Trapezoidal integration of a (downward acceleration) from sample i0 on, v and z given there.
void IntegrateForward(const std::vector<double>& t, const std::vector<double>& a, std::size_t i0,
                      std::vector<double>* v, std::vector<double>* z) {
  for (std::size_t i = i0 + 1; i < t.size(); ++i) {
    const double h = t[i] - t[i - 1];
    (*v)[i] = (*v)[i - 1] + 0.5 * (a[i - 1] + a[i]) * h;
    (*z)[i] = (*z)[i - 1] + 0.5 * ((*v)[i - 1] + (*v)[i]) * h;
  }
}

// From the release: v = 0 at the release, z relative to the impact position; sets the impact
// velocity. A given release time must lie inside the record, before the impact; else the release
// detected in a record that starts at rest (FindFreeFall). The pounder is held still before the
// release: v = z = 0 up to quiet_guard_s before the detected release (the filtered step has
// settled there: 1 ms is 9 time constants of the 1500 Hz filter), then the trapezoidal integral.
// Integrating the rest period as well would add its reading's error: a 1 % gain error reads
// 1.01 g at rest, -0.098 m/s^2, i.e. -0.98 m/s after 10 s at rest.
void IntegrateFromRelease(const SensorRecord& record, const FreeFall& ff,
                          const SensorOptions& options, const std::vector<double>& a,
                          std::vector<double>* v, std::vector<double>* z, SensorSummary* s) {
  const std::vector<double>& t = record.time_s;
  const double g = options.g_m_s2;
  std::size_t i0 = 0;
  if (std::isfinite(options.release_time_s)) {
    const double tr = options.release_time_s;
    if (!(tr >= t.front() && tr < s->impact_time_s)) {
      throw Error(ErrorKind::kInvalidValue, "sensor.release_time_s", fmt::format("{} s", tr),
                  fmt::format("a time inside the record, which spans [{:.6g} s, {:.6g} s], and "
                              "before the detected impact at {:.6g} s",
                              t.front(), t.back(), s->impact_time_s))
          .WithFile(record.path);
    }
    s->release_time_s = tr;
    i0 = FirstIndexAtOrAfter(t, tr);
    const double fall = t[i0] - tr;  // Free fall between the release and sample i0.
    (*v)[i0] = g * fall;
    (*z)[i0] = 0.5 * g * fall * fall;
  } else if (!ff.starts_at_rest || ff.release_index >= t.size()) {
    throw Error(ErrorKind::kInvalidValue, "integrate_from = release",
                ff.starts_at_rest
                    ? fmt::format("a record starting at rest in which no release was found "
                                  "before the impact at {:.6g} s",
                                  s->impact_time_s)
                    : fmt::format("a record starting at {:.3g} g (the first {} s), not at rest "
                                  "(1 g)",
                                  ff.first_mean - s->offset_g, options.quiet_window_s),
                "a record that starts with the pounder held at rest, a release time inside the "
                "record, or integration from the impact with a given impact velocity")
        .WithFile(record.path);
  } else {
    i0 = FirstIndexAtOrAfter(t, s->release_time_s - options.quiet_guard_s);
  }
  IntegrateForward(t, a, i0, v, z);
  s->impact_velocity_m_s = InterpolateSeries(t, *v, s->impact_time_s);
  const double zi = InterpolateSeries(t, *z, s->impact_time_s);
  for (double& zk : *z) zk -= zi;
}

// From the impact with the given impact velocity: forwards and backwards from there.
void IntegrateFromImpact(const std::vector<double>& t, const std::vector<double>& a,
                         const SensorOptions& options, std::vector<double>* v,
                         std::vector<double>* z, SensorSummary* s) {
  const double ti = s->impact_time_s, v0 = options.impact_velocity_m_s;
  const std::size_t m = FirstIndexAtOrAfter(t, ti);
  const double ai = InterpolateSeries(t, a, ti);
  (*v)[m] = v0 + 0.5 * (ai + a[m]) * (t[m] - ti);
  (*z)[m] = 0.5 * (v0 + (*v)[m]) * (t[m] - ti);
  IntegrateForward(t, a, m, v, z);
  for (std::size_t i = m; i-- > 0;) {
    const double h = t[i + 1] - t[i];
    (*v)[i] = (*v)[i + 1] - 0.5 * (a[i] + a[i + 1]) * h;
    (*z)[i] = (*z)[i + 1] - 0.5 * ((*v)[i] + (*v)[i + 1]) * h;
  }
  s->impact_velocity_m_s = v0;
}

// The integrated impact velocity against the expected one (SensorOptions): a warning beyond
// kImpactVelocityWarnFraction, Error beyond kImpactVelocityAbsurdFactor.
void CheckImpactVelocity(const SensorRecord& record, const SensorOptions& options,
                         SensorSummary* s) {
  const double expected = options.expected_impact_velocity_m_s;
  const double v0 = s->impact_velocity_m_s;
  if (std::isnan(expected) || options.integrate_from != IntegrationStart::kRelease) return;
  const std::string source = options.expected_impact_velocity_source.empty()
                                 ? std::string("the expected impact velocity")
                                 : options.expected_impact_velocity_source;
  const std::string integrated = fmt::format(
      "an impact velocity of {:.4g} m/s integrated from the release at {:.6g} s to the "
      "impact at {:.6g} s",
      v0, s->release_time_s, s->impact_time_s);
  if (!(v0 > expected / kImpactVelocityAbsurdFactor &&
        v0 < expected * kImpactVelocityAbsurdFactor)) {
    throw Error(ErrorKind::kInvalidValue, "sensor impact velocity", integrated,
                fmt::format("within a factor {} of the {:.4g} m/s of {}: check the release time, "
                            "the acceleration unit and the scene's test section",
                            kImpactVelocityAbsurdFactor, expected, source))
        .WithFile(record.path);
  }
  const double deviation = v0 / expected - 1;
  if (std::abs(deviation) > kImpactVelocityWarnFraction) {
    s->warnings.push_back(fmt::format(
        "{} differs by {:+.1f} % from the {:.4g} m/s of {} (more than the {:.0f} % that the drop "
        "height's measurement, air drag and guide friction explain)",
        integrated, 100 * deviation, expected, source, 100 * kImpactVelocityWarnFraction));
  }
}

// Stop: the first sample after the impact where v <= stop_velocity (the zero crossing located by
// linear interpolation when v goes through 0 there); else the velocity minimum, with a warning.
// Returns the stop's sample.
std::size_t FindStop(const std::vector<double>& t, const std::vector<double>& v,
                     const std::vector<double>& z, std::size_t ki, const SensorOptions& options,
                     SensorSummary* s) {
  const std::size_t n = t.size();
  std::size_t k = ki + 1;
  while (k < n && v[k] > options.stop_velocity_m_s) ++k;
  if (k < n) {
    s->stopped = true;
    const double level = (v[k] <= 0 && v[k - 1] > 0) ? 0.0 : options.stop_velocity_m_s;
    const double f = (v[k - 1] - level) / (v[k - 1] - v[k]);
    s->stop_time_s = t[k - 1] + std::clamp(f, 0.0, 1.0) * (t[k] - t[k - 1]);
    s->final_penetration_m = InterpolateSeries(t, z, s->stop_time_s);
    return k;
  }
  const auto it = std::min_element(v.begin() + static_cast<std::ptrdiff_t>(ki), v.end());
  const auto kend = static_cast<std::size_t>(it - v.begin());
  s->stop_time_s = t[kend];
  s->final_penetration_m = z[kend];
  s->warnings.push_back(fmt::format(
      "the pounder velocity never fell to {} m/s after the impact (minimum {:.4g} m/s at "
      "t = {:.6g} s); the final penetration is taken there",
      options.stop_velocity_m_s, *it, t[kend]));
  return kend;
}

// Peak deceleration (a_g - 1) between impact and stop, refined by a parabola through the largest
// sample and its neighbours.
void FindPeakDeceleration(const std::vector<double>& t, const std::vector<double>& acc,
                          std::size_t ki, std::size_t kend, SensorSummary* s) {
  const std::size_t n = t.size();
  std::size_t kp = PeakDecelerationSample(t, acc, t[ki], 0.0, t[std::min(kend, n - 1)] - t[ki]);
  if (kp >= n) kp = ki;
  const RefinedPeak peak = RefinePeak(t, acc, kp);
  s->peak_deceleration_g = peak.value - 1;
  s->peak_time_s = peak.time_s;
  s->t_peak_s = peak.time_s - s->impact_time_s;
}

// One base force channel (BaseForceChannel): unit, offset over the pre-impact rest, filter,
// sign, peak and onset.
BaseForceChannel ProcessBaseChannel(const SensorRecord& record, std::size_t c,
                                    const SensorOptions& options, const FirstOrderLowpass& lp,
                                    const SensorSummary& s) {
  const std::vector<double>& t = record.time_s;
  const std::size_t n = t.size();
  BaseForceChannel ch;
  ch.column = options.columns.base_force[c];
  ch.unit = options.base.units[c];
  const double to_n = NewtonsPer(ch.unit);
  // The pre-impact rest: the quiet window before the impact (as the accelerometer's free-fall
  // window), at least 8 samples.
  const std::size_t r1 = FirstIndexAtOrAfter(t, s.impact_time_s - options.quiet_guard_s);
  const std::size_t r0 =
      FirstIndexAtOrAfter(t, s.impact_time_s - options.quiet_guard_s - options.quiet_window_s);
  if (r1 < r0 + 8) {
    throw Error(
        ErrorKind::kInvalidValue, "base force column '" + ch.column + "'",
        fmt::format("{} samples of rest before the impact at {:.6g} s", r1 - r0, s.impact_time_s),
        "at least 8 samples in sensor.quiet_window_s before the impact (less "
        "sensor.quiet_guard_s) to take the offset from")
        .WithFile(record.path);
  }
  std::vector<double> raw(n);
  for (std::size_t i = 0; i < n; ++i) raw[i] = to_n * record.base_force[c][i];
  ch.offset_n = Mean(raw, r0, r1);
  for (double& f : raw) f -= ch.offset_n;
  ch.force_n = FiltFilt(lp, raw);
  ch.noise_n = StdDev(ch.force_n, r0, r1);
  const std::size_t ki = s.impact_index;
  const auto [lo, hi] =
      std::minmax_element(ch.force_n.begin() + static_cast<std::ptrdiff_t>(ki), ch.force_n.end());
  const double noise_floor = kBaseArrivalSigma * ch.noise_n;
  if (-*lo > *hi && -*lo > noise_floor) {
    throw Error(
        ErrorKind::kInvalidValue, "sensor.base_columns: column '" + ch.column + "'",
        fmt::format("a dynamic force of {:.4g} N at t = {:.6g} s after the impact, larger "
                    "in magnitude than its largest positive {:.4g} N",
                    *lo, t[static_cast<std::size_t>(lo - ch.force_n.begin())] - s.impact_time_s,
                    *hi),
        "compression reading positive (a wave loads a base sensor): the channel's sign is "
        "reversed (wiring or DAQ setting), or the column is not a base force sensor")
        .WithFile(record.path);
  }
  if (!(*hi > noise_floor)) {
    ch.problem = fmt::format(
        "no arrival: the largest dynamic force after the impact, {:.3g} N, is not above {} "
        "standard deviations ({:.3g} N) of the filtered pre-impact rest",
        *hi, kBaseArrivalSigma, noise_floor);
    return ch;
  }
  const auto kp = static_cast<std::size_t>(hi - ch.force_n.begin());
  const RefinedPeak peak = RefinePeak(t, ch.force_n, kp);
  ch.peak_time_s = peak.time_s;
  ch.peak_force_n = peak.value;
  OnsetOptions onset;
  // The accelerometer's threshold as a fraction of its peak reading (free fall 0 g), so that both
  // onsets are fitted over the same part of their rise. Any unit: the channel's [N].
  const double fraction =
      std::clamp(options.impact_threshold_g / (1 + s.peak_deceleration_g), 0.05, 0.5);
  onset.threshold_g = fraction * peak.value;
  onset.noise_band_sigma = options.noise_band_sigma;
  onset.window_s = options.quiet_window_s;
  onset.guard_s = options.quiet_guard_s;
  std::size_t index = 0;
  ch.onset_time_s = DetectImpactOnset(t, raw, ch.force_n, ki, onset, &index);
  return ch;
}

}  // namespace

SensorResult ProcessAccelerometer(const SensorRecord& record, const SensorOptions& options) {
  WallTimer timer;
  options.Check();
  const double fs = SampleRate(record, options);
  const std::size_t n = record.time_s.size();
  const std::vector<double>& t = record.time_s;
  const FirstOrderLowpass lp = DesignButterworthLowpass1(options.cutoff_hz, fs);
  const std::vector<double> filtered_raw = FiltFilt(lp, record.accel_g);

  SensorResult out;
  SensorSummary& s = out.summary;
  s.sample_rate_hz = fs;
  s.samples = n;
  s.cutoff_hz = options.cutoff_hz;
  const FreeFall ff = FindFreeFall(record, filtered_raw, options, fs, &s);
  EstimateOffset(record, ff, options, &s);

  std::vector<double> raw(n), acc(n);
  for (std::size_t i = 0; i < n; ++i) {
    raw[i] = record.accel_g[i] - s.offset_g;
    acc[i] = filtered_raw[i] - s.offset_g;  // The filter has unit DC gain and is linear.
  }
  OnsetOptions onset;
  onset.threshold_g = options.impact_threshold_g;
  onset.noise_band_sigma = options.noise_band_sigma;
  onset.window_s = options.quiet_window_s;
  onset.guard_s = options.quiet_guard_s;
  std::size_t ki = 0;
  s.impact_time_s = DetectImpactOnset(t, raw, acc, 0, onset, &ki);
  s.impact_index = ki;

  out.time_s = t;
  out.accel_g = acc;
  out.accel_down_m_s2.resize(n);
  for (std::size_t i = 0; i < n; ++i) out.accel_down_m_s2[i] = options.g_m_s2 * (1 - acc[i]);
  const std::vector<double>& a = out.accel_down_m_s2;
  std::vector<double> v(n, 0.0), z(n, 0.0);
  if (options.integrate_from == IntegrationStart::kRelease)
    IntegrateFromRelease(record, ff, options, a, &v, &z, &s);
  else
    IntegrateFromImpact(t, a, options, &v, &z, &s);
  CheckImpactVelocity(record, options, &s);
  const std::size_t kend = FindStop(t, v, z, ki, options, &s);
  FindPeakDeceleration(t, acc, ki, kend, &s);
  if (s.impact_time_s - t.front() < 0.01)
    s.warnings.push_back("less than 10 ms of record before the impact");

  out.velocity_m_s = std::move(v);
  out.penetration_m = std::move(z);
  out.path = record.path;
  s.seconds = timer.ElapsedSeconds();
  return out;
}

SensorResult ProcessSensor(const SensorRecord& record, const SensorOptions& options) {
  WallTimer timer;
  SensorResult out = ProcessAccelerometer(record, options);
  SensorSummary& s = out.summary;
  const FirstOrderLowpass lp = DesignButterworthLowpass1(options.cutoff_hz, s.sample_rate_hz);
  out.exposure = record.exposure;
  out.column_names = record.column_names;
  out.force_names = record.force_names;
  for (const auto& f : record.force) out.force.push_back(FiltFilt(lp, f));
  CheckValue(record.base_force.size() == options.columns.base_force.size(), "sensor record",
             fmt::format("{} base force channels", record.base_force.size()),
             fmt::format("the {} of sensor.base_columns", options.columns.base_force.size()));
  for (std::size_t c = 0; c < record.base_force.size(); ++c)
    out.base.push_back(ProcessBaseChannel(record, c, options, lp, s));
  out.reading_g = record.accel_g;
  out.options = options;
  s.seconds = timer.ElapsedSeconds();
  for (const auto& wmsg : s.warnings) LogWarning("sensor: {}", wmsg);
  return out;
}

SensorResult AnalyzeSensorCsv(const std::string& path, const SensorOptions& options) {
  options.Check();
  const SensorRecord record =
      ReadSensorCsv(path, options.columns, options.g_m_s2, options.max_step_deviation);
  return ProcessSensor(record, options);
}

std::string SensorSummary::BriefReport() const {
  return fmt::format(
      "impact at {:.6f} s, v0 = {:.4f} m/s, crater depth = {:.5f} m, peak deceleration = {:.1f} g "
      "at {:.3f} ms after impact{}",
      impact_time_s, impact_velocity_m_s, final_penetration_m, peak_deceleration_g, 1e3 * t_peak_s,
      warnings.empty() ? "" : fmt::format(" ({} warnings)", warnings.size()));
}

std::string SensorSummary::FullReport() const {
  std::string r;
  r += fmt::format("sample rate           {:.1f} Hz ({} samples)\n", sample_rate_hz, samples);
  r += fmt::format("low-pass cut-off      {:.1f} Hz (zero-phase 1st-order Butterworth)\n",
                   cutoff_hz);
  r += fmt::format("offset / noise        {:.5f} g (from {:.6f} s to {:.6f} s) / {:.5f} g\n",
                   offset_g, offset_window_s[0], offset_window_s[1], noise_g);
  r += fmt::format("release time          {:.6f} s\n", release_time_s);
  r += fmt::format("impact time           {:.6f} s (sample {})\n", impact_time_s, impact_index);
  r += fmt::format("impact velocity       {:.5f} m/s\n", impact_velocity_m_s);
  r += fmt::format("peak deceleration     {:.2f} g at {:.4f} ms after impact\n",
                   peak_deceleration_g, 1e3 * t_peak_s);
  r += fmt::format("stop time             {:.6f} s{}\n", stop_time_s,
                   stopped ? "" : " (not stopped)");
  r += fmt::format("final penetration     {:.6f} m\n", final_penetration_m);
  r += fmt::format("processing time       {:.4f} s\n", seconds);
  for (const auto& w : warnings) r += "warning: " + w + "\n";
  return r;
}

std::size_t PeakDecelerationSample(const std::vector<double>& time_s,
                                   const std::vector<double>& accel_g, double t_ref_s,
                                   double from_s, double to_s) {
  std::size_t peak = time_s.size();
  for (std::size_t i = 0; i < time_s.size() && i < accel_g.size(); ++i) {
    const double dt = time_s[i] - t_ref_s;
    if (dt >= from_s && dt <= to_s && (peak == time_s.size() || accel_g[i] > accel_g[peak]))
      peak = i;
  }
  return peak;
}

RefinedPeak RefinePeak(const std::vector<double>& time_s, const std::vector<double>& series,
                       std::size_t k) {
  RefinedPeak peak{time_s[k], series[k]};
  if (k > 0 && k + 1 < time_s.size()) {
    const double ym = series[k - 1], y0 = series[k], yp = series[k + 1];
    const double den = ym - 2 * y0 + yp;
    if (den < 0) {
      const double d = 0.5 * (ym - yp) / den;
      peak.time_s = time_s[k] + d * (time_s[k + 1] - time_s[k - 1]) / 2;
      peak.value = y0 - 0.25 * (ym - yp) * d;
    }
  }
  return peak;
}

std::vector<double> SampleSeries(const std::vector<double>& time_s,
                                 const std::vector<double>& series,
                                 const std::vector<double>& query_s, const std::string& what) {
  CheckValue(time_s.size() >= 2 && series.size() == time_s.size(), what,
             fmt::format("{} times and {} values", time_s.size(), series.size()),
             "equal lengths >= 2");
  std::vector<double> out(query_s.size());
  for (std::size_t i = 0; i < query_s.size(); ++i) {
    const double q = query_s[i];
    if (!(q >= time_s.front() && q <= time_s.back())) {
      throw Error(ErrorKind::kInvalidValue, what, fmt::format("query {} at t = {:.6g} s", i, q),
                  fmt::format("times inside the record [{:.6g} s, {:.6g} s]: the sensor record "
                              "does not cover the frames",
                              time_s.front(), time_s.back()));
    }
    out[i] = InterpolateSeries(time_s, series, q);
  }
  return out;
}

}  // namespace impactdic
