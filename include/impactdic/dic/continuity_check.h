// A post-check of a correlated frame (docs/dic_real_images.md, "Realistic footage: straddling
// subsets"): flags converged subsets that are likely to straddle a discontinuity (a body edge, a
// shear band), whose displacement is then a mixture of both sides and not the motion of their
// centre.
//
// The correlator cannot see this by itself: on realistic footage (synth/realistic.h) a subset half
// on the pounder and half on the static wall converges with ZNCC 0.998 and an error of 1 px.
// Three criteria on the subset grid (ContinuityCheckOptions in options.h):
//  * misfit: 1 - ZNCC above `misfit_ratio` times the median of 1 - ZNCC of the converged subsets
//    in the 7 x 7 neighbourhood and above `min_misfit`: one affine warp cannot fit both sides of
//    a shear band, so the residual rises above what the noise and texture around explain;
//  * second difference: |d_i - (d_left + d_right) / 2| along a grid row (or column) above
//    `max_second_difference_px`: a smooth field has second differences of about u'' step^2, a
//    jump J between neighbours gives J / 2 on both sides of it;
//  * jump: the displacement of a subset and of an adjacent one along a row (or column) differ by
//    more than `max_neighbour_difference_px` (a subset midway across an edge interpolates
//    linearly between both sides, which the second difference does not see).
// The last two also need the value above `local_ratio` times the median of the same quantity in
// the same grid direction over the 7 x 7 neighbourhood: a smooth field with a large strain at a
// coarse step has large differences everywhere around, a discontinuity only next to it; keeping
// the directions apart stops a strong gradient along a band from hiding the jump across it.
// Correlator::Correlate runs it on every frame when DicOptions::continuity.enabled (the default);
// flagged subsets become `discontinuous`. By hand on a result of a correlator with it off:
//
//   const ContinuityFlags flags =
//       CheckContinuity(result, correlator.cols(), correlator.rows(), ContinuityCheckOptions{});
//   ApplyContinuityFlags(flags, &result);  // flagged subsets become kDiscontinuous, NaN
#ifndef IMPACTDIC_DIC_CONTINUITY_CHECK_H_
#define IMPACTDIC_DIC_CONTINUITY_CHECK_H_

#include <cstdint>
#include <vector>

#include "impactdic/dic/correlator.h"
#include "impactdic/dic/options.h"

namespace impactdic {

struct ContinuityFlags {
  std::vector<std::uint8_t> misfit, discontinuous;  // Per subset, 1 = flagged.
  int flagged = 0;                                  // Subsets with either flag.
};

// `result` of a grid of cols x rows subsets (row-major). Only converged subsets are flagged.
ContinuityFlags CheckContinuity(const FrameResult& result, int cols, int rows,
                                const ContinuityCheckOptions& options);
// Sets the flagged subsets to kDiscontinuous with NaN displacement and sigmas.
void ApplyContinuityFlags(const ContinuityFlags& flags, FrameResult* result);

}  // namespace impactdic

#endif  // IMPACTDIC_DIC_CONTINUITY_CHECK_H_
