// Soil kinematics from the correlation results (docs/analysis.md): pixels -> panel millimetres,
// then velocity and acceleration of every subset by finite differences in time.
//
// Frames: panel axes are image-aligned, x to the right and y DOWN, so a positive vertical
// velocity is downward (the momentum module's convention). A homography must map image pixels to
// a panel frame with the same orientation.
//
// Differences (dt = 1 / fps; e.g. Fornberg 1988, doi:10.1090/S0025-5718-1988-0935077-0):
//   velocity      interior  (f[k+1] - f[k-1]) / (2 dt)                   error  dt^2/6 f'''
//                 ends      (-3 f[0] + 4 f[1] - f[2]) / (2 dt) (mirrored)  error -dt^2/3 f'''
//   acceleration  interior  (f[k+1] - 2 f[k] + f[k-1]) / dt^2             error  dt^2/12 f''''
//                 ends      (2 f[0] - 5 f[1] + 4 f[2] - f[3]) / dt^2 (mirrored), 2nd order
// All are exact for quadratic motion. NaN-aware: a derivative that uses a NaN (invalid) sample is
// NaN; no other derivative is affected, and averages over subsets skip NaN entries.
//
//   CorrelationSeries dic = ...;  // positions, displacements [frames x subsets], validity
//   PanelMapping map; map.mm_per_px = 0.25;
//   KinematicsResult k = ComputeKinematics(dic, map, KinematicsOptions{});
//   double v = MeanOverSubsets(k.vel_y_mm_s, k.subsets, /*frame=*/10, ids);
#ifndef IMPACTDIC_KINEMATICS_KINEMATICS_H_
#define IMPACTDIC_KINEMATICS_KINEMATICS_H_

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace impactdic {

// Image pixels -> panel millimetres: a uniform scale, or a 3x3 homography (row-major,
// [X Y W]^T = H [x y 1]^T, panel mm = (X / W, Y / W)) when one is set.
struct PanelMapping {
  double mm_per_px = 0;                             // > 0 unless a homography is given.
  std::optional<std::array<double, 9>> homography;  // Image px -> panel mm.
  void Check() const;
  void Map(double x_px, double y_px, double* x_mm, double* y_mm) const;
  // Local scale [mm/px] at an image point (sqrt of the Jacobian determinant); mm_per_px if uniform.
  double LocalScale(double x_px, double y_px) const;
};

// The correlation results one scene produces (the dic module's output, as plain arrays).
struct CorrelationSeries {
  std::size_t frames = 0, subsets = 0;
  std::vector<double> x_px, y_px;   // Subset centres in the reference frame [subsets].
  std::vector<double> u_px, v_px;   // Displacement since frame 0 [frames x subsets], row-major.
  std::vector<std::uint8_t> valid;  // [frames x subsets], 1 = valid; empty = valid where finite.
  // Estimated standard deviations of u and v (dic FrameResult::sigma_u_px, sigma_v_px; 0 in the
  // reference frame) [frames x subsets] [px]; empty = not known.
  std::vector<float> sigma_u_px, sigma_v_px;
  // Throws Error(kInvalidValue) naming the inconsistent field.
  void Check() const;
};

// The downstream use of the correlation's uncertainty (scene key `momentum.max_sigma_px`): marks
// the samples whose sigma_u_px or sigma_v_px exceeds max_sigma_px [px] invalid (valid = 0; u and
// v are kept), so the kinematics (which take an invalid sample as NaN: derivatives touching them
// are NaN) and the momentum grid mean (NaN subsets skipped) leave them out; returns their count.
// Samples without a sigma (NaN: failed subsets) are already invalid. Error naming `where` if
// max_sigma_px is not > 0 or the series has no sigmas (results written before they existed).
std::size_t ExcludeUncertainSamples(double max_sigma_px, const std::string& where,
                                    CorrelationSeries* series);
// ExcludeUncertainSamples, returning the warning the pipeline reports (`run` in summary.json,
// `analyze` in its log): "kinematics: N of M subset samples left out (sigma_u or sigma_v > WHERE
// = LIMIT px)".
std::string ExcludeUncertainSamplesWithWarning(double max_sigma_px, const std::string& where,
                                               CorrelationSeries* series);

// The default downstream use of the correlation's uncertainty (scene key
// `momentum.max_sigma_ratio`, when `momentum.max_sigma_px` is not set): in each frame, marks the
// samples whose sigma_u_px or sigma_v_px exceeds `ratio` times the median over the frame's valid
// samples of max(sigma_u_px, sigma_v_px) invalid, as ExcludeUncertainSamples does: a limit
// relative to what the texture allows in this recording, not a fixed one. Frames with fewer than
// 3 valid samples are left as they are. Returns their count; Error naming `where` if ratio is not
// > 1 or the series has no sigmas.
std::size_t ExcludeSamplesAboveMedianSigma(double ratio, const std::string& where,
                                           CorrelationSeries* series);
// ExcludeSamplesAboveMedianSigma, returning the warning the pipeline reports (empty when no sample
// was left out: the default rule speaks only when it acts).
std::string ExcludeSamplesAboveMedianSigmaWithWarning(double ratio, const std::string& where,
                                                      CorrelationSeries* series);

struct KinematicsOptions {
  double fps = 1600;  // Camera frame rate [1/s], > 0; dt = 1 / fps.
  void Check() const;
};

struct KinematicsSummary {
  std::size_t valid_samples = 0, invalid_samples = 0;  // Over frames x subsets.
  double seconds = 0;
  std::vector<std::string> warnings;
  std::string BriefReport() const;
};

struct KinematicsResult {
  std::size_t frames = 0, subsets = 0;
  std::vector<double> time_s;      // k / fps [frames].
  std::vector<double> x_mm, y_mm;  // Reference subset centres on the panel [subsets].
  // [frames x subsets], row-major; NaN where invalid.
  std::vector<double> disp_x_mm, disp_y_mm;
  std::vector<double> vel_x_mm_s, vel_y_mm_s;
  std::vector<double> acc_x_mm_s2, acc_y_mm_s2;
  // Standard deviation of disp_y_mm from the correlation's sigma_v_px times the local scale at the
  // subset [frames x subsets] [mm]; NaN where invalid, empty when the series has no sigmas. What
  // the momentum stage propagates (momentum/uncertainty.h).
  std::vector<float> disp_y_sigma_mm;
  KinematicsSummary summary;
};

KinematicsResult ComputeKinematics(const CorrelationSeries& dic, const PanelMapping& mapping,
                                   const KinematicsOptions& options);

// First / second derivative of a uniformly sampled series (spacing h > 0) with the stencils of
// the file comment; needs n >= 3 (first) or n >= 4 (second).
std::vector<double> FirstDerivative(const std::vector<double>& f, double h);
std::vector<double> SecondDerivative(const std::vector<double>& f, double h);

// Mean of field[frame * subsets + id] over `ids`, skipping NaN entries; NaN if none is finite.
// *count (optional) receives the number of finite entries used.
double MeanOverSubsets(const std::vector<double>& field, std::size_t subsets, std::size_t frame,
                       const std::vector<std::size_t>& ids, std::size_t* count = nullptr);

}  // namespace impactdic

#endif  // IMPACTDIC_KINEMATICS_KINEMATICS_H_
