// The standard uncertainty of the momentum analysis' headline figures (docs/analysis.md,
// "Uncertainty of the figures"), by Monte Carlo over the inputs (JCGM 101:2008, "Propagation of
// distributions using a Monte Carlo method"): the analysis (t_e's frame and its sub-frame
// refinement, p_max, m_add, the sigmoid fit, ...) is repeated `draws` times on inputs perturbed
// by their own errors, and each figure's uncertainty is the standard deviation of its draws.
// Perturbed per draw:
//  - the momentum grid's subset displacements, by the correlation's own sigma_v (KinematicsResult::
//    disp_y_sigma_mm), with the correlation of the errors the correlation makes: half of each
//    sample's variance comes from the reference image's noise and is common to every frame
//    correlated against that reference (it cancels in velocities and in the gap of t_e), the
//    other half from the frame's own noise; overlapping subsets share pixels, so their errors
//    correlate by the overlap fraction of their areas (subset_size_mm);
//  - the accelerometer record: processed again in each draw (sensor ProcessAccelerometer: offset,
//    zero-phase filter, release and impact detection, integration, stop) with fresh white noise
//    of the record's own standard deviation (SensorSummary::noise_g, the free-fall window before
//    the impact) added to the reading as read (SensorResult::reading_g). So the offset's error,
//    the noise integrated into v_p and z_p, and the jitter of the detected release (the
//    integration's start) and impact onset (v0 = v_p there; the time origin of t_e and of the
//    sigmoid's samples; the start of p_max's search) all enter, each through the code that makes
//    it. A sensor result without its reading (not made by ProcessSensor) propagates no
//    accelerometer noise, and a note says so;
//  - the scale (mm/px; displacements, velocities and the grid area scale with it), the density
//    and the out-of-plane depth t_z, each by its stated standard uncertainty (relative for the
//    scale), default 0.
// t_e lies on the frame grid refined to a sub-frame time: the draws repeat the pick of the frame
// and the refinement, so frame jumps enter its spread; where t_e was not refined (the fallback,
// or too few frames), the grid's own resolution, a uniform error over one frame interval
// (dt / sqrt(12)), is added in quadrature. The draws run in parallel, each with its own random
// stream seeded by its index (the result does not depend on the number of threads).
// Limits (tests/pipeline/uncertainty_seed_test.cc measures the model against the scatter over
// noise seeds; docs/analysis.md has the table): a draw's reading carries the nominal's noise and
// the fresh one, sqrt(2) times the record's, and the onset's change-point fit is not linear in
// the noise at that level: the draws scatter the onset ~2x as much as the noise seeds do (7.8 us
// against 3.9-5.3 us on the small synthetic scene), which enters the sigmoid's T (its time
// origin) at full weight and t_e and v0 little. Not covered: a bias of the correlation (e.g.
// subpixel bias, the same in every draw); a coloured accelerometer noise; the growth of the
// displacement error across reference updates (the sigma is against the current reference).
#ifndef IMPACTDIC_MOMENTUM_UNCERTAINTY_H_
#define IMPACTDIC_MOMENTUM_UNCERTAINTY_H_

#include <string>
#include <vector>

#include "impactdic/core/numeric.h"
#include "impactdic/core/range.h"

namespace impactdic {

inline constexpr ValueRange kUncertaintyDrawsRange{0, 100000, ""};
inline constexpr ValueRange kNonNegativeUncertaintyRange{0, 1e300, ""};

// How the uncertainties are propagated, as summary.json and /momentum state it.
inline constexpr const char* kMomentumUncertaintyMethod =
    "Monte Carlo over the inputs (JCGM 101): the momentum analysis repeated on inputs perturbed "
    "by their errors (DIC sigma, the accelerometer record processed again with fresh noise of its "
    "measured level, scale, density, depth); u = standard deviation of the draws "
    "(docs/analysis.md)";

struct MomentumUncertaintyOptions {
  // Monte Carlo draws, kUncertaintyDrawsRange; 0 = no uncertainty (the figures' _u are NaN).
  // 200 draws give each standard deviation to ~5 % (1 / sqrt(2 (N - 1))).
  int draws = 200;
  double density_u_kg_m3 = 0;   // Standard uncertainty of rho_d [kg/m^3], >= 0.
  double depth_u_m = 0;         // Standard uncertainty of t_z [m], >= 0.
  double scale_u_fraction = 0;  // Relative standard uncertainty of the scale (mm/px), >= 0.
  // Side of a DIC subset on the panel [mm], >= 0, for the correlation of overlapping subsets'
  // errors; 0 = the subsets' errors are independent.
  double subset_size_mm = 0;
  void Check() const;
};

// The figures' standard uncertainties (NaN: not estimated, or the figure is NaN) and what they
// were propagated from.
struct MomentumUncertainty {
  int draws = 0;  // 0: not estimated.
  double impact_velocity_m_s = kNaN, p_max_kg_m_s = kNaN, t_end_peak_s = kNaN;
  double p_gran_te_kg_m_s = kNaN, v_sand_te_m_s = kNaN, added_mass_max_kg = kNaN;
  double momentum_conservation_error = kNaN, momentum_ratio = kNaN, v_sand_max_m_s = kNaN;
  double sigmoid_M_kg = kNaN, sigmoid_b_per_s = kNaN, sigmoid_T_s = kNaN;
  // The frame grid's term in t_end_peak_s (0 when t_e was refined to a sub-frame time).
  double t_end_grid_s = 0;
  // Inputs.
  double accel_noise_g = kNaN;        // White noise of the accelerometer (SensorSummary).
  double dic_sigma_median_mm = kNaN;  // Median sigma of the grid's displacements.
  double scale_u_fraction = 0, density_u_kg_m3 = 0, depth_u_m = 0, subset_size_mm = 0;
  std::vector<std::string> notes;
};

}  // namespace impactdic

#endif  // IMPACTDIC_MOMENTUM_UNCERTAINTY_H_
