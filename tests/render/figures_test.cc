// The paper's figures from synthetic data: each is a valid PNG of sensible size.
#include "impactdic/render/figures.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "impactdic/core/error.h"
#include "impactdic/model/impact_model.h"
#include "test_util.h"

namespace impactdic {
namespace {

using test::IsPngOfSize;
using test::ScratchDir;

// Synthetic impact: pounder momentum decays, granular momentum rises so that the total stays at
// p_max until t_e = 2 ms and then declines (the shape of the paper's Fig. 4).
MomentumFigureData SyntheticMomentum() {
  MomentumFigureData d;
  const double p_max = 39.0, t_e = 2e-3;
  for (int i = 0; i <= 40; ++i) {
    const double t = i * 1.0 / 1600.0 * 0.25;
    const double pp = p_max * std::exp(-t / 3e-3);
    const double pg = t <= t_e
                          ? p_max - pp
                          : (p_max - p_max * std::exp(-t_e / 3e-3)) * std::exp(-(t - t_e) / 2e-3);
    d.t_s.push_back(t);
    d.p_pounder_Ns.push_back(pp);
    d.p_gran_Ns.push_back(pg);
    d.p_total_Ns.push_back(pp + pg);
  }
  d.p_max_Ns = p_max;
  d.t_e_s = t_e;
  return d;
}

TEST(Figures, MomentumPlotHasThreeSeriesAndTwoMarkers) {
  const Plot plot = MakeMomentumPlot(SyntheticMomentum());
  EXPECT_EQ(plot.series.size(), 3u);
  EXPECT_EQ(plot.markers.size(), 2u);
  EXPECT_NE(plot.x_label.find("[ms]"), std::string::npos);
  EXPECT_NE(plot.y_label.find("[N s]"), std::string::npos);
  EXPECT_DOUBLE_EQ(plot.markers[1].value, 2.0);  // t_e in ms
}

TEST(Figures, MomentumPng) {
  ScratchDir dir("fig");
  PlotMomentum(SyntheticMomentum(), dir / "momentum.png");
  EXPECT_TRUE(IsPngOfSize(dir / "momentum.png", 640, 480));
}

TEST(Figures, DecelerationPng) {
  ScratchDir dir("fig");
  DecelerationFigureData d;
  for (int i = 0; i < 250; ++i) {  // 25 kHz, 10 ms, with a peak at 1.5 ms and a plateau
    const double t = i / 25000.0;
    const double g = 80.0 * std::exp(-std::pow((t - 1.5e-3) / 0.5e-3, 2)) + 30.0 * (t > 1e-3);
    d.measured_t_s.push_back(t);
    d.measured_decel_g.push_back(g + 3.0 * std::sin(7000.0 * t));
    d.model_t_s.push_back(t);
    d.model_decel_g.push_back(g);
  }
  d.t_e_s = 2e-3;
  PlotDeceleration(d, dir / "decel.png");
  EXPECT_TRUE(IsPngOfSize(dir / "decel.png", 640, 480));
}

TEST(Figures, DecelerationAxisIgnoresTheModelsSingularEnd) {
  // The model's -dv/dt grows like v^-n as v -> 0 at its stop: the last samples may be huge. The
  // y axis follows the peak (80 g) and the measured record, not the end spike (1e4 g).
  DecelerationFigureData d;
  for (int i = 0; i <= 100; ++i) {
    const double t = i * 1e-4;
    const double g = 80.0 * std::exp(-std::pow((t - 1.5e-3) / 0.5e-3, 2)) + 10.0;
    d.model_t_s.push_back(t);
    d.model_decel_g.push_back(i == 100 ? 1e4 : g);
    d.measured_t_s.push_back(t);
    d.measured_decel_g.push_back(g + 5.0);
  }
  const Plot plot = MakeDecelerationPlot(d);
  EXPECT_NEAR(plot.y_max, 1.15 * 95.0, 1e-9);
  EXPECT_NEAR(plot.x_max, 11.0, 1e-9);
}

TEST(Figures, AddedMassPngWithFit) {
  ScratchDir dir("fig");
  AddedMassFigureData d;
  d.sigmoid_M_kg = 12.0;
  d.sigmoid_b_per_s = 2500.0;
  d.sigmoid_T_s = 2e-3;
  for (int i = 0; i < 12; ++i) {
    const double t = i / 1600.0;
    d.t_s.push_back(t);
    d.m_add_kg.push_back(AddedMassAt(12.0, 2500.0, 2e-3, t).m_add_kg + 0.3 * std::sin(i));
  }
  const Plot plot = MakeAddedMassPlot(d);
  ASSERT_EQ(plot.series.size(), 2u);
  EXPECT_EQ(plot.series[1].x.size(), 400u);
  PlotAddedMass(d, dir / "madd.png");
  EXPECT_TRUE(IsPngOfSize(dir / "madd.png", 640, 480));
}

TEST(Figures, GenericLogLogPng) {
  ScratchDir dir("fig");
  XyFigureData d;
  d.title = "Work precision";
  d.x_label = "wall time [s]";
  d.y_label = "relative error of crater depth [-]";
  d.log_x = d.log_y = true;
  XySeries a{{1e-5, 3e-5, 1e-4, 4e-4}, {1e-3, 1e-6, 1e-9, 1e-12}, "Dormand-Prince 5(4)"};
  XySeries b{{2e-5, 5e-5, 2e-4, 9e-4}, {1e-4, 1e-7, 1e-10, 1e-12}, "Rosenbrock"};
  d.series = {a, b};
  PlotXy(d, dir / "wp.png");
  EXPECT_TRUE(IsPngOfSize(dir / "wp.png", 640, 480));
}

TEST(Figures, RejectsSeriesOfTheWrongLength) {
  MomentumFigureData d = SyntheticMomentum();
  d.p_gran_Ns.pop_back();
  try {
    MakeMomentumPlot(d);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("p_gran"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace impactdic
