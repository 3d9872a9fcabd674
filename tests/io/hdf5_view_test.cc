// H5Writer::WriteView (results.xdmf's views, io/hdf5_store.h): an HDF5 virtual dataset reads as
// the row (or whole 1-D dataset) it maps, 0 where nothing is mapped, stores none of the data, and
// a part of the wrong shape is an Error naming the view and the source.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/io/hdf5_store.h"
#include "test_dir.h"

namespace impactdic {
namespace {

TEST(Hdf5View, ReadsTheMappedRowsAndColumnsWithoutCopying) {
  TestDir dir;
  const std::string path = dir.File("views.h5");
  const std::vector<double> u = {1, 2, 3, 4, 5, 6};  // [2 x 3]
  const std::vector<double> v = {-1, -2, -3, -4, -5, -6};
  {
    H5Writer out(path);
    out.Write("/dic/u_px", u, {2, 3}, "px", "u");
    out.Write("/dic/v_px", v, {2, 3}, "px", "v");
    out.Write("/dic/status", std::vector<std::int32_t>{0, 1, 2, 3, 4, 5}, {2, 3}, "1", "s");
    out.Write("/dic/x_px", std::vector<double>{10, 20, 30}, "px", "x");
    EXPECT_TRUE(out.Exists("/dic/u_px"));
    EXPECT_FALSE(out.Exists("/strain/exx"));
    EXPECT_EQ(out.Dimensions("/dic/u_px"), (Dims{2, 3}));
    EXPECT_EQ(out.List("/dic").size(), 4u);
    out.WriteView("/xdmf/f1/displacement", {3, 3}, {{"/dic/u_px", 1, 0}, {"/dic/v_px", 1, 1}}, "px",
                  "row 1 of u, v");
    out.WriteView("/xdmf/f1/status", {3}, {{"/dic/status", 1, 0}}, "1", "row 1 of status");
    out.WriteView("/xdmf/x", {3}, {{"/dic/x_px", std::nullopt, 0}}, "px", "x");
    EXPECT_THROW(out.WriteView("/xdmf/bad", {4}, {{"/dic/u_px", 0, 0}}, "px", "N = 4"), Error);
    EXPECT_THROW(out.WriteView("/xdmf/bad", {3}, {{"/dic/u_px", 2, 0}}, "px", "row 2"), Error);
    EXPECT_THROW(out.WriteView("/xdmf/bad", {3, 2}, {{"/dic/u_px", 0, 2}}, "px", "column 2"),
                 Error);
    out.Commit();
  }
  const H5Reader in(path);
  EXPECT_EQ(in.ReadDouble("/xdmf/f1/displacement"),
            (std::vector<double>{4, -4, 0, 5, -5, 0, 6, -6, 0}));
  EXPECT_EQ(in.ReadInt("/xdmf/f1/status"), (std::vector<std::int32_t>{3, 4, 5}));
  EXPECT_EQ(in.Type("/xdmf/f1/status").kind, H5Reader::NumberKind::kInt);
  EXPECT_EQ(in.Type("/xdmf/f1/status").bytes, 4u);
  EXPECT_EQ(in.Type("/xdmf/f1/displacement").kind, H5Reader::NumberKind::kFloat);
  EXPECT_EQ(in.ReadDouble("/xdmf/x"), (std::vector<double>{10, 20, 30}));
  EXPECT_FALSE(in.Exists("/xdmf/bad"));
}

}  // namespace
}  // namespace impactdic
