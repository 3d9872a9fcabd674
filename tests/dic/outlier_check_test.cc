// The normalized median test (dic/outlier_check.h) on hand-made frame results.
#include "impactdic/dic/outlier_check.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/dic/options.h"

namespace impactdic {
namespace {

constexpr int kCols = 12, kRows = 10;

// A converged grid with displacement u(col, row), v(col, row) and sigma 0.01 px.
template <typename U, typename V>
FrameResult Field(U u, V v) {
  FrameResult f;
  const int n = kCols * kRows;
  f.u_px.resize(n);
  f.v_px.resize(n);
  f.zncc.assign(n, 0.99f);
  f.sigma_u_px.assign(n, 0.01f);
  f.sigma_v_px.assign(n, 0.01f);
  f.sigma_px.assign(n, 0.01f);
  f.iterations.assign(n, 3);
  f.status.assign(n, SubsetStatus::kConverged);
  for (int r = 0; r < kRows; ++r) {
    for (int c = 0; c < kCols; ++c) {
      f.u_px[r * kCols + c] = u(c, r);
      f.v_px[r * kCols + c] = v(c, r);
    }
  }
  return f;
}

std::vector<int> Flagged(const FrameResult& f, const OutlierCheckOptions& options = {}) {
  const OutlierFlags flags = FindOutliers(f, kCols, kRows, options);
  std::vector<int> which;
  for (std::size_t i = 0; i < flags.outlier.size(); ++i)
    if (flags.outlier[i]) which.push_back(static_cast<int>(i));
  EXPECT_EQ(flags.flagged, static_cast<int>(which.size()));
  return which;
}

// Spurious vectors in a smooth field are found, and only they.
TEST(OutlierCheck, FindsSpuriousVectorsInASmoothField) {
  FrameResult f = Field([](int c, int r) { return 0.3 * c + 0.1 * r; },
                        [](int c, int r) { return 2 * std::sin(0.3 * c) + 0.05 * r; });
  const std::vector<int> spikes = {2 * kCols + 3, 5 * kCols + 8, 8 * kCols + 1};
  f.u_px[spikes[0]] += 1.5;
  f.v_px[spikes[1]] -= 2.0;
  f.u_px[spikes[2]] += 1.2;
  f.v_px[spikes[2]] += 1.2;
  EXPECT_EQ(Flagged(f), spikes);
  const OutlierFlags flags = FindOutliers(f, kCols, kRows, OutlierCheckOptions{});
  ApplyOutlierFlags(flags, &f);
  for (const int i : spikes) {
    EXPECT_EQ(f.status[i], SubsetStatus::kOutlier);
    EXPECT_TRUE(std::isnan(f.u_px[i]) && std::isnan(f.v_px[i]) && std::isnan(f.sigma_px[i]));
  }
}

// Coherent motion with a strong gradient (the soil under a pounder: 3 px per grid step at the
// top, decaying with depth) and a jump between two bodies (a shear band: 4 px between two
// columns) are the motion the tool exists to measure: nothing is flagged.
TEST(OutlierCheck, KeepsCoherentHighGradientMotionAndShearBands) {
  const FrameResult core = Field([](int c, int r) { return 0.2 * (c - 6) * std::exp(-0.2 * r); },
                                 [](int c, int r) {
                                   const double x = (c - 5.5) / 2.5;
                                   return 12 * std::exp(-0.5 * x * x) * std::exp(-0.25 * r);
                                 });
  EXPECT_TRUE(Flagged(core).empty());
  const FrameResult band = Field([](int, int) { return 0.0; },
                                 [](int c, int r) { return (c >= 6 ? 4.0 : 0.0) + 0.01 * r; });
  EXPECT_TRUE(Flagged(band).empty());
}

// A poorly textured subset that departs from its neighbours within its own uncertainty is kept
// (reported with its sigma); the same departure with a small sigma is an outlier.
TEST(OutlierCheck, KeepsADepartureWithinTheSubsetsOwnSigma) {
  FrameResult f = Field([](int c, int) { return 0.1 * c; }, [](int, int r) { return 0.1 * r; });
  const int i = 4 * kCols + 5;
  f.u_px[i] += 0.5;
  f.sigma_u_px[i] = f.sigma_v_px[i] = f.sigma_px[i] = 0.2f;  // 3 sigma = 0.85 px.
  EXPECT_TRUE(Flagged(f).empty());
  f.sigma_u_px[i] = f.sigma_v_px[i] = f.sigma_px[i] = 0.02f;
  EXPECT_EQ(Flagged(f), std::vector<int>{i});
}

// Failed subsets are neither judged nor used; neighbours count in opposite pairs that both
// converged, and a subset with fewer than min_neighbours of them (the grid's edge: one pair) is
// not judged.
TEST(OutlierCheck, IgnoresFailedSubsetsAndNeedsNeighbourPairs) {
  FrameResult f = Field([](int, int) { return 1.0; }, [](int, int) { return 0.0; });
  const int i = 3 * kCols + 3;
  f.u_px[i] = 5;
  // Fail one of each pair but the row pair: one pair (2 neighbours) left.
  for (const int j : {2 * kCols + 2, 2 * kCols + 3, 2 * kCols + 4}) {
    f.status[j] = SubsetStatus::kLowCorrelation;
    f.u_px[j] = f.v_px[j] = std::numeric_limits<double>::quiet_NaN();
  }
  EXPECT_TRUE(Flagged(f).empty());
  OutlierCheckOptions one_pair;
  one_pair.min_neighbours = 2;
  EXPECT_EQ(Flagged(f, one_pair), std::vector<int>{i});
  // A spike on the grid's edge is not judged by default (one pair along the edge).
  FrameResult edge = Field([](int, int) { return 1.0; }, [](int, int) { return 0.0; });
  edge.u_px[5] = 5;
  EXPECT_TRUE(Flagged(edge).empty());
}

TEST(OutlierCheck, OptionsAreChecked) {
  OutlierCheckOptions o;
  EXPECT_NO_THROW(o.Check());
  o.threshold = 0;
  EXPECT_THROW(o.Check(), Error);
  o = {};
  o.noise_px = -1;
  EXPECT_THROW(o.Check(), Error);
  o = {};
  o.min_neighbours = 1;
  EXPECT_THROW(o.Check(), Error);
}

}  // namespace
}  // namespace impactdic
