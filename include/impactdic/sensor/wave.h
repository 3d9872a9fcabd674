// The compression wave under the pounder, from the base force channels (docs/wave.md; the paper's
// section 3.3: Loewe, Thiele, Kanty, Kirstein, "Experimental investigation and modeling of impact
// stages during dynamic compaction"): per base sensor the arrival (onset and peak), the wave speed
// from the peak travel time (the paper's definition) and from the onsets with their
// uncertainties, the predicted return time of the reflection at the surface, the peak stress and
// its ratio to the pounder's, and whether the pounder's deceleration shows a local maximum around
// the return time.
//
//   SensorResult sensor = AnalyzeSensorCsv("daq.csv", options);  // options.columns.base_force set
//   WaveOptions wave{.pounder_mass_kg = 10, .pounder_width_m = 0.15, .pounder_depth_m = 0.192};
//   WaveResult r = AnalyzeWave(sensor, options, wave);
//   for (const WaveChannel& c : r.channels) std::cout << c.column << " " << c.speed_peak_m_s;
//
// Definitions (every time on the DAQ clock unless "after the impact"):
//  * distance r = sqrt(offset^2 + depth^2): the straight line from the impact point (the pounder's
//    base on its centre line at the undisturbed surface) to the sensor. For the sensor under the
//    pounder it is the depth, the paper's distance; for an off-centre sensor the front from the
//    contact reaches it along that line. The pounder's penetration by its peak (a few mm) is not
//    subtracted: < 1 % of the paper's 600 mm.
//  * peak travel time = the sensor's peak - the pounder's peak deceleration (SensorSummary::
//    peak_time_s); onset travel time = the sensor's onset - the impact (onset) time: both found by
//    the same rules on the same filtered records (BaseForceChannel);
//  * speed = r / travel time, uncertainty sigma_c = c sigma_t / travel time with
//    sigma_t = sqrt(2 dt^2 / 12 + tau_f^2): each of the two times is located on samples dt apart
//    (dt^2 / 12 each, a uniform error over one interval), and the zero-phase filter, which moves
//    no peak or onset of a pulse that keeps its shape, may move those of two differently shaped
//    pulses by up to about its time constant tau_f = 1 / (2 pi f_c);
//  * return time (after the impact) = 2 depth / c_peak: down to the base and back to the surface;
//    its uncertainty 2 depth sigma_c / c^2;
//  * peak stress = peak force / sensing area; the pounder's peak stress m_p a_peak / (D t_z)
//    with a_peak = g * SensorSummary::peak_deceleration_g; their ratio is the attenuation.
//  * reflection check: the filtered pounder deceleration in the window return time +- w,
//    w = max(kReflectionMinHalfWindowS, 3 sigma_return). Statistic: the largest prominence of a
//    local maximum inside the window (its height above the higher of the lowest values on either
//    side of it, within the window). A local maximum "shows" when that prominence exceeds
//    kReflectionSigma standard deviations of the filtered reading over the pre-impact window
//    (SensorSummary::offset_window_s).
// Plausibility (a figure that fails is NaN, the reason in WaveChannel::problems, never a silent
// wrong number): a travel time > 0; a speed within kWaveSpeedRange (soils' compression-wave
// speeds); a stress ratio below 1 (the bed spreads and damps the stress; a ratio above 1 means a
// wrong unit or area, e.g. kN given for a record in N).
#ifndef IMPACTDIC_SENSOR_WAVE_H_
#define IMPACTDIC_SENSOR_WAVE_H_

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "impactdic/core/numeric.h"
#include "impactdic/core/range.h"
#include "impactdic/sensor/sensor.h"

namespace impactdic {

// Compression-wave speeds soils can have: loose dry sand ~50-100 m/s (the paper: 65 m/s), dense
// or saturated soils up to ~1500-1800 m/s (water's 1480 m/s bounds a saturated soil's from below).
inline constexpr ValueRange kWaveSpeedRange{10, 2000, "m/s"};
// The reflection check's least half-window [s] and its threshold in noise standard deviations.
inline constexpr double kReflectionMinHalfWindowS = 1e-3;
inline constexpr double kReflectionSigma = 3;

// The pounder's stress: its mass and contact area D x t_z (from the scene's test.*).
struct WaveOptions {
  double pounder_mass_kg = 10;     // m_p [kg], kPounderMassRange.
  double pounder_width_m = 0.15;   // D [m], kPounderSizeRange.
  double pounder_depth_m = 0.192;  // t_z [m], kPounderSizeRange.
  double g_m_s2 = 9.81;            // [m/s^2], > 0.
  // Throws Error(kInvalidValue) naming the broken field.
  void Check() const;
};

// Reflection check of one channel's return time (definitions in the file comment).
struct ReflectionCheck {
  bool checked = false;                        // The window lies inside the record.
  std::string note;                            // Why not checked ("" when checked).
  std::array<double, 2> window_s{kNaN, kNaN};  // After the impact.
  double prominence_g = kNaN;  // The largest local maximum's prominence in the window (0: none).
  double threshold_g = kNaN;   // kReflectionSigma x the filtered pre-impact noise.
  bool local_maximum = false;  // prominence_g > threshold_g.
};

// The DIC half of the reflection check (momentum/wave_front.h, CheckDicReflections): the
// near-surface soil's mean vertical velocity in the same window as `ReflectionCheck`.
struct DicReflectionCheck {
  bool checked = false;           // The window lies inside the analysed frames, with their noise.
  std::string note;               // Why not checked ("" when checked).
  std::size_t subsets = 0;        // The near-surface subsets averaged.
  double prominence_mm_s = kNaN;  // The largest local maximum's prominence, either sign (0: none).
  double threshold_mm_s = kNaN;   // kReflectionSigma x the signal's pre-impact noise.
  bool local_maximum = false;     // prominence_mm_s > threshold_mm_s.
};

struct WaveChannel {
  std::string column;
  std::string unit;  // The column's unit as given (N, kN).
  double offset_mm = kNaN, depth_mm = kNaN, area_mm2 = kNaN;
  double distance_mm = kNaN;             // r = sqrt(offset^2 + depth^2).
  double onset_s = kNaN, peak_s = kNaN;  // Arrival after the impact.
  double travel_onset_s = kNaN, travel_peak_s = kNaN;
  double speed_peak_m_s = kNaN, speed_peak_sigma_m_s = kNaN;
  double speed_onset_m_s = kNaN, speed_onset_sigma_m_s = kNaN;
  double return_time_s = kNaN, return_time_sigma_s = kNaN;  // After the impact.
  double peak_force_n = kNaN, peak_stress_pa = kNaN;
  double stress_ratio = kNaN;  // peak_stress_pa / WaveResult::pounder_peak_stress_pa.
  ReflectionCheck reflection;
  DicReflectionCheck dic_reflection;
  std::vector<std::string> problems;  // Why a figure is NaN (implausible, not found).
};

// An exponential u(z) = u0 exp(-z / lambda) fitted by least squares to ln u against the depth z
// below the pounder's base along its centre line (the front's DecayFit, docs/wave.md "The front in
// the DIC field"); u a vertical displacement [mm] or velocity [mm/s], downward positive.
struct DepthDecayFit {
  double time_s = kNaN;           // After the impact (the frame's time).
  std::size_t subsets = 0;        // Centre-line subsets with u > 0 that entered the fit.
  double surface_value = kNaN;    // u0 at z = 0 (the pounder's base) [mm or mm/s].
  double decay_length_mm = kNaN;  // lambda; NaN = not determined (`problem` says why).
  std::array<double, 2> decay_length_ci_mm{kNaN, kNaN};  // 95 %; [1] NaN: unbounded above.
  double depth_of_influence_mm = kNaN;  // Below the surface: u falls to kInfluenceFraction u0.
  std::string problem;                  // Why a figure is NaN ("" = all determined).
  // The profile the fit saw, one entry per centre-line subset (WaveFront::centre_line's order):
  // its depth below the pounder's base at the frame [mm] (NaN: not below it) and u (NaN: not
  // measured); in_fit 1 = the subset entered the fit (u above its noise criterion).
  std::vector<double> profile_depth_mm, profile_value;
  std::vector<std::uint8_t> profile_in_fit;
};

// The vertical velocity on the centre line against depth and time (the space-time diagram): the
// centre-line subsets grouped by their reference row, each row's mean downward velocity per frame.
struct SpaceTime {
  std::vector<double> time_s;           // [F] each frame's time after the impact.
  std::vector<double> depth_mm;         // [R] each row's depth below the undisturbed surface.
  std::vector<double> velocity_mm_s;    // [F x R] mean downward velocity, NaN = none measured.
  std::vector<double> pounder_base_mm;  // [F] the pounder's base below the surface (penetration).
  std::size_t rows() const { return depth_mm.size(); }
};

// The front in the DIC field (momentum/wave_front.h: the definitions in full).
struct WaveFront {
  bool computed = false;  // The stage had the kinematics and the pounder's position.
  std::string problem;    // Why the front speed is NaN ("" = measured).
  // Per subset [S] (the kinematics' order): its reference centre's distance from the impact
  // point [mm] and the arrival of its motion after the impact [s] (NaN: no arrival), and whether
  // the speed fit used it.
  std::vector<double> distance_mm, arrival_s;
  std::vector<std::uint8_t> in_fit;
  double noise_factor = kNaN, peak_fraction = kNaN;  // The arrival criterion's k and f.
  std::size_t arrivals = 0, fit_subsets = 0;
  double speed_m_s = kNaN;                         // 1 / slope of arrival against distance.
  std::array<double, 2> speed_ci_m_s{kNaN, kNaN};  // 95 %; [1] NaN: unbounded above.
  double intercept_s = kNaN;                       // Arrival at distance 0.
  double rms_residual_s = kNaN;
  // Centre line: the subsets within half a pounder width of it, below the undisturbed surface
  // (their indices in the kinematics' order); the fits use those below the pounder's base.
  std::size_t centre_line_subsets = 0;
  std::vector<std::size_t> centre_line;
  SpaceTime space_time;
  double pounder_base_depth_mm = kNaN;  // At t_e (the crater depth's reference), below surface.
  DepthDecayFit displacement_te, velocity_te, displacement_end, velocity_end;
  double crater_depth_mm = kNaN;  // The sensor's final penetration, beside the depth of influence.
};

// The depth of influence's threshold: the fitted displacement at kInfluenceFraction of u0.
inline constexpr double kInfluenceFraction = 0.1;

struct WaveResult {
  double pounder_peak_stress_pa = kNaN;  // m_p a_peak / (D t_z).
  double pounder_peak_s = kNaN;          // The pounder's peak deceleration after the impact.
  double sample_interval_s = kNaN;       // dt.
  double filter_time_constant_s = kNaN;  // tau_f = 1 / (2 pi f_c).
  double travel_time_sigma_s = kNaN;     // sigma_t = sqrt(2 dt^2 / 12 + tau_f^2).
  double noise_g = kNaN;                 // Filtered pounder reading's pre-impact noise [g].
  std::vector<WaveChannel> channels;     // One per base channel, in sensor.base_columns' order.
  WaveFront front;                       // The front in the DIC field (the momentum stage).
  // "column: problem" for every problem of every channel.
  std::vector<std::string> Warnings() const;
  // The channel nearest the pounder's centre line (smallest |offset|, the first of equals: the
  // paper's sensor under the pounder); nullptr without channels.
  const WaveChannel* CentreChannel() const;
};

// One base channel's dynamic force series [N] as written under /wave/force_N
// (ReadBaseForceRecords).
struct BaseForceRecord {
  std::string column;
  std::vector<double> force_n;
};

// The largest prominence of an interior local maximum of y over [a, b] (indices, inclusive): its
// height above the higher of the lowest values on its left and on its right within [a, b]; 0 when
// there is no interior local maximum. The reflection checks' statistic.
double LargestProminence(const std::vector<double>& y, std::size_t a, std::size_t b);

// The wave figures of every base channel of `sensor` (ProcessSensor with options.columns.
// base_force). `options` gives the channels' positions and areas and the filter.
WaveResult AnalyzeWave(const SensorResult& sensor, const SensorOptions& options,
                       const WaveOptions& wave);

}  // namespace impactdic

#endif  // IMPACTDIC_SENSOR_WAVE_H_
