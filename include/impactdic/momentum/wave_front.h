// The front of the impact's compression wave in the DIC field (docs/wave.md "The front in the DIC
// field"; the paper's Fig. 3: the velocity "propagates in a wave-like form into more distant soil
// regions", and section 3.3: the displacements decrease exponentially with depth).
//
//   WaveFrontOptions o;  // the pounder's centre line, the surface and its width on the panel
//   o.pounder_center_x_mm = 200; o.surface_y_mm = 60; o.pounder_width_mm = 150;
//   WaveFront f = AnalyzeWaveFront(kinematics, timeline.daq_time_s, sensor, t_e, o);
//   std::cout << f.speed_m_s << " [" << f.speed_ci_m_s[0] << ", " << f.speed_ci_m_s[1] << "]";
//
// Definitions (panel mm, y down; times after the impact = frame DAQ time - the sensor's impact):
//  * noise of a subset: the standard deviation of its vertical velocity (and displacement) over
//    the frames whose velocity stencil lies wholly before the impact (frame f with frame f + 2
//    before it); needs kMinNoiseFrames such frames.
//  * arrival of a subset: the first time its downward vertical velocity exceeds
//    max(k sd, f peak) (k = noise_factor, f = peak_fraction, peak = its largest downward velocity
//    after the impact), linear between the frame below and the frame above the threshold. A
//    subset whose peak does not exceed k sd has no arrival.
//  * distance r: from the impact point (the pounder's centre line at the undisturbed surface) to
//    the subset's reference centre.
//  * front speed: ordinary least squares of arrival = t0 + r / c over the subsets below the
//    surface and outside the pounder's footprint columns (|x - x_c| > D / 2: the soil under the
//    pounder is pushed at the contact, not reached by a front) whose threshold is f peak (peak
//    >= k sd / f: every arrival in the fit is the same phase of its pulse; where the noise term
//    governs, the crossing comes later in a weak pulse and would bias c), with one pass that drops
//    the arrivals more than kOutlierSigma robust standard deviations (1.4826 x the median absolute
//    residual) off the first fit; c = 1 / slope, its interval 1 / (slope -+ t se) at `confidence`
//    (t of Student with n - 2 degrees of freedom; the upper end NaN when slope - t se <= 0).
//  * centre line: the subsets within D / 2 of x_c below the pounder's base; depth z = the
//    subset's reference y - (surface + the pounder's penetration at the frame, from the sensor).
//  * decay: ln u = ln u0 - z / lambda by least squares over the centre-line subsets whose u
//    (vertical displacement, or velocity, downward) exceeds k times its noise, at the frame
//    nearest t_e and at the last frame; lambda's interval -1 / (slope -+ t se) (upper end NaN
//    when slope + t se >= 0); lambda NaN with the reason when fewer than 3 subsets qualify or the
//    slope is not negative.
//  * depth of influence: below the undisturbed surface, where the fitted displacement falls to
//    kInfluenceFraction of u0: the pounder base's depth + lambda ln(1 / kInfluenceFraction).
#ifndef IMPACTDIC_MOMENTUM_WAVE_FRONT_H_
#define IMPACTDIC_MOMENTUM_WAVE_FRONT_H_

#include <vector>

#include "impactdic/core/numeric.h"
#include "impactdic/kinematics/kinematics.h"
#include "impactdic/sensor/sensor.h"
#include "impactdic/sensor/wave.h"

namespace impactdic {

inline constexpr int kMinNoiseFrames = 3;
inline constexpr double kOutlierSigma = 4;

struct WaveFrontOptions {
  double noise_factor = 5;     // k: the arrival threshold in noise standard deviations, > 0.
  double peak_fraction = 0.5;  // f: the arrival threshold as a fraction of the peak, (0, 1).
  double confidence = 0.95;    // Level of the intervals, kConfidenceRange.
  // The pounder on the panel [mm] (momentum footprint): its centre line, the undisturbed surface
  // and its width D; NaN = not known (the front is not computed, WaveFront::problem says why).
  double pounder_center_x_mm = kNaN, surface_y_mm = kNaN, pounder_width_mm = kNaN;
  void Check() const;
};

// The front of `kinematics` (frame f taken at frame_daq_time_s[f]); `sensor` gives the impact
// time, the pounder's penetration and the crater depth; t_end_peak_s is t_e after the impact
// (NaN: not measured, the t_e fits say so).
WaveFront AnalyzeWaveFront(const KinematicsResult& kinematics,
                           const std::vector<double>& frame_daq_time_s, const SensorResult& sensor,
                           double t_end_peak_s, const WaveFrontOptions& options);

// The DIC half of the reflection check (sensor/wave.h, "reflection check"), for each channel's
// window (ReflectionCheck::window_s, set by AnalyzeWave):
//  * signal: the mean downward vertical velocity of the near-surface subsets: the shallowest row
//    below the undisturbed surface outside the pounder's footprint columns (|x - x_c| > D / 2;
//    soil the reflected wave reaches, not the pounder);
//  * statistic: the largest prominence (LargestProminence) of a local maximum of the signal or of
//    its negative (the reflected compression wave moves the surface soil upward; either sign
//    shows) over the frames from the last one at or before the window's start to the first at or
//    after its end;
//  * a local maximum shows when the prominence exceeds kReflectionSigma standard deviations of the
//    signal over the front's noise frames (frame f with frame f + 2 before the impact).
// Not checked (DicReflectionCheck::note says why): no window (no return time), the pounder's
// position unknown, no near-surface subset, too few noise frames, the frames end before the
// window's end.
void CheckDicReflections(const KinematicsResult& kinematics,
                         const std::vector<double>& frame_daq_time_s, const SensorResult& sensor,
                         const WaveFrontOptions& options, std::vector<WaveChannel>* channels);

}  // namespace impactdic

#endif  // IMPACTDIC_MOMENTUM_WAVE_FRONT_H_
