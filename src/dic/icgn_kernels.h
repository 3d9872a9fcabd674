// Internal: the IC-GN kernels of one instruction set, and their choice at run time.
//
// The per-pixel passes of IC-GN (icgn.cc) exist in three builds of one source,
// icgn_kernel_body.h: scalar (the compiler's baseline, SSE2 on x86-64), AVX2 + FMA (8 pixels per
// instruction) and AVX-512 (16). Each is its own translation unit compiled with its own flags
// (src/dic/CMakeLists.txt), so one library holds every kernel the compiler can build, and the
// first call picks the best one the CPU supports (__builtin_cpu_supports). The environment
// variable IMPACTDIC_DIC_KERNEL=scalar|avx2|avx512 forces one (a kernel the library lacks or the
// CPU cannot run is an Error naming it).
//
// The kernel units see only this header and <immintrin.h>: plain data and raw pointers, no
// inline function of a library header (std::, cv::), whose out-of-line copy, compiled with the
// kernel's instructions, the linker could otherwise pick for the whole program.
#ifndef IMPACTDIC_SRC_DIC_ICGN_KERNELS_H_
#define IMPACTDIC_SRC_DIC_ICGN_KERNELS_H_

#include <cstddef>

namespace impactdic::internal {

enum class DicKernel { kScalar, kAvx2, kAvx512 };

// The sums of one IC-GN pass over a subset (icgn.cc, the expansion at its top).
struct PassSums {
  double sg = 0, sgg = 0, sfg = 0;
  double a[2][3][3] = {};  // sum g' grad_a xi^p eta^q, a = x/y, p + q <= 2.
};

// One subset for an IC-GN pass.
struct PassInput {
  int half = 0;  // The subset is (2 half + 1)^2 pixels.
  // The reference subset's top-left pixel in the intensity and gradient images (CV_32F).
  const float *f = nullptr, *gx = nullptr, *gy = nullptr;
  std::ptrdiff_t ref_stride = 0;  // Floats per row of f, gx and gy.
  float f_mean = 0;               // SubsetRef::f_mean.
  // The deformed image's B-spline coefficients at the subset centre moved by the warp's integer
  // translation (iu, iv), and their floats per row.
  const float* centre = nullptr;
  std::ptrdiff_t stride = 0;
  // The warp's parameters (Params; nm monomials per component), and its translation less
  // (iu, iv) [px].
  const double* p = nullptr;
  int nm = 3;
  double u = 0, v = 0;
  // Where the pass writes g' = g - f_mean of every pixel (row-major, (2 half + 1)^2 floats): the
  // residuals of the uncertainty are taken from the pass that converged.
  float* g_out = nullptr;
};

// The reference moments of PrepareSubset over one subset: gg[k][p][q] = sum g_a g_b xi^p eta^q
// (k: xx, xy, yy; p + q <= pmax), gs[a][p][q] = sum g_a xi^p eta^q and gf[a][p][q] = sum g_a
// (f - mean) xi^p eta^q (p + q <= pmax / 2), ss = sum (f - mean)^2.
struct MomentSums {
  double mean = 0;
  int saturated = 0;  // Pixels <= 0 or >= the full scale.
  double gg[3][5][5] = {}, gs[2][3][3] = {}, gf[2][3][3] = {}, ss = 0;
};

struct MomentInput {
  int half = 0;
  const float *f = nullptr, *gx = nullptr, *gy = nullptr;  // The subset's top-left pixel.
  std::ptrdiff_t stride = 0;
  double full_scale = 255;
  int pmax = 2;  // 2 (affine) or 4 (quadratic).
};

// Half-width [px] of the lag window over which the residuals' spatial covariance is estimated.
constexpr int kResidualLagPx = 2;
// Float lanes of the uncertainty's sums (one AVX-512 register; the per-lane sums are added up in a
// fixed order, so every kernel sums in the same order).
constexpr int kResidualLanes = 16;

// The per-pixel arrays of the uncertainty (residuals r, influences au and av) in a padded layout:
// pixel (i, j) of the subset at lead + j * stride + i, stride = 2 half + 1 + kResidualLagPx, the
// other cells zero (the last kResidualLagPx of each row, lead cells before the subset and enough
// after it), so a lag d = (dx, dy) with |dx|, dy <= kResidualLagPx is one dot product of the whole
// array with itself moved by dy stride + dx: a pixel whose partner lies outside the subset meets a
// zero. Sums run over `length` cells from `lead` (a multiple of kResidualLanes covering the
// subset); the array holds lead + length + 2 stride + kResidualLanes cells at least.
struct ResidualInput {
  int half = 0;
  // The reference subset's top-left pixel in f, gx and gy, their floats per row and the subset's
  // mean intensity (SubsetRef::f_mean).
  const float *f = nullptr, *gx = nullptr, *gy = nullptr;
  std::ptrdiff_t ref_stride = 0;
  float f_mean = 0;
  // The converged pass's g' = g - f_mean (PassInput::g_out), their mean and f_norm / g_norm: the
  // residuals are r = (f - f_mean) - ratio (g' - g'_mean).
  const float* g = nullptr;
  float g_mean = 0, ratio = 0;
  // The pass's increment dp as J dp along each row: (c0 + xi (c1 + xi c2)) gx + (c3 + xi (c4 +
  // xi c5)) gy with step[6 j .. 6 j + 5]; added to the residuals, it takes them to the converged
  // warp to first order (the least-squares residuals of the pass).
  const float* step = nullptr;
  int stride = 0, lead = 0, length = 0;
  // 1 at the cells whose central differences in x (resp. y) lie inside the subset (columns
  // 1 .. size - 2, resp. rows 1 .. size - 2), else 0; same layout.
  const float *x_inside = nullptr, *y_inside = nullptr;
};

// One kernel: the passes of IC-GN in one instruction set. taps: 4 (bicubic) or 6 (biquintic);
// quad: the quadratic shape function.
struct IcgnKernel {
  DicKernel kind = DicKernel::kScalar;
  // One IC-GN pass (accumulate[taps == 6][quad]).
  void (*accumulate[2][2])(const PassInput& in, PassSums* out) = {};
  void (*moments)(const MomentInput& in, MomentSums* out) = nullptr;
  // The residuals r = (f - f_mean) - ratio (g' - g'_mean) + J dp into r (padded layout) and the
  // sums of the squares of their central differences 2 dr/dx, 2 dr/dy over the subset into noise
  // (icgn.cc, GradientNoise).
  void (*residuals)(const ResidualInput& in, float* r, double noise[2]) = nullptr;
  // The influences a_u, a_v of each pixel (au, av, padded layout): along row j,
  // a = (c0 + xi (c1 + xi c2)) gx + (c3 + xi (c4 + xi c5)) gy with coef[12 j .. 12 j + 5] for u
  // and coef[12 j + 6 .. 12 j + 11] for v; then sum_d rho(d) A(d) over the lags d with |dx|,
  // |dy| <= kResidualLagPx for u and v (icgn.cc, CorrelatedResidualSigma) into sums.
  void (*correlated_sums)(const ResidualInput& in, const float* r, const float* coef, float* au,
                          float* av, double sums[2]) = nullptr;
};

// The kernel of each unit (icgn_kernel_<name>.cc; icgn_kernels.cc refers only to those the
// compiler built).
namespace scalar {
const IcgnKernel* Kernel();
}
namespace avx2 {
const IcgnKernel* Kernel();
}
namespace avx512 {
const IcgnKernel* Kernel();
}

// "scalar", "avx2", "avx512".
const char* ToString(DicKernel kernel);
// Whether the library holds the kernel and the CPU can run it.
bool DicKernelAvailable(DicKernel kernel);
// The kernel in use: IMPACTDIC_DIC_KERNEL if set (Error if it names no kernel, or one that is
// not available), else the best available. Chosen on the first call.
const IcgnKernel& ActiveIcgnKernel();

// Tests only: runs IC-GN with `kernel` (which must be available) while the object lives.
class ScopedIcgnKernelForTesting {
 public:
  explicit ScopedIcgnKernelForTesting(DicKernel kernel);
  ~ScopedIcgnKernelForTesting();
  ScopedIcgnKernelForTesting(const ScopedIcgnKernelForTesting&) = delete;
  ScopedIcgnKernelForTesting& operator=(const ScopedIcgnKernelForTesting&) = delete;

 private:
  const IcgnKernel* previous_;
};

}  // namespace impactdic::internal

#endif  // IMPACTDIC_SRC_DIC_ICGN_KERNELS_H_
