// The campaign's comparison figures: the least-squares fit against values worked out by hand, the
// plot's 1:1 line, fit line and per-width markers, and the PNG.
#include "impactdic/render/comparison_figures.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "impactdic/core/error.h"
#include "impactdic/core/numeric.h"
#include "test_util.h"

namespace impactdic {
namespace {

using test::IsPngOfSize;
using test::ScratchDir;

// (1, 2), (2, 3), (3, 5) and two tests without a value. By hand: mean x = 2, mean y = 10/3,
// Sxx = 2, Sxy = 3, Syy = 14/3; slope = 3/2, intercept = 10/3 - 3 = 1/3,
// R^2 = Sxy^2 / (Sxx Syy) = 9 / (28/3) = 27/28; observed/predicted - 1 = 1, 1/2, 2/3, so the RMS
// is sqrt((1 + 1/4 + 4/9) / 3) = sqrt(61/108) and the largest 1.
std::vector<ComparisonPoint> HandPoints() {
  return {{.predicted = 1, .observed = 2, .width_m = 0.1, .label = "a"},
          {.predicted = 2, .observed = 3, .width_m = 0.2, .label = "b"},
          {.predicted = kNaN, .observed = 4, .width_m = 0.1, .label = "no model"},
          {.predicted = 3, .observed = 5, .width_m = 0.1, .label = "c"},
          {.predicted = 2, .observed = HUGE_VAL, .width_m = 0.2, .label = "diverged"}};
}

TEST(ComparisonFit, MatchesTheHandComputedLeastSquaresLine) {
  const ComparisonFit fit = FitComparison(HandPoints());
  EXPECT_EQ(fit.n, 3);
  EXPECT_EQ(fit.skipped, 2);
  EXPECT_NEAR(fit.slope, 1.5, 1e-14);
  EXPECT_NEAR(fit.intercept, 1.0 / 3.0, 1e-14);
  EXPECT_NEAR(fit.r_squared, 27.0 / 28.0, 1e-14);
  EXPECT_NEAR(fit.rms_relative_deviation, std::sqrt(61.0 / 108.0), 1e-14);
  EXPECT_NEAR(fit.max_relative_deviation, 1.0, 1e-14);
}

TEST(ComparisonFit, PointsOnTheOneToOneLineFitExactly) {
  std::vector<ComparisonPoint> points;
  for (double v : {0.5, 1.0, 4.0, 7.5}) points.push_back({.predicted = v, .observed = v});
  const ComparisonFit fit = FitComparison(points);
  EXPECT_EQ(fit.n, 4);
  EXPECT_EQ(fit.skipped, 0);
  EXPECT_NEAR(fit.slope, 1.0, 1e-14);
  EXPECT_NEAR(fit.intercept, 0.0, 1e-14);
  EXPECT_NEAR(fit.r_squared, 1.0, 1e-14);
  EXPECT_EQ(fit.rms_relative_deviation, 0.0);
  EXPECT_EQ(fit.max_relative_deviation, 0.0);
}

TEST(ComparisonFit, LargeCloseValuesKeepTheirPrecision) {
  // y = 2 x - 1e6 around x = 1e6: the centred sums give the line to rounding.
  std::vector<ComparisonPoint> points;
  for (double d : {0.0, 1.0, 2.0, 3.0}) {
    points.push_back({.predicted = 1e6 + d, .observed = 2 * (1e6 + d) - 1e6});
  }
  const ComparisonFit fit = FitComparison(points);
  EXPECT_NEAR(fit.slope, 2.0, 1e-9);
  EXPECT_NEAR(fit.intercept, -1e6, 1e-3);
  EXPECT_NEAR(fit.r_squared, 1.0, 1e-12);
}

TEST(ComparisonFit, OnePointHasNoLineButADeviation) {
  const ComparisonFit fit =
      FitComparison({{.predicted = 2, .observed = 3}, {.predicted = kNaN, .observed = kNaN}});
  EXPECT_EQ(fit.n, 1);
  EXPECT_EQ(fit.skipped, 1);
  EXPECT_TRUE(std::isnan(fit.slope));
  EXPECT_TRUE(std::isnan(fit.intercept));
  EXPECT_TRUE(std::isnan(fit.r_squared));
  EXPECT_DOUBLE_EQ(fit.rms_relative_deviation, 0.5);
  EXPECT_DOUBLE_EQ(fit.max_relative_deviation, 0.5);
}

TEST(ComparisonFit, NoPointLeavesEverythingNaN) {
  const ComparisonFit fit = FitComparison({{.predicted = kNaN, .observed = 1}});
  EXPECT_EQ(fit.n, 0);
  EXPECT_EQ(fit.skipped, 1);
  EXPECT_TRUE(std::isnan(fit.slope));
  EXPECT_TRUE(std::isnan(fit.r_squared));
  EXPECT_TRUE(std::isnan(fit.rms_relative_deviation));
  EXPECT_TRUE(std::isnan(fit.max_relative_deviation));
}

TEST(ComparisonFit, OnePredictedValueHasNoSlope) {
  const ComparisonFit fit =
      FitComparison({{.predicted = 2, .observed = 1}, {.predicted = 2, .observed = 3}});
  EXPECT_EQ(fit.n, 2);
  EXPECT_TRUE(std::isnan(fit.slope));
  EXPECT_TRUE(std::isnan(fit.r_squared));
  EXPECT_DOUBLE_EQ(fit.max_relative_deviation, 0.5);
}

TEST(ComparisonFit, AZeroPredictionIsLeftOutOfTheRelativeDeviation) {
  // observed/predicted is undefined for predicted = 0; the line still uses the point.
  const ComparisonFit fit = FitComparison({{.predicted = 0, .observed = 1},
                                           {.predicted = 1, .observed = 2},
                                           {.predicted = 2, .observed = 3}});
  EXPECT_EQ(fit.n, 3);
  EXPECT_NEAR(fit.slope, 1.0, 1e-14);
  EXPECT_NEAR(fit.intercept, 1.0, 1e-14);
  EXPECT_NEAR(fit.max_relative_deviation, 1.0, 1e-14);                            // 2/1 - 1
  EXPECT_NEAR(fit.rms_relative_deviation, std::sqrt((1.0 + 0.25) / 2.0), 1e-14);  // 1, 3/2 - 1
}

const PlotSeries* FindSeries(const Plot& plot, const std::string& label_start) {
  for (const auto& s : plot.series) {
    if (s.label.rfind(label_start, 0) == 0) return &s;
  }
  return nullptr;
}

TEST(ComparisonPlot, HasTheOneToOneLineOverTheDataRangeAndTheFitInTheKey) {
  const Plot plot = MakeComparisonPlot(
      {.title = "Added mass", .x_label = "x [kg]", .y_label = "y [kg]", .points = HandPoints()});
  EXPECT_EQ(plot.title, "Added mass (2 of 5 tests without a value, not drawn)");
  // Finite values span 1..5 on both axes; 5 % margins; equal axes.
  EXPECT_DOUBLE_EQ(plot.x_min, 0.8);
  EXPECT_DOUBLE_EQ(plot.x_max, 5.2);
  EXPECT_DOUBLE_EQ(plot.y_min, plot.x_min);
  EXPECT_DOUBLE_EQ(plot.y_max, plot.x_max);
  const PlotSeries* identity = FindSeries(plot, "1:1");
  ASSERT_NE(identity, nullptr);
  ASSERT_EQ(identity->x.size(), 2u);
  EXPECT_DOUBLE_EQ(identity->x[0], 0.8);
  EXPECT_DOUBLE_EQ(identity->x[1], 5.2);
  EXPECT_EQ(identity->x, identity->y);
  const PlotSeries* fit = FindSeries(plot, "fit: ");
  ASSERT_NE(fit, nullptr);
  EXPECT_EQ(fit->label, "fit: y = 1.5 x + 0.333, R^2 = 0.964, n = 3");
  ASSERT_EQ(fit->x.size(), 2u);
  EXPECT_NEAR(fit->y[0], 1.5 * 0.8 + 1.0 / 3.0, 1e-12);
  EXPECT_NEAR(fit->y[1], 1.5 * 5.2 + 1.0 / 3.0, 1e-12);
}

TEST(ComparisonPlot, OneMarkerAndColourPerWidth) {
  const Plot plot = MakeComparisonPlot({.points = HandPoints()});
  const PlotSeries* d10 = FindSeries(plot, "D = 0.10 m");
  const PlotSeries* d20 = FindSeries(plot, "D = 0.20 m");
  ASSERT_NE(d10, nullptr);
  ASSERT_NE(d20, nullptr);
  EXPECT_EQ(d10->x, (std::vector<double>{1, 3}));  // the finite tests with D = 0.1 m
  EXPECT_EQ(d10->y, (std::vector<double>{2, 5}));
  EXPECT_EQ(d20->x, (std::vector<double>{2}));
  EXPECT_EQ(d10->style, SeriesStyle::kPoints);
  EXPECT_NE(d10->color, d20->color);
  EXPECT_NE(d10->point_type, d20->point_type);
  EXPECT_EQ(plot.series.size(), 4u);  // 1:1, fit, two widths
}

TEST(ComparisonPlot, WidthLabelsGainDecimalsToStayDistinct) {
  const Plot plot =
      MakeComparisonPlot({.points = {{.predicted = 1, .observed = 1, .width_m = 0.1},
                                     {.predicted = 2, .observed = 2, .width_m = 0.105},
                                     {.predicted = 3, .observed = 3}}});
  EXPECT_NE(FindSeries(plot, "D = 0.100 m"), nullptr);
  EXPECT_NE(FindSeries(plot, "D = 0.105 m"), nullptr);
  EXPECT_NE(FindSeries(plot, "D unknown"), nullptr);
  std::set<int> types;
  for (const auto& s : plot.series) {
    if (s.style == SeriesStyle::kPoints) types.insert(s.point_type);
  }
  EXPECT_EQ(types.size(), 3u);
}

TEST(ComparisonPlot, NoFitLineWithoutTwoPredictedValues) {
  const Plot plot =
      MakeComparisonPlot({.points = {{.predicted = 2, .observed = 3, .width_m = 0.1}}});
  EXPECT_EQ(FindSeries(plot, "fit: "), nullptr);
  EXPECT_NE(FindSeries(plot, "1:1"), nullptr);
  EXPECT_NE(FindSeries(plot, "D = 0.10 m"), nullptr);
}

TEST(ComparisonPlot, TheScriptDrawsEachWidthWithItsOwnPointType) {
  const Plot plot = MakeComparisonPlot({.points = HandPoints()});
  const std::string script = GnuplotScript(plot, {}, "pngcairo", "d.dat", "o.png");
  EXPECT_NE(script.find("with points pt 7 ps 1.8 "), std::string::npos) << script;
  EXPECT_NE(script.find("with points pt 5 ps 1.8 "), std::string::npos) << script;
  EXPECT_NE(script.find("title 'D = 0.10 m'"), std::string::npos) << script;
}

TEST(ComparisonPlot, RendersAPng) {
  ScratchDir dir("comparison");
  const auto summary = PlotComparison({.title = "Added mass (Fig. 5)",
                                       .x_label = "m_add,max by Eq. 4 [kg]",
                                       .y_label = "m_add,max measured [kg]",
                                       .points = HandPoints()},
                                      dir / "fig5.png");
  EXPECT_EQ(summary.series, 4);
  EXPECT_TRUE(IsPngOfSize(dir / "fig5.png", 640, 480));
}

TEST(ComparisonPlot, NoFinitePointIsAnErrorAndWritesNothing) {
  ScratchDir dir("comparison");
  try {
    PlotComparison({.title = "Fig. 7", .points = {{.predicted = kNaN, .observed = 1}}},
                   dir / "fig7.png");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kInvalidValue);
    EXPECT_NE(std::string(e.what()).find("Fig. 7"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("fig7.png"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(dir.Entries().empty());
}

}  // namespace
}  // namespace impactdic
