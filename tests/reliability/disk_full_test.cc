// Full disk (docs/reliability.md): every writer of every command exits 1 with
// one message naming the file and "no space left", leaves no temporary file, keeps an older file
// of that name intact, and does not crash. The disk is a small tmpfs mounted for each test and
// filled to leave chosen room, so that the space runs out at a chosen output. Mounting needs root:
// without it every test is skipped, saying so (CTest reports them as skipped).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "../cli/cli_runner.h"
#include "../io/test_dir.h"
#include "small_disk.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

#define MOUNT_OR_SKIP(disk, size_bytes)                                           \
  std::string why_not;                                                            \
  const std::unique_ptr<SmallDisk> disk = SmallDisk::Mount(size_bytes, &why_not); \
  if (!disk) GTEST_SKIP() << "disk-full tests skipped: " << why_not

constexpr std::size_t kTwoMb = std::size_t{2} << 20;

std::string ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// What a writer must do on a full disk: exit 1; one error line (and nothing from a library:
// libpng, HDF5, OpenCV) naming `file` and saying "no space left"; no temporary file on the disk.
void ExpectOneCleanNoSpaceError(const CliResult& r, const std::string& file,
                                const SmallDisk& disk) {
  EXPECT_EQ(r.exit_code, 1) << r.output;
  std::istringstream lines(r.output);
  int errors = 0;
  for (std::string line; std::getline(lines, line);) {
    if (line.empty() || line.rfind("[warning]", 0) == 0) continue;
    ++errors;
    EXPECT_EQ(line.rfind("impactdic: error: ", 0), 0u) << "a stray line: " << line;
    EXPECT_NE(line.find(file), std::string::npos) << line;
    EXPECT_NE(line.find("no space left"), std::string::npos) << line;
  }
  EXPECT_EQ(errors, 1) << r.output;
  EXPECT_TRUE(disk.TemporaryFiles().empty())
      << "temporary file left: " << disk.TemporaryFiles().front();
}

// The regular files of `folder` in the order they were written (modification time).
struct Written {
  std::string name;
  std::size_t size;
};
std::vector<Written> FilesInWriteOrder(const fs::path& folder) {
  std::vector<std::pair<fs::file_time_type, Written>> found;
  for (const auto& e : fs::recursive_directory_iterator(folder))
    if (e.is_regular_file())
      found.push_back(
          {e.last_write_time(),
           {fs::relative(e.path(), folder).string(), static_cast<std::size_t>(e.file_size())}});
  std::sort(found.begin(), found.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<Written> files;
  for (const auto& f : found) files.push_back(f.second);
  return files;
}

// Room for the files before `index`, one page short of room for file `index`, plus the page of
// the output folder's lock file (`.NAME.lock` beside the folder, held while the command writes).
std::size_t RoomUpTo(const std::vector<Written>& files, std::size_t index) {
  std::size_t room = SmallDisk::kPage;
  for (std::size_t i = 0; i < index; ++i) room += SmallDisk::Pages(files[i].size);
  return room + SmallDisk::Pages(files[index].size) - SmallDisk::kPage;
}

// One tiny synthetic scene (synth --preset tiny), its write order and a good run's outputs, made
// once for the whole program.
class DiskFull : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TestDir("DiskFullScene");
    const CliResult synth =
        RunCli("-q synth --preset tiny --no-calibrate -o " + dir_->File("scene"));
    ASSERT_EQ(synth.exit_code, 0) << synth.output;
    synth_files_ = new std::vector<Written>(FilesInWriteOrder(dir_->path() / "scene"));
    // The same scene without outputs.hdf5, beside it (relative paths stay valid).
    std::string text = ReadBytes(dir_->File("scene/scene.yaml"));
    const std::size_t at = text.find("hdf5: true");
    ASSERT_NE(at, std::string::npos) << text;
    dir_->Write("scene/scene_no_hdf5.yaml", text.replace(at, 10, "hdf5: false"));
    for (const char* which : {"scene", "scene_no_hdf5"}) {
      const CliResult run = RunCli("-q run " + dir_->File(std::string("scene/") + which + ".yaml") +
                                   " -o " + dir_->File(std::string("good_") + which));
      ASSERT_EQ(run.exit_code, 0) << run.output;
    }
    run_files_ = new std::vector<Written>(FilesInWriteOrder(dir_->path() / "good_scene"));
    run_files_no_hdf5_ =
        new std::vector<Written>(FilesInWriteOrder(dir_->path() / "good_scene_no_hdf5"));
  }
  static void TearDownTestSuite() {
    delete run_files_no_hdf5_;
    delete run_files_;
    delete synth_files_;
    delete dir_;
  }
  static std::string Scene(const std::string& name = "scene.yaml") {
    return dir_->File("scene/" + name);
  }

  static TestDir* dir_;
  static std::vector<Written>* synth_files_;
  static std::vector<Written>* run_files_;
  static std::vector<Written>* run_files_no_hdf5_;
};
TestDir* DiskFull::dir_ = nullptr;
std::vector<Written>* DiskFull::synth_files_ = nullptr;
std::vector<Written>* DiskFull::run_files_ = nullptr;
std::vector<Written>* DiskFull::run_files_no_hdf5_ = nullptr;

constexpr const char* kModel = "-q model --mass 10 --height 0.7 --width 0.15 --rtol 1e-10";

TEST_F(DiskFull, ModelSeriesHdf5AndCsv) {
  MOUNT_OR_SKIP(disk, kTwoMb);
  // An older file of the name, written while there was room, is kept byte for byte.
  ASSERT_EQ(RunCli(std::string(kModel) + " -o " + disk->File("old.h5")).exit_code, 0);
  const std::string old_bytes = ReadBytes(disk->File("old.h5"));
  ASSERT_TRUE(disk->LeaveFree(0));
  for (const char* name : {"x.h5", "x.csv", "old.h5"}) {
    SCOPED_TRACE(name);
    const CliResult r = RunCli(std::string(kModel) + " -o " + disk->File(name));
    ExpectOneCleanNoSpaceError(r, disk->File(name), *disk);
  }
  EXPECT_FALSE(fs::exists(disk->File("x.h5")));
  EXPECT_FALSE(fs::exists(disk->File("x.csv")));
  EXPECT_EQ(ReadBytes(disk->File("old.h5")), old_bytes);
}

TEST_F(DiskFull, CorrelateHdf5AndCsv) {
  MOUNT_OR_SKIP(disk, kTwoMb);
  ASSERT_TRUE(disk->LeaveFree(0));
  const std::string frames = Scene("frames/");
  for (const char* name : {"dic.h5", "dic.csv"}) {
    SCOPED_TRACE(name);
    const CliResult r =
        RunCli("-q correlate --reference " + frames + "frame_0000.png --deformed " + frames +
               "frame_0004.png --subset 21 --step 20 -o " + disk->File(name));
    ExpectOneCleanNoSpaceError(r, disk->File(name), *disk);
    EXPECT_FALSE(fs::exists(disk->File(name)));
  }
}

TEST_F(DiskFull, AnalyzeSensorOutput) {
  MOUNT_OR_SKIP(disk, kTwoMb);
  ASSERT_TRUE(disk->LeaveFree(0));
  const CliResult r = RunCli("-q analyze --sensor " + Scene("sensor.csv") +
                             " --from-release --output " + disk->File("sensor.h5"));
  ExpectOneCleanNoSpaceError(r, disk->File("sensor.h5"), *disk);
  EXPECT_FALSE(fs::exists(disk->File("sensor.h5")));
}

TEST_F(DiskFull, SynthFramesAndTruthHdf5) {
  MOUNT_OR_SKIP(disk, kTwoMb);
  // No room at all: the first frame PNG.
  ASSERT_TRUE(disk->LeaveFree(0));
  const CliResult first = RunCli("-q synth --preset tiny --no-calibrate -o " + disk->File("a"));
  ExpectOneCleanNoSpaceError(first, disk->File("a/frames/frame_0000.png"), *disk);
  // Room for everything before truth.h5 (frames, sensor CSV, spec), one page short for it.
  const auto truth = std::find_if(synth_files_->begin(), synth_files_->end(),
                                  [](const Written& w) { return w.name == "truth.h5"; });
  ASSERT_NE(truth, synth_files_->end());
  fs::remove_all(disk->File("a"));
  ASSERT_TRUE(disk->LeaveFree(RoomUpTo(*synth_files_, truth - synth_files_->begin())))
      << disk->FreeBytes();
  const CliResult r = RunCli("-q synth --preset tiny --no-calibrate -o " + disk->File("b"));
  ExpectOneCleanNoSpaceError(r, disk->File("b/truth.h5"), *disk);
  EXPECT_FALSE(fs::exists(disk->File("b/truth.h5")));
  EXPECT_FALSE(fs::exists(disk->File("b/scene.yaml")));  // Written last: a scene is complete.
}

TEST_F(DiskFull, RunRunsOutOfSpaceAtEachOutput) {
  std::size_t total = 0;
  for (const Written& w : *run_files_) total += SmallDisk::Pages(w.size);
  MOUNT_OR_SKIP(disk, total + kTwoMb);
  // results.h5 (HDF5), the gnuplot figures, velocity_field_te.png (OpenCV), the video,
  // summary.json and summary.csv: the disk runs out at each in turn.
  std::vector<std::string> names;
  for (const Written& w : *run_files_) names.push_back(w.name);
  for (const char* expected :
       {"results.h5", "momentum.png", "velocity_field_te.png", "summary.json", "summary.csv"})
    ASSERT_NE(std::find(names.begin(), names.end(), expected), names.end()) << expected;
  for (std::size_t i = 0; i < run_files_->size(); ++i) {
    const std::string& name = (*run_files_)[i].name;
    SCOPED_TRACE(name);
    fs::remove_all(disk->File("out"));
    ASSERT_TRUE(disk->LeaveFree(RoomUpTo(*run_files_, i))) << disk->FreeBytes();
    const CliResult r = RunCli("-q run " + Scene() + " -o " + disk->File("out"));
    ExpectOneCleanNoSpaceError(r, name, *disk);
    EXPECT_FALSE(fs::exists(disk->File("out/" + name)));
  }
}

TEST_F(DiskFull, RunWithNoRoomAtAllNamesTheOutputFolder) {
  MOUNT_OR_SKIP(disk, kTwoMb);
  ASSERT_TRUE(disk->LeaveFree(0));
  const CliResult r = RunCli("-q run " + Scene() + " -o " + disk->File("out"));
  ExpectOneCleanNoSpaceError(r, disk->File("out"), *disk);
}

TEST_F(DiskFull, RunWithoutHdf5NeedsNoRoomForResultsH5) {
  // outputs.hdf5: false renders the figures from memory: room for its outputs is enough.
  std::size_t room = 0;
  for (const Written& w : *run_files_no_hdf5_) {
    EXPECT_NE(w.name, "results.h5");
    room += SmallDisk::Pages(w.size);
  }
  const auto h5 = std::find_if(run_files_->begin(), run_files_->end(),
                               [](const Written& w) { return w.name == "results.h5"; });
  ASSERT_NE(h5, run_files_->end());
  ASSERT_GT(h5->size, 4 * SmallDisk::kPage);  // So the slack below cannot hold it.
  MOUNT_OR_SKIP(disk, room + kTwoMb);
  ASSERT_TRUE(disk->LeaveFree(room + 2 * SmallDisk::kPage));
  const CliResult r = RunCli("-q run " + Scene("scene_no_hdf5.yaml") + " -o " + disk->File("out"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_FALSE(fs::exists(disk->File("out/results.h5")));
  EXPECT_TRUE(fs::exists(disk->File("out/momentum.png")));
  EXPECT_TRUE(fs::exists(disk->File("out/summary.json")));
  EXPECT_TRUE(disk->TemporaryFiles().empty());
}

}  // namespace
}  // namespace impactdic
