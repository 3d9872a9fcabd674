// The accelerometer's results (the /sensor group of results.h5 and of `impactdic analyze
// --output`): the names, one writer, one reader. Other modules read /sensor through these names
// (namespace results_layout, like every group's; io/results_layout.h lists the owners).
//
//   H5Writer out("run/results.h5");
//   WriteSensorResults(out, sensor);  // sensor = AnalyzeSensorCsv(...)
//   out.Commit();
//   const SensorResultsGroup back = ReadSensorResults(H5Reader("run/results.h5"), "results.h5");
#ifndef IMPACTDIC_SENSOR_SENSOR_RESULTS_H_
#define IMPACTDIC_SENSOR_SENSOR_RESULTS_H_

#include <string>
#include <vector>

#include "impactdic/io/hdf5_store.h"
#include "impactdic/sensor/sensor.h"

namespace impactdic {
namespace results_layout {

// [K] each, K = samples of the record. Time since the detected impact [s]; DAQ clock time [s];
// pounder deceleration accel_g - 1 [g] (positive = slowing); the offset-corrected, filtered
// reading [g] (axis up: 0 in free fall, 1 at rest); the pounder's acceleration g (1 - accel_g)
// [m/s^2], velocity [m/s] and position relative to the impact [m], all downward positive; each
// force channel as kSensorForceGroup/<its CSV name> (units as in the CSV).
inline constexpr const char* kSensorGroup = "/sensor";
inline constexpr const char* kSensorT = "/sensor/t_s";
inline constexpr const char* kSensorTimeDaq = "/sensor/time_daq_s";
inline constexpr const char* kSensorDecel = "/sensor/decel_g";
inline constexpr const char* kSensorAccel = "/sensor/accel_g";
inline constexpr const char* kSensorAccelDown = "/sensor/accel_down_m_s2";
inline constexpr const char* kSensorVelocity = "/sensor/velocity_m_s";
inline constexpr const char* kSensorPenetration = "/sensor/penetration_m";
inline constexpr const char* kSensorForceGroup = "/sensor/force";
// Number attributes of kSensorGroup (SensorSummary): sample_rate_hz, cutoff_hz, offset_g,
// noise_g, impact_time_s, impact_velocity_m_s, final_penetration_m, peak_deceleration_g,
// t_peak_s, stop_time_s, release_time_s; the string attribute sign_convention.
inline constexpr const char* kSensorSignConventionAttr = "sign_convention";

}  // namespace results_layout

// /sensor as read: the record's processed series and summary numbers (ReadSensorResults fills
// time_s, accel_g, accel_down_m_s2, velocity_m_s, penetration_m, force_names, force and the
// summary's numbers of the attributes above), and the two series derived from them.
struct SensorResultsGroup {
  SensorResult sensor;
  std::vector<double> t_after_impact_s;  // kSensorT.
  std::vector<double> decel_g;           // kSensorDecel.
  std::string sign_convention;
};

// Writes /sensor (replacing an existing group), with units and descriptions on every dataset.
void WriteSensorResults(H5Writer& out, const SensorResult& sensor);

// Reads /sensor back. Error kFileFormat naming `file` and the group or dataset when it is missing
// or a series' length differs from the others'.
SensorResultsGroup ReadSensorResults(const H5Reader& in, const std::string& file);

}  // namespace impactdic

#endif  // IMPACTDIC_SENSOR_SENSOR_RESULTS_H_
