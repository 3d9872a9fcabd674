#include "impactdic/momentum/fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "impactdic/core/error.h"
#include "impactdic/model/impact_model.h"

namespace impactdic {
namespace {

// Reference quantiles (tables of the t distribution, 7+ digits).
TEST(StudentT, KnownQuantiles) {
  EXPECT_NEAR(StudentTQuantile(0.975, 1), 12.7062047, 1e-6);
  EXPECT_NEAR(StudentTQuantile(0.975, 5), 2.5705818, 1e-6);
  EXPECT_NEAR(StudentTQuantile(0.975, 23), 2.0686576, 1e-6);
  EXPECT_NEAR(StudentTQuantile(0.95, 10), 1.8124611, 1e-6);
  EXPECT_NEAR(StudentTQuantile(0.975, 1e7), 1.9599640, 1e-5);
  EXPECT_NEAR(StudentTQuantile(0.025, 5), -2.5705818, 1e-6);
  EXPECT_NEAR(StudentTCdf(0, 3), 0.5, 1e-15);
}

// m_add(t) = M / (1 + exp(-b (t - T))) + white noise (sigma 0.15 kg, seeded), 0..6 ms, 61 points:
// the fit recovers M, b, T within its 95 % intervals, and over 300 seeds the intervals cover the
// truth in 95 % +- 3 % of the fits (binomial sd 1.3 %, so the band is > 2 sd wide).
TEST(Sigmoid, RecoversParametersWithinIntervals) {
  const double M = 8, b = 2500, T = 0.002;
  int covered[3] = {0, 0, 0};
  const int runs = 300;
  for (int seed = 0; seed < runs; ++seed) {
    std::mt19937 rng(static_cast<unsigned>(seed));
    std::normal_distribution<double> noise(0, 0.15);
    std::vector<double> t, y;
    for (int i = 0; i <= 60; ++i) {
      t.push_back(i * 1e-4);
      y.push_back(AddedMassAt(M, b, T, t.back()).m_add_kg + noise(rng));
    }
    const SigmoidFit f = FitSigmoid(t, y, SigmoidFitOptions{});
    ASSERT_TRUE(f.converged) << f.message;
    covered[0] += f.ci_M_kg[0] <= M && M <= f.ci_M_kg[1];
    covered[1] += f.ci_b_per_s[0] <= b && b <= f.ci_b_per_s[1];
    covered[2] += f.ci_T_s[0] <= T && T <= f.ci_T_s[1];
    if (seed < 3) {  // The first seeds individually.
      EXPECT_GE(M, f.ci_M_kg[0]);
      EXPECT_LE(M, f.ci_M_kg[1]);
      EXPECT_GE(b, f.ci_b_per_s[0]);
      EXPECT_LE(b, f.ci_b_per_s[1]);
      EXPECT_GE(T, f.ci_T_s[0]);
      EXPECT_LE(T, f.ci_T_s[1]);
      EXPECT_NEAR(f.rms_residual_kg, 0.15, 0.05);
    }
  }
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(covered[k] / static_cast<double>(runs), 0.95, 0.03) << "parameter " << k;
  }
}

TEST(Sigmoid, ExactDataConvergesToTruth) {
  std::vector<double> t, y;
  for (int i = 0; i <= 40; ++i) {
    t.push_back(i * 1.5e-4);
    y.push_back(AddedMassAt(3.5, 4000, 0.0025, t.back()).m_add_kg);
  }
  const SigmoidFit f = FitSigmoid(t, y, SigmoidFitOptions{});
  EXPECT_NEAR(f.M_kg, 3.5, 1e-8);
  EXPECT_NEAR(f.b_per_s, 4000, 1e-5);
  EXPECT_NEAR(f.T_s, 0.0025, 1e-11);
}

std::vector<PowerLawSample> Campaign(unsigned seed, double noise_sd) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, noise_sd);
  std::vector<PowerLawSample> s;
  for (double m : {7.0, 10.0, 13.0})
    for (double h : {0.2, 0.7, 1.2})
      for (double d : {0.10, 0.15, 0.20}) {
        PowerLawSample p;
        p.mass_kg = m;
        p.velocity_m_s = std::sqrt(2 * 9.81 * h);
        p.area_m2 = d * 0.192;
        p.added_mass_kg = 425 * std::pow(m, 0.1) * std::pow(p.velocity_m_s, 0.2) *
                          std::pow(p.area_m2, 1.3) * std::exp(noise(rng));
        s.push_back(p);
      }
  return s;
}

// 27 synthetic tests made with the paper's coefficients (c = 425, a = 0.1, b = 0.2, g = 1.3) and
// 5 % log-normal noise: the regression recovers them within its 95 % intervals, and the intervals
// cover the truth in 95 % +- 3 % of 300 campaigns.
TEST(PowerLaw, RecoversEq4CoefficientsWithinIntervals) {
  const PowerLawFit f = FitPowerLaw(Campaign(42, 0.05));
  EXPECT_EQ(f.n, 27u);
  EXPECT_EQ(f.dof, 23u);
  EXPECT_TRUE(f.ci_c[0] <= 425 && 425 <= f.ci_c[1]) << f.BriefReport();
  EXPECT_TRUE(f.ci_a[0] <= 0.1 && 0.1 <= f.ci_a[1]) << f.BriefReport();
  EXPECT_TRUE(f.ci_b[0] <= 0.2 && 0.2 <= f.ci_b[1]) << f.BriefReport();
  EXPECT_TRUE(f.ci_g[0] <= 1.3 && 1.3 <= f.ci_g[1]) << f.BriefReport();
  EXPECT_GT(f.r_squared, 0.95);
  int covered = 0;
  for (unsigned seed = 0; seed < 300; ++seed) {
    const PowerLawFit g = FitPowerLaw(Campaign(seed + 1000, 0.05));
    covered += g.ci_g[0] <= 1.3 && 1.3 <= g.ci_g[1];
  }
  EXPECT_NEAR(covered / 300.0, 0.95, 0.03);
  // Noise-free: exact.
  const PowerLawFit e = FitPowerLaw(Campaign(1, 0.0));
  EXPECT_NEAR(e.c, 425, 1e-8);
  EXPECT_NEAR(e.a, 0.1, 1e-12);
  EXPECT_NEAR(e.g, 1.3, 1e-12);
  EXPECT_NEAR(e.r_squared, 1, 1e-12);
}

TEST(PowerLaw, DegenerateCampaignIsAnError) {
  std::vector<PowerLawSample> s = Campaign(1, 0.05);
  for (auto& p : s) p.mass_kg = 10;  // No spread in mass.
  EXPECT_THROW(FitPowerLaw(s), Error);
  s = Campaign(1, 0.05);
  s[3].added_mass_kg = -1;
  try {
    FitPowerLaw(s);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("power-law test 3"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace impactdic
