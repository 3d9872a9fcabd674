// The strain of the soil in truth.h5 (docs/synth.md "Truth file", docs/validation_strain.md
// "Strain"): the displacement gradient at the DIC subset centres and every strain measure of
// strain/strain.h computed from it, under the same names as results.h5's /strain, so a run's
// /strain compares with truth.h5's soil/ name by name. Internal to the synth module.
#ifndef IMPACTDIC_SRC_SYNTH_STRAIN_TRUTH_H_
#define IMPACTDIC_SRC_SYNTH_STRAIN_TRUTH_H_

#include <string>
#include <vector>

#include "impactdic/io/hdf5_store.h"

namespace impactdic::synth_internal {

// The displacement gradient H = [[du/dX, du/dY], [dv/dX, dv/dY]] (ideal pixels of the first
// frame, x right, y down; dimensionless) per frame and subset, row-major [frame][subset], NaN
// where unknown.
struct GradientTruth {
  std::vector<double> dudx, dudy, dvdx, dvdy;
};

// Writes soil/dudx, dudy, dvdx, dvdy and soil/exx, eyy, exy, green_lagrange_xx, _yy, _xy, eps_v,
// eps_1, eps_2, theta_1_rad, gamma_max with `fdims` (F x R x C); `how` says where the gradient
// comes from (the attribute soil/strain_source).
void WriteStrainTruth(const GradientTruth& g, const Dims& fdims, const std::string& how,
                      H5Writer& out);

}  // namespace impactdic::synth_internal

#endif  // IMPACTDIC_SRC_SYNTH_STRAIN_TRUTH_H_
