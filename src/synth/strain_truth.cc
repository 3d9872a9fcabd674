// The strain of the soil in truth.h5 (strain_truth.h).
#include "strain_truth.h"

#include <cstddef>
#include <string>
#include <vector>

#include "impactdic/io/hdf5_store.h"
#include "impactdic/strain/strain.h"

namespace impactdic::synth_internal {

void WriteStrainTruth(const GradientTruth& g, const Dims& fdims, const std::string& how,
                      H5Writer& out) {
  out.Write("soil/dudx", g.dudx, fdims, "1", "displacement gradient du/dX (" + how + ")");
  out.Write("soil/dudy", g.dudy, fdims, "1", "displacement gradient du/dY, Y down");
  out.Write("soil/dvdx", g.dvdx, fdims, "1", "displacement gradient dv/dX, v down");
  out.Write("soil/dvdy", g.dvdy, fdims, "1", "displacement gradient dv/dY");
  out.SetAttribute("soil", "strain_source", how);
  const std::size_t n = g.dudx.size();
  std::vector<double> exx(n), eyy(n), exy(n), gxx(n), gyy(n), gxy(n), eps_v(n), eps_1(n), eps_2(n),
      theta(n), gamma(n);
  for (std::size_t i = 0; i < n; ++i) {
    const StrainAtPoint s = StrainFromGradient(g.dudx[i], g.dudy[i], g.dvdx[i], g.dvdy[i]);
    exx[i] = s.exx, eyy[i] = s.eyy, exy[i] = s.exy, gxx[i] = s.gxx, gyy[i] = s.gyy;
    gxy[i] = s.gxy, eps_v[i] = s.eps_v, eps_1[i] = s.eps_1, eps_2[i] = s.eps_2;
    theta[i] = s.theta_1_rad, gamma[i] = s.gamma_max;
  }
  out.Write("soil/exx", exx, fdims, "1", "small strain (H + H^T) / 2, xx, tension positive");
  out.Write("soil/eyy", eyy, fdims, "1", "small strain, yy (y down), tension positive");
  out.Write("soil/exy", exy, fdims, "1", "small strain, tensor shear xy");
  out.Write("soil/green_lagrange_xx", gxx, fdims, "1",
            "Green-Lagrange strain (H + H^T + H^T H) / 2, xx, tension positive");
  out.Write("soil/green_lagrange_yy", gyy, fdims, "1", "Green-Lagrange strain, yy");
  out.Write("soil/green_lagrange_xy", gxy, fdims, "1", "Green-Lagrange strain, xy");
  out.Write("soil/eps_v", eps_v, fdims, "1",
            "volumetric strain -(exx + eyy), COMPRESSION positive (plane strain)");
  out.Write("soil/eps_1", eps_1, fdims, "1", "major principal small strain");
  out.Write("soil/eps_2", eps_2, fdims, "1", "minor principal small strain");
  out.Write("soil/theta_1_rad", theta, fdims, "rad",
            "direction of eps_1 from +x towards +y (clockwise on screen), (-pi/2, pi/2]");
  out.Write("soil/gamma_max", gamma, fdims, "1", "maximum engineering shear strain eps_1 - eps_2");
  out.SetAttribute("soil", "strain_convention",
                   "strain/strain.h: image axes x right, y down; tension positive except eps_v "
                   "(compression positive)");
}

}  // namespace impactdic::synth_internal
