// The one DIC results layout (io/dic_results.h): what the writer writes the reader reads back,
// with its layout_version; files of the earlier layouts (version 1 of `impactdic run` and of
// `impactdic correlate`, written here with plain H5Writer calls as those versions wrote them) are
// read into the same rows.
#include "impactdic/io/dic_results.h"

#include <gtest/gtest.h>

#include <cmath>

#include "../core/expect_error.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/results_layout.h"
#include "test_dir.h"

namespace impactdic {
namespace {

namespace L = results_layout;

// 3 rows (the reference and two deformed frames) x 2 subsets; subset 1 fails in frame 2.
DicResultsTable SmallTable() {
  DicResultsTable t;
  t.rows = 3;
  t.subsets = 2;
  t.x_px = {10, 20};
  t.y_px = {30, 40};
  t.u_px = {0, 0, 0.25, 0.5, 0.75, std::nan("")};
  t.v_px = {0, 0, -0.125, 1, 2, std::nan("")};
  t.status = {0, 0, 0, 0, 0, 2};
  t.iterations = {0, 0, 4, 5, 6, 20};
  t.zncc = {1, 1, 0.99f, 0.98f, 0.97f, 0.2f};
  t.sigma_u_px = {0, 0, 0.01f, 0.02f, 0.03f, std::nanf("")};
  t.sigma_v_px = {0, 0, 0.02f, 0.03f, 0.04f, std::nanf("")};
  t.sigma_px = {0, 0, 0.02f, 0.03f, 0.04f, std::nanf("")};
  t.frame = {7, 8, 9};
  t.reference_frame = {7, 7, 7};
  t.frame_number = {107, 108, 109};
  t.first_frame = 7;
  t.status_codes = "0=converged, 2=low_correlation";
  t.text_attributes = {{"shape", "affine"}};
  t.number_attributes = {{"subset_size_px", 21}};
  return t;
}

void ExpectSameRows(const DicResultsTable& a, const DicResultsTable& b) {
  ASSERT_EQ(a.rows, b.rows);
  ASSERT_EQ(a.subsets, b.subsets);
  EXPECT_EQ(a.x_px, b.x_px);
  EXPECT_EQ(a.y_px, b.y_px);
  for (std::size_t k = 0; k < a.u_px.size(); ++k) {
    EXPECT_TRUE(a.u_px[k] == b.u_px[k] || (std::isnan(a.u_px[k]) && std::isnan(b.u_px[k]))) << k;
    EXPECT_TRUE(a.v_px[k] == b.v_px[k] || (std::isnan(a.v_px[k]) && std::isnan(b.v_px[k]))) << k;
  }
  EXPECT_EQ(a.status, b.status);
  EXPECT_EQ(a.frame, b.frame);
}

TEST(DicResults, WrittenTableIsReadBackWithItsLayoutVersion) {
  TestDir dir;
  const std::string path = dir.File("r.h5");
  const DicResultsTable t = SmallTable();
  {
    H5Writer out(path);
    WriteDicResults(out, t);
    out.Commit();
  }
  const H5Reader in(path);
  EXPECT_EQ(in.ReadNumberAttribute(L::kDicGroup, L::kLayoutVersionAttr), L::kDicLayoutVersion);
  // One name per attribute: the status codes under `codes` only.
  EXPECT_EQ(in.ReadStringAttribute(L::kDicStatus, L::kStatusCodesAttr), t.status_codes);
  EXPECT_FALSE(in.HasAttribute(L::kDicStatus, "status_names"));
  EXPECT_EQ(in.ReadStringAttribute(L::kDicGroup, "shape"), "affine");
  EXPECT_EQ(in.ReadNumberAttribute(L::kDicGroup, "subset_size_px"), 21);
  const DicResultsTable r = ReadDicResults(in, path);
  EXPECT_EQ(r.layout_version, L::kDicLayoutVersion);
  ExpectSameRows(t, r);
  EXPECT_EQ(r.iterations, t.iterations);
  EXPECT_EQ(r.zncc, t.zncc);
  EXPECT_EQ(r.reference_frame, t.reference_frame);
  EXPECT_EQ(r.frame_number, t.frame_number);
  EXPECT_EQ(r.first_frame, 7);
  EXPECT_EQ(r.status_codes, t.status_codes);
  // Valid: converged only.
  EXPECT_TRUE(r.IsValid(4));
  EXPECT_FALSE(r.IsValid(5));
}

// As `impactdic correlate -o X.h5` wrote it before layout versions: the deformed images only
// (F - 1 rows), /dic/frame 1-based, u/v double, the codes under two names.

// DicFields::kDisplacements (render's velocity field): the same grid, displacements and row
// indices, without the four per-sample arrays of status and quality.
TEST(DicResults, DisplacementsOnlyReadsTheMotionWithoutTheQualityArrays) {
  TestDir dir;
  const std::string path = dir.File("r.h5");
  const DicResultsTable t = SmallTable();
  {
    H5Writer out(path);
    WriteDicResults(out, t);
    out.Commit();
  }
  const DicResultsTable r = ReadDicResults(H5Reader(path), path, DicFields::kDisplacements);
  DicResultsTable expected = t;
  expected.status.clear();
  ExpectSameRows(expected, r);
  EXPECT_EQ(r.reference_frame, t.reference_frame);
  EXPECT_EQ(r.frame_number, t.frame_number);
  EXPECT_EQ(r.first_frame, t.first_frame);
  EXPECT_TRUE(r.status.empty());
  EXPECT_TRUE(r.iterations.empty());
  EXPECT_TRUE(r.zncc.empty());
  EXPECT_TRUE(r.sigma_u_px.empty() && r.sigma_v_px.empty() && r.sigma_px.empty());
}
TEST(DicResults, ReadsTheVersion1CorrelateLayoutWithTheReferenceRowPrepended) {
  TestDir dir;
  const std::string path = dir.File("correlate_v1.h5");
  const DicResultsTable want = SmallTable();
  {
    H5Writer out(path);
    const Dims fn{2, 2};
    out.Write("dic/x_px", want.x_px, "px", "x");
    out.Write("dic/y_px", want.y_px, "px", "y");
    out.Write("dic/u_px", std::vector<double>(want.u_px.begin() + 2, want.u_px.end()), fn, "px",
              "u");
    out.Write("dic/v_px", std::vector<double>(want.v_px.begin() + 2, want.v_px.end()), fn, "px",
              "v");
    out.Write("dic/zncc", std::vector<float>{0.99f, 0.98f, 0.97f, 0.2f}, fn, "1", "zncc");
    out.Write("dic/status", std::vector<std::int32_t>{0, 0, 0, 2}, fn, "1", "status");
    out.Write("dic/iterations", std::vector<std::int32_t>{4, 5, 6, 20}, fn, "1", "iterations");
    out.Write("dic/frame", std::vector<std::int32_t>{1, 2}, Dims{2}, "1", "1-based");
    out.Write("dic/frame_number", std::vector<double>{108, 109}, "1", "from the names");
    out.Write("dic/reference_frame", std::vector<std::int32_t>{0, 0}, Dims{2}, "1", "ref");
    out.SetAttribute("dic/status", "codes", "0=converged");
    out.SetAttribute("dic/status", "status_names", "0=converged");
    out.SetAttribute("dic", "shape_function", "affine");
    out.Commit();
  }
  const DicResultsTable r = ReadDicResults(H5Reader(path), path);
  EXPECT_EQ(r.layout_version, 1);
  DicResultsTable expected = want;
  expected.frame = {0, 1, 2};
  ExpectSameRows(expected, r);
  EXPECT_EQ(r.zncc, (std::vector<float>{1, 1, 0.99f, 0.98f, 0.97f, 0.2f}));
  EXPECT_EQ(r.iterations, (std::vector<std::int32_t>{0, 0, 4, 5, 6, 20}));
  EXPECT_EQ(r.reference_frame, (std::vector<std::int32_t>{0, 0, 0}));
  EXPECT_EQ(r.frame_number[1], 108);
  EXPECT_EQ(r.first_frame, -1);  // Not known: the caller's default applies.
  EXPECT_EQ(r.status_codes, "0=converged");
}

// As `impactdic run` wrote results.h5 before layout versions: the reference row included, u/v as
// float, no /dic/frame but /time/frame_index, the codes under `status_names` (and `codes`).
TEST(DicResults, ReadsTheVersion1RunLayout) {
  TestDir dir;
  const std::string path = dir.File("run_v1.h5");
  const DicResultsTable want = SmallTable();
  {
    H5Writer out(path);
    const Dims fn{3, 2};
    out.Write("/time/t_ms", std::vector<double>{-0.1, 0.5, 1.1}, "ms", "t");
    out.Write("/time/frame_index", std::vector<double>{7, 8, 9}, "1", "index");
    out.Write("/dic/x_px", want.x_px, "px", "x");
    out.Write("/dic/y_px", want.y_px, "px", "y");
    out.Write("/dic/u_px", std::vector<float>(want.u_px.begin(), want.u_px.end()), fn, "px", "u");
    out.Write("/dic/v_px", std::vector<float>(want.v_px.begin(), want.v_px.end()), fn, "px", "v");
    out.Write("/dic/status", want.status, fn, "1", "status");
    out.Write("/dic/sigma_u_px", want.sigma_u_px, fn, "px", "su");
    out.Write("/dic/sigma_v_px", want.sigma_v_px, fn, "px", "sv");
    out.SetAttribute("/dic/status", "status_names", "0=converged, 2=low_correlation");
    out.SetAttribute("/dic", "first_frame", 7.0);
    out.Commit();
  }
  const DicResultsTable r = ReadDicResults(H5Reader(path), path);
  EXPECT_EQ(r.layout_version, 1);
  ExpectSameRows(want, r);  // The values are exact in float.
  EXPECT_EQ(r.sigma_u_px.size(), want.sigma_u_px.size());
  EXPECT_EQ(r.first_frame, 7);
  EXPECT_EQ(r.status_codes, "0=converged, 2=low_correlation");
}

TEST(DicResults, BadFilesAreNamedWithTheDataset) {
  TestDir dir;
  // A layout newer than this build.
  const std::string newer = dir.File("newer.h5");
  {
    H5Writer out(newer);
    WriteDicResults(out, SmallTable());
    out.SetAttribute(L::kDicGroup, L::kLayoutVersionAttr, 99.0);
    out.Commit();
  }
  ExpectErrorContaining([&] { ReadDicResults(H5Reader(newer), newer); }, "layout_version");
  ExpectErrorContaining([&] { ReadDicResults(H5Reader(newer), newer); }, "newer.h5");
  // Version 1 frame indices that are not one per row.
  const std::string gaps = dir.File("gaps.h5");
  {
    H5Writer out(gaps);
    out.Write("dic/x_px", std::vector<double>{1}, "px", "x");
    out.Write("dic/y_px", std::vector<double>{1}, "px", "y");
    out.Write("dic/u_px", std::vector<double>{0, 1}, Dims{2, 1}, "px", "u");
    out.Write("dic/v_px", std::vector<double>{0, 1}, Dims{2, 1}, "px", "v");
    out.Write("dic/frame", std::vector<std::int32_t>{1, 3}, Dims{2}, "1", "gap");
    out.Commit();
  }
  ExpectErrorContaining([&] { ReadDicResults(H5Reader(gaps), gaps); }, "/dic/frame");
  // No displacement at all.
  const std::string empty = dir.File("empty.h5");
  {
    H5Writer out(empty);
    out.Write("other/x", std::vector<double>{1}, "1", "x");
    out.Commit();
  }
  ExpectErrorContaining([&] { ReadDicResults(H5Reader(empty), empty); }, "/dic/x_px");
}

}  // namespace
}  // namespace impactdic
