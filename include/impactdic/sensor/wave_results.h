// The wave figures' results (the /wave group of results.h5, only when the scene has base force
// channels): the names, the writer and the reader. Definitions: sensor/wave.h, docs/wave.md.
//
//   H5Writer out("run/results.h5");
//   WriteWaveResults(out, sensor, wave);  // wave = AnalyzeWave(sensor, options, wave_options)
//   out.Commit();
//   const WaveResult back = ReadWaveResults(H5Reader("run/results.h5"), "results.h5");
#ifndef IMPACTDIC_SENSOR_WAVE_RESULTS_H_
#define IMPACTDIC_SENSOR_WAVE_RESULTS_H_

#include <string>
#include <vector>

#include "impactdic/io/hdf5_store.h"
#include "impactdic/sensor/sensor.h"
#include "impactdic/sensor/wave.h"

namespace impactdic {
namespace results_layout {

// [C] each, C = base channels in the order of the string attribute kWaveColumnsAttr (the CSV
// columns, comma-separated), NaN = not available (the reason in the string attribute
// kWaveProblemsAttr, one "column: problem" per line): the position (horizontal offset, depth,
// straight distance from the impact point) [mm], the sensing area [mm^2], the arrival after the
// impact (onset, peak) [s], the wave speed from the peak and from the onset travel times and
// their standard uncertainties [m/s], the predicted return time at the surface after the impact
// and its uncertainty [s], the peak dynamic force [N] and stress [Pa], the stress ratio to the
// pounder's peak stress [1], and the reflection check: the window's start and end after the
// impact [s], the statistic (largest prominence of a local maximum of the pounder's deceleration
// in it) and its threshold [g], and its outcome (1 = a local maximum, 0 = none, NaN = not
// checked); its DIC half (momentum/wave_front.h CheckDicReflections): the statistic for the
// near-surface soil's mean vertical velocity and its threshold [mm/s], the outcome (the same
// codes) and the subsets averaged. kWaveForceGroup/<column>: each channel's dynamic force [K] [N]
// (offset-corrected, filtered; the time axis is /sensor/t_s).
inline constexpr const char* kWaveGroup = "/wave";
inline constexpr const char* kWaveOffset = "/wave/offset_mm";
inline constexpr const char* kWaveDepth = "/wave/depth_mm";
inline constexpr const char* kWaveDistance = "/wave/distance_mm";
inline constexpr const char* kWaveArea = "/wave/area_mm2";
inline constexpr const char* kWaveOnset = "/wave/onset_s";
inline constexpr const char* kWavePeak = "/wave/peak_s";
inline constexpr const char* kWaveSpeedPeak = "/wave/speed_peak_m_s";
inline constexpr const char* kWaveSpeedPeakSigma = "/wave/speed_peak_sigma_m_s";
inline constexpr const char* kWaveSpeedOnset = "/wave/speed_onset_m_s";
inline constexpr const char* kWaveSpeedOnsetSigma = "/wave/speed_onset_sigma_m_s";
inline constexpr const char* kWaveReturnTime = "/wave/return_time_s";
inline constexpr const char* kWaveReturnTimeSigma = "/wave/return_time_sigma_s";
inline constexpr const char* kWavePeakForce = "/wave/peak_force_N";
inline constexpr const char* kWavePeakStress = "/wave/peak_stress_Pa";
inline constexpr const char* kWaveStressRatio = "/wave/stress_ratio";
inline constexpr const char* kWaveReflectionStart = "/wave/reflection_window_start_s";
inline constexpr const char* kWaveReflectionEnd = "/wave/reflection_window_end_s";
inline constexpr const char* kWaveReflectionProminence = "/wave/reflection_prominence_g";
inline constexpr const char* kWaveReflectionThreshold = "/wave/reflection_threshold_g";
inline constexpr const char* kWaveReflectionLocalMax = "/wave/reflection_local_maximum";
inline constexpr const char* kWaveDicReflectionProminence = "/wave/reflection_dic_prominence_mm_s";
inline constexpr const char* kWaveDicReflectionThreshold = "/wave/reflection_dic_threshold_mm_s";
inline constexpr const char* kWaveDicReflectionLocalMax = "/wave/reflection_dic_local_maximum";
inline constexpr const char* kWaveDicReflectionSubsets = "/wave/reflection_dic_subsets";
inline constexpr const char* kWaveForceGroup = "/wave/force_N";
// The front in the DIC field (only when the run measured it: WaveFront::computed), definitions in
// momentum/wave_front.h. [S] per subset of /kinematics, in its order: the reference centre's
// distance from the impact point [mm], the arrival of its motion after the impact [s] (NaN =
// none), 1 = in the speed fit. [1] each: the front speed and its interval's ends [m/s] (NaN =
// not determined, the reason in the string attribute kWaveFrontProblemAttr), the fit's intercept
// and rms residual [s]. The decay along the centre line, [2] each (row 0 at the frame nearest
// t_e, row 1 at the last frame; NaN = not determined, the reasons in the string attribute
// kWaveFrontProblemAttr of the group, one "row: problem" per line): the frame's time after the
// impact [s], the subsets fitted [1], u0 at the pounder's base [mm or mm/s], the decay length
// and its interval's ends [mm], and for the displacement the depth of influence below the
// surface [mm]. Number attributes of kWaveFrontGroup: noise_factor, peak_fraction, arrivals,
// centre_line_subsets, pounder_base_depth_te_mm, crater_depth_mm, influence_fraction.
inline constexpr const char* kWaveFrontGroup = "/wave/front";
inline constexpr const char* kWaveFrontDistance = "/wave/front/distance_mm";
inline constexpr const char* kWaveFrontArrival = "/wave/front/arrival_s";
inline constexpr const char* kWaveFrontInFit = "/wave/front/in_fit";
inline constexpr const char* kWaveFrontSpeed = "/wave/front/speed_m_s";
inline constexpr const char* kWaveFrontSpeedCiLow = "/wave/front/speed_ci_low_m_s";
inline constexpr const char* kWaveFrontSpeedCiHigh = "/wave/front/speed_ci_high_m_s";
inline constexpr const char* kWaveFrontIntercept = "/wave/front/intercept_s";
inline constexpr const char* kWaveFrontRms = "/wave/front/rms_residual_s";
inline constexpr const char* kWaveFrontDisplacementGroup = "/wave/front/displacement";
inline constexpr const char* kWaveFrontVelocityGroup = "/wave/front/velocity";
inline constexpr const char* kWaveFrontProblemAttr = "problem";
// The centre line (WaveFront::centre_line): [C] the subsets' indices in /kinematics' order; each
// decay group holds [2 x C] profile_depth_mm (below the pounder's base at the row's frame, NaN =
// not below it), profile_value (u, NaN = not measured) and profile_in_fit (1 = in the fit). The
// space-time diagram's data (SpaceTime): time_s [F] after the impact, depth_mm [R] below the
// undisturbed surface, velocity_mm_s [F x R] each row's mean downward velocity, pounder_base_mm
// [F] the pounder's base below the surface.
inline constexpr const char* kWaveFrontCentreLine = "/wave/front/centre_line";
inline constexpr const char* kWaveSpaceTimeGroup = "/wave/front/space_time";
inline constexpr const char* kWaveSpaceTimeT = "/wave/front/space_time/time_s";
inline constexpr const char* kWaveSpaceTimeDepth = "/wave/front/space_time/depth_mm";
inline constexpr const char* kWaveSpaceTimeVelocity = "/wave/front/space_time/velocity_mm_s";
inline constexpr const char* kWaveSpaceTimeBase = "/wave/front/space_time/pounder_base_mm";
// Number attributes of kWaveGroup: pounder_peak_stress_Pa, pounder_peak_s, sample_interval_s,
// filter_time_constant_s, travel_time_sigma_s, noise_g (WaveResult); string attributes:
inline constexpr const char* kWaveColumnsAttr = "columns";
inline constexpr const char* kWaveUnitsAttr =
    "units";  // The columns' units as given, comma-separated.
inline constexpr const char* kWaveProblemsAttr = "problems";
inline constexpr const char* kWaveDefinitionsAttr = "definitions";

}  // namespace results_layout

// Writes /wave (replacing an existing group), with units and descriptions on every dataset.
void WriteWaveResults(H5Writer& out, const SensorResult& sensor, const WaveResult& wave);

// Reads /wave back: every channel's figures, problems and the reflection check's outcome and
// statistic (not its note), the group's numbers, and the front when /wave/front exists. Error
// kFileFormat naming `file` and the group or dataset when it is missing or a dataset's length
// differs from the columns'.
WaveResult ReadWaveResults(const H5Reader& in, const std::string& file);

// The dynamic force series under kWaveForceGroup (time axis /sensor/t_s), one per channel of
// `wave` that has one, in its order.
std::vector<BaseForceRecord> ReadBaseForceRecords(const H5Reader& in, const std::string& file,
                                                  const WaveResult& wave);

}  // namespace impactdic

#endif  // IMPACTDIC_SENSOR_WAVE_RESULTS_H_
