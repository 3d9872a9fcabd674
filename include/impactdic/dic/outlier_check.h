// A post-check of a correlated frame for spurious vectors: the normalized median test of
// Westerweel & Scarano (2005, Exp. Fluids 39:1096), the standard outlier test of PIV, on the
// subset grid (OutlierCheckOptions in options.h).
//
// For a converged subset 0 with displacement d_0 = (u, v) and its neighbours d_i in the 3 x 3 grid
// neighbourhood, taken in opposite pairs whose two subsets both converged (at least
// `min_neighbours`, so a subset on the grid's edge, with one pair, is not judged): d_m is the
// component-wise median of the d_i, r_i = |d_i - d_m| the neighbours' own residuals and r_m their
// median. Pairs make the median of a linear field its centre value: with a one-sided
// neighbourhood the median is off by the local gradient (Westerweel & Scarano's test assumes a
// full neighbourhood). The subset is an `outlier` when
//   |d_0 - d_m| / (r_m + noise_px) > threshold   (the normalized median test), and
//   |d_0 - d_m| > sigma_factor x sigma_0           (the deviation is significant for this subset:
//                                                   sigma_0 = hypot(sigma_u, sigma_v), NaN: 0).
// Coherent motion with a strong gradient (the soil under a pounder) is not flagged: the
// neighbours' residuals r_m grow with the gradient, so the test is relative to the local
// variation. Nor is a straddling subset between two bodies whose neighbours lie on both sides.
// The ZNCC of the fit is checked by the correlator itself (IcgnOptions::min_zncc,
// `low_correlation`).
//
// Correlator::Correlate runs it on every frame when DicOptions::outliers.enabled (the default);
// flagged subsets become `outlier` (NaN). By hand on a result of a correlator with it off:
//
//   const OutlierFlags flags =
//       FindOutliers(result, correlator.cols(), correlator.rows(), OutlierCheckOptions{});
//   ApplyOutlierFlags(flags, &result);  // flagged subsets become kOutlier, NaN
#ifndef IMPACTDIC_DIC_OUTLIER_CHECK_H_
#define IMPACTDIC_DIC_OUTLIER_CHECK_H_

#include <cstdint>
#include <vector>

#include "impactdic/dic/correlator.h"
#include "impactdic/dic/options.h"

namespace impactdic {

struct OutlierFlags {
  std::vector<std::uint8_t> outlier;  // Per subset, 1 = flagged.
  // Per subset: the normalized residual |d_0 - d_m| / (r_m + noise_px); NaN where not judged
  // (not converged, too few converged neighbours).
  std::vector<double> normalized_residual;
  int flagged = 0;
};

// `result` of a grid of cols x rows subsets (row-major). Only converged subsets are flagged.
OutlierFlags FindOutliers(const FrameResult& result, int cols, int rows,
                          const OutlierCheckOptions& options);
// Sets the flagged subsets to kOutlier with NaN displacement and sigmas.
void ApplyOutlierFlags(const OutlierFlags& flags, FrameResult* result);

}  // namespace impactdic

#endif  // IMPACTDIC_DIC_OUTLIER_CHECK_H_
