// The continuity post-check (dic/continuity_check.h) on hand-made frame results.
#include "impactdic/dic/continuity_check.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
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

TEST(ContinuityCheck, ALargeSmoothStrainAtACoarseStepIsNotFlagged) {
  // As in the committed sample (step 32 px under the pounder): adjacent subsets differ by
  // 0.6..1.04 px and the second difference is 0.04 px everywhere; nothing is discontinuous.
  const FrameResult r = Grid(12, 9, [](int c, int) { return 0.6 * c + 0.02 * c * c; });
  EXPECT_EQ(CheckContinuity(r, 12, 9, {}).flagged, 0);
  // The thresholds alone (no comparison with the neighbourhood) flag it.
  ContinuityCheckOptions absolute;
  absolute.local_ratio = std::numeric_limits<double>::infinity();
  EXPECT_GT(CheckContinuity(r, 12, 9, absolute).flagged, 50);
}

TEST(ContinuityCheck, ASubsetMidwayAcrossASmallSlipIsFlagged) {
  // The 4096 x 3000 realistic pair's deep shear band: a slip of 1.3 px, the subset across it
  // reports 0.65 px (half of each side), linear across: only the jump (0.65 px) sees it.
  const FrameResult r = Grid(12, 9, [](int c, int) { return c < 6 ? 1.3 : (c == 6 ? 0.65 : 0.0); });
  const ContinuityFlags flags = CheckContinuity(r, 12, 9, {});
  for (int row = 0; row < 9; ++row) {
    EXPECT_TRUE(flags.discontinuous[row * 12 + 6]) << row;
    EXPECT_FALSE(flags.discontinuous[row * 12 + 3]) << row;
    EXPECT_FALSE(flags.discontinuous[row * 12 + 9]) << row;
  }
}

TEST(ContinuityCheck, AStrongGradientAlongTheBandDoesNotHideAJumpAcrossIt) {
  // The realistic scene's core under the pounder: its displacement decays with depth by 0.6 px
  // per grid step (row), while a vertical shear band between columns 4 and 6 makes a jump across
  // the rows; column 5 straddles it (half of each side). The differences are compared with the
  // neighbourhood per grid direction: the vertical gradient does not raise the horizontal median.
  const FrameResult r = Grid(12, 9, [](int c, int rw) {
    const double core = 0.6 * rw + 1;
    return c < 5 ? 0.0 : (c == 5 ? 0.5 * core : core);
  });
  const ContinuityFlags flags = CheckContinuity(r, 12, 9, {});
  for (int row = 0; row < 9; ++row) {
    EXPECT_TRUE(flags.discontinuous[row * 12 + 5]) << row;
    EXPECT_FALSE(flags.discontinuous[row * 12 + 2]) << row;
    EXPECT_FALSE(flags.discontinuous[row * 12 + 9]) << row;
  }
}

TEST(ContinuityCheck, SmallVariationsOfAGoodFitAreNotMisfits) {
  // Clean speckle: 1 - ZNCC 5x its neighbours' but only 0.001 (below min_misfit).
  FrameResult r = Grid(9, 9, [](int, int) { return 0.5; });
  r.zncc.assign(81, 0.9998f);
  r.zncc[40] = 0.999f;
  ContinuityCheckOptions misfit;
  misfit.misfit_ratio = 2.5;
  EXPECT_EQ(CheckContinuity(r, 9, 9, misfit).flagged, 0);
  ContinuityCheckOptions no_floor = misfit;
  no_floor.min_misfit = 0;
  EXPECT_TRUE(CheckContinuity(r, 9, 9, no_floor).misfit[40]);
}

TEST(ContinuityCheck, APoorFitAmongGoodOnesIsFlaggedAndApplied) {
  FrameResult r = Grid(9, 9, [](int, int) { return 0.5; });
  r.zncc[40] = 0.95f;  // 1 - ZNCC five times the neighbours'.
  // The misfit criterion is off by default (ContinuityCheckOptions::misfit_ratio).
  EXPECT_EQ(CheckContinuity(r, 9, 9, {}).flagged, 0);
  ContinuityCheckOptions misfit;
  misfit.misfit_ratio = 2.5;
  const ContinuityFlags flags = CheckContinuity(r, 9, 9, misfit);
  EXPECT_TRUE(flags.misfit[40]);
  EXPECT_EQ(flags.flagged, 1);
  ApplyContinuityFlags(flags, &r);
  EXPECT_EQ(r.status[40], SubsetStatus::kDiscontinuous);
  EXPECT_TRUE(std::isnan(r.u_px[40]));
  EXPECT_EQ(r.status[39], SubsetStatus::kConverged);
}

TEST(ContinuityCheck, RefusesAGridThatDoesNotMatch) {
  const FrameResult r = Grid(4, 4, [](int, int) { return 0.0; });
  EXPECT_THROW(CheckContinuity(r, 5, 4, {}), Error);
  ContinuityCheckOptions bad;
  bad.misfit_ratio = 0.5;
  EXPECT_THROW(CheckContinuity(r, 4, 4, bad), Error);
  // Each bad field is named.
  const auto expect_names = [&r](ContinuityCheckOptions o, const std::string& name) {
    try {
      CheckContinuity(r, 4, 4, o);
      ADD_FAILURE() << name;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  };
  ContinuityCheckOptions o;
  o.min_misfit = 1;
  expect_names(o, "dic.continuity.min_misfit");
  o = {};
  o.max_second_difference_px = 0;
  expect_names(o, "dic.continuity.max_second_difference_px");
  o = {};
  o.max_neighbour_difference_px = -1;
  expect_names(o, "dic.continuity.max_neighbour_difference_px");
  o = {};
  o.local_ratio = 1;
  expect_names(o, "dic.continuity.local_ratio");
}

}  // namespace
}  // namespace impactdic
