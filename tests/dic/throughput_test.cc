// The throughput changes for long recordings keep the numbers: node gradients over a rectangle, the
// reference images' patch layout and the reused coefficient buffer give the values of the
// whole-image computation bit for bit, and a sparse grid on a sequence of known motion is tracked
// as before.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <opencv2/core.hpp>
#include <vector>

#include "../../src/dic/icgn.h"
#include "dic_test_util.h"
#include "impactdic/dic/bspline.h"
#include "impactdic/dic/correlator.h"
#include "impactdic/synth/fields.h"

namespace impactdic {
namespace {

// Bit-for-bit equality of two CV_32F images of the same size.
bool SameBits(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size() || a.type() != b.type()) return false;
  for (int r = 0; r < a.rows; ++r) {
    if (std::memcmp(a.ptr(r), b.ptr(r), a.cols * a.elemSize()) != 0) return false;
  }
  return true;
}

cv::Mat RandomImage(int width, int height, int seed) {
  cv::Mat image(height, width, CV_8U);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, 256);
  return image;
}

TEST(Throughput, NodeGradientsOverARectangleEqualTheWholeRegionsBitForBit) {
  const cv::Mat image = RandomImage(90, 70, 3);
  for (Interpolation kind : {Interpolation::kBicubic, Interpolation::kBiquintic}) {
    BsplineImage spline;
    spline.Build(image, kind, cv::Rect(14, 12, 50, 40), /*guard_px=*/6);
    const cv::Rect region = spline.region();
    cv::Mat gx, gy;
    spline.NodeGradients(&gx, &gy);
    // Inside, at each corner and edge of the region (mirrored taps), one pixel, the region.
    const std::vector<cv::Rect> rects = {cv::Rect(region.x + 20, region.y + 15, 25, 25),
                                         cv::Rect(region.x, region.y, 25, 25),
                                         cv::Rect(region.br().x - 25, region.br().y - 25, 25, 25),
                                         cv::Rect(region.x, region.y + 10, 3, 7),
                                         cv::Rect(region.br().x - 1, region.y + 5, 1, 1),
                                         region};
    for (const cv::Rect& rect : rects) {
      cv::Mat rx, ry;
      spline.NodeGradients(rect, &rx, &ry);
      const cv::Rect local = rect - region.tl();
      EXPECT_TRUE(SameBits(rx, gx(local))) << ToString(kind) << " " << rect;
      EXPECT_TRUE(SameBits(ry, gy(local))) << ToString(kind) << " " << rect;
    }
  }
}

TEST(Throughput, ARebuiltSplineEqualsAFreshOne) {
  // The second Build reuses the first's larger buffer (a view of it): same coefficients, values
  // and gradients as a spline built from scratch.
  const cv::Mat first = RandomImage(120, 100, 4), second = RandomImage(120, 100, 5);
  const cv::Rect region(30, 20, 40, 35);
  BsplineImage reused, fresh;
  reused.Build(first, Interpolation::kBicubic);
  reused.Build(second, Interpolation::kBicubic, region);
  fresh.Build(second, Interpolation::kBicubic, region);
  ASSERT_EQ(reused.region(), fresh.region());
  EXPECT_TRUE(SameBits(reused.coefficients(), fresh.coefficients()));
  cv::Mat ga, gb, ha, hb;
  reused.NodeGradients(&ga, &ha);
  fresh.NodeGradients(&gb, &hb);
  EXPECT_TRUE(SameBits(ga, gb) && SameBits(ha, hb));
  double va, vb, xa, xb, ya, yb;
  reused.ValueGradient(50.3, 40.8, &va, &xa, &ya);
  fresh.ValueGradient(50.3, 40.8, &vb, &xb, &yb);
  EXPECT_EQ(va, vb);
  EXPECT_EQ(xa, xb);
  EXPECT_EQ(ya, yb);
}

TEST(Throughput, PatchLayoutGivesTheRegionLayoutsResults) {
  testing::Scene scene(160, 140, /*noise_sigma=*/2, /*seed=*/7, /*supersampling=*/2);
  const cv::Mat ref = scene.Render(ZeroField(), 1);
  const cv::Mat def = scene.Render(Affine(0.4, -0.3, 0.002, 0, 0, -0.001, 80, 70), 2);
  IcgnOptions options;
  const internal::Shape shape = internal::MakeShape(ShapeFunction::kAffine, /*half=*/12);
  BsplineImage ref_spline, def_spline;
  ref_spline.Build(ref, options.interpolation);
  def_spline.Build(def, options.interpolation);
  internal::RefImages whole;
  whole.region = ref_spline.region();
  ref.convertTo(whole.f, CV_32F);
  ref_spline.NodeGradients(&whole.gx, &whole.gy);
  const std::vector<cv::Point> centres = {{40, 40}, {80, 70}, {115, 95}, {13, 13}};
  internal::RefImages patches;
  patches.region = whole.region;
  patches.patch_size = 25;
  patches.patch_cols = 3;
  patches.f.create(50, 75, CV_32F);
  patches.gx.create(50, 75, CV_32F);
  patches.gy.create(50, 75, CV_32F);
  internal::DeformedImage view{&def_spline, 0, 0, 160, 140};
  for (int k = 0; k < static_cast<int>(centres.size()); ++k) {
    internal::SubsetRef a, b;
    a.cx = b.cx = centres[k].x;
    a.cy = b.cy = centres[k].y;
    b.patch = k;
    const cv::Rect box(a.cx - 12, a.cy - 12, 25, 25);
    cv::Mat f = patches.f(patches.Patch(k)), gx = patches.gx(patches.Patch(k)),
            gy = patches.gy(patches.Patch(k));
    ref(box).convertTo(f, CV_32F);
    ref_spline.NodeGradients(box, &gx, &gy);
    std::vector<double> ha(36), hb(36);
    internal::PrepareSubset(shape, whole, options, &a, ha.data());
    internal::PrepareSubset(shape, patches, options, &b, hb.data());
    ASSERT_EQ(a.status, SubsetStatus::kConverged) << k;
    EXPECT_EQ(a.f_mean, b.f_mean);
    EXPECT_EQ(a.f_norm, b.f_norm);
    EXPECT_EQ(ha, hb);
    internal::Params p0{};
    p0[0] = 0.4;
    p0[3] = -0.3;
    const internal::IcgnResult ra =
        internal::RunIcgn(shape, whole, a, ha.data(), view, options, p0);
    const internal::IcgnResult rb =
        internal::RunIcgn(shape, patches, b, hb.data(), view, options, p0);
    EXPECT_EQ(ra.status, rb.status);
    EXPECT_EQ(ra.p, rb.p);
    EXPECT_EQ(ra.zncc, rb.zncc);
    EXPECT_EQ(ra.sigma_px, rb.sigma_px);
  }
}

TEST(Throughput, SparseGridFollowsAKnownMotionThroughReferenceUpdates) {
  // Subset 25, step 50 (most of the image is read by no subset), translation of (0.35, -0.2) px
  // and a stretch of 0.1 % per frame, `auto` updates. Noise sigma 2 grey levels: the error of one
  // subset is ~0.01 px per correlation, accumulated over the updates.
  testing::Scene scene(640, 480, /*noise_sigma=*/2, /*seed=*/11, /*supersampling=*/2);
  DicOptions options;
  options.grid.step = 50;
  std::vector<cv::Mat> images;
  std::vector<DisplacementField> truth;
  for (int k = 0; k < 5; ++k) {
    truth.push_back(Affine(0.35 * k, -0.2 * k, 0.001 * k, 0, 0, 0.001 * k, 320, 240));
    images.push_back(scene.Render(truth.back(), 40 + k));
  }
  const DicResult result = CorrelateSequence(images, options);
  ASSERT_EQ(result.frames.size(), 4u);
  for (int k = 1; k < 5; ++k) {
    const testing::ErrorStats e = testing::Errors(result.positions, result.frames[k - 1], truth[k]);
    EXPECT_GE(e.valid, static_cast<int>(0.95 * result.positions.size())) << "frame " << k;
    EXPECT_LT(e.rms, 0.03) << "frame " << k;
    EXPECT_LT(e.max_abs, 0.1) << "frame " << k;
  }
}

}  // namespace
}  // namespace impactdic
