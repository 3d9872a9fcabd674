#include "impactdic/io/hdf5_store.h"

#include <H5Cpp.h>
#include <gtest/gtest.h>
#include <stdio.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/version.h"
#include "impactdic/io/input_file.h"
#include "test_dir.h"

// Under AddressSanitizer (the asan preset) freed blocks stay in its quarantine (256 MB by
// default), so the resident set would grow with every chunk buffer HDF5 and zlib ever freed: this
// binary runs without it (the hook is ASan's; unused in other builds).
extern "C" const char* __asan_default_options() { return "quarantine_size_mb=0"; }

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

// Compressed datasets of one chunk are filtered on workers and their chunks written when the file
// is flushed: every type reads back exactly, a dataset written twice keeps its second values, one
// removed is gone, and the chunks carry HDF5's shuffle and deflate filters.
TEST(Hdf5Store, DeferredChunksReadBackAsWritten) {
  TestDir dir;
  const std::string path = dir.File("deferred.h5");
  std::mt19937 random(3);
  std::uniform_real_distribution<double> value(-1, 1);
  std::vector<double> d(5000), replaced(5000, 2.5);
  for (double& v : d) v = value(random);
  std::vector<float> f(6000);
  for (float& v : f) v = static_cast<float>(value(random));
  std::vector<std::int32_t> i(4096);
  for (std::size_t k = 0; k < i.size(); ++k) i[k] = static_cast<std::int32_t>(k * 7919 % 1000);
  {
    H5Writer out(path);
    out.Write("a/d", replaced, {50, 100}, "px", "first, replaced");
    out.Write("a/d", d, {50, 100}, "px", "random");
    out.Write("a/f", f, {6000}, "1", "random");
    out.Write("a/i", i, {64, 64}, "1", "pattern");
    out.Write("a/gone", d, {5000}, "1", "removed");
    out.Remove("a/gone");
    // 40 x 512 KB: more than the writer keeps waiting, so some are written on the way.
    for (int k = 0; k < 40; ++k)
      out.Write("many/" + std::to_string(k), std::vector<double>(65536, k), {65536}, "1", "k");
    out.Commit();
  }
  H5Reader in(path);
  EXPECT_EQ(in.ReadDouble("a/d"), d);
  EXPECT_EQ(in.ReadFloat("a/f"), f);
  EXPECT_EQ(in.ReadInt("a/i"), i);
  for (int k : {0, 17, 39}) EXPECT_EQ(in.ReadDouble("many/" + std::to_string(k)).at(65535), k);
  H5::H5File file(path, H5F_ACC_RDONLY);
  EXPECT_FALSE(file.nameExists("/a/gone"));
  EXPECT_EQ(file.openDataSet("/a/d").getCreatePlist().getNfilters(), 2);  // shuffle, deflate
}

// Commit() writes the file from the core driver's buffer (the temporary file itself, or memory)
// instead of a copy of it (H5Fget_file_image): the bytes on the disk are still exactly those
// HDF5's copy holds (its superblock's consistency flags cleared as H5Fget_file_image clears them).
TEST(Hdf5Store, CommitWritesTheBytesOfHdf5sFileImage) {
  TestDir dir;
  std::mt19937 random(7);
  std::uniform_real_distribution<double> value(-1, 1);
  // 12 MB of random doubles (deflate keeps them as they are): the file on the disk passes through
  // several 4 MB steps at which its pages are handed back to the page cache.
  std::vector<double> field(std::size_t{1500} * 1000);
  for (double& v : field) v = value(random);
  auto fill = [&](H5Writer& out) {
    out.Write("/dic/u_px", field, {1500, 1000}, "px", "random");
    out.Write("/time_ms", std::vector<double>{0, 1, 2}, "ms", "time");
    out.SetAttribute("/dic", "interpolation", "bicubic");
  };
  H5Writer to_memory(dir.File("a.h5"), H5Writer::Mode::kCreate, "", H5Writer::Backing::kMemory);
  fill(to_memory);
  const std::vector<char> image = to_memory.CommitToMemory();
  // Built in a temporary file (the default) or in memory, the committed bytes are HDF5's image.
  for (const H5Writer::Backing backing : {H5Writer::Backing::kFile, H5Writer::Backing::kMemory}) {
    const std::string path = dir.File(backing == H5Writer::Backing::kFile ? "b.h5" : "c.h5");
    H5Writer to_disk(path, H5Writer::Mode::kCreate, "", backing);
    fill(to_disk);
    to_disk.Commit();
    const std::string on_disk = ReadInputFile(path, "an HDF5 file", 1u << 30);
    ASSERT_EQ(on_disk.size(), image.size()) << path;
    EXPECT_TRUE(std::equal(image.begin(), image.end(), on_disk.begin())) << path;
    EXPECT_EQ(H5Reader(path).ReadDouble("/dic/u_px"), field);
  }
  // The same for an update of an existing file (kUpdate copies it into the buffer first).
  H5Writer update(dir.File("b.h5"), H5Writer::Mode::kUpdate);
  update.Write("/time_ms", std::vector<double>{0, 1, 2, 3}, "ms", "time");
  update.Commit();
  H5Writer update_in_memory(dir.File("c.h5"), H5Writer::Mode::kUpdate, "",
                            H5Writer::Backing::kMemory);
  update_in_memory.Write("/time_ms", std::vector<double>{0, 1, 2, 3}, "ms", "time");
  update_in_memory.Commit();
  EXPECT_EQ(ReadInputFile(dir.File("b.h5"), "an HDF5 file", 1u << 30),
            ReadInputFile(dir.File("c.h5"), "an HDF5 file", 1u << 30));
  EXPECT_EQ(H5Reader(dir.File("b.h5")).ReadDouble("/time_ms").size(), 4u);
  EXPECT_TRUE(H5Reader(dir.File("b.h5")).Exists("/dic/u_px"));
}

// The resident memory a process gains from its start while it builds and commits a file of
// `images` incompressible 2048 x 2048 8-bit images written one at a time (WriteStack), measured
// in a child process (VmHWM after the peak was reset, minus VmRSS then) [bytes]; -1 if it could
// not be measured.
long long CommitPeakGrowth(const std::string& path, int images, H5Writer::Backing backing) {
  const pid_t pid = fork();
  if (pid == 0) {
    auto status_kb = [](const char* key) {
      std::ifstream in("/proc/self/status");
      std::string line;
      while (std::getline(in, line))
        if (line.rfind(key, 0) == 0) return std::atoll(line.c_str() + std::strlen(key));
      return -1LL;
    };
    std::ofstream("/proc/self/clear_refs") << "5";  // Resets VmHWM to VmRSS (Linux >= 4.0).
    const long long start_kb = status_kb("VmRSS:");
    std::mt19937 random(11);
    try {
      H5Writer out(path, H5Writer::Mode::kCreate, "", backing);
      const std::size_t side = 2048;
      out.WriteStack(
          "/frames/images", {static_cast<std::size_t>(images), side, side}, 8,
          [&](std::size_t, void* buffer) {
            auto* p = static_cast<std::uint32_t*>(buffer);
            for (std::size_t i = 0; i < side * side / 4; ++i) p[i] = random();
          },
          "grey level", "random");
      out.Commit();
    } catch (...) {
      _exit(2);
    }
    const long long peak_kb = status_kb("VmHWM:");
    // The growth in MB (0..255) as the exit code.
    _exit(start_kb < 0 || peak_kb < 0 ? 255 : static_cast<int>((peak_kb - start_kb) / 1024));
  }
  int status = 0;
  if (pid < 0 || waitpid(pid, &status, 0) != pid || !WIFEXITED(status)) return -1;
  const int code = WEXITSTATUS(status);
  return code == 255 || code == 2 ? -1 : static_cast<long long>(code) << 20;
}

// Built in its temporary file (Backing::kFile, the default), a file does not stay in memory: the
// pages written are returned to the page cache every 4 MB of growth, so the peak is HDF5's and
// zlib's buffers for a 4 MB chunk plus that step (measured: 21 MB for a 96 MB file). In memory
// (Backing::kMemory) it is held once (measured: 117 MB); before, Commit() copied the core
// driver's image out before writing it, so the peak held the file twice.
TEST(Hdf5Store, AFileBuiltOnTheDiskIsNotHeldInMemory) {
  TestDir dir;
  const int images = 24;  // 96 MB of random bytes: deflate keeps them as they are.
  const long long on_disk = CommitPeakGrowth(dir.File("big.h5"), images, H5Writer::Backing::kFile);
  const long long in_memory =
      CommitPeakGrowth(dir.File("big_memory.h5"), images, H5Writer::Backing::kMemory);
  ASSERT_GE(on_disk, 0) << "the child could not measure its memory";
  ASSERT_GE(in_memory, 0) << "the child could not measure its memory";
  const auto file_bytes = static_cast<long long>(std::filesystem::file_size(dir.File("big.h5")));
  EXPECT_GT(file_bytes, images * (2048LL * 2048));
  EXPECT_EQ(file_bytes,
            static_cast<long long>(std::filesystem::file_size(dir.File("big_memory.h5"))));
  RecordProperty("peak_growth_mb_file", std::to_string(on_disk >> 20));
  RecordProperty("peak_growth_mb_memory", std::to_string(in_memory >> 20));
  EXPECT_LT(on_disk, 40LL << 20) << "peak memory growth " << (on_disk >> 20) << " MB for a "
                                 << (file_bytes >> 20) << " MB file built on the disk";
  EXPECT_GT(in_memory, file_bytes) << "the file in memory: the measurement sees it";
  EXPECT_LT(in_memory, file_bytes + (32LL << 20))
      << "peak memory growth " << (in_memory >> 20) << " MB for a " << (file_bytes >> 20)
      << " MB file in memory";
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
