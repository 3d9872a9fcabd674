#include "impactdic/io/hdf5_store.h"

#include <H5Cpp.h>
#include <gtest/gtest.h>
#include <stdio.h>

#include <cmath>
#include <filesystem>
#include <random>

#include "impactdic/core/error.h"
#include "impactdic/core/version.h"
#include "impactdic/io/input_file.h"
#include "test_dir.h"

namespace impactdic {
namespace {

TEST(Hdf5Store, RoundTripOfValuesUnitsAttributesAndProvenance) {
  TestDir dir;
  const std::string path = dir.File("results.h5");
  std::vector<double> series = {0.0, 1.5, -2.25, std::nan("")};
  std::vector<float> field(3 * 4 * 5 * 2);
  for (std::size_t i = 0; i < field.size(); ++i) field[i] = 0.5f * static_cast<float>(i);
  std::vector<std::int32_t> status = {0, 1, 2, 3, 4, 5};
  {
    H5Writer out(path);
    out.WriteProvenance("name: demo\n");
    out.Write("sensor/t_s", series, "s", "time since impact");
    out.Write("dic/field", field, {3, 4, 5, 2}, "px", "a 4-D field");
    out.Write("dic/status", status, {2, 3}, "1", "status codes");
    out.SetAttribute("dic", "interpolation", "bicubic");
    out.SetAttribute("dic/field", "scale_mm_per_px", 0.25);
    out.Commit();
  }
  H5Reader in(path);
  Dims dims;
  const auto t = in.ReadDouble("sensor/t_s", &dims);
  ASSERT_EQ(dims, Dims{4});
  EXPECT_EQ(t[1], 1.5);
  EXPECT_EQ(t[2], -2.25);
  EXPECT_TRUE(std::isnan(t[3]));
  EXPECT_EQ(in.ReadStringAttribute("sensor/t_s", "units"), "s");
  EXPECT_EQ(in.ReadStringAttribute("sensor/t_s", "description"), "time since impact");
  const auto f = in.ReadFloat("dic/field", &dims);
  EXPECT_EQ(dims, (Dims{3, 4, 5, 2}));
  EXPECT_EQ(f, field);
  const auto s = in.ReadInt("/dic/status", &dims);
  EXPECT_EQ(dims, (Dims{2, 3}));
  EXPECT_EQ(s, status);
  EXPECT_EQ(in.ReadStringAttribute("dic", "interpolation"), "bicubic");
  EXPECT_EQ(in.ReadNumberAttribute("dic/field", "scale_mm_per_px"), 0.25);
  EXPECT_EQ(in.ReadStringAttribute("/", "tool_version"), Version());
  EXPECT_EQ(in.ReadStringAttribute("/", "git_revision"), GitRevision());
  EXPECT_EQ(in.ReadStringAttribute("/provenance", "scene_yaml"), "name: demo\n");
  EXPECT_TRUE(in.Exists("dic/field"));
  EXPECT_FALSE(in.Exists("dic/nothing/here"));
  const auto members = in.List("dic");
  EXPECT_EQ(members.size(), 2u);
}

TEST(Hdf5Store, UnsignedImagesAreStoredWithTheirDepthAndReadConverted) {
  TestDir dir;
  const std::string path = dir.File("frames.h5");
  const std::vector<std::uint8_t> grey8 = {0, 1, 127, 255, 200, 3};
  const std::vector<std::uint16_t> grey16 = {0, 1, 4095, 65535, 40000, 7};
  {
    H5Writer out(path);
    out.Write("frames/u8", grey8, {2, 3}, "grey level", "8-bit");
    out.Write("frames/u16", grey16, {3, 2}, "grey level", "16-bit");
    out.Commit();
  }
  H5Reader in(path);
  Dims dims;
  const auto a = in.ReadFloat("frames/u8", &dims);
  EXPECT_EQ(dims, (Dims{2, 3}));
  const auto b = in.ReadInt("frames/u16", &dims);
  EXPECT_EQ(dims, (Dims{3, 2}));
  for (std::size_t i = 0; i < grey8.size(); ++i) {
    EXPECT_EQ(a[i], static_cast<float>(grey8[i]));
    EXPECT_EQ(b[i], static_cast<std::int32_t>(grey16[i]));
  }
  // Stored as 1 and 2 bytes per value (not converted to a wider type on disk).
  H5::H5File file(path, H5F_ACC_RDONLY);
  EXPECT_EQ(file.openDataSet("frames/u8").getDataType().getSize(), 1u);
  EXPECT_EQ(file.openDataSet("frames/u16").getDataType().getSize(), 2u);
}

TEST(Hdf5Store, LargeDatasetsAreChunkedAndCompressed) {
  TestDir dir;
  const std::string path = dir.File("big.h5");
  std::vector<float> field(100 * 200, 1.0f);
  {
    H5Writer out(path);
    out.Write("f", field, {100, 200}, "px", "constant");
    out.Commit();
  }
  H5::H5File file(path, H5F_ACC_RDONLY);
  H5::DataSet ds = file.openDataSet("/f");
  H5::DSetCreatPropList props = ds.getCreatePlist();
  EXPECT_EQ(props.getLayout(), H5D_CHUNKED);
  EXPECT_GE(props.getNfilters(), 1);
  EXPECT_LT(ds.getStorageSize(), field.size() * sizeof(float) / 10);  // constant data compresses
}

TEST(Hdf5Store, InterruptedWriteLeavesNoFinalFile) {
  TestDir dir;
  const std::string path = dir.File("results.h5");
  {
    H5Writer out(path);
    out.Write("x", std::vector<double>{1, 2, 3}, "m", "x");
    // While writing, only a temporary file exists.
    EXPECT_FALSE(std::filesystem::exists(path));
    // Destroyed without Commit(), as when a stage throws.
  }
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_TRUE(std::filesystem::is_empty(dir.path())) << "temporary file left behind";
}

TEST(Hdf5Store, ErrorsNameTheFileAndDataset) {
  TestDir dir;
  const std::string path = dir.File("r.h5");
  {
    H5Writer out(path);
    out.Write("x", std::vector<double>{1}, "m", "x");
    EXPECT_THROW(out.Write("y", std::vector<double>{1, 2, 3}, Dims{2, 2}, "m", "bad dims"), Error);
    out.Commit();
  }
  H5Reader in(path);
  try {
    in.ReadDouble("missing/dataset");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("missing/dataset"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("r.h5"), std::string::npos);
  }
  EXPECT_THROW(H5Reader(dir.File("none.h5")), Error);
  const std::string not_h5 = dir.Write("text.h5", "hello");
  EXPECT_THROW(H5Reader{not_h5}, Error);
  EXPECT_THROW(H5Writer(dir.File("no/such/folder/r.h5")), Error);
}

}  // namespace
}  // namespace impactdic

namespace impactdic {
namespace {

// The files open in h5py without conversion (Debian's python3-h5py, installed by
// scripts/install_deps.sh): values, shapes, units and string attributes.
TEST(Hdf5Store, ReadableByH5py) {
  TestDir dir;
  const std::string path = dir.File("py.h5");
  {
    H5Writer out(path);
    out.WriteProvenance("name: py\n");
    out.Write("dic/u_px", std::vector<float>{1, 2, 3, 4, 5, 6}, {2, 3}, "px", "u");
    out.Commit();
  }
  const std::string script = dir.Write("check.py", R"(
import sys, h5py
f = h5py.File(sys.argv[1], "r")
d = f["dic/u_px"]
assert d.shape == (2, 3), d.shape
assert float(d[1, 2]) == 6.0
assert d.attrs["units"] == "px", d.attrs["units"]
assert f.attrs["tool"] == "impactdic"
assert f["provenance"].attrs["scene_yaml"] == "name: py\n"
print("h5py-ok")
)");
  const std::string command = "/usr/bin/python3 " + script + " " + path + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  char buffer[4096];
  std::string output;
  while (fgets(buffer, sizeof buffer, pipe)) output += buffer;
  EXPECT_EQ(pclose(pipe), 0) << output;
  EXPECT_NE(output.find("h5py-ok"), std::string::npos) << output;
}

}  // namespace
}  // namespace impactdic

namespace impactdic {
namespace {

TEST(Hdf5Store, UpdateAddsAndReplacesGroupsAtomically) {
  TestDir dir;
  const std::string path = dir.File("r.h5");
  {
    H5Writer out(path);
    out.Write("dic/u_px", std::vector<double>{1, 2}, "px", "u");
    out.Write("momentum/p", std::vector<double>{5}, "N s", "old");
    out.Commit();
  }
  {
    H5Writer update(path, H5Writer::Mode::kUpdate);
    update.Remove("momentum");
    update.Write("momentum/q", std::vector<double>{7}, "N s", "new");
    // Before Commit() the original is untouched.
    EXPECT_TRUE(H5Reader(path).Exists("momentum/p"));
    update.Commit();
  }
  H5Reader in(path);
  EXPECT_EQ(in.ReadDouble("dic/u_px")[1], 2);
  EXPECT_FALSE(in.Exists("momentum/p"));
  EXPECT_EQ(in.ReadDouble("momentum/q")[0], 7);
  EXPECT_THROW(H5Writer(dir.File("missing.h5"), H5Writer::Mode::kUpdate), Error);
}

// A results file with its frames is far larger than a text file: an update (analyze SCENE,
// correlate -o into an existing file) must read it whole, not refuse it at the text-file limit.
TEST(Hdf5Store, UpdatesAFileLargerThanTheTextFileLimit) {
  TestDir dir;
  const std::string path = dir.File("big.h5");
  const std::size_t n = static_cast<std::size_t>(kMaxTextFileBytes) + (std::size_t{1} << 20);
  {
    H5Writer out(path);
    // Random bytes: the writer deflates large datasets, and noise does not shrink.
    std::mt19937 random(11);
    std::vector<std::uint8_t> frames(n);
    for (auto& b : frames) b = static_cast<std::uint8_t>(random());
    out.Write("frames/images", frames, {n}, "grey level", "frames");
    out.Commit();
  }
  ASSERT_GT(std::filesystem::file_size(path), kMaxTextFileBytes);
  {
    H5Writer update(path, /*owned_groups=*/{"/momentum"});
    update.Write("momentum/p", std::vector<double>{5}, "N s", "new");
    update.Commit();
  }
  H5Reader in(path);
  EXPECT_EQ(in.ReadDouble("momentum/p")[0], 5);
  EXPECT_TRUE(in.Exists("frames/images"));
}

}  // namespace
}  // namespace impactdic
