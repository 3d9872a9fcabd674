// The IC-GN's region check covers every pixel a quadratic subset samples: a quadratic warp bends
// a pixel row into a parabola whose vertex can leave the valid region while the subset's corners
// and edge midpoints stay inside (the old check read past the image there and crashed now and
// then on `correlate --shape quadratic`).
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <vector>

#include "../../src/dic/icgn.h"
#include "dic_test_util.h"
#include "impactdic/dic/bspline.h"
#include "impactdic/dic/correlator.h"
#include "impactdic/synth/fields.h"

namespace impactdic {
namespace {

struct OneSubset {
  internal::Shape shape;
  BsplineImage ref_spline, def_spline;
  internal::RefImages ref;
  internal::SubsetRef subset;
  std::vector<double> hinv = std::vector<double>(144);
  IcgnOptions options;

  explicit OneSubset(ShapeFunction kind) : shape(internal::MakeShape(kind, /*half=*/12)) {
    testing::Scene scene(160, 140, /*noise_sigma=*/2, /*seed=*/7, /*supersampling=*/2);
    const cv::Mat f = scene.Render(ZeroField(), 1);
    ref_spline.Build(f, options.interpolation);
    def_spline.Build(scene.Render(ZeroField(), 2), options.interpolation);
    ref.region = ref_spline.region();
    f.convertTo(ref.f, CV_32F);
    ref_spline.NodeGradients(&ref.gx, &ref.gy);
    subset.cx = 80;
    subset.cy = 70;
    internal::PrepareSubset(shape, ref, options, &subset, hinv.data());
  }
};

TEST(IcgnBounds, AQuadraticRowWhoseVertexLeavesTheRegionIsOutOfImage) {
  OneSubset s(ShapeFunction::kQuadratic);
  ASSERT_EQ(s.subset.status, SubsetStatus::kConverged);
  // u = 0.1 xi^2: x = 80 + xi + 0.1 xi^2 is 82.4 and 106.4 at the row ends, 80 at the middle and
  // 77.5 at the vertex xi = -5. The valid region starts at x = 78.5: with the 1 px margin the
  // corners and edge midpoints are inside, the vertex is not.
  internal::Params p{};
  p[3] = 0.2;  // The coefficient of xi^2 / 2 in u.
  const internal::DeformedImage region{&s.def_spline, 78.5, 160, 0, 140};
  const internal::IcgnResult r =
      internal::RunIcgn(s.shape, s.ref, s.subset, s.hinv.data(), region, s.options, p);
  EXPECT_EQ(r.status, SubsetStatus::kOutOfImage);
  EXPECT_EQ(r.iterations, 1);
  // With the region's edge 1.1 px further out the first iteration's check passes (the next ones
  // undo the bend, and the straight subset's left end is outside this region).
  const internal::DeformedImage wider{&s.def_spline, 76.4, 160, 0, 140};
  EXPECT_GT(
      internal::RunIcgn(s.shape, s.ref, s.subset, s.hinv.data(), wider, s.options, p).iterations,
      1);
}

TEST(IcgnBounds, AnAffineSubsetIsCheckedAtItsCorners) {
  OneSubset s(ShapeFunction::kAffine);
  ASSERT_EQ(s.subset.status, SubsetStatus::kConverged);
  internal::Params p{};
  p[0] = 0.5;  // x from 68.5 to 92.5: its left corners need the region to start at 67.5 or less.
  const internal::DeformedImage tight{&s.def_spline, 67.6, 160, 0, 140};
  EXPECT_EQ(internal::RunIcgn(s.shape, s.ref, s.subset, s.hinv.data(), tight, s.options, p).status,
            SubsetStatus::kOutOfImage);
  // Room for the shifted corners and for the unshifted ones the iterations return to (67).
  const internal::DeformedImage loose{&s.def_spline, 66.9, 160, 0, 140};
  EXPECT_NE(internal::RunIcgn(s.shape, s.ref, s.subset, s.hinv.data(), loose, s.options, p).status,
            SubsetStatus::kOutOfImage);
}

}  // namespace
}  // namespace impactdic
