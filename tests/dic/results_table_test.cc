// The dic result as the rows of the results layout (dic MakeDicResultsTable): which statuses are
// valid, the reference row, frame indices offset by the first frame.
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <utility>
#include <vector>

#include "impactdic/dic/correlator.h"
#include "impactdic/dic/dic_io.h"
#include "impactdic/dic/options.h"
#include "impactdic/io/dic_results.h"
#include "impactdic/io/results_layout.h"

namespace impactdic {
namespace {

// Two deformed frames of three subsets: subset 1 is masked (the reference's fault), subset 2
// decorrelates in frame 2.
DicResult HandMadeResult() {
  DicResult r;
  r.positions = {{10, 10}, {20, 10}, {30, 10}};
  for (int k = 1; k <= 2; ++k) {
    FrameResult f;
    f.frame = k;
    f.reference_frame = 0;
    f.u_px = {0.5 * k, std::nan(""), k == 2 ? std::nan("") : 0.25};
    f.v_px = {-0.5 * k, std::nan(""), k == 2 ? std::nan("") : 0.75};
    f.zncc = {0.99f, std::nanf(""), 0.9f};
    f.sigma_u_px = f.sigma_v_px = f.sigma_px = {0.01f, std::nanf(""), 0.02f};
    f.iterations = {4, 0, 7};
    f.status = {SubsetStatus::kConverged, SubsetStatus::kMasked,
                k == 2 ? SubsetStatus::kLowCorrelation : SubsetStatus::kConverged};
    r.frames.push_back(f);
  }
  return r;
}

// A result passed by move gives the same table and has its frames' arrays released (the
// pipeline's correlate stage: the subsets x frames results in memory once, not twice).
TEST(ResultsTable, MovedResultGivesTheSameTableAndReleasesItsRows) {
  const DicResult kept = HandMadeResult();
  const DicResultsTable from_copy = MakeDicResultsTable(kept, DicOptions{}, /*first_frame=*/4);
  DicResult moved = HandMadeResult();
  const DicResultsTable from_move =
      MakeDicResultsTable(std::move(moved), DicOptions{}, /*first_frame=*/4);
  EXPECT_EQ(from_move.status, from_copy.status);
  EXPECT_EQ(from_move.iterations, from_copy.iterations);
  EXPECT_EQ(from_move.frame, from_copy.frame);
  EXPECT_EQ(from_move.reference_frame, from_copy.reference_frame);
  ASSERT_EQ(from_move.u_px.size(), from_copy.u_px.size());
  for (std::size_t k = 0; k < from_copy.u_px.size(); ++k) {
    EXPECT_TRUE(from_move.u_px[k] == from_copy.u_px[k] ||
                (std::isnan(from_move.u_px[k]) && std::isnan(from_copy.u_px[k])))
        << k;
  }
  EXPECT_EQ(kept.frames[1].u_px.size(), 3u);  // A const result is left as it was.
  // NOLINTNEXTLINE(bugprone-use-after-move): the rows' release is what is tested.
  for (const FrameResult& f : moved.frames) {
    EXPECT_TRUE(f.u_px.empty() && f.v_px.empty() && f.status.empty() && f.zncc.empty());
  }
}

TEST(ResultsTable, OnlyConvergedIsValidAndReferenceFaultsShowInRowZero) {
  EXPECT_TRUE(IsValidStatus(SubsetStatus::kConverged));
  for (SubsetStatus s : {SubsetStatus::kMaxIterations, SubsetStatus::kLowCorrelation,
                         SubsetStatus::kUncertain, SubsetStatus::kLost, SubsetStatus::kMasked})
    EXPECT_FALSE(IsValidStatus(s)) << ToString(s);
  EXPECT_TRUE(FailsInReference(SubsetStatus::kMasked));
  EXPECT_TRUE(FailsInReference(SubsetStatus::kSaturated));
  EXPECT_FALSE(FailsInReference(SubsetStatus::kLowCorrelation));

  const DicResultsTable t = MakeDicResultsTable(HandMadeResult(), DicOptions{}, /*first_frame=*/4);
  ASSERT_EQ(t.rows, 3u);
  ASSERT_EQ(t.subsets, 3u);
  EXPECT_EQ(t.layout_version, results_layout::kDicLayoutVersion);
  // Row 0: the reference: zero displacement, valid, except the masked subset.
  EXPECT_EQ(t.u_px[0], 0.0);
  EXPECT_TRUE(t.IsValid(0));
  EXPECT_TRUE(std::isnan(t.u_px[1]));
  EXPECT_EQ(t.status[1], static_cast<int>(SubsetStatus::kMasked));
  EXPECT_FALSE(t.IsValid(1));
  EXPECT_TRUE(t.IsValid(2));  // Decorrelates only later.
  // Row 2 (frame 2): subset 2 invalid there.
  EXPECT_EQ(t.u_px[2 * 3 + 0], 1.0);
  EXPECT_FALSE(t.IsValid(2 * 3 + 2));
  // Frame indices in the camera sequence: the first reference is frame 4.
  EXPECT_EQ(t.frame, (std::vector<std::int32_t>{4, 5, 6}));
  EXPECT_EQ(t.reference_frame, (std::vector<std::int32_t>{4, 4, 4}));
  EXPECT_EQ(t.first_frame, 4);
  // Unknown first frame (`impactdic correlate`): indices of the images given, no attribute.
  const DicResultsTable c = MakeDicResultsTable(HandMadeResult(), DicOptions{}, -1);
  EXPECT_EQ(c.frame, (std::vector<std::int32_t>{0, 1, 2}));
  EXPECT_EQ(c.first_frame, -1);
}

}  // namespace
}  // namespace impactdic
