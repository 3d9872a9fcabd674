#include "impactdic/kinematics/kinematics.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "../core/expect_error.h"

namespace impactdic {
namespace {

// Quadratic motion: both stencils (interior and one-sided ends) are exact; tolerance is rounding.
TEST(Differences, ExactForQuadraticMotion) {
  const double h = 1 / 1600.0, a = 0.3, b = -2.0, c = 123.0;
  std::vector<double> f(20);
  for (std::size_t k = 0; k < f.size(); ++k) {
    const double t = static_cast<double>(k) * h;
    f[k] = a + b * t + c * t * t;
  }
  const std::vector<double> v = FirstDerivative(f, h), acc = SecondDerivative(f, h);
  for (std::size_t k = 0; k < f.size(); ++k) {
    const double t = static_cast<double>(k) * h;
    EXPECT_NEAR(v[k], b + 2 * c * t, 1e-9) << k;
    EXPECT_NEAR(acc[k], 2 * c, 1e-5) << k;  // Rounding: ~1e-16 / h^2 ~ 3e-10 relative to f.
  }
}

// Sinusoid: the interior error equals the exact truncation error w cos(wt) (sin(wh)/(wh) - 1),
// whose leading term is h^2/6 f'''; their ratio is 1 - (wh)^2/20 + O(h^4). At the start the
// one-sided stencil's error leads with -h^2/3 f''' (relative correction O(h^2) at t = 0, where
// f'''' = 0). Halving h quarters the error (second order).
TEST(Differences, SinusoidErrorMatchesTruncationTheory) {
  const double w = 2 * std::numbers::pi * 50;  // 50 Hz motion
  double max_err_prev = 0;
  for (double fps : {1600.0, 3200.0, 6400.0}) {
    const double h = 1 / fps;
    std::vector<double> f(200);
    for (std::size_t k = 0; k < f.size(); ++k) f[k] = std::sin(w * static_cast<double>(k) * h);
    const std::vector<double> v = FirstDerivative(f, h);
    const double x = w * h;
    double max_err = 0;
    for (std::size_t k = 1; k + 1 < f.size(); ++k) {
      const double t = static_cast<double>(k) * h;
      const double err = v[k] - w * std::cos(w * t);
      EXPECT_NEAR(err, w * std::cos(w * t) * (std::sin(x) / x - 1), 1e-9) << k;
      const double leading = h * h / 6 * (-w * w * w * std::cos(w * t));
      if (std::abs(std::cos(w * t)) > 0.3) {
        EXPECT_NEAR(err / leading, 1 - x * x / 20, x * x * x * x / 500 + 1e-6) << k;
      }
      max_err = std::max(max_err, std::abs(err));
    }
    const double end_err = v[0] - w;
    const double end_leading = -h * h / 3 * (-w * w * w);
    EXPECT_NEAR(end_err / end_leading, 1.0, x * x) << fps;
    if (max_err_prev > 0) {
      EXPECT_NEAR(max_err_prev / max_err, 4.0, 0.05) << fps;
    }
    max_err_prev = max_err;
  }
}

// Two subsets; subset 1 invalid at frame 5. Only the derivatives that use that sample are NaN;
// subset 0 and the averages over subsets are not contaminated.
TEST(Kinematics, NanAwareDerivativesAndAverages) {
  CorrelationSeries dic;
  dic.frames = 10;
  dic.subsets = 2;
  dic.x_px = {100, 110};
  dic.y_px = {200, 200};
  const double fps = 1000, scale = 0.5;
  for (std::size_t k = 0; k < dic.frames; ++k) {
    const double t = static_cast<double>(k) / fps;
    for (int i = 0; i < 2; ++i) {
      dic.u_px.push_back(10 * t);
      dic.v_px.push_back(1000 * t * t + (i ? 4 * t : 0.0));  // px; y down = downward motion
    }
  }
  dic.valid.assign(dic.frames * dic.subsets, 1);
  dic.valid[5 * 2 + 1] = 0;
  dic.u_px[7 * 2 + 1] = std::nan("");  // Also a NaN value without a flag.
  PanelMapping map;
  map.mm_per_px = scale;
  KinematicsOptions opt;
  opt.fps = fps;
  const KinematicsResult r = ComputeKinematics(dic, map, opt);
  EXPECT_EQ(r.summary.invalid_samples, 2u);
  EXPECT_DOUBLE_EQ(r.x_mm[1], 55);
  for (std::size_t k = 0; k < dic.frames; ++k) {
    const double t = static_cast<double>(k) / fps;
    // Subset 0: exact, every frame.
    EXPECT_NEAR(r.vel_y_mm_s[k * 2], scale * 2000 * t, 1e-9) << k;
    EXPECT_NEAR(r.acc_y_mm_s2[k * 2], scale * 2000, 1e-6) << k;
    EXPECT_NEAR(r.vel_x_mm_s[k * 2], scale * 10, 1e-9) << k;
    // Subset 1 (invalid at 5 and 7): velocity uses k-1 and k+1, acceleration k-1, k, k+1.
    const bool v_nan = k == 4 || k == 6 || k == 8 || k == 9;  // 9: one-sided end uses 7
    const bool a_nan = k >= 4;                                // the end stencil at 9 uses 6..9
    EXPECT_EQ(std::isnan(r.vel_y_mm_s[k * 2 + 1]), v_nan) << k;
    EXPECT_EQ(std::isnan(r.acc_y_mm_s2[k * 2 + 1]), a_nan) << k;
    if (!v_nan) {
      EXPECT_NEAR(r.vel_y_mm_s[k * 2 + 1], scale * (2000 * t + 4), 1e-9) << k;
    }
    // Mean over both subsets skips the NaN one.
    std::size_t count = 0;
    const double mean = MeanOverSubsets(r.vel_y_mm_s, 2, k, {0, 1}, &count);
    EXPECT_EQ(count, v_nan ? 1u : 2u);
    EXPECT_NEAR(mean, scale * (2000 * t + (v_nan ? 0 : 2)), 1e-9) << k;
  }
}

// Samples above the sigma limit are left out (invalid; their u and v kept, as the run's kinematics
// borrow the /dic rows) before the derivatives, which are NaN there; the mean over the grid then
// skips them; samples within the limit, and those already invalid, are untouched.
TEST(Kinematics, UncertainSamplesAreLeftOutAboveTheSigmaLimit) {
  CorrelationSeries dic;
  dic.frames = 4;
  dic.subsets = 2;
  dic.x_px = {0, 10};
  dic.y_px = {0, 0};
  dic.u_px = {0, 0, 1, 1, 2, 2, 3, 3};
  dic.v_px = {0, 0, 0, 0, 0, 0, 0, 0};
  dic.valid = {1, 1, 1, 1, 1, 0, 1, 1};
  dic.sigma_u_px = {0, 0, 0.01f, 0.01f, 0.01f, NAN, 0.02f, 0.02f};
  dic.sigma_v_px = {0, 0, 0.01f, 0.04f, 0.01f, NAN, 0.02f, 0.02f};
  EXPECT_EQ(ExcludeUncertainSamples(0.03, "momentum.max_sigma_px", &dic), 1u);
  EXPECT_EQ(dic.valid, (std::vector<std::uint8_t>{1, 1, 1, 0, 1, 0, 1, 1}));
  EXPECT_EQ(dic.u_px, (std::vector<double>{0, 0, 1, 1, 2, 2, 3, 3}));
  EXPECT_EQ(dic.v_px, std::vector<double>(8, 0.0));
  PanelMapping map;
  map.mm_per_px = 1;
  KinematicsOptions opt;
  opt.fps = 1;
  const KinematicsResult r = ComputeKinematics(dic, map, opt);
  std::size_t count = 0;
  EXPECT_NEAR(MeanOverSubsets(r.disp_x_mm, 2, 1, {0, 1}, &count), 1, 1e-12);
  EXPECT_EQ(count, 1u);
  EXPECT_TRUE(std::isnan(r.disp_x_mm[3]) && std::isnan(r.vel_x_mm_s[1]) &&
              std::isnan(r.acc_x_mm_s2[3]));
  EXPECT_TRUE(std::isfinite(r.disp_x_mm[2]));
  ExpectErrorContaining([&] { ExcludeUncertainSamples(0, "momentum.max_sigma_px", &dic); },
                        "momentum.max_sigma_px");
  dic.sigma_u_px.clear();
  dic.sigma_v_px.clear();
  ExpectErrorContaining([&] { ExcludeUncertainSamples(0.03, "momentum.max_sigma_px", &dic); },
                        "no sigma_u_px");
}

// The default rule (momentum.max_sigma_ratio): per frame, samples whose sigma exceeds ratio x the
// frame's median sigma are left out; the reference frame (sigma 0) and frames with fewer than 3
// valid samples are left alone.
TEST(Kinematics, ExcludesSamplesFarAboveTheFramesMedianSigma) {
  CorrelationSeries dic;
  dic.frames = 4;
  dic.subsets = 5;
  dic.x_px = {0, 10, 20, 30, 40};
  dic.y_px = {0, 0, 0, 0, 0};
  dic.u_px.assign(20, 1.0);
  dic.v_px.assign(20, 2.0);
  dic.valid.assign(20, 1);
  // Frame 0: the reference; frame 1: median 0.03, samples at 0.3 and 0.15 (> 4 x 0.03); frame 2:
  // all poor alike (median 0.2, none left out), one failed; frame 3: one failed, 2 valid left.
  dic.sigma_u_px = {0,    0,    0,    0,    0,   0.02f, 0.02f, 0.3f, 0.01f, 0.02f,
                    0.2f, 0.2f, 0.3f, 0.2f, NAN, 0.01f, 0.5f,  NAN,  NAN,   NAN};
  dic.sigma_v_px = {0,    0,    0,    0,    0,   0.02f, 0.03f, 0.01f, 0.02f, 0.15f,
                    0.2f, 0.2f, 0.2f, 0.2f, NAN, 0.01f, 0.01f, NAN,   NAN,   NAN};
  for (const std::size_t failed : {14, 17, 18, 19}) {
    dic.valid[failed] = 0;
    dic.u_px[failed] = dic.v_px[failed] = NAN;
  }
  EXPECT_EQ(ExcludeSamplesAboveMedianSigma(4, "momentum.max_sigma_ratio", &dic), 2u);
  EXPECT_EQ(dic.valid, (std::vector<std::uint8_t>{1, 1, 1, 1, 1, 1, 1, 0, 1, 0,
                                                  1, 1, 1, 1, 0, 1, 1, 0, 0, 0}));
  EXPECT_EQ(dic.u_px[7], 1.0);  // Left out by `valid`; the displacements are kept.
  EXPECT_EQ(dic.v_px[9], 2.0);
  ExpectErrorContaining(
      [&] { ExcludeSamplesAboveMedianSigma(1, "momentum.max_sigma_ratio", &dic); },
      "momentum.max_sigma_ratio");
}

// A homography that is a scale + translation gives the same velocities as the scale.
TEST(Kinematics, HomographyMatchesScale) {
  CorrelationSeries dic;
  dic.frames = 6;
  dic.subsets = 1;
  dic.x_px = {50};
  dic.y_px = {60};
  for (std::size_t k = 0; k < 6; ++k) {
    dic.u_px.push_back(0.3 * static_cast<double>(k));
    dic.v_px.push_back(0.1 * static_cast<double>(k * k));
  }
  PanelMapping scale;
  scale.mm_per_px = 0.2;
  PanelMapping homog;
  homog.homography = std::array<double, 9>{0.4, 0, 7, 0, 0.4, -3, 0, 0, 2};
  const KinematicsResult a = ComputeKinematics(dic, scale, {}),
                         b = ComputeKinematics(dic, homog, {});
  for (std::size_t k = 0; k < 6; ++k) {
    EXPECT_NEAR(a.vel_x_mm_s[k], b.vel_x_mm_s[k], 1e-9);
    EXPECT_NEAR(a.vel_y_mm_s[k], b.vel_y_mm_s[k], 1e-9);
    EXPECT_NEAR(a.acc_y_mm_s2[k], b.acc_y_mm_s2[k], 1e-6);
  }
  EXPECT_NEAR(homog.LocalScale(10, 10), 0.2, 1e-12);
}

TEST(Kinematics, InconsistentInputsAreNamed) {
  CorrelationSeries dic;
  dic.frames = 5;
  dic.subsets = 2;
  dic.x_px = {1, 2};
  dic.y_px = {1, 2};
  dic.u_px.assign(10, 0);
  dic.v_px.assign(9, 0);
  PanelMapping map;
  map.mm_per_px = 1;
  std::string msg = ErrorText([&] { ComputeKinematics(dic, map, {}); });
  EXPECT_NE(msg.find("u_px / v_px"), std::string::npos) << msg;
  dic.v_px.assign(10, 0);
  map.mm_per_px = 0;
  msg = ErrorText([&] { ComputeKinematics(dic, map, {}); });
  EXPECT_NE(msg.find("mm_per_px"), std::string::npos) << msg;
  map.mm_per_px = 1;
  KinematicsOptions opt;
  opt.fps = 0;
  msg = ErrorText([&] { ComputeKinematics(dic, map, opt); });
  EXPECT_NE(msg.find("fps"), std::string::npos) << msg;
  dic.frames = 3;
  msg = ErrorText([&] { ComputeKinematics(dic, map, {}); });
  EXPECT_NE(msg.find("frames"), std::string::npos) << msg;
}

}  // namespace
}  // namespace impactdic
