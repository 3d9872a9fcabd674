// The strain of the soil in truth.h5 (strain_truth.h).
#include "strain_truth.h"

#include <cstddef>
#include <string>
#include <vector>

#include "impactdic/io/hdf5_store.h"

namespace impactdic::synth_internal {

void WriteStrainTruth(const GradientTruth& g, const Dims& fdims, const std::string& how,
                      H5Writer& out) {
  out.Write("soil/dudx", g.dudx, fdims, "1", "displacement gradient du/dX (" + how + ")");
  out.Write("soil/dudy", g.dudy, fdims, "1", "displacement gradient du/dY, Y down");
  out.Write("soil/dvdx", g.dvdx, fdims, "1", "displacement gradient dv/dX, v down");
  out.Write("soil/dvdy", g.dvdy, fdims, "1", "displacement gradient dv/dY");
  out.SetAttribute("soil", "strain_source", how);
}

}  // namespace impactdic::synth_internal
