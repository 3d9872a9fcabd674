// The IC-GN kernels (src/dic/icgn_kernels.h) give the same correlation. Every kernel
// this machine runs correlates the same synthetic pair (speckle under a known subpixel translation
// with a small strain and rotation, noise) for both interpolators and both shape functions; each
// kernel's displacements, uncertainties and outcomes are compared with the scalar kernel's.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "../../src/dic/icgn_kernels.h"
#include "dic_test_util.h"
#include "impactdic/core/error.h"
#include "impactdic/dic/correlator.h"
#include "impactdic/dic/options.h"
#include "impactdic/synth/fields.h"

namespace impactdic {
namespace {

using internal::DicKernel;

// The kernels sum the same terms in other orders and in float lanes (FMA, 8 or 16 lanes), so they
// agree to the float rounding of the per-pass sums, not bit for bit. Measured on this pair, the
// largest differences from the scalar kernel over the four interpolator x shape cases
// (2026-11-28, AVX2 and AVX-512): displacement 2.8e-6 px (quadratic; affine 5.7e-7), sigma
// 6.6e-4 relative (the residuals' lag sums take differences of nearly equal numbers). The bounds
// are ~7x those, and far below a displacement's noise here (~0.005 px): the kernels are
// exchangeable.
constexpr double kMaxDisplacementDiffPx = 2e-5;
constexpr double kMaxSigmaRelDiff = 5e-3;
// Subsets whose outcome may differ between kernels: a subset on the edge of a threshold (ZNCC,
// uncertainty, iterations) can fall either side; none did in the measurement.
constexpr int kMaxOutcomeChanges = 1;

// The pair: speckle moved by a subpixel translation, 0.2 % strain and 0.1 degree rotation.
struct Pair {
  cv::Mat ref, def;
};
Pair MakePair() {
  testing::Scene scene(160, 160, /*noise_sigma=*/1.0, /*seed=*/7, /*supersampling=*/2);
  const DisplacementField field = Affine(0.37, -0.61, 0.002, -0.0017, 0.0017, -0.001, 80, 80);
  return {scene.Render(ZeroField(), 11), scene.Render(field, 12)};
}

FrameResult Correlate(const Pair& pair, Interpolation interpolation, ShapeFunction shape) {
  DicOptions options;
  options.grid.subset_size = 21;
  options.grid.step = 10;
  options.icgn.interpolation = interpolation;
  options.icgn.shape = shape;
  DicResult result = CorrelateSequence({pair.ref, pair.def}, options);
  return result.frames.at(0);
}

TEST(DicKernels, EveryAvailableKernelGivesTheScalarKernelsCorrelation) {
  const Pair pair = MakePair();
  std::vector<DicKernel> others;
  for (DicKernel k : {DicKernel::kAvx2, DicKernel::kAvx512}) {
    if (internal::DicKernelAvailable(k)) others.push_back(k);
  }
  if (others.empty()) GTEST_SKIP() << "only the scalar kernel is available here";
  for (Interpolation interpolation : {Interpolation::kBicubic, Interpolation::kBiquintic}) {
    for (ShapeFunction shape : {ShapeFunction::kAffine, ShapeFunction::kQuadratic}) {
      FrameResult scalar;
      {
        internal::ScopedIcgnKernelForTesting use(DicKernel::kScalar);
        scalar = Correlate(pair, interpolation, shape);
      }
      for (DicKernel kernel : others) {
        internal::ScopedIcgnKernelForTesting use(kernel);
        const FrameResult other = Correlate(pair, interpolation, shape);
        const std::string what = std::string(internal::ToString(kernel)) + " " +
                                 ToString(interpolation) + " " + ToString(shape);
        ASSERT_EQ(other.status.size(), scalar.status.size()) << what;
        double max_du = 0, max_sigma = 0;
        int changed = 0, converged = 0;
        for (std::size_t i = 0; i < scalar.status.size(); ++i) {
          if (other.status[i] != scalar.status[i]) {
            ++changed;
            continue;
          }
          if (scalar.status[i] != SubsetStatus::kConverged) continue;
          ++converged;
          max_du = std::max({max_du, std::abs(other.u_px[i] - scalar.u_px[i]),
                             std::abs(other.v_px[i] - scalar.v_px[i])});
          max_sigma =
              std::max(max_sigma, std::abs(double(other.sigma_px[i]) / scalar.sigma_px[i] - 1));
        }
        std::printf("%s: %d converged, %d outcomes changed, max |du| %.3g px, sigma %.3g\n",
                    what.c_str(), converged, changed, max_du, max_sigma);
        EXPECT_GT(converged, 150) << what;
        EXPECT_LE(changed, kMaxOutcomeChanges) << what;
        EXPECT_LE(max_du, kMaxDisplacementDiffPx) << what;
        EXPECT_LE(max_sigma, kMaxSigmaRelDiff) << what;
      }
    }
  }
}

TEST(DicKernels, TheScalarKernelIsAlwaysAvailable) {
  EXPECT_TRUE(internal::DicKernelAvailable(DicKernel::kScalar));
}

}  // namespace
}  // namespace impactdic
