#include "impactdic/sensor/wave_results.h"

#include <cmath>
#include <cstddef>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "impactdic/core/strings.h"
#include "impactdic/io/results_io.h"

namespace impactdic {
namespace L = results_layout;
namespace {

constexpr const char* kDefinitions =
    "distance = straight line from the impact point (pounder centre line at the surface) to the "
    "sensor; speed_peak = distance / (sensor peak - pounder peak deceleration); speed_onset = "
    "distance / (sensor onset - impact); sigma_t = sqrt(2 dt^2 / 12 + tau_f^2), tau_f = 1 / (2 pi "
    "f_c); sigma_c = c sigma_t / travel time; return time = 2 depth / speed_peak after the "
    "impact; stress ratio = peak stress / (m_p a_peak / (D t_z)); reflection: largest prominence "
    "of a local maximum of the filtered pounder deceleration within return time +- max(1 ms, "
    "3 sigma_return), a local maximum when above 3 noise standard deviations (docs/wave.md)";

// A [C] dataset of /wave: one number per channel, bound to its field.
struct Figure {
  const char* path;
  double& (*field)(WaveChannel&);
  const char* units;
  const char* description;
};

const std::vector<Figure>& Figures() {
  static const std::vector<Figure> kFigures = {
      {L::kWaveOffset, [](WaveChannel& c) -> double& { return c.offset_mm; }, "mm",
       "horizontal offset of the sensor from the pounder's centre line"},
      {L::kWaveDepth, [](WaveChannel& c) -> double& { return c.depth_mm; }, "mm",
       "depth of the sensor below the undisturbed surface"},
      {L::kWaveDistance, [](WaveChannel& c) -> double& { return c.distance_mm; }, "mm",
       "straight distance from the impact point to the sensor"},
      {L::kWaveArea, [](WaveChannel& c) -> double& { return c.area_mm2; }, "mm^2", "sensing area"},
      {L::kWaveOnset, [](WaveChannel& c) -> double& { return c.onset_s; }, "s",
       "arrival onset after the impact"},
      {L::kWavePeak, [](WaveChannel& c) -> double& { return c.peak_s; }, "s",
       "arrival peak after the impact"},
      {L::kWaveSpeedPeak, [](WaveChannel& c) -> double& { return c.speed_peak_m_s; }, "m/s",
       "wave speed from the peak travel time (pounder peak to sensor peak)"},
      {L::kWaveSpeedPeakSigma, [](WaveChannel& c) -> double& { return c.speed_peak_sigma_m_s; },
       "m/s", "standard uncertainty of speed_peak"},
      {L::kWaveSpeedOnset, [](WaveChannel& c) -> double& { return c.speed_onset_m_s; }, "m/s",
       "wave speed from the onset travel time (impact to sensor onset)"},
      {L::kWaveSpeedOnsetSigma, [](WaveChannel& c) -> double& { return c.speed_onset_sigma_m_s; },
       "m/s", "standard uncertainty of speed_onset"},
      {L::kWaveReturnTime, [](WaveChannel& c) -> double& { return c.return_time_s; }, "s",
       "predicted return of the reflection at the surface after the impact, 2 depth / speed_peak"},
      {L::kWaveReturnTimeSigma, [](WaveChannel& c) -> double& { return c.return_time_sigma_s; },
       "s", "standard uncertainty of return_time"},
      {L::kWavePeakForce, [](WaveChannel& c) -> double& { return c.peak_force_n; }, "N",
       "peak dynamic force"},
      {L::kWavePeakStress, [](WaveChannel& c) -> double& { return c.peak_stress_pa; }, "Pa",
       "peak dynamic stress, force / area"},
      {L::kWaveStressRatio, [](WaveChannel& c) -> double& { return c.stress_ratio; }, "1",
       "peak stress / the pounder's peak stress m_p a_peak / (D t_z)"},
      {L::kWaveReflectionStart, [](WaveChannel& c) -> double& { return c.reflection.window_s[0]; },
       "s", "reflection check window start after the impact"},
      {L::kWaveReflectionEnd, [](WaveChannel& c) -> double& { return c.reflection.window_s[1]; },
       "s", "reflection check window end after the impact"},
      {L::kWaveReflectionProminence,
       [](WaveChannel& c) -> double& { return c.reflection.prominence_g; }, "g",
       "largest prominence of a local maximum of the pounder's deceleration in the window"},
      {L::kWaveReflectionThreshold,
       [](WaveChannel& c) -> double& { return c.reflection.threshold_g; }, "g",
       "prominence above which a local maximum shows (3 noise standard deviations)"},
  };
  return kFigures;
}

// "column: problem" lines (WaveResult::Warnings) back to the channels' problems.
void SetProblems(const std::string& text, std::vector<WaveChannel>* channels) {
  std::stringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    for (WaveChannel& c : *channels)
      if (line.rfind(c.column + ": ", 0) == 0)
        c.problems.push_back(line.substr(c.column.size() + 2));
  }
}

}  // namespace

void WriteWaveResults(H5Writer& out, const SensorResult& sensor, const WaveResult& wave) {
  out.Remove(L::kWaveGroup);
  std::vector<WaveChannel> channels = wave.channels;  // Figure binds mutable fields.
  for (const Figure& f : Figures()) {
    std::vector<double> v;
    v.reserve(channels.size());
    for (WaveChannel& c : channels) v.push_back(f.field(c));
    out.Write(f.path, v, f.units, f.description);
  }
  std::vector<double> local_maximum;
  local_maximum.reserve(channels.size());
  for (const WaveChannel& c : channels)
    local_maximum.push_back(c.reflection.checked ? (c.reflection.local_maximum ? 1.0 : 0.0) : kNaN);
  out.Write(L::kWaveReflectionLocalMax, local_maximum, "1",
            "1 = the deceleration shows a local maximum around the return time, 0 = none, NaN = "
            "not checked");
  std::vector<std::string> columns, units;
  for (const WaveChannel& c : wave.channels) {
    columns.push_back(c.column);
    units.push_back(c.unit);
  }
  for (const BaseForceChannel& b : sensor.base) {
    out.Write(std::string(L::kWaveForceGroup) + "/" + b.column, b.force_n, "N",
              "dynamic base force (pre-impact rest subtracted), zero-phase low-pass filtered; "
              "time axis /sensor/t_s");
  }
  out.SetAttribute(L::kWaveGroup, "pounder_peak_stress_Pa", wave.pounder_peak_stress_pa);
  out.SetAttribute(L::kWaveGroup, "pounder_peak_s", wave.pounder_peak_s);
  out.SetAttribute(L::kWaveGroup, "sample_interval_s", wave.sample_interval_s);
  out.SetAttribute(L::kWaveGroup, "filter_time_constant_s", wave.filter_time_constant_s);
  out.SetAttribute(L::kWaveGroup, "travel_time_sigma_s", wave.travel_time_sigma_s);
  out.SetAttribute(L::kWaveGroup, "noise_g", wave.noise_g);
  out.SetAttribute(L::kWaveGroup, L::kWaveColumnsAttr, Join(columns, ","));
  out.SetAttribute(L::kWaveGroup, L::kWaveUnitsAttr, Join(units, ","));
  std::string problems;
  for (const std::string& p : wave.Warnings()) problems += (problems.empty() ? "" : "\n") + p;
  out.SetAttribute(L::kWaveGroup, L::kWaveProblemsAttr, problems.empty() ? "none" : problems);
  out.SetAttribute(L::kWaveGroup, L::kWaveDefinitionsAttr, kDefinitions);
}

WaveResult ReadWaveResults(const H5Reader& in, const std::string& file) {
  RequireGroup(in, L::kWaveGroup, file, "the wave figures (a run with sensor.base_columns)");
  WaveResult w;
  std::stringstream columns(ReadStringAttributeOr(in, L::kWaveGroup, L::kWaveColumnsAttr, ""));
  std::stringstream units(ReadStringAttributeOr(in, L::kWaveGroup, L::kWaveUnitsAttr, ""));
  for (std::string name, unit; std::getline(columns, name, ',');) {
    std::getline(units, unit, ',');
    WaveChannel& c = w.channels.emplace_back();
    c.column = name;
    c.unit = unit;
  }
  std::size_t n = w.channels.size();
  for (const Figure& f : Figures()) {
    const std::vector<double> v = ReadSeries(in, f.path, file, &n);
    for (std::size_t k = 0; k < n; ++k) f.field(w.channels[k]) = v[k];
  }
  const std::vector<double> local_maximum = ReadSeries(in, L::kWaveReflectionLocalMax, file, &n);
  for (std::size_t k = 0; k < n; ++k) {
    w.channels[k].reflection.checked = !std::isnan(local_maximum[k]);
    w.channels[k].reflection.local_maximum = local_maximum[k] == 1;
  }
  const std::string problems = ReadStringAttributeOr(in, L::kWaveGroup, L::kWaveProblemsAttr, "");
  if (problems != "none") SetProblems(problems, &w.channels);
  for (const auto& [name, value] : std::vector<std::pair<const char*, double*>>{
           {"pounder_peak_stress_Pa", &w.pounder_peak_stress_pa},
           {"pounder_peak_s", &w.pounder_peak_s},
           {"sample_interval_s", &w.sample_interval_s},
           {"filter_time_constant_s", &w.filter_time_constant_s},
           {"travel_time_sigma_s", &w.travel_time_sigma_s},
           {"noise_g", &w.noise_g}})
    *value = ReadNumberAttributeOr(in, L::kWaveGroup, name, kNaN);
  return w;
}

}  // namespace impactdic
