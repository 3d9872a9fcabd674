#include "impactdic/sensor/wave_results.h"

#include <cmath>
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "impactdic/core/strings.h"

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

}  // namespace

void WriteWaveResults(H5Writer& out, const SensorResult& sensor, const WaveResult& wave) {
  out.Remove(L::kWaveGroup);
  const auto column = [&wave](const std::function<double(const WaveChannel&)>& get) {
    std::vector<double> v;
    for (const WaveChannel& c : wave.channels) v.push_back(get(c));
    return v;
  };
  struct Figure {
    const char* path;
    std::function<double(const WaveChannel&)> get;
    const char* units;
    const char* description;
  };
  const std::vector<Figure> figures = {
      {L::kWaveOffset, [](const WaveChannel& c) { return c.offset_mm; }, "mm",
       "horizontal offset of the sensor from the pounder's centre line"},
      {L::kWaveDepth, [](const WaveChannel& c) { return c.depth_mm; }, "mm",
       "depth of the sensor below the undisturbed surface"},
      {L::kWaveDistance, [](const WaveChannel& c) { return c.distance_mm; }, "mm",
       "straight distance from the impact point to the sensor"},
      {L::kWaveArea, [](const WaveChannel& c) { return c.area_mm2; }, "mm^2", "sensing area"},
      {L::kWaveOnset, [](const WaveChannel& c) { return c.onset_s; }, "s",
       "arrival onset after the impact"},
      {L::kWavePeak, [](const WaveChannel& c) { return c.peak_s; }, "s",
       "arrival peak after the impact"},
      {L::kWaveSpeedPeak, [](const WaveChannel& c) { return c.speed_peak_m_s; }, "m/s",
       "wave speed from the peak travel time (pounder peak to sensor peak)"},
      {L::kWaveSpeedPeakSigma, [](const WaveChannel& c) { return c.speed_peak_sigma_m_s; }, "m/s",
       "standard uncertainty of speed_peak"},
      {L::kWaveSpeedOnset, [](const WaveChannel& c) { return c.speed_onset_m_s; }, "m/s",
       "wave speed from the onset travel time (impact to sensor onset)"},
      {L::kWaveSpeedOnsetSigma, [](const WaveChannel& c) { return c.speed_onset_sigma_m_s; },
       "m/s", "standard uncertainty of speed_onset"},
      {L::kWaveReturnTime, [](const WaveChannel& c) { return c.return_time_s; }, "s",
       "predicted return of the reflection at the surface after the impact, 2 depth / speed_peak"},
      {L::kWaveReturnTimeSigma, [](const WaveChannel& c) { return c.return_time_sigma_s; }, "s",
       "standard uncertainty of return_time"},
      {L::kWavePeakForce, [](const WaveChannel& c) { return c.peak_force_n; }, "N",
       "peak dynamic force"},
      {L::kWavePeakStress, [](const WaveChannel& c) { return c.peak_stress_pa; }, "Pa",
       "peak dynamic stress, force / area"},
      {L::kWaveStressRatio, [](const WaveChannel& c) { return c.stress_ratio; }, "1",
       "peak stress / the pounder's peak stress m_p a_peak / (D t_z)"},
      {L::kWaveReflectionStart, [](const WaveChannel& c) { return c.reflection.window_s[0]; }, "s",
       "reflection check window start after the impact"},
      {L::kWaveReflectionEnd, [](const WaveChannel& c) { return c.reflection.window_s[1]; }, "s",
       "reflection check window end after the impact"},
      {L::kWaveReflectionProminence, [](const WaveChannel& c) { return c.reflection.prominence_g; },
       "g", "largest prominence of a local maximum of the pounder's deceleration in the window"},
      {L::kWaveReflectionThreshold, [](const WaveChannel& c) { return c.reflection.threshold_g; },
       "g", "prominence above which a local maximum shows (3 noise standard deviations)"},
      {L::kWaveReflectionLocalMax,
       [](const WaveChannel& c) {
         return c.reflection.checked ? (c.reflection.local_maximum ? 1.0 : 0.0) : kNaN;
       },
       "1", "1 = the deceleration shows a local maximum around the return time, 0 = none, NaN = "
            "not checked"},
  };
  for (const Figure& f : figures) out.Write(f.path, column(f.get), f.units, f.description);
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

}  // namespace impactdic
