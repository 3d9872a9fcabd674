// Strain and compaction of the soil from the correlation results (docs/strain.md): the
// displacement gradient per subset and frame (from the subset warp, or from a least-squares fit of
// the neighbours' displacements), small strain and Green-Lagrange strain, volumetric strain
// (compression positive, the geotechnical convention), maximum shear strain, principal strains and
// directions, strain rates, the density field and the compacted zone, and shear bands.
//
// Axes: image axes, x right and y DOWN, in the first reference (material coordinates X, Y). The
// displacement gradient is H = [[du/dX, du/dY], [dv/dX, dv/dY]] (dimensionless); F = I + H.
//   small strain      eps = (H + H^T) / 2                      (tension positive)
//   Green-Lagrange    E   = (H + H^T + H^T H) / 2              (tension positive)
//   volumetric        eps_v = -(eps_xx + eps_yy)               (plane strain; COMPRESSION positive)
//   principal         eps_1 >= eps_2 of eps; theta_1 [rad] = direction of eps_1 from +x towards +y
//                     (clockwise on screen), in (-pi/2, pi/2]
//   maximum shear     gamma_max = eps_1 - eps_2                (engineering shear strain, >= 0)
//   rates             d/dt of eps_xx, eps_yy, eps_xy, eps_v, gamma_max [1/s] by the kinematics
//                     module's differences (FirstDerivative), NaN-aware like the velocity.
//
//   CorrelationSeries dic = ...;  // grid positions, displacements [frames x subsets], validity
//   DisplacementGradient g = FitDisplacementGradient(dic, /*window=*/5);
//   StrainField s = ComputeStrain(g, /*fps=*/1600);
//   CompactedZone z = FindCompactedZone(s, dic, frame, options, /*mm_per_px=*/0.25);
#ifndef IMPACTDIC_STRAIN_STRAIN_H_
#define IMPACTDIC_STRAIN_STRAIN_H_

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "impactdic/core/enum_names.h"
#include "impactdic/core/numeric.h"
#include "impactdic/kinematics/kinematics.h"

namespace impactdic {

// Where the displacement gradient comes from (scene key strain.gradient: "warp" | "fit").
//   kWarp: the subset warp's affine terms (IC-GN's du/dx, du/dy, dv/dx, dv/dy), composed across
//          reference updates (dic DicOptions::keep_warp_gradient; /dic/dudx_warp ...).
//   kFit:  a least-squares plane u = a + b X + c Y (and v) through the valid displacements of the
//          window x window grid neighbourhood centred on each subset (at least 3 non-collinear).
enum class StrainGradient { kWarp, kFit };
inline constexpr EnumNames<StrainGradient, 2> kStrainGradientNames{
    {{{StrainGradient::kWarp, "warp"}, {StrainGradient::kFit, "fit"}}}};

struct StrainOptions {
  bool enabled = false;  // Scene key strain.enabled: compute /strain at all.
  StrainGradient gradient = StrainGradient::kFit;
  // kFit: neighbourhood side in grid points, odd, >= 3, and at most the subset grid's columns and
  // rows (checked by FitDisplacementGradient, where the grid is known). Default 3:
  // docs/validation_strain.md "Strain".
  int window = 3;
  // The compacted zone: samples whose eps_v exceeds this (compression positive, dimensionless).
  double compaction_threshold = 0.01;
  // Shear bands: ridge samples of gamma_max whose value exceeds this (dimensionless).
  double shear_band_threshold = 0.02;
  void Check() const;  // Error naming the strain.* key and the range expected.
};

// The displacement gradient per subset and frame, [frames x subsets] row-major, NaN where unknown
// (invalid sample, too few neighbours). Row 0 (the first reference) is 0 where the subset is valid.
struct DisplacementGradient {
  std::size_t frames = 0, subsets = 0;
  std::vector<double> dudx, dudy, dvdx, dvdy;
};

// kFit: the gradient from the neighbours' displacements. The grid is found from dic.x_px, dic.y_px
// (a regular grid with one step in x and y, possibly with holes: ROI, mask); cols x rows is its
// extent, holes included. window odd >= 3, and window <= cols and window <= rows: the window must
// fit inside the grid in both directions. A larger one reaches across the whole grid from the
// subsets near the middle, and from every subset once window >= 2 max(cols, rows) - 1, where
// the "local" fit is one plane through the whole grid. Error naming strain.window, the window and
// cols x rows otherwise (a grid with fewer than 3 rows or columns takes no window).
DisplacementGradient FitDisplacementGradient(const CorrelationSeries& dic, int window);

// The strain measures of one gradient (tension positive except eps_v; see the file comment).
struct StrainAtPoint {
  double exx = 0, eyy = 0, exy = 0;  // Small strain (tensor shear exy).
  double gxx = 0, gyy = 0, gxy = 0;  // Green-Lagrange.
  double eps_v = 0;                  // Volumetric, compression positive.
  double eps_1 = 0, eps_2 = 0, theta_1_rad = 0, gamma_max = 0;
};
StrainAtPoint StrainFromGradient(double dudx, double dudy, double dvdx, double dvdy);

// Every measure per subset and frame, [frames x subsets] row-major, NaN where the gradient is NaN;
// the rates [1/s] by FirstDerivative with dt = 1 / fps.
struct StrainField {
  std::size_t frames = 0, subsets = 0;
  std::vector<double> exx, eyy, exy, gxx, gyy, gxy, eps_v, eps_1, eps_2, theta_1_rad, gamma_max;
  std::vector<double> exx_rate, eyy_rate, exy_rate, eps_v_rate, gamma_max_rate;
};
StrainField ComputeStrain(const DisplacementGradient& gradient, double fps);

// Dry density after compaction rho = rho_d / (1 - eps_v) [kg/m^3] per sample (NaN where eps_v is
// NaN or >= 1).
std::vector<double> DensityField(const StrainField& strain, double dry_density_kg_m3);

// The compacted zone in one frame: the valid samples with eps_v > compaction_threshold. Area =
// their count times the grid cell area on the panel [mm^2]; depth = the deepest such subset's
// reference y minus the soil surface's y, on the panel [mm] (0 and 0 when none; never < 0; NaN
// and NaN when the frame has no finite eps_v at all: not measured, not "no compaction"). The
// soil surface is surface_y_px (image y of the undisturbed surface, e.g. the scene's
// momentum.surface_y_px) when finite, else the grid's top row y.
struct CompactedZone {
  std::size_t frame = 0;
  std::size_t samples = 0;
  double area_mm2 = 0, depth_mm = 0;
};
CompactedZone FindCompactedZone(const StrainField& strain, const CorrelationSeries& dic,
                                std::size_t frame, const StrainOptions& options, double mm_per_px,
                                double surface_y_px = kNaN);

// Shear bands: 1 where gamma_max is a ridge (a local maximum across the band: larger than both
// grid neighbours along at least one of the four grid directions) and exceeds
// options.shear_band_threshold, else 0; [frames x subsets].
std::vector<std::uint8_t> ShearBands(const StrainField& strain, const CorrelationSeries& dic,
                                     const StrainOptions& options);

}  // namespace impactdic

#endif  // IMPACTDIC_STRAIN_STRAIN_H_
