// Accelerometer processing: DAQ CSV -> pounder acceleration, velocity and penetration, impact
// detection and the frame timeline (docs/analysis.md).
//
// Sign convention (stated once, used everywhere): the accelerometer axis points UP. Its reading
// a_g (in g) is 0 in free fall, +1 at rest and 1 + deceleration / g while the sand stops the
// pounder. The pounder's DOWNWARD acceleration is therefore
//     a_down = g (1 - a_g)          [m/s^2, downward positive],
// and its velocity v (downward positive) and position z (downward positive) are the trapezoidal
// integrals of a_down. Deceleration in g = a_g - 1.
//
//   SensorOptions opt;                       // 1500 Hz, offset from the free fall before impact
//   opt.integrate_from = IntegrationStart::kRelease;
//   SensorResult r = AnalyzeSensorCsv("daq.csv", opt);
//   std::cout << r.summary.BriefReport();
//   FrameTimeline frames = MakeFrameTimeline(0, /*count=*/200, CameraClock{.fps = 1600}, &r);  //
//   frame_timeline.h
#ifndef IMPACTDIC_SENSOR_SENSOR_H_
#define IMPACTDIC_SENSOR_SENSOR_H_

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "impactdic/core/enum_names.h"
#include "impactdic/core/numeric.h"
#include "impactdic/core/range.h"

namespace impactdic {

// Unit of the acceleration column. kAuto: from the column name ("..._g" = g, "..._m_s2" or
// "...m/s^2" = m/s^2).
enum class AccelUnit { kAuto, kG, kMetrePerSecond2 };
inline constexpr EnumNames<AccelUnit, 3> kAccelUnitNames{
    {{{AccelUnit::kAuto, "auto"},
      {AccelUnit::kG, "g"},
      {AccelUnit::kMetrePerSecond2, "m/s^2", "m_s2 m/s2"}}},
    /*ignore_case=*/true};
const char* ToString(AccelUnit unit);
AccelUnit AccelUnitFromString(const std::string& text);

// Which quiet window fixes the accelerometer's additive offset.
//   kFreeFall: the free fall must read 0 g (default): the whole free fall from the release
//              (+ quiet_guard_s) to the impact (- quiet_guard_s) when the record contains the
//              release, else the quiet window just before the impact. The offset's statistical
//              error is noise / sqrt(samples): 0.05 g noise over a 5 ms window leaves 0.0045 g,
//              i.e. 0.45 % of the impact velocity after a 0.38 s fall; the whole fall, 0.0005 g;
//   kFreeFallWindow: only the quiet window just before the impact must read 0 g;
//   kRest:     the first window of the record (pounder held before release) must read 1 g;
//   kNone:     no correction.
enum class OffsetReference { kFreeFall, kFreeFallWindow, kRest, kNone };
inline constexpr EnumNames<OffsetReference, 4> kOffsetReferenceNames{
    {{{OffsetReference::kFreeFall, "free-fall", "freefall free_fall"},
      {OffsetReference::kFreeFallWindow, "free-fall-window"},
      {OffsetReference::kRest, "rest"},
      {OffsetReference::kNone, "none"}}},
    /*ignore_case=*/true};
const char* ToString(OffsetReference reference);
OffsetReference OffsetReferenceFromString(const std::string& text);

// Where the velocity integration starts.
//   kRelease: v = 0 at release: the release detected in a record that starts with the pounder at
//             rest (reading ~1 g; v = 0 until then, so the rest period's reading, e.g. a gain
//             error, does not enter), or release_time_s, which must lie inside the record before
//             the impact. A record that starts in free fall needs kImpact;
//   kImpact:  v = impact_velocity_m_s at the detected impact time, z = 0 there.
enum class IntegrationStart { kRelease, kImpact };
inline constexpr EnumNames<IntegrationStart, 2> kIntegrationStartNames{
    {{{IntegrationStart::kRelease, "release"}, {IntegrationStart::kImpact, "impact"}}},
    /*ignore_case=*/true};
const char* ToString(IntegrationStart start);
IntegrationStart IntegrationStartFromString(const std::string& text);

struct SensorColumns {
  std::string time = "time_s";  // Time column [s], strictly increasing, uniform sampling.
  // Acceleration column; empty = the first of "accel_g", "accel_m_s2" present in the file.
  std::string accel = "accel_g";
  AccelUnit accel_unit = AccelUnit::kAuto;
  // Camera exposure channel (high while the shutter is open); empty or absent in the file = none.
  std::string exposure = "exposure";
  // Force channels kept (filtered); empty = every column whose name starts with "force".
  std::vector<std::string> force;
  // Base force channels (the force sensors under the sand bed, docs/wave.md): processed like the
  // accelerometer (BaseForceChannel) and read by the wave analysis (sensor/wave.h); one entry of
  // each of SensorOptions::base's lists per column. Empty: none.
  std::vector<std::string> base_force;
};

// Unit of a base force channel's column.
enum class ForceUnit { kNewton, kKilonewton };
inline constexpr EnumNames<ForceUnit, 2> kForceUnitNames{
    {{{ForceUnit::kNewton, "N"}, {ForceUnit::kKilonewton, "kN"}}}};
const char* ToString(ForceUnit unit);
ForceUnit ForceUnitFromString(const std::string& text);
double NewtonsPer(ForceUnit unit);  // 1 or 1000.

// Where each base force sensor sits and what it senses: lists parallel to
// SensorColumns::base_force (entry k describes column k; each list as long as it). Positions are
// relative to the pounder's impact point on the undisturbed sand surface.
inline constexpr ValueRange kBaseOffsetRange{-1e5, 1e5, "mm"};                 // Horizontal offset.
inline constexpr ValueRange kBaseDepthRange{0, 1e5, "mm", /*min_open=*/true};  // Below the surface.
inline constexpr ValueRange kBaseAreaRange{0, 1e8, "mm^2", /*min_open=*/true};  // Sensing area.
struct BaseForceOptions {
  std::vector<ForceUnit> units;   // Unit of each column (N or kN).
  std::vector<double> offset_mm;  // Horizontal offset from the pounder's centre line [mm].
  std::vector<double> depth_mm;   // Depth of the sensing face below the sand surface [mm].
  std::vector<double> area_mm2;   // Sensing area [mm^2]: the stress is force / area.
};

// The allowed values, defined once: read by SensorOptions::Check(), the scene's sensor.* keys and
// `analyze`'s flags. The cut-off must also lie below the record's Nyquist frequency (checked
// with the record).
inline constexpr ValueRange kCutoffRange{0, 1e300, "Hz", /*min_open=*/true};
inline constexpr ValueRange kQuietWindowRange{0, 1e3, "s", /*min_open=*/true};
// A reading above the rest level (1 g).
inline constexpr ValueRange kImpactThresholdRange{1, 1e300, "g", /*min_open=*/true};
inline constexpr ValueRange kQuietGuardRange{0, 1e300, "s"};
inline constexpr ValueRange kNoiseBandSigmaRange{0, 1e300, "", /*min_open=*/true};
inline constexpr ValueRange kStopVelocityRange{0, 1e300, "m/s"};

struct SensorOptions {
  SensorColumns columns;
  double g_m_s2 = 9.81;     // Gravitational acceleration [m/s^2], > 0.
  double cutoff_hz = 1500;  // Low-pass cut-off [Hz], kCutoffRange, < f_s / 2 (paper: 1500 Hz).
  OffsetReference offset_reference = OffsetReference::kFreeFall;
  double quiet_window_s = 0.005;  // Length of the offset / noise window [s], kQuietWindowRange.
  double quiet_guard_s = 0.001;   // Gap between the free-fall window and the impact [s],
                                  // kQuietGuardRange.
  IntegrationStart integrate_from = IntegrationStart::kRelease;
  // kImpact: the impact velocity [m/s], > 0 (NaN otherwise).
  double impact_velocity_m_s = kNaN;
  // kRelease: release time on the DAQ clock [s], inside the record and before the impact (Error
  // naming the record's span otherwise); NaN = detected (the record starts at rest). Only NaN
  // with kImpact (no release to start from).
  double release_time_s = kNaN;
  // A filtered reading above this [g] is certainly the impact (coarse search only; the impact time
  // is the onset found backwards from it), kImpactThresholdRange (above the rest level).
  double impact_threshold_g = 5;
  // Half-width of the noise band around the free-fall level, in standard deviations,
  // kNoiseBandSigmaRange.
  double noise_band_sigma = 4;
  // The pounder has stopped when its velocity falls to this [m/s] after the peak,
  // kStopVelocityRange.
  double stop_velocity_m_s = 0.01;
  // Largest relative deviation of one time step from the median step, in (0, 0.5].
  double max_step_deviation = 0.01;
  // kRelease: the impact velocity the test should give [m/s] (a pipeline sets the scene's
  // sqrt(2 g h) or its test.impact_velocity_m_s), > 0; NaN = not checked. The integrated v0 is
  // checked against it (CheckImpactVelocity); `expected_impact_velocity_source` says where it
  // comes from, for the messages (e.g. "a free fall from test.drop_height_m = 0.7 m").
  double expected_impact_velocity_m_s = kNaN;
  std::string expected_impact_velocity_source;
  // The base force channels' units, positions and areas (columns.base_force names them).
  BaseForceOptions base;

  // Throws Error(kInvalidValue) naming the broken field (the base lists by their scene keys,
  // sensor.base_units, ...: each as long as sensor.base_columns, every value in its range).
  void Check() const;
};

// How far the integrated impact velocity may lie from the expected one (SensorOptions::
// expected_impact_velocity_m_s) before a warning: 5 %. What separates them in a sound test: the
// drop height measured to +-1 cm (+-2.5 % of v0 at the paper's lowest 0.2 m), air drag (a 10 kg,
// 0.15 x 0.192 m pounder at 3.7 m/s: 0.3 N against its 98 N weight, -0.1 % of v0) and guide
// friction (a few %). The accelerometer's gain error does not enter: integration starts at the
// release and the free fall reads 0 g whatever the gain (the offset is taken from the free fall);
// the offset's noise adds ~0.05 %.
inline constexpr double kImpactVelocityWarnFraction = 0.05;
// Beyond this factor either way (the implied drop height off by its square, 4x) the integrated
// v0 is absurd and the sensor stage fails: no calibration, drag or height error comes near it
// (the paper's heights 0.2-1.2 m span a factor 2.45 in v0, i.e. 1.6 about the middle); it means a
// wrong release time, record, unit or scene.
inline constexpr double kImpactVelocityAbsurdFactor = 2;

// The raw record as read (acceleration converted to g).
struct SensorRecord {
  std::string path;
  std::vector<double> time_s;
  std::vector<double> accel_g;   // Accelerometer reading [g], axis up (see the file comment).
  std::vector<double> exposure;  // Empty when there is no exposure channel.
  std::vector<std::string> force_names;
  std::vector<std::vector<double>> force;  // force[channel][sample], units as in the file.
  // SensorColumns::base_force's columns as read [sample], units as in the file.
  std::vector<std::vector<double>> base_force;
  double sample_rate_hz = 0;              // 1 / median time step.
  std::vector<std::string> column_names;  // Every column of the file, in its order.
};

// Reads and validates the DAQ CSV: columns present, every value finite, time strictly increasing
// and uniformly sampled (no gaps). Errors name the file, column and row.
SensorRecord ReadSensorCsv(const std::string& path, const SensorColumns& columns,
                           double g_m_s2 = 9.81, double max_step_deviation = 0.01);

struct SensorSummary {
  double sample_rate_hz = 0;
  std::size_t samples = 0;
  double cutoff_hz = 0;
  double offset_g = 0;  // Subtracted from the reading.
  // First and last sample time of the window the offset was taken from (NaN: none).
  std::array<double, 2> offset_window_s{kNaN, kNaN};
  double noise_g = 0;            // Standard deviation of the raw reading in the quiet window.
  double release_time_s = kNaN;  // DAQ clock; NaN = unknown.
  double impact_time_s = kNaN;   // DAQ clock (onset).
  std::size_t impact_index = 0;  // First sample at or after the impact.
  double impact_velocity_m_s = kNaN;
  double peak_deceleration_g = kNaN;  // max(a_g - 1).
  double t_peak_s = kNaN;             // After impact.
  double peak_time_s = kNaN;          // DAQ clock.
  double stop_time_s = kNaN;          // DAQ clock.
  double final_penetration_m = kNaN;  // Crater depth.
  bool stopped = false;               // The velocity returned to ~0 inside the record.
  double seconds = 0;                 // Processing wall time.
  std::vector<std::string> warnings;

  bool IsUsable() const {
    return std::isfinite(impact_time_s) && std::isfinite(final_penetration_m);
  }
  std::string BriefReport() const;
  std::string FullReport() const;
};

// One base force channel processed like the accelerometer (ProcessSensor):
//  * unit: the column's unit converted to N (BaseForceOptions::units);
//  * offset: the mean of the raw reading over the pre-impact rest, the quiet window
//    [impact - quiet_guard_s - quiet_window_s, impact - quiet_guard_s) (the sand's static load
//    and the sensor's zero), subtracted: the series is the DYNAMIC force, compression positive;
//  * the accelerometer's zero-phase filter (sensor.cutoff_hz);
//  * peak: the largest filtered dynamic force after the impact (PeakDecelerationSample, the
//    accelerometer's definition, refined by the same parabola, RefinePeak);
//  * onset (arrival): DetectImpactOnset, the accelerometer's impact onset, on the channel with the
//    threshold at the fraction of its peak that impact_threshold_g is of the accelerometer's peak
//    reading (clamped to [0.05, 0.5]), so that both onsets are fitted over the same part of their
//    rise: walk back from the first filtered sample above it to the last one inside the noise
//    band (noise_band_sigma standard deviations of the filtered pre-impact rest), then the
//    change-point fit on the raw dynamic force;
//  * an arrival needs a peak above kBaseArrivalSigma standard deviations of the filtered rest;
//    without one, onset and peak are NaN and `problem` says why.
// A channel whose largest excursion after the impact is negative (and beyond the noise) reads
// compression as tension: ProcessSensor refuses it (Error naming sensor.base_columns and the
// column), as no sign key exists to guess with.
inline constexpr double kBaseArrivalSigma = 5;
struct BaseForceChannel {
  std::string column;
  ForceUnit unit = ForceUnit::kNewton;
  std::vector<double> force_n;  // Dynamic force [N], offset-corrected and filtered.
  double offset_n = kNaN;       // Subtracted pre-impact level [N].
  double noise_n = kNaN;        // Standard deviation of the filtered pre-impact rest [N].
  double onset_time_s = kNaN;   // DAQ clock.
  double peak_time_s = kNaN;    // DAQ clock.
  double peak_force_n = kNaN;
  std::string problem;  // Why onset and peak are NaN ("" when found).
};

struct SensorResult {
  std::vector<double> time_s;
  std::vector<double> accel_g;          // Offset-corrected, filtered reading [g].
  std::vector<double> accel_down_m_s2;  // g (1 - accel_g), downward positive.
  std::vector<double> velocity_m_s;     // Downward positive.
  std::vector<double> penetration_m;    // z - z(impact), downward positive.
  std::vector<double> exposure;         // Raw exposure channel (empty if none).
  std::vector<std::string> force_names;
  std::vector<std::vector<double>> force;  // Filtered force channels.
  std::vector<BaseForceChannel> base;      // The base force channels (SensorColumns::base_force).
  std::string path;                        // The record's file (empty: not from a file).
  std::vector<std::string> column_names;   // Every column of the file, in its order.
  SensorSummary summary;
  // The accelerometer's reading as read [g] (SensorRecord::accel_g) and the options it was
  // processed with, so that it can be processed again: the momentum uncertainty's draws
  // (momentum/uncertainty.h) repeat ProcessAccelerometer on it with fresh noise. Empty (and the
  // default options) when the result was not made by ProcessSensor.
  std::vector<double> reading_g;
  SensorOptions options;
};

// Offset correction, zero-phase filter, impact detection, integration, summary; the force and
// base force channels; the warnings logged.
SensorResult ProcessSensor(const SensorRecord& record, const SensorOptions& options);
// ProcessSensor's accelerometer part alone: time_s, accel_g, accel_down_m_s2, velocity_m_s,
// penetration_m, path and the summary (its warnings kept there, not logged); no exposure, force
// or base channels, no reading_g. What the momentum uncertainty's draws repeat on a reading with
// fresh noise (options.columns.base_force may name channels the record lacks: they are not read).
SensorResult ProcessAccelerometer(const SensorRecord& record, const SensorOptions& options);
// ReadSensorCsv + ProcessSensor.
SensorResult AnalyzeSensorCsv(const std::string& path, const SensorOptions& options);

// Linear interpolation of y(t) at tq (t increasing, as long as y); the end values outside
// [t.front(), t.back()], NaN when t is empty. E.g. the pounder's penetration at a frame's time.
double InterpolateSeries(const std::vector<double>& t, const std::vector<double>& y, double tq);

// Impact onset on a (offset-corrected) reading that is ~0 g in free fall:
//  1. the first filtered sample above threshold_g (after `search_from`) is certainly in the impact;
//  2. walk back to the last filtered sample inside the free-fall noise band;
//  3. refine with a change-point fit on the raw reading: constant before, step + ramp after, the
//     change point chosen by least squares over the samples around the walk-back point; the onset
//     is where the fitted ramp leaves the baseline (clamped to the preceding sample interval).
// Returns the onset time; *index receives the first sample at or after it.
struct OnsetOptions {
  double threshold_g = 5;
  double noise_band_sigma = 4;
  double window_s = 0.005;  // Baseline window before the coarse crossing.
  double guard_s = 0.001;
};
double DetectImpactOnset(const std::vector<double>& time_s, const std::vector<double>& raw_g,
                         const std::vector<double>& filtered_g, std::size_t search_from,
                         const OnsetOptions& options, std::size_t* index);

// --- Camera timing (src/sensor/camera_timing.cc) ----------------------------------------------

// Rising edges of the exposure channel (threshold halfway between its low and high levels),
// located by linear interpolation between the samples either side. Times on the DAQ clock.
std::vector<double> ExposureRisingEdges(const std::vector<double>& time_s,
                                        const std::vector<double>& exposure);

// How far the frame rate given for a sequence (the kinematics' dt = 1/fps) may lie from the one
// its exposure edges give: 1 % (velocities and accelerations are off by as much), plus one DAQ
// sample over the span of the edges (each edge is located to within half a sample). A camera's
// rate is quartz-timed (ppm); 1 % lets a rounded nominal rate pass and stops a wrong one
// (16000 for 1600 gave 10x velocities).
inline constexpr double kFrameRateTolerance = 0.01;

// How the camera times its frames, besides the DAQ's exposure channel.
struct CameraClock {
  double fps = 0;       // Frame rate [1/s]; 0 or NaN: unknown (only with an exposure channel).
  double offset_s = 0;  // DAQ time of frame 0 without an exposure channel [s].
  // The camera's own time stamps of frames 0.. (a camera file's; any origin); empty: k / fps.
  std::vector<double> time_s;
  // Where the rate comes from, in messages: the scene key or the camera file.
  std::string fps_name = "inputs.fps";
};

// Times of frames 0..n_frames-1 on the DAQ clock: the exposure rising edges when the record has
// an exposure channel, else offset_s + k / fps, or offset_s + time_s[k] - time_s[0] when the
// camera's time stamps are given. Error (kInvalidValue) if there are fewer edges (or time stamps)
// than frames or a frame lies outside the sensor record. With an exposure channel, fps (0 or NaN:
// unknown) must agree with the rate of the frames' edges within kFrameRateTolerance (Error
// naming clock.fps_name and both rates). `edges_found` (optional) receives the number of exposure
// edges in the record (0 without an exposure channel). Called by MakeFrameTimeline
// (sensor/frame_timeline.h) alone: every other code reads a FrameTimeline.
std::vector<double> FrameTimes(const SensorResult& result, int n_frames, const CameraClock& clock,
                               std::size_t* edges_found = nullptr);

// Frames timed by a record need its exposure channel when one is named: Error (kFileFormat)
// naming the file, the missing column (`column`, the scene's sensor.exposure_column), the columns
// found and the alternative (an empty exposure_column: frame_time_offset_s + k / fps). Nothing
// when `column` is empty or the record has the channel.
void RequireExposureChannel(const SensorResult& result, const std::string& column);

// The first frame to correlate for an impact at impact_time_s (DAQ clock): the last frame exposed
// at or before it (nothing earlier moves), 0 if none is; daq_time_s: FrameTimeline::daq_time_s.
int ReferenceFrameForImpact(const std::vector<double>& daq_time_s, double impact_time_s);

// --- Series of the record (src/sensor/sensor.cc) -----------------------------------------------

// THE definition of the measured peak deceleration: the sample of largest filtered deceleration
// accel_g - 1 among those with from_s <= time_s - t_ref_s <= to_s (the first of equal ones);
// time_s.size() if there is none. SensorSummary::peak_deceleration_g takes it between the impact
// and the stop (refined by a parabola), the pipeline's peak stage between the impact and t_e
// (momentum MeasuredPeakDeceleration).
std::size_t PeakDecelerationSample(const std::vector<double>& time_s,
                                   const std::vector<double>& accel_g, double t_ref_s,
                                   double from_s, double to_s);

// A sampled maximum refined by the parabola through sample k and its neighbours: its time and
// value (sample k's own when k is at an end or the three samples are not concave).
struct RefinedPeak {
  double time_s = kNaN;
  double value = kNaN;
};
RefinedPeak RefinePeak(const std::vector<double>& time_s, const std::vector<double>& series,
                       std::size_t k);

// Linear interpolation of series(time) at the query times; Error naming `what` when a query lies
// outside [time.front(), time.back()].
std::vector<double> SampleSeries(const std::vector<double>& time_s,
                                 const std::vector<double>& series,
                                 const std::vector<double>& query_s, const std::string& what);

}  // namespace impactdic

#endif  // IMPACTDIC_SENSOR_SENSOR_H_
