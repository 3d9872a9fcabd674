#include "impactdic/strain/strain.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "impactdic/core/error.h"

namespace impactdic {
namespace {

constexpr double kTol = 1e-12;

// An affine displacement field u = H (X - X0) (H per frame: scale * h) sampled on a cols x rows
// grid of step `step` px from (x0, y0), with the grid points listed in `holes` left out (ROI) and
// the subsets listed in reverse order (the grid must be found from the positions, not the order).
struct AffineSeries {
  CorrelationSeries dic;
  std::vector<double> scale;  // Per frame.
};

AffineSeries MakeAffine(const std::array<double, 4>& h, int cols, int rows,
                        const std::vector<std::pair<int, int>>& holes, std::size_t frames = 4) {
  AffineSeries a;
  CorrelationSeries& d = a.dic;
  const double x0 = 100, y0 = 50, step = 10;
  for (int r = rows - 1; r >= 0; --r) {
    for (int c = cols - 1; c >= 0; --c) {
      if (std::find(holes.begin(), holes.end(), std::make_pair(c, r)) != holes.end()) continue;
      d.x_px.push_back(x0 + step * c);
      d.y_px.push_back(y0 + step * r);
    }
  }
  d.subsets = d.x_px.size();
  d.frames = frames;
  for (std::size_t f = 0; f < frames; ++f) {
    const double s = static_cast<double>(f) / static_cast<double>(frames - 1);
    a.scale.push_back(s);
    for (std::size_t i = 0; i < d.subsets; ++i) {
      const double dx = d.x_px[i] - 130, dy = d.y_px[i] - 70;
      d.u_px.push_back(s * (h[0] * dx + h[1] * dy) + 3 * s);
      d.v_px.push_back(s * (h[2] * dx + h[3] * dy) - 2 * s);
    }
  }
  d.valid.assign(d.u_px.size(), 1);
  return a;
}

std::size_t IdAt(const CorrelationSeries& d, double x, double y) {
  for (std::size_t i = 0; i < d.subsets; ++i)
    if (d.x_px[i] == x && d.y_px[i] == y) return i;
  ADD_FAILURE() << "no subset at " << x << ", " << y;
  return 0;
}

TEST(StrainFromGradient, GreenLagrangeOfALargeGradientByHand) {
  // H = [[0.2, 0.3], [-0.1, -0.25]]: H^T H = [[0.05, 0.085], [0.085, 0.1525]].
  const StrainAtPoint s = StrainFromGradient(0.2, 0.3, -0.1, -0.25);
  EXPECT_NEAR(s.exx, 0.2, kTol);
  EXPECT_NEAR(s.eyy, -0.25, kTol);
  EXPECT_NEAR(s.exy, 0.1, kTol);
  // E = (H + H^T + H^T H) / 2 (H H^T would give 0.265, -0.1625, 0.1375).
  EXPECT_NEAR(s.gxx, 0.2 + 0.025, kTol);
  EXPECT_NEAR(s.gyy, -0.25 + 0.07625, kTol);
  EXPECT_NEAR(s.gxy, 0.1 + 0.0425, kTol);
  EXPECT_NEAR(s.eps_v, 0.05, kTol);  // -(0.2 - 0.25): net compression.
}

TEST(StrainFromGradient, PureRotationHasNoGreenLagrangeStrain) {
  const double a = 0.3, c = std::cos(a), s = std::sin(a);
  // F = [[c, -s], [s, c]], H = F - I.
  const StrainAtPoint p = StrainFromGradient(c - 1, -s, s, c - 1);
  EXPECT_NEAR(p.gxx, 0, kTol);
  EXPECT_NEAR(p.gyy, 0, kTol);
  EXPECT_NEAR(p.gxy, 0, kTol);
  // The small strain sees the rotation as compression (cos a - 1 each way).
  EXPECT_NEAR(p.exx, c - 1, kTol);
  EXPECT_NEAR(p.eyy, c - 1, kTol);
  EXPECT_NEAR(p.exy, 0, kTol);
  EXPECT_LT(p.exx, -0.04);
}

TEST(StrainFromGradient, UniaxialCompressionIsPositiveVolumetricStrain) {
  // Vertical shortening (y down): v = -0.05 (Y - Y0), dv/dY = -0.05.
  const StrainAtPoint p = StrainFromGradient(0, 0, 0, -0.05);
  EXPECT_NEAR(p.eps_v, 0.05, kTol);
  EXPECT_NEAR(p.eps_1, 0, kTol);
  EXPECT_NEAR(p.eps_2, -0.05, kTol);
  EXPECT_NEAR(p.gamma_max, 0.05, kTol);
  // eps_1 (0) is horizontal.
  EXPECT_NEAR(p.theta_1_rad, 0, kTol);
  EXPECT_NEAR(StrainFromGradient(0.02, 0, 0, 0.03).eps_v, -0.05, kTol);  // Dilation.
}

TEST(StrainFromGradient, PrincipalStrainsAndDirections) {
  // Pure shear exy = 0.1: eps_1 = 0.1 along +45 degrees (from +x towards +y, y down).
  StrainAtPoint p = StrainFromGradient(0, 0.1, 0.1, 0);
  EXPECT_NEAR(p.eps_1, 0.1, kTol);
  EXPECT_NEAR(p.eps_2, -0.1, kTol);
  EXPECT_NEAR(p.gamma_max, 0.2, kTol);
  EXPECT_NEAR(p.theta_1_rad, std::numbers::pi / 4, kTol);
  p = StrainFromGradient(0, -0.1, -0.1, 0);
  EXPECT_NEAR(p.theta_1_rad, -std::numbers::pi / 4, kTol);
  // eps_yy > eps_xx: eps_1 vertical, theta = +pi/2 (the interval is (-pi/2, pi/2]).
  p = StrainFromGradient(-0.01, 0, 0, 0.02);
  EXPECT_NEAR(p.eps_1, 0.02, kTol);
  EXPECT_NEAR(p.theta_1_rad, std::numbers::pi / 2, kTol);
  // General case: eps_1, eps_2 are the eigenvalues, theta_1 the eigenvector of eps_1.
  p = StrainFromGradient(0.03, 0.01, 0.05, -0.02);
  const double exx = 0.03, eyy = -0.02, exy = 0.03;
  const double c = std::cos(p.theta_1_rad), s = std::sin(p.theta_1_rad);
  EXPECT_NEAR(exx * c + exy * s, p.eps_1 * c, kTol);
  EXPECT_NEAR(exy * c + eyy * s, p.eps_1 * s, kTol);
  EXPECT_NEAR(p.eps_1 + p.eps_2, exx + eyy, kTol);
  EXPECT_NEAR(p.eps_1 * p.eps_2, exx * eyy - exy * exy, kTol);
  EXPECT_NEAR(p.gamma_max, p.eps_1 - p.eps_2, kTol);
  EXPECT_GE(p.eps_1, p.eps_2);
}

TEST(FitDisplacementGradient, RecoversALargeAffineGradientWithSignOnAGridWithHoles) {
  const std::array<double, 4> h{0.2, 0.3, -0.1, -0.25};
  // 7 x 6 grid with ROI holes (a corner and an interior point).
  const AffineSeries a = MakeAffine(h, 7, 6, {{0, 0}, {1, 0}, {0, 1}, {3, 3}});
  const DisplacementGradient g = FitDisplacementGradient(a.dic, /*window=*/3);
  ASSERT_EQ(g.frames, a.dic.frames);
  ASSERT_EQ(g.subsets, a.dic.subsets);
  for (std::size_t f = 0; f < g.frames; ++f) {
    for (std::size_t i = 0; i < g.subsets; ++i) {
      const std::size_t j = f * g.subsets + i;
      ASSERT_TRUE(std::isfinite(g.dudx[j])) << "frame " << f << " subset " << i;
      EXPECT_NEAR(g.dudx[j], a.scale[f] * h[0], 1e-12);
      EXPECT_NEAR(g.dudy[j], a.scale[f] * h[1], 1e-12);
      EXPECT_NEAR(g.dvdx[j], a.scale[f] * h[2], 1e-12);
      EXPECT_NEAR(g.dvdy[j], a.scale[f] * h[3], 1e-12);
    }
  }
  // Row 0 (the first reference) is exactly 0.
  for (std::size_t i = 0; i < g.subsets; ++i) EXPECT_EQ(g.dvdy[i], 0.0);
  // The whole chain: E from the fitted gradient matches (H + H^T + H^T H) / 2 in the last frame.
  const StrainField s = ComputeStrain(g, /*fps=*/1000);
  const std::size_t last = (g.frames - 1) * g.subsets;
  EXPECT_NEAR(s.gxx[last], 0.225, 1e-12);
  EXPECT_NEAR(s.gyy[last], -0.17375, 1e-12);
  EXPECT_NEAR(s.gxy[last], 0.1425, 1e-12);
  EXPECT_NEAR(s.eps_v[last], 0.05, 1e-12);
}

TEST(FitDisplacementGradient, NaNWhereInvalidOrTooFewNeighbours) {
  const std::array<double, 4> h{0.01, 0, 0, -0.02};
  // 5 x 5 grid; the corner (4, 4) is isolated by holes at (3, 4), (4, 3), (3, 3).
  AffineSeries a = MakeAffine(h, 5, 5, {{3, 4}, {4, 3}, {3, 3}});
  CorrelationSeries& d = a.dic;
  const std::size_t n = d.subsets;
  const std::size_t centre = IdAt(d, 120, 70), corner = IdAt(d, 140, 90);
  const std::size_t left = IdAt(d, 100, 50), right = IdAt(d, 110, 50), below = IdAt(d, 100, 60);
  // Frame 2: the centre sample invalid (flag), another one NaN; frame 3: the top-left corner
  // keeps only two valid neighbours (itself and one more).
  d.valid[2 * n + centre] = 0;
  d.u_px[2 * n + IdAt(d, 130, 60)] = std::nan("");
  d.valid[3 * n + right] = 0;
  d.valid[3 * n + IdAt(d, 110, 60)] = 0;
  const DisplacementGradient g = FitDisplacementGradient(d, /*window=*/3);
  EXPECT_TRUE(std::isnan(g.dudx[2 * n + centre]));
  EXPECT_TRUE(std::isnan(g.dvdy[2 * n + IdAt(d, 130, 60)]));
  // Its neighbours fit without it (the field is affine: still exact).
  EXPECT_NEAR(g.dudx[2 * n + IdAt(d, 110, 70)], a.scale[2] * 0.01, 1e-12);
  EXPECT_NEAR(g.dvdy[2 * n + IdAt(d, 130, 70)], a.scale[2] * -0.02, 1e-12);
  // The isolated corner has one sample in its window in every frame.
  for (std::size_t f = 0; f < d.frames; ++f) EXPECT_TRUE(std::isnan(g.dudx[f * n + corner]));
  EXPECT_TRUE(std::isnan(g.dudx[3 * n + left]));   // Itself and `below`: 2 < 3.
  EXPECT_FALSE(std::isnan(g.dudx[2 * n + left]));  // 4 samples.
  EXPECT_FALSE(std::isnan(g.dudx[3 * n + below]));
  // NaN gradients give NaN strains and leave the others alone.
  const StrainField s = ComputeStrain(g, /*fps=*/1000);
  EXPECT_TRUE(std::isnan(s.eps_v[2 * n + centre]));
  EXPECT_TRUE(std::isnan(s.gamma_max[2 * n + centre]));
  EXPECT_NEAR(s.eps_v[2 * n + left], a.scale[2] * 0.01, 1e-12);
}

TEST(FitDisplacementGradient, CollinearNeighboursGiveNaN) {
  // A 5 x 5 grid whose frame 2 keeps only its middle row valid: no dY information there.
  AffineSeries a = MakeAffine({0.01, 0, 0, 0}, 5, 5, {});
  CorrelationSeries& d = a.dic;
  const std::size_t n = d.subsets;
  for (std::size_t i = 0; i < n; ++i)
    if (d.y_px[i] != 70) d.valid[2 * n + i] = 0;
  const DisplacementGradient g = FitDisplacementGradient(d, /*window=*/5);
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_TRUE(std::isnan(g.dudx[2 * n + i])) << "subset " << i;
    EXPECT_NEAR(g.dudx[3 * n + i], a.scale[3] * 0.01, 1e-12) << "subset " << i;
  }
}

// The window must fit inside the grid in both directions: on 18 x 10, 9 is the largest (window
// 99 was one plane through the whole grid). A grid of fewer than 3 rows takes no window.
TEST(FitDisplacementGradient, RefusesAWindowLargerThanTheGrid) {
  const AffineSeries a = MakeAffine({0.01, 0, 0, -0.02}, 18, 10, {}, /*frames=*/2);
  const DisplacementGradient g = FitDisplacementGradient(a.dic, /*window=*/9);
  EXPECT_NEAR(g.dvdy[a.dic.subsets], -0.02, 1e-12);
  for (int window : {11, 19, 99}) {
    try {
      FitDisplacementGradient(a.dic, window);
      FAIL() << "window " << window << ": no error";
    } catch (const Error& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("strain.window"), std::string::npos) << what;
      EXPECT_NE(what.find(std::to_string(window) + " on a subset grid of 18 columns x 10 rows"),
                std::string::npos)
          << what;
      EXPECT_NE(what.find("at most 9"), std::string::npos) << what;
    }
  }
  // Holes do not shrink the grid (its extent is the ROI's): a 5 x 5 grid with a hole takes 5.
  EXPECT_NO_THROW(FitDisplacementGradient(MakeAffine({0.01, 0, 0, 0}, 5, 5, {{2, 2}}).dic, 5));
  // A single row or two: no window fits.
  for (int rows : {1, 2}) {
    try {
      FitDisplacementGradient(MakeAffine({0.01, 0, 0, 0}, 6, rows, {}).dic, /*window=*/3);
      FAIL() << rows << " row(s): no error";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("a grid of at least 3 x 3 subsets"), std::string::npos)
          << e.what();
    }
  }
}

TEST(FitDisplacementGradient, RefusesAnOffGridSubsetAndABadWindow) {
  AffineSeries a = MakeAffine({0.01, 0, 0, 0}, 4, 4, {});
  EXPECT_THROW(FitDisplacementGradient(a.dic, /*window=*/4), Error);
  EXPECT_THROW(FitDisplacementGradient(a.dic, /*window=*/1), Error);
  a.dic.x_px[0] += 3.3;
  try {
    FitDisplacementGradient(a.dic, /*window=*/3);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("regular grid"), std::string::npos) << e.what();
  }
}

DisplacementGradient GradientSeries(std::size_t frames, std::size_t subsets,
                                    const std::array<double, 4>& per_frame) {
  DisplacementGradient g;
  g.frames = frames;
  g.subsets = subsets;
  for (std::size_t f = 0; f < frames; ++f) {
    for (std::size_t i = 0; i < subsets; ++i) {
      const auto k = static_cast<double>(f);
      g.dudx.push_back(k * per_frame[0]);
      g.dudy.push_back(k * per_frame[1]);
      g.dvdx.push_back(k * per_frame[2]);
      g.dvdy.push_back(k * per_frame[3]);
    }
  }
  return g;
}

TEST(ComputeStrain, RatesOfALinearInTimeField) {
  const double fps = 2000;
  DisplacementGradient g = GradientSeries(6, 2, {0.001, 0, 0, -0.003});
  g.dudx[3 * 2 + 1] = std::nan("");  // Frame 3 of subset 1 unknown.
  const StrainField s = ComputeStrain(g, fps);
  for (std::size_t f = 0; f < 6; ++f) {
    const std::size_t j = f * 2;
    EXPECT_NEAR(s.exx_rate[j], 0.001 * fps, 1e-9) << f;
    EXPECT_NEAR(s.eyy_rate[j], -0.003 * fps, 1e-9) << f;
    EXPECT_NEAR(s.exy_rate[j], 0, 1e-9) << f;
    EXPECT_NEAR(s.eps_v_rate[j], 0.002 * fps, 1e-9) << f;
    EXPECT_NEAR(s.gamma_max_rate[j], 0.004 * fps, 1e-9) << f;
  }
  // Subset 1: the derivatives whose stencil uses frame 3 (the central ones at frames 2 and 4, the
  // one-sided one at the last frame 5) are NaN, the others exact (as the kinematics' velocity).
  for (std::size_t f : {2, 4, 5}) EXPECT_TRUE(std::isnan(s.exx_rate[f * 2 + 1])) << f;
  for (std::size_t f : {0, 1, 3}) EXPECT_NEAR(s.exx_rate[f * 2 + 1], 0.001 * fps, 1e-9) << f;
  EXPECT_THROW(ComputeStrain(g, /*fps=*/0), Error);
}

TEST(DensityField, CompressionRaisesTheDensity) {
  StrainField s;
  s.frames = 1;
  s.subsets = 4;
  s.eps_v = {0.2, -0.1, 1.0, std::nan("")};
  const std::vector<double> rho = DensityField(s, /*dry_density_kg_m3=*/1600);
  EXPECT_NEAR(rho[0], 2000, 1e-9);
  EXPECT_NEAR(rho[1], 1600 / 1.1, 1e-9);
  EXPECT_TRUE(std::isnan(rho[2]));
  EXPECT_TRUE(std::isnan(rho[3]));
  EXPECT_THROW(DensityField(s, 0), Error);
}

// A 5 x 5 grid (step 10 px from (100, 50)) with eps_v given per subset in frame 1.
struct ZoneCase {
  CorrelationSeries dic;
  StrainField strain;
};

ZoneCase MakeZoneCase() {
  ZoneCase z;
  z.dic = MakeAffine({0, 0, 0, 0}, 5, 5, {{4, 4}}).dic;
  const std::size_t n = z.dic.subsets;
  z.strain.frames = 2;
  z.strain.subsets = n;
  z.strain.eps_v.assign(2 * n, 0.0);
  z.strain.gamma_max.assign(2 * n, 0.0);
  return z;
}

TEST(FindCompactedZone, AreaAndDepthFromTheTopRowOrTheSurface) {
  ZoneCase z = MakeZoneCase();
  const std::size_t n = z.dic.subsets;
  StrainOptions options;  // compaction_threshold 0.01.
  z.strain.eps_v[n + IdAt(z.dic, 120, 60)] = 0.05;
  z.strain.eps_v[n + IdAt(z.dic, 120, 80)] = 0.02;
  z.strain.eps_v[n + IdAt(z.dic, 130, 80)] = 0.01;  // Not above the threshold.
  z.strain.eps_v[n + IdAt(z.dic, 110, 90)] = std::nan("");
  CompactedZone c = FindCompactedZone(z.strain, z.dic, 1, options, /*mm_per_px=*/0.5);
  EXPECT_EQ(c.frame, 1u);
  EXPECT_EQ(c.samples, 2u);
  EXPECT_NEAR(c.area_mm2, 2 * 10 * 10 * 0.25, 1e-12);
  EXPECT_NEAR(c.depth_mm, (80 - 50) * 0.5, 1e-12);
  // Measured from the soil surface when given.
  c = FindCompactedZone(z.strain, z.dic, 1, options, 0.5, /*surface_y_px=*/44);
  EXPECT_NEAR(c.depth_mm, (80 - 44) * 0.5, 1e-12);
  // A surface below the zone: never negative.
  c = FindCompactedZone(z.strain, z.dic, 1, options, 0.5, /*surface_y_px=*/200);
  EXPECT_EQ(c.depth_mm, 0.0);
  // None in frame 0.
  c = FindCompactedZone(z.strain, z.dic, 0, options, 0.5);
  EXPECT_EQ(c.samples, 0u);
  EXPECT_EQ(c.area_mm2, 0.0);
  EXPECT_EQ(c.depth_mm, 0.0);
  EXPECT_THROW(FindCompactedZone(z.strain, z.dic, 2, options, 0.5), Error);
}

// A frame without any finite eps_v: the zone was not measured (NaN), not empty (0).
TEST(FindCompactedZone, NaNWhenTheFrameHasNoFiniteStrain) {
  ZoneCase z = MakeZoneCase();
  const std::size_t n = z.dic.subsets;
  for (std::size_t i = 0; i < n; ++i) z.strain.eps_v[n + i] = std::nan("");
  const CompactedZone c = FindCompactedZone(z.strain, z.dic, 1, StrainOptions{}, 0.5);
  EXPECT_EQ(c.samples, 0u);
  EXPECT_TRUE(std::isnan(c.area_mm2));
  EXPECT_TRUE(std::isnan(c.depth_mm));
  // One finite sample below the threshold: measured, no compaction.
  z.strain.eps_v[n + IdAt(z.dic, 120, 60)] = 0.0;
  const CompactedZone one = FindCompactedZone(z.strain, z.dic, 1, StrainOptions{}, 0.5);
  EXPECT_EQ(one.area_mm2, 0.0);
  EXPECT_EQ(one.depth_mm, 0.0);
}

TEST(ShearBands, RidgesOfMaximumShearAboveTheThreshold) {
  ZoneCase z = MakeZoneCase();
  const std::size_t n = z.dic.subsets;
  StrainOptions options;
  options.shear_band_threshold = 0.02;
  // Frame 1: a vertical band at x = 120 (a ridge across it, horizontally).
  for (double y : {50.0, 60.0, 70.0, 80.0, 90.0}) {
    z.strain.gamma_max[n + IdAt(z.dic, 110, y)] = 0.02;
    z.strain.gamma_max[n + IdAt(z.dic, 120, y)] = 0.05;
    z.strain.gamma_max[n + IdAt(z.dic, 130, y)] = 0.03;
  }
  const std::vector<std::uint8_t> band = ShearBands(z.strain, z.dic, options);
  ASSERT_EQ(band.size(), 2 * n);
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_EQ(band[i], 0) << "frame 0, subset " << i;
    EXPECT_EQ(band[n + i], z.dic.x_px[i] == 120 ? 1 : 0) << z.dic.x_px[i] << ", " << z.dic.y_px[i];
  }
  // Below the threshold: none.
  options.shear_band_threshold = 0.06;
  for (std::uint8_t b : ShearBands(z.strain, z.dic, options)) EXPECT_EQ(b, 0);
  // A plateau is not a ridge.
  std::fill(z.strain.gamma_max.begin() + static_cast<std::ptrdiff_t>(n), z.strain.gamma_max.end(),
            0.1);
  for (std::uint8_t b : ShearBands(z.strain, z.dic, options)) EXPECT_EQ(b, 0);
}

TEST(StrainOptions, DefaultsPassAndEachBadFieldIsNamed) {
  StrainOptions defaults;
  EXPECT_NO_THROW(defaults.Check());
  EXPECT_EQ(defaults.gradient, StrainGradient::kFit);
  EXPECT_FALSE(defaults.enabled);
  auto expect_named = [](StrainOptions o, const std::string& key) {
    try {
      o.Check();
      ADD_FAILURE() << key << " accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  };
  StrainOptions o;
  o.window = 4;
  expect_named(o, "strain.window");
  o = {};
  o.window = 1;
  expect_named(o, "strain.window");
  o = {};
  o.compaction_threshold = -0.1;
  expect_named(o, "strain.compaction_threshold");
  o = {};
  o.compaction_threshold = std::nan("");
  expect_named(o, "strain.compaction_threshold");
  o = {};
  o.shear_band_threshold = -1;
  expect_named(o, "strain.shear_band_threshold");
  EXPECT_EQ(kStrainGradientNames.Parse("warp", "strain.gradient"), StrainGradient::kWarp);
  EXPECT_EQ(std::string(kStrainGradientNames.Name(StrainGradient::kFit)), "fit");
  EXPECT_THROW(kStrainGradientNames.Parse("spline", "strain.gradient"), Error);
}

}  // namespace
}  // namespace impactdic
