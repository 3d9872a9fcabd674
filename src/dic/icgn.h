// Internal: shape-function algebra and the IC-GN kernel of the correlator (see correlator.h).
#ifndef IMPACTDIC_SRC_DIC_ICGN_H_
#define IMPACTDIC_SRC_DIC_ICGN_H_

#include <algorithm>
#include <array>
#include <opencv2/core.hpp>
#include <vector>

#include "impactdic/dic/bspline.h"
#include "impactdic/dic/options.h"

namespace impactdic::internal {

// Warp parameters: [u, ux, uy, (uxx, uxy, uyy,) v, vx, vy, (vxx, vxy, vyy)] with
// u(xi, eta) = u + ux xi + uy eta + uxx xi^2 / 2 + uxy xi eta + uyy eta^2 / 2, (xi, eta) the
// offset from the subset centre [px].
using Params = std::array<double, 12>;

struct Shape {
  ShapeFunction kind = ShapeFunction::kAffine;
  int nm = 3;  // Monomials per component.
  int n = 6;   // Parameters.
  int half = 12;
  // Least-squares fit of quadratic parameters to displacements sampled on a 5x5 grid (quadratic
  // warp composition); 6 x 25, row-major.
  std::vector<double> fit;
  // Sums over the subset's pixels of the products of the shape monomials (nm x nm of 6 x 6, the
  // Hessian's structure per unit gradient): the gradient-noise term of the uncertainty model.
  std::array<double, 36> monomial_moments{};
};
Shape MakeShape(ShapeFunction kind, int half);

// Inverse of a symmetric positive definite n x n matrix (row-major, 1 <= n <= 12) by Cholesky
// factorisation A = L L^T, inv = L^-T L^-1, in plain loops (spd_inverse.cc). Returns false, leaving
// inv unspecified, if a pivot L_jj^2 is not above 1e-10 of its diagonal entry A_jj (the data cannot
// determine a parameter).
bool InvertSpd(const double* a, int n, double* inv);

// Displacement (du, dv) of the warp at (xi, eta).
void Displacement(const Shape& s, const Params& p, double xi, double eta, double* du, double* dv);
// The same warp expressed about a centre moved by (ox, oy).
Params Transfer(const Shape& s, const Params& p, double ox, double oy);
// W(p) o W(dp)^-1 (inverse-compositional update). Exact for affine warps; for quadratic warps
// the composed map is fitted by a quadratic warp on a 5x5 grid (exact when dp = 0, so the
// converged solution is unaffected).
Params ComposeInverse(const Shape& s, const Params& p, const Params& dp);

// Reference data of one subset (computed once per reference).
struct SubsetRef {
  int cx = 0, cy = 0;            // Integer centre in the reference image [px].
  double ox = 0, oy = 0;         // Tracked material point = centre + (ox, oy).
  float f_mean = 0, f_norm = 0;  // Mean and sqrt(sum (f - mean)^2) of the reference subset.
  SubsetStatus status = SubsetStatus::kConverged;  // kConverged = usable.
  int patch = -1;          // Its patch in RefImages' patch layout; -1: RefImages cover a region.
  double sum_j[12] = {};   // sum of the steepest-descent images J.
  double sum_jf[12] = {};  // sum J (f - f_mean).
};

// Reference images (CV_32F): intensities and gradients at integer pixels. Two layouts:
//  * region (patch_size == 0): the images cover `region` of the reference image;
//  * patches (patch_size > 0): only the subsets' own pixels are stored, subset s (SubsetRef::patch
//    = k >= 0) in the patch_size x patch_size square k of a grid of patch_cols squares per row
//    (row-major); `region` is then the part of the reference image the subsets may lie in.
// The patch layout costs the subsets' area, not the image's, at every reference update.
struct RefImages {
  cv::Rect region;
  cv::Mat f, gx, gy;
  double full_scale = 255;
  // The reference frame's estimated noise and used grey-level range (ImageLevelsOf): the noise
  // of the predicted uncertainty (IcgnOptions::max_predicted_uncertainty_px) and the scale of
  // IcgnOptions::min_contrast (full_scale when 0).
  double noise = 0, range = 0;
  int patch_size = 0, patch_cols = 0;
  // The square of patch k in f, gx and gy.
  cv::Rect Patch(int k) const {
    return {(k % patch_cols) * patch_size, (k / patch_cols) * patch_size, patch_size, patch_size};
  }
};

// Where the centre pixel of subset s is in ref's images (column, row).
inline cv::Point RefCentre(const RefImages& ref, const SubsetRef& s) {
  if (s.patch < 0) return {s.cx - ref.region.x, s.cy - ref.region.y};
  const cv::Rect p = ref.Patch(s.patch);
  return {p.x + p.width / 2, p.y + p.height / 2};
}

// What a reference image's grey levels say about the contrast its subsets need.
struct ImageLevels {
  // The standard deviation of the image's noise [grey levels] by Immerkaer's estimator (1996, the
  // mean absolute response to the difference of two Laplacians, which cancels locally planar
  // intensity and passes white noise with a known gain) in 16 x 16 px blocks: the flattest
  // tenth of the blocks. Texture everywhere raises it (sharp speckle, DIC Challenge Sample 3:
  // about 2x the pair-difference noise); compression that removes the fine noise lowers it (4k
  // JPEG sand): good for a limit that tells texture from noise, not for a measurement.
  double noise = 0;
  // The grey levels the image uses: its 99.9th less its 0.1st percentile (0: unknown).
  double range = 0;
};
// ImageLevels of region of a one-channel image; rows are sampled in bands so that at most about
// 2^18 pixels are read.
ImageLevels ImageLevelsOf(const cv::Mat& image, const cv::Rect& region);

// Computes the subset's reference data and its inverse Hessian (n x n, row-major, into hinv),
// setting the status to kOutOfImage / kSaturated / kSingularHessian / kLowContrast if unusable
// (low contrast: IcgnOptions::max_predicted_uncertainty_px with ref.noise, min_contrast with
// ref.range).
void PrepareSubset(const Shape& shape, const RefImages& ref, const IcgnOptions& options,
                   SubsetRef* subset, double* hinv);

struct IcgnResult {
  Params p{};
  float zncc = 0;
  // Estimated standard deviations of the centre displacement [px]: u, v and the larger of both.
  float sigma_u_px = 0, sigma_v_px = 0, sigma_px = 0;
  int iterations = 0;
  SubsetStatus status = SubsetStatus::kNotFound;
};

// The deformed image's B-spline and the rectangle the warped subsets must stay in.
struct DeformedImage {
  const BsplineImage* spline = nullptr;
  double x_min = 0, x_max = 0, y_min = 0, y_max = 0;
};

IcgnResult RunIcgn(const Shape& shape, const RefImages& ref, const SubsetRef& subset,
                   const double* hinv, const DeformedImage& def, const IcgnOptions& options,
                   const Params& initial);

// Asks the CPU to load what RunIcgn will read of subset s first (its reference intensities and
// node gradients, and the B-spline coefficients around it displaced by about (u, v) px) while
// the caller works on another subset: subsets far apart in the image (the propagation's waves)
// then do not wait for memory. A hint only: nothing is read or changed.
void PrefetchSubset(const Shape& shape, const RefImages& ref, const SubsetRef& s,
                    const DeformedImage& def, double u, double v);

}  // namespace impactdic::internal

#endif  // IMPACTDIC_SRC_DIC_ICGN_H_
