// Accuracy of the correlator on pairs of synthetic speckle images with known fields.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "dic_test_util.h"
#include "impactdic/core/error.h"
#include "impactdic/dic/bspline.h"
#include "impactdic/dic/correlator.h"
#include "impactdic/dic/options.h"
#include "impactdic/dic/reference_update.h"
#include "impactdic/synth/fields.h"
#include "impactdic/synth/speckle.h"

namespace impactdic {
namespace {

using testing::Errors;
using testing::ErrorStats;
using testing::Scene;

DicResult CorrelatePair(const cv::Mat& ref, const cv::Mat& def, const DicOptions& options) {
  return CorrelateSequence({ref, def}, options);
}

// The Cramer-Rao-type noise limit of a subset displacement with noise sigma in both images:
// sd(u) = sqrt(2) sigma / sqrt(sum over the subset of (dI/dx)^2) (and dI/dy for v), averaged as
// variances over the subsets. Gradients from the noise-free reference.
void NoiseLimit(const cv::Mat& clean, const std::vector<cv::Point2d>& centres, int half,
                double sigma, double* limit_u, double* limit_v) {
  BsplineImage spline;
  spline.Build(clean, Interpolation::kBicubic);
  cv::Mat gx, gy;
  spline.NodeGradients(&gx, &gy);
  double vu = 0, vv = 0;
  for (const auto& c : centres) {
    double sx = 0, sy = 0;
    for (int r = -half; r <= half; ++r) {
      for (int k = -half; k <= half; ++k) {
        const float a = gx.at<float>(static_cast<int>(c.y) + r, static_cast<int>(c.x) + k);
        const float b = gy.at<float>(static_cast<int>(c.y) + r, static_cast<int>(c.x) + k);
        sx += a * a;
        sy += b * b;
      }
    }
    vu += 2 * sigma * sigma / sx / centres.size();
    vv += 2 * sigma * sigma / sy / centres.size();
  }
  *limit_u = std::sqrt(vu);
  *limit_v = std::sqrt(vv);
}

TEST(Icgn, SubpixelTranslationsAreUnbiasedAtTheNoiseLimit) {
  const double sigma = 2;
  const int size = 400;
  Scene scene(size, size, sigma, /*seed=*/1, /*supersampling=*/2);
  const cv::Mat ref = scene.Render(ZeroField(), 100);
  RenderOptions clean_options = scene.render;
  clean_options.noise_sigma = 0;
  const cv::Mat clean = RenderImage(scene.pattern, size, size, ZeroField(), clean_options);
  DicOptions options;
  options.grid.step = 25;  // Non-overlapping subsets: independent errors.
  std::vector<cv::Mat> deformed_x, deformed_y;
  for (int k = 0; k <= 10; ++k) {
    deformed_x.push_back(scene.Render(Translation(0.1 * k, 0), 200 + k));
    deformed_y.push_back(scene.Render(Translation(0, 0.1 * k), 300 + k));
  }
  double limit_u = 0, limit_v = 0;
  for (Interpolation interp : {Interpolation::kBicubic, Interpolation::kBiquintic}) {
    options.icgn.interpolation = interp;
    for (int k = 0; k <= 10; ++k) {
      for (int axis = 0; axis < 2; ++axis) {
        const double shift = 0.1 * k;
        const DisplacementField truth = axis == 0 ? Translation(shift, 0) : Translation(0, shift);
        const DicResult r = CorrelatePair(ref, axis == 0 ? deformed_x[k] : deformed_y[k], options);
        if (limit_u == 0) {
          NoiseLimit(clean, r.positions, options.grid.subset_size / 2, sigma, &limit_u, &limit_v);
          // Sanity of the limit itself: a few thousandths of a pixel for this speckle.
          EXPECT_GT(limit_u, 1e-3);
          EXPECT_LT(limit_u, 2e-2);
        }
        const ErrorStats e = Errors(r.positions, r.frames[0], truth);
        if (std::getenv("DIC_TEST_VERBOSE"))
          std::printf(
              "%s axis %d shift %.1f: bias %.5f %.5f sd %.5f %.5f limit %.5f %.5f it %.2f\n",
              ToString(interp), axis, shift, e.bias_u, e.bias_v, e.sd_u, e.sd_v, limit_u, limit_v,
              r.summary.mean_iterations);
        SCOPED_TRACE(std::string(ToString(interp)) + (axis ? " y " : " x ") +
                     std::to_string(shift));
        EXPECT_EQ(e.valid, static_cast<int>(r.positions.size()));
        // The bounds: |bias| <= 0.002 px; sd within 1.3x of the noise limit (it may be a
        // little below: interpolating the deformed image smooths its noise).
        EXPECT_LE(std::abs(e.bias_u), 0.002);
        EXPECT_LE(std::abs(e.bias_v), 0.002);
        EXPECT_LE(e.sd_u, 1.3 * limit_u);
        EXPECT_LE(e.sd_v, 1.3 * limit_v);
        EXPECT_GE(e.sd_u, limit_u / 1.3);
        EXPECT_GE(e.sd_v, limit_v / 1.3);
        EXPECT_GT(r.summary.mean_iterations, 0);
      }
    }
  }
}

TEST(Icgn, AffineRecoversUniformStrainAndRotation) {
  Scene scene(300, 300, /*noise_sigma=*/2);
  const cv::Mat ref = scene.Render(ZeroField(), 1);
  const DisplacementField fields[] = {Affine(0.2, -0.3, 0.01, 0, 0, 0.01, 150, 150),
                                      Rotation(2 * M_PI / 180, 150, 150)};
  DicOptions options;
  int k = 0;
  for (const auto& field : fields) {
    const DicResult r = CorrelatePair(ref, scene.Render(field, 10 + k++), options);
    const ErrorStats e = Errors(r.positions, r.frames[0], field);
    // Rotation moves the corner subsets out of the image; the others must all be valid.
    EXPECT_GE(e.valid, 0.9 * r.positions.size());
    EXPECT_LE(e.rms, 0.01);
  }
}

TEST(Icgn, ZnssdIgnoresABrightnessAndContrastChange) {
  // The deformed image 30 % darker with an offset (I' = 0.7 I + 0.1, e.g. the lighting changed):
  // ZNSSD is invariant to it, so the shift is found as well as without the change.
  Scene scene(300, 300, /*noise_sigma=*/2);
  const cv::Mat ref = scene.Render(ZeroField(), 1);
  const DisplacementField shift = Translation(0.35, -0.45);
  DicOptions options;
  const DicResult same = CorrelatePair(ref, scene.Render(shift, 2), options);
  scene.render.gain = 0.7;
  scene.render.offset = 0.1;
  const DicResult changed = CorrelatePair(ref, scene.Render(shift, 2), options);
  const ErrorStats a = Errors(same.positions, same.frames[0], shift);
  const ErrorStats b = Errors(changed.positions, changed.frames[0], shift);
  EXPECT_EQ(b.valid, static_cast<int>(changed.positions.size()));
  EXPECT_LE(std::abs(b.bias_u), 0.002);
  EXPECT_LE(std::abs(b.bias_v), 0.002);
  // The same noise on a 0.7x signal: the error grows by at most ~1/0.7.
  EXPECT_LE(b.rms, a.rms / 0.7 * 1.1) << a.rms;
}

TEST(Icgn, FloatImagesPassTheSameSubsetsAsTheir8BitOriginal) {
  // Float data has no saturation level: scaled to 0..1 or kept at 0..255 it must be correlated
  // like the 8-bit images (before, every subset of a float pair was `singular_hessian`).
  Scene scene(200, 200, /*noise_sigma=*/2);
  const cv::Mat ref = scene.Render(ZeroField(), 1);
  const DisplacementField shift = Translation(0.35, -0.45);
  const cv::Mat def = scene.Render(shift, 2);
  DicOptions options;
  const DicResult bytes = CorrelatePair(ref, def, options);
  const ErrorStats eight = Errors(bytes.positions, bytes.frames[0], shift);
  ASSERT_EQ(eight.valid, static_cast<int>(bytes.positions.size()));
  for (const double scale : {1.0 / 255, 1.0}) {
    cv::Mat ref_f, def_f;
    ref.convertTo(ref_f, CV_32F, scale);
    def.convertTo(def_f, CV_32F, scale);
    const DicResult floats = CorrelatePair(ref_f, def_f, options);
    const ErrorStats f = Errors(floats.positions, floats.frames[0], shift);
    EXPECT_EQ(f.valid, eight.valid) << "scale " << scale;
    EXPECT_NEAR(f.rms, eight.rms, 1e-4) << "scale " << scale;
    EXPECT_LE(f.rms, 0.02) << "scale " << scale;
  }
}

TEST(Icgn, QuadraticShapeBeatsAffineOnAQuadraticField) {
  Scene scene(300, 300, /*noise_sigma=*/1);
  const cv::Mat ref = scene.Render(ZeroField(), 1);
  const DisplacementField field = Quadratic(1e-3, 6e-4, 1.2e-3, 150, 150);
  const cv::Mat def = scene.Render(field, 2);
  DicOptions options;
  options.grid.roi = cv::Rect(40, 40, 220, 220);
  const ErrorStats affine = Errors(CorrelatePair(ref, def, options).positions,
                                   CorrelatePair(ref, def, options).frames[0], field);
  options.icgn.shape = ShapeFunction::kQuadratic;
  const DicResult q = CorrelatePair(ref, def, options);
  const ErrorStats quadratic = Errors(q.positions, q.frames[0], field);
  EXPECT_EQ(quadratic.valid, static_cast<int>(q.positions.size()));
  // Affine subsets see the curvature as a bias of about a * S^2 / 12 ~ 0.05 px; the quadratic
  // shape function has none.
  EXPECT_GT(affine.rms, 0.02);
  EXPECT_LT(quadratic.rms, 0.01);
  EXPECT_LT(quadratic.rms, 0.3 * affine.rms);
}

TEST(Icgn, ExtremeImagesAreFlaggedNotGarbage) {
  Scene scene(300, 240, /*noise_sigma=*/2);
  // A translation larger than half a subset (17 px > 12.5 px), by whole pixels so that patches
  // painted on the material can be placed exactly in both images.
  const cv::Point shift(17, -13);
  const DisplacementField field = Translation(shift.x, shift.y);
  cv::Mat ref = scene.Render(ZeroField(), 1);
  cv::Mat def = scene.Render(field, 2);
  // Patches on the material (they move with it): featureless (flat, noise-free), very low
  // contrast (the speckle squashed to 1/50 of its amplitude) and saturated.
  const cv::Rect flat(20, 40, 60, 60), dim(110, 40, 60, 60), bright(200, 40, 60, 60);
  for (cv::Mat* image : {&ref, &def}) {
    const cv::Point d = image == &def ? shift : cv::Point(0, 0);
    (*image)(flat + d).setTo(128);
    cv::Mat low;
    (*image)(dim + d).convertTo(low, CV_8U, 0.02, 120);
    low.copyTo((*image)(dim + d));
    (*image)(bright + d).setTo(255);
  }
  DicOptions options;
  const DicResult r = CorrelatePair(ref, def, options);
  const FrameResult& f = r.frames[0];
  const int h = options.grid.subset_size / 2;
  int flagged[3] = {0, 0, 0};
  for (std::size_t i = 0; i < r.positions.size(); ++i) {
    const cv::Rect box(static_cast<int>(r.positions[i].x) - h,
                       static_cast<int>(r.positions[i].y) - h, 2 * h + 1, 2 * h + 1);
    const cv::Rect grown(box.x - 8, box.y - 8, box.width + 16, box.height + 16);
    const bool valid = f.status[i] == SubsetStatus::kConverged;
    // Failed subsets are NaN, never garbage.
    EXPECT_EQ(valid, !std::isnan(f.u_px[i]));
    EXPECT_EQ(valid, !std::isnan(f.v_px[i]));
    // Subsets well inside a patch (8 px clear of its edge: the spline's prefilter spreads the
    // neighbouring speckle into it by 0.27^d) are flagged with the patch's reason.
    if ((grown & flat) == grown) {
      EXPECT_EQ(f.status[i], SubsetStatus::kSingularHessian) << i;
      ++flagged[0];
    } else if ((box & dim) == box) {
      EXPECT_EQ(f.status[i], SubsetStatus::kLowContrast) << i;
      ++flagged[1];
    } else if ((box & bright) == box) {
      EXPECT_EQ(f.status[i], SubsetStatus::kSaturated) << i;
      ++flagged[2];
    }
    if (valid) {
      // Whatever converged is right: within 0.05 px away from the patches; subsets partly on a
      // patch have fewer features and a larger (reported, bounded) uncertainty: within 4 sigma.
      const bool touches =
          (box & flat).area() > 0 || (box & dim).area() > 0 || (box & bright).area() > 0;
      const double tol = touches ? 4 * f.sigma_px[i] : 0.05;
      EXPECT_LE(f.sigma_px[i], options.icgn.max_uncertainty_px);
      EXPECT_NEAR(f.u_px[i], shift.x, tol) << i << " zncc " << f.zncc[i];
      EXPECT_NEAR(f.v_px[i], shift.y, tol) << i << " zncc " << f.zncc[i];
    }
  }
  for (int k = 0; k < 3; ++k) EXPECT_GT(flagged[k], 0);
  // The subsets that stay in the image and outside the patches are found despite the large
  // displacement (by the integer search at the seeds and propagation).
  EXPECT_GT(r.summary.valid_fraction, 0.5);
  // Status names round-trip (for CSV/HDF5).
  for (int s = 0; s < kSubsetStatusCount; ++s) {
    const auto status = static_cast<SubsetStatus>(s);
    EXPECT_EQ(SubsetStatusFromString(ToString(status)), status);
  }
}

TEST(Icgn, OptionsCheckNamesTheBrokenField) {
  DicOptions o;
  EXPECT_NO_THROW(o.Check());
  auto expect_names = [](DicOptions bad, const std::string& name) {
    try {
      bad.Check();
      ADD_FAILURE() << name;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  };
  DicOptions b = o;
  b.grid.subset_size = 24;
  expect_names(b, "subset_size");
  b = o;
  b.grid.step = 0;
  expect_names(b, "step");
  b = o;
  b.icgn.max_iterations = 0;
  expect_names(b, "max_iterations");
  b = o;
  b.icgn.convergence_px = 0;
  expect_names(b, "convergence_px");
  b = o;
  b.update.policy = "every:0";
  expect_names(b, "update.policy");
  b = o;
  b.init.search_radius_px = 0;
  expect_names(b, "search_radius_px");
  EXPECT_EQ(ReferenceUpdatePolicyFromString("every:7")->Name(), "every:7");
  EXPECT_THROW(ReferenceUpdatePolicyFromString("every:0"), Error);
  EXPECT_THROW(ReferenceUpdatePolicyFromString("sometimes"), Error);
  EXPECT_EQ(ShapeFunctionFromString("quadratic"), ShapeFunction::kQuadratic);
}

}  // namespace
}  // namespace impactdic
