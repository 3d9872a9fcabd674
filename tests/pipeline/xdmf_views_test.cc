// WriteXdmfViews (src/pipeline/outputs/xdmf_writer.cc): the /xdmf views of results.xdmf list
// every [F x N] dataset of /strain and the /dic and /kinematics fields the file holds, and only
// those (the strain group is another module's; a file without it has no strain
// views, one with it needs no change here).
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

#include "../../src/pipeline/outputs/writers.h"
#include "../io/test_dir.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/results_layout.h"

namespace impactdic {
namespace {

namespace L = results_layout;

TEST(XdmfViews, ListEveryStrainFieldAndOnlyTheDatasetsPresent) {
  TestDir dir;
  const std::string path = dir.File("results.h5");
  const std::size_t frames = 2, n = 3;
  const std::vector<double> field = {0, 1, 2, 3, 4, 5};
  {
    H5Writer out(path);
    out.Write(L::kTimeMs, std::vector<double>{0, 1}, "ms", "t");
    out.Write(L::kDicX, std::vector<double>{1, 2, 3}, "px", "x");
    out.Write(L::kDicY, std::vector<double>{4, 5, 6}, "px", "y");
    out.Write(L::kDicU, field, {frames, n}, "px", "u");
    out.Write(L::kDicV, field, {frames, n}, "px", "v");
    out.Write(L::kDicStatus, std::vector<std::int32_t>(6, 0), {frames, n}, "1", "status");
    out.Write(L::kStrainEpsV, field, {frames, n}, "1", "eps_v");
    out.Write(L::kStrainShearBand, std::vector<std::uint8_t>(6, 1), {frames, n}, "1", "band");
    out.Write("/strain/not_a_field", std::vector<double>{1, 2}, "1", "[2], not [F x N]");
    outputs::WriteXdmfViews(out);
    out.Commit();
  }
  const H5Reader in(path);
  EXPECT_EQ(in.List("/xdmf/frame_000001"),
            (std::vector<std::string>{"displacement_px", "eps_v", "shear_band", "status"}));
  EXPECT_EQ(in.ReadDouble("/xdmf/frame_000001/eps_v"), (std::vector<double>{3, 4, 5}));
  EXPECT_EQ(in.Type("/xdmf/frame_000001/shear_band").kind, H5Reader::NumberKind::kUInt);
  EXPECT_EQ(in.ReadDouble(L::kXdmfPoints), (std::vector<double>{1, 4, 2, 5, 3, 6}));
  EXPECT_EQ(in.ReadInt(L::kXdmfVertices), (std::vector<std::int32_t>{0, 1, 2}));
  EXPECT_FALSE(in.Exists("/xdmf/frame_000002"));
}

}  // namespace
}  // namespace impactdic
