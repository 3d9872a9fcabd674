// The continuity post-check (dic/continuity_check.h) on hand-made frame results.
#include "impactdic/dic/continuity_check.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "impactdic/core/error.h"
#include "impactdic/dic/options.h"

namespace impactdic {
namespace {

// A cols x rows grid of converged subsets with u = f(col, row), v = 0, ZNCC 0.99.
FrameResult Grid(int cols, int rows, double (*f)(int, int)) {
  FrameResult r;
  const int n = cols * rows;
  r.status.assign(n, SubsetStatus::kConverged);
  r.zncc.assign(n, 0.99f);
  r.sigma_u_px.assign(n, 0.01f);
  r.sigma_v_px.assign(n, 0.01f);
  r.sigma_px.assign(n, 0.01f);
  r.v_px.assign(n, 0);
  for (int i = 0; i < n; ++i) r.u_px.push_back(f(i % cols, i / cols));
  return r;
}

TEST(ContinuityCheck, AnAffineFieldIsNotFlagged) {
  // 0.05 px per subset step (strain 0.005 at step 10) in x and y.
  const FrameResult r = Grid(12, 9, [](int c, int rw) { return 0.05 * c - 0.03 * rw + 1; });
  const ContinuityFlags flags = CheckContinuity(r, 12, 9, {});
  EXPECT_EQ(flags.flagged, 0);
}

TEST(ContinuityCheck, SubsetsMidwayAcrossAnEdgeAreFlagged) {
  // A body edge between columns 5 and 7: column 6 straddles it and reports a mixture (half the
  // jump): linear across the edge, so only the jump criterion sees it.
  const FrameResult r = Grid(12, 9, [](int c, int) { return c < 6 ? 0.0 : (c == 6 ? 1.0 : 2.0); });
  const ContinuityFlags flags = CheckContinuity(r, 12, 9, {});
  for (int row = 0; row < 9; ++row) {
    EXPECT_TRUE(flags.discontinuous[row * 12 + 6]) << row;
    EXPECT_FALSE(flags.discontinuous[row * 12 + 2]) << row;
    EXPECT_FALSE(flags.discontinuous[row * 12 + 9]) << row;
  }
}

TEST(ContinuityCheck, APoorFitAmongGoodOnesIsFlaggedAndApplied) {
  FrameResult r = Grid(9, 9, [](int, int) { return 0.5; });
  r.zncc[40] = 0.95f;  // 1 - ZNCC five times the neighbours'.
  const ContinuityFlags flags = CheckContinuity(r, 9, 9, {});
  EXPECT_TRUE(flags.misfit[40]);
  EXPECT_EQ(flags.flagged, 1);
  ApplyContinuityFlags(flags, &r);
  EXPECT_EQ(r.status[40], SubsetStatus::kLowCorrelation);
  EXPECT_TRUE(std::isnan(r.u_px[40]));
  EXPECT_EQ(r.status[39], SubsetStatus::kConverged);
}

TEST(ContinuityCheck, RefusesAGridThatDoesNotMatch) {
  const FrameResult r = Grid(4, 4, [](int, int) { return 0.0; });
  EXPECT_THROW(CheckContinuity(r, 5, 4, {}), Error);
  ContinuityCheckOptions bad;
  bad.misfit_ratio = 0.5;
  EXPECT_THROW(CheckContinuity(r, 4, 4, bad), Error);
}

}  // namespace
}  // namespace impactdic
