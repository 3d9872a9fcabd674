#include "impactdic/sensor/sensor_results.h"

#include <cstddef>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "impactdic/io/results_io.h"

namespace impactdic {
namespace L = results_layout;
namespace {

// The number attributes of /sensor bound to a summary (const for the writer, mutable for the
// reader).
template <typename Summary>
auto SummaryAttributes(Summary& s) {
  using Number = std::remove_reference_t<decltype((s.sample_rate_hz))>;
  return std::vector<std::pair<const char*, Number*>>{
      {"sample_rate_hz", &s.sample_rate_hz},
      {"cutoff_hz", &s.cutoff_hz},
      {"offset_g", &s.offset_g},
      {"noise_g", &s.noise_g},
      {"impact_time_s", &s.impact_time_s},
      {"impact_velocity_m_s", &s.impact_velocity_m_s},
      {"final_penetration_m", &s.final_penetration_m},
      {"peak_deceleration_g", &s.peak_deceleration_g},
      {"t_peak_s", &s.t_peak_s},
      {"stop_time_s", &s.stop_time_s},
      {"release_time_s", &s.release_time_s}};
}

constexpr const char* kSignConvention =
    "accelerometer axis up (reads 0 g in free fall, 1 g at rest); velocity and penetration "
    "downward positive";

}  // namespace

void WriteSensorResults(H5Writer& out, const SensorResult& sensor) {
  const SensorSummary& s = sensor.summary;
  out.Remove(L::kSensorGroup);
  std::vector<double> t_after(sensor.time_s.size()), decel(sensor.accel_g.size());
  for (std::size_t i = 0; i < t_after.size(); ++i) t_after[i] = sensor.time_s[i] - s.impact_time_s;
  for (std::size_t i = 0; i < decel.size(); ++i) decel[i] = sensor.accel_g[i] - 1;
  out.Write(L::kSensorT, t_after, "s", "time since the detected impact");
  out.Write(L::kSensorTimeDaq, sensor.time_s, "s", "DAQ clock time");
  out.Write(L::kSensorDecel, decel, "g",
            "pounder deceleration accel_g - 1 (positive = slowing down)");
  out.Write(L::kSensorAccel, sensor.accel_g, "g",
            "accelerometer reading (axis up; 0 in free fall, 1 at rest), offset-corrected and "
            "zero-phase low-pass filtered");
  out.Write(L::kSensorAccelDown, sensor.accel_down_m_s2, "m/s^2",
            "pounder acceleration g (1 - accel_g), downward positive");
  out.Write(L::kSensorVelocity, sensor.velocity_m_s, "m/s", "pounder velocity, downward positive");
  out.Write(L::kSensorPenetration, sensor.penetration_m, "m",
            "pounder position relative to the impact position, downward positive");
  for (std::size_t c = 0; c < sensor.force.size(); ++c) {
    out.Write(std::string(L::kSensorForceGroup) + "/" + sensor.force_names[c], sensor.force[c],
              "as in the CSV", "force channel, zero-phase low-pass filtered");
  }
  for (const auto& [name, value] : SummaryAttributes(s))
    out.SetAttribute(L::kSensorGroup, name, *value);
  out.SetAttribute(L::kSensorGroup, L::kSensorSignConventionAttr, kSignConvention);
}

SensorResultsGroup ReadSensorResults(const H5Reader& in, const std::string& file) {
  RequireGroup(in, L::kSensorGroup, file,
               "the accelerometer results (impactdic run, or analyze --output)");
  SensorResultsGroup g;
  SensorResult& r = g.sensor;
  std::size_t k = kAnyLength;
  g.t_after_impact_s = ReadSeries(in, L::kSensorT, file, &k);
  r.time_s = ReadSeries(in, L::kSensorTimeDaq, file, &k);
  g.decel_g = ReadSeries(in, L::kSensorDecel, file, &k);
  r.accel_g = ReadSeries(in, L::kSensorAccel, file, &k);
  r.accel_down_m_s2 = ReadSeries(in, L::kSensorAccelDown, file, &k);
  r.velocity_m_s = ReadSeries(in, L::kSensorVelocity, file, &k);
  r.penetration_m = ReadSeries(in, L::kSensorPenetration, file, &k);
  if (in.Exists(L::kSensorForceGroup)) {
    for (const std::string& name : in.List(L::kSensorForceGroup)) {
      r.force_names.push_back(name);
      r.force.push_back(ReadSeries(in, std::string(L::kSensorForceGroup) + "/" + name, file, &k));
    }
  }
  SensorSummary& s = r.summary;
  for (const auto& [name, value] : SummaryAttributes(s))
    *value = ReadNumberAttributeOr(in, L::kSensorGroup, name, kNaN);
  s.samples = k;
  g.sign_convention = ReadStringAttributeOr(in, L::kSensorGroup, L::kSensorSignConventionAttr, "");
  return g;
}

}  // namespace impactdic
