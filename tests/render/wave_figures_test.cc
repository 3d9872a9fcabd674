// The wave figures (render/wave_figures.h) from a synthetic wave whose front runs down at a known
// speed: what each plot holds, and the space-time PNG's pixels show the front running downward.
#include "impactdic/render/wave_figures.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "impactdic/core/error.h"
#include "test_util.h"

namespace impactdic {
namespace {

using test::IsPngOfSize;
using test::ScratchDir;

constexpr double kSpeed = 80;  // [m/s] = [mm/ms]

// A centre line of rows every 5 mm down to 200 mm, frames every 0.2 ms from -1 to 6 ms; the
// downward velocity is a pulse of 2 m/s arriving at depth / kSpeed; two base sensors at 600 mm.
WaveResult SyntheticWave() {
  WaveResult w;
  SpaceTime& st = w.front.space_time;
  for (int r = 0; r < 40; ++r) st.depth_mm.push_back(5.0 * r);
  for (int f = 0; f <= 35; ++f) {
    const double t_ms = -1 + 0.2 * f;
    st.time_s.push_back(1e-3 * t_ms);
    st.pounder_base_mm.push_back(std::max(0.0, 3 * t_ms));
    for (double z : st.depth_mm) {
      const double arrival = z / kSpeed;
      st.velocity_mm_s.push_back(t_ms < arrival ? 0 : 2000 * std::exp(-(t_ms - arrival) / 1.5));
    }
  }
  w.front.computed = true;
  w.front.speed_m_s = kSpeed;
  w.front.speed_ci_m_s = {78, 82};
  w.front.intercept_s = 0;
  w.pounder_peak_s = 1e-3;
  for (const auto& [name, offset] : {std::pair{"base_center_N", 0.0}, {"base_offset_N", 300.0}}) {
    WaveChannel& c = w.channels.emplace_back();
    c.column = name;
    c.depth_mm = 600;
    c.offset_mm = offset;
    c.distance_mm = std::hypot(600.0, offset);
    c.onset_s = 1e-3 * c.distance_mm / kSpeed;
    c.peak_s = c.onset_s + 1e-3;
    c.return_time_s = 2 * 600 / kSpeed * 1e-3;
    c.return_time_sigma_s = 1e-4;
  }
  DepthDecayFit& d = w.front.displacement_te;
  d.time_s = 2e-3;
  d.surface_value = 4;
  d.decay_length_mm = 50;
  d.decay_length_ci_mm = {45, 56};
  d.depth_of_influence_mm = 10 + 50 * std::log(10);
  for (int k = 0; k < 30; ++k) {
    d.profile_depth_mm.push_back(5.0 * k + 1);
    d.profile_value.push_back(4 * std::exp(-(5.0 * k + 1) / 50));
    d.profile_in_fit.push_back(k < 25 ? 1 : 0);
  }
  w.front.pounder_base_depth_mm = 10;
  return w;
}

TEST(WaveFigures, SpaceTimeHasACellPerFrameAndRowTheFrontAndTheArrivals) {
  const WaveResult w = SyntheticWave();
  const Plot plot = MakeSpaceTimePlot(w);
  EXPECT_EQ(plot.cells.value.size(), 36u * 40u);
  EXPECT_TRUE(plot.reverse_y);
  EXPECT_NEAR(plot.cells.half_width, 0.1, 1e-12);  // Half the frame interval [ms].
  EXPECT_NEAR(plot.cells.half_height, 2.5, 1e-12);
  // The pounder's base, the front line and an onset and a peak per sensor.
  ASSERT_EQ(plot.series.size(), 6u);
  const PlotSeries& front = plot.series[1];
  EXPECT_NE(front.label.find("c = 80.0 m/s"), std::string::npos) << front.label;
  // The front reaches the deepest sensor (600 mm) at 600 / 80 = 7.5 ms.
  EXPECT_NEAR(front.x.back(), 7.5, 1e-12);
  EXPECT_NEAR(front.y.back(), 600, 1e-12);
  EXPECT_NEAR(plot.series[2].x[0], 7.5, 1e-12);  // base_center_N's onset [ms]
}

TEST(WaveFigures, SpaceTimePngShowsTheFrontRunningDownward) {
  ScratchDir dir("wave");
  WaveResult w = SyntheticWave();
  w.channels.clear();  // The field only: the PNG's red cells are the pulse.
  w.front.speed_m_s = kNaN;
  PlotSpaceTime(w, dir / "st.png");
  ASSERT_TRUE(IsPngOfSize(dir / "st.png", 640, 480));
  int rows = 0;
  EXPECT_GT(test::FrontRankCorrelation(dir / "st.png", &rows), 0.95);
  EXPECT_GT(rows, 200);
  // A front running upward (arrival decreasing with depth) gives the opposite sign: the check
  // reads the figure, not the fact that it exists.
  SpaceTime& st = w.front.space_time;
  const std::size_t R = st.rows();
  for (std::size_t f = 0; f < st.time_s.size(); ++f)
    for (std::size_t r = 0; r < R; ++r) {
      const double arrival = st.depth_mm[R - 1 - r] / kSpeed, t_ms = 1e3 * st.time_s[f];
      st.velocity_mm_s[f * R + r] = t_ms < arrival ? 0 : 2000 * std::exp(-(t_ms - arrival) / 1.5);
    }
  PlotSpaceTime(w, dir / "up.png");
  EXPECT_LT(test::FrontRankCorrelation(dir / "up.png", &rows), -0.9);
}

TEST(WaveFigures, SpaceTimeWithoutDataIsRefused) {
  WaveResult w;
  EXPECT_THROW(MakeSpaceTimePlot(w), Error);
}

TEST(WaveFigures, BaseForceHasEachRecordItsArrivalsAndTheReturnTimes) {
  const WaveResult w = SyntheticWave();
  std::vector<double> t_s;
  std::vector<BaseForceRecord> records = {{"base_center_N", {}}, {"base_offset_N", {}}};
  for (int k = -200; k < 4000; ++k) {
    const double t = k * 1e-5;
    t_s.push_back(t);
    for (std::size_t i = 0; i < 2; ++i) {
      const double p = w.channels[i].peak_s;
      records[i].force_n.push_back(20 * std::exp(-std::pow((t - p) / 1e-3, 2)));
    }
  }
  const Plot plot = MakeBaseForcePlot(t_s, records, w);
  ASSERT_EQ(plot.series.size(), 6u);           // A record, its onset and its peak, per channel.
  EXPECT_NEAR(plot.series[2].y[0], 20, 1e-9);  // The peak marker sits on the record's peak.
  // The return time of each channel (one label: the same depth) and the pounder's peak.
  ASSERT_EQ(plot.markers.size(), 3u);
  EXPECT_NEAR(plot.markers[0].value, 15, 1e-9);
  EXPECT_EQ(plot.markers[0].label, "return 15.0 ms");
  EXPECT_EQ(plot.markers[1].label, "");
  EXPECT_EQ(plot.markers[2].label, "pounder peak");
  // The window ends a quarter past the later of the return time + 3 sigma (15.3 ms) and twice
  // the latest peak (the offset sensor's: 2 x (670.8 / 80 + 1) = 18.77 ms).
  EXPECT_NEAR(plot.x_max, 1.25 * 2 * 1e3 * w.channels[1].peak_s, 1e-9);
  ScratchDir dir("wave");
  PlotBaseForce(t_s, records, w, dir / "base.png");
  EXPECT_TRUE(IsPngOfSize(dir / "base.png", 640, 480));
  records[1].force_n.pop_back();
  EXPECT_THROW(MakeBaseForcePlot(t_s, records, w), Error);
}

TEST(WaveFigures, DepthProfileHasThePointsTheFitAndTheDepthOfInfluence) {
  const WaveResult w = SyntheticWave();
  const Plot plot = MakeDepthProfilePlot(w.front);
  EXPECT_TRUE(plot.log_y);
  ASSERT_EQ(plot.series.size(), 3u);  // In the fit, below the noise, the fit.
  EXPECT_EQ(plot.series[0].x.size(), 25u);
  EXPECT_EQ(plot.series[1].x.size(), 5u);
  EXPECT_NEAR(plot.series[2].y.front(), 4, 1e-12);
  EXPECT_NE(plot.series[2].label.find("lambda = 50.0 mm [45.0, 56.0]"), std::string::npos);
  ASSERT_EQ(plot.markers.size(), 1u);
  EXPECT_NEAR(plot.markers[0].value, 50 * std::log(10), 1e-9);
  ScratchDir dir("wave");
  PlotDepthProfile(w.front, dir / "profile.png");
  EXPECT_TRUE(IsPngOfSize(dir / "profile.png", 640, 480));
  EXPECT_THROW(MakeDepthProfilePlot(WaveFront{}), Error);
}

}  // namespace
}  // namespace impactdic
