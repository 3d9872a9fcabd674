// The synthetic campaign end to end in the test suite: the 27 Table 1 tests of
// docs/campaign/table1_synthetic.yaml (measured m_add,max = Eq. 4 x log-normal noise, sd 0.05,
// seed 1), reduced in frames rather than in tests: 12 frames each (enough for t_e, ~4 ms after
// the impact) with the accelerometer record running 50 ms on (the pounder's stop, for crater
// depth and plateau), no per-test figures or video: ~40 s on 2 cores.
//
// Why 27 tests and not 8: the regression has 4 parameters. A 2 x 2 x 2 subset leaves 4 degrees of
// freedom, and its 95 % intervals (from the residual scatter of 8 points) are too narrow to hold
// the pipeline's measurement error, which is not independent noise: t_e is found on the frame grid
// (docs/campaign.md), so m_add,max is off by up to 8.3 % in steps. Measured: the 8-test subset gave
// b = 0.292, CI [0.248, 0.336], excluding the paper's 0.2 AND the 0.237 that the same fit gives
// from the 8 exact M values. With 27 tests (23 degrees of freedom) the intervals are honest, and
// the test asserts what the issue asks:
//  - each measured m_add,max equals the M it was synthesised with, within 10 % (worst 8.3 %);
//  - the paper's c, a, b, g lie inside the 95 % intervals of the fit over the measured values.
//    (Not asserted: that the fit over the 27 exact M values, b = 0.176, lies inside them too. The
//    measurement error is not independent noise: m_add,max comes out 4 % low on average at
//    h = 0.2 m and 1 % high at 1.2 m, also at 320 x 240 px, which moves b to 0.239, CI
//    [0.185, 0.293]. docs/campaign.md reports it.)
//  - the comparison points lie on the 1:1 line within the noise sources (FitComparison): Fig. 5
//    within the 5 % added-mass noise plus the measurement error; Figs. 7-10 (sensor and DIC values
//    against the model run with the same M) within the sensor's error: the 1500 Hz low-pass lowers
//    the peak deceleration by ~3 % (slope 0.97).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "../io/test_dir.h"
#include "impactdic/momentum/fit.h"
#include "impactdic/pipeline/campaign.h"
#include "impactdic/render/comparison_figures.h"

namespace impactdic {
namespace {

TEST(CampaignSynthetic, Table1CampaignRecoversEq4WithinItsIntervalsAndTheOneToOneLines) {
  TestDir dir;
  const std::string file = dir.Write(
      "c.yaml",
      "synthesise:\n  added_mass_noise: 0.05\n  seed: 1\n  spec:\n    frames:\n      count: 12\n"
      "    sensor:\n      tail_s: 0.05\noutputs:\n  animation: false\n  figures: false\n");
  CampaignOptions o;
  o.output_folder = dir.File("out");
  o.threads = 2;
  const CampaignSummary s = RunCampaignPlan(LoadCampaignFile(file), o);
  ASSERT_EQ(s.rows.size(), 27u);
  for (const CampaignRow& r : s.rows) {
    ASSERT_EQ(r.status, "ok") << r.name << ": " << r.error;
    const double measured = r.Figure("added_mass_max_kg");
    EXPECT_LT(std::abs(measured / r.added_mass_given_kg - 1), 0.10)
        << r.name << ": measured " << measured << " kg, given " << r.added_mass_given_kg;
  }
  ASSERT_TRUE(s.fitted) << s.fit_note;
  const auto inside = [](double v, const std::array<double, 2>& ci) {
    return ci[0] <= v && v <= ci[1];
  };
  // The paper's values (the law the M were drawn around).
  EXPECT_TRUE(inside(425, s.fit.ci_c)) << s.fit.BriefReport();
  EXPECT_TRUE(inside(0.1, s.fit.ci_a)) << s.fit.BriefReport();
  EXPECT_TRUE(inside(0.2, s.fit.ci_b)) << s.fit.BriefReport();
  EXPECT_TRUE(inside(1.3, s.fit.ci_g)) << s.fit.BriefReport();

  ASSERT_EQ(s.comparisons.size(), 5u);
  for (const auto& [name, fit] : s.comparisons) {
    EXPECT_EQ(fit.n, 27) << name;
    EXPECT_GT(fit.r_squared, 0.9) << name;
  }
  const auto rms = [&](std::size_t i) { return s.comparisons[i].second.rms_relative_deviation; };
  EXPECT_LT(rms(0), 0.10) << "Fig. 5, added mass";       // measured: 0.054
  EXPECT_LT(rms(1), 0.05) << "Fig. 7, peak";             // 0.030 (filter: ~3 % low)
  EXPECT_LT(rms(2), 0.02) << "Fig. 8, plateau";          // 0.0045
  EXPECT_LT(rms(3), 0.02) << "Fig. 9, penetration";      // 0.0035
  EXPECT_LT(rms(4), 0.07) << "Fig. 10, momentum ratio";  // 0.041
  EXPECT_NEAR(s.comparisons[1].second.slope, 0.97, 0.03) << "Fig. 7";
  for (std::size_t i : {2u, 3u}) EXPECT_NEAR(s.comparisons[i].second.slope, 1.0, 0.02) << i;
  for (const char* png :
       {"fig5_added_mass.png", "fig7_peak_deceleration.png", "fig8_plateau_deceleration.png",
        "fig9_relative_penetration.png", "fig10_momentum_ratio.png"}) {
    EXPECT_GT(std::filesystem::file_size(dir.File(std::string("out/") + png)), 10000u) << png;
  }
}

// The wave columns and the attenuation figure (docs/wave.md, docs/campaign.md): three tests
// synthesised with base force sensors (soil.wave_speed_m_s 80 m/s) give the wave speed from the
// peak travel time, the stress ratio (each equal to the test's own summary), and
// wave_attenuation.png with its fit over the three; a campaign without base sensors (the test
// above) draws no such figure and has no such comparison.
TEST(CampaignSynthetic, WaveColumnsAndTheAttenuationFigure) {
  TestDir dir;
  const std::string file =
      dir.Write("c.yaml",
                "synthesise:\n  mass_kg: [7, 10, 13]\n  drop_height_m: [0.7]\n  width_m: [0.15]\n"
                "  spec:\n    frames:\n      count: 12\n    sensor:\n      tail_s: 0.05\n"
                "    soil: {wave_speed_m_s: 80}\n    base_sensors:\n      columns: [base_center_N, "
                "base_offset_N]\n      offsets_mm: [0, 300]\n      depths_mm: [600, 600]\n"
                "      areas_mm2: [2000, 2000]\noutputs:\n  animation: false\n  figures: false\n");
  CampaignOptions o;
  o.output_folder = dir.File("out");
  o.threads = 2;
  const CampaignSummary s = RunCampaignPlan(LoadCampaignFile(file), o);
  ASSERT_EQ(s.rows.size(), 3u);
  for (const CampaignRow& r : s.rows) {
    ASSERT_EQ(r.status, "ok") << r.name << ": " << r.error;
    // The synth's wave at 80 m/s, read from the peaks 600 mm down (docs/wave.md: within 5 %).
    EXPECT_NEAR(r.Figure("wave_speed_peak_m_s"), 80, 4) << r.name;
    const double ratio = r.Figure("wave_stress_ratio");
    EXPECT_GT(ratio, 0) << r.name;
    EXPECT_LT(ratio, 1) << r.name;
  }
  CampaignOptions table;
  table.output_folder = dir.File("table");
  table.figures = false;
  const std::vector<CampaignRow> back =
      RegressCampaignTable(dir.File("out/campaign.csv"), table).rows;
  ASSERT_EQ(back.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    for (const char* column : {"wave_speed_peak_m_s", "wave_stress_ratio", "wave_front_speed_m_s",
                               "wave_decay_length_te_mm"}) {
      const double a = s.rows[i].Figure(column), b = back[i].Figure(column);
      EXPECT_TRUE(a == b || (std::isnan(a) && std::isnan(b))) << column << ": " << a << " " << b;
    }
  }
  const auto it = std::find_if(s.comparisons.begin(), s.comparisons.end(),
                               [](const auto& c) { return c.first == "wave_attenuation"; });
  ASSERT_NE(it, s.comparisons.end());
  EXPECT_EQ(it->second.n, 3);
  EXPECT_GT(std::filesystem::file_size(dir.File("out/wave_attenuation.png")), 10000u);
}

}  // namespace
}  // namespace impactdic
