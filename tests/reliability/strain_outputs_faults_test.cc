// Fault injection: scene settings that used to give silent wrong output with exit 0. results.xdmf
// asked for without results.h5 (it is a set of views into that file), a strain window larger than
// the subset grid (the "local" fit becomes one plane through the grid), and a run whose
// correlation leaves no finite strain after the reference (the compacted zone read 0 mm^2, 0 mm).
// Each now gives an error naming the keys and values, or null figures with the reason.
//
// Ground truth: the committed sample scene (sample_frames/scene.yaml): 25 px subsets 32 px apart
// in the ROI [36, 131, 605, 444], a grid of 18 columns x 10 rows.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "../cli/cli_runner.h"
#include "../io/test_dir.h"
#include "fault_util.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// The sample scene with the strain gradient from a least-squares fit over strain.window.
const std::pair<std::string, std::string> kFitGradient{"gradient: warp", "gradient: fit"};

// outputs.xdmf without outputs.hdf5: refused before any work (no output folder), naming both keys,
// whether the flags ask for it (checked by the run) or the scene file (checked when it is read).
TEST(StrainOutputsFaults, XdmfWithoutHdf5IsRefusedAtSceneLoad) {
  TestDir dir("XdmfWithoutHdf5");
  const std::string scene = SampleScene(dir, {});  // The sample asks for outputs.xdmf: true.
  const std::string output = ExpectCliFailure(
      "run " + scene + " --outputs.hdf5 false --outputs.xdmf true -o " + dir.File("out"),
      {scene, "outputs.xdmf", "true with outputs.hdf5 false", "results.xdmf's fields are views"});
  EXPECT_FALSE(fs::exists(dir.File("out"))) << output;
  // In the file: the sample's xdmf: true with hdf5: false.
  TestDir file_dir("XdmfWithoutHdf5File");
  const std::string in_file = SampleScene(file_dir, {{"hdf5: true", "hdf5: false"}});
  ExpectCliFailure("run " + in_file + " -o " + file_dir.File("out"),
                   {in_file, "outputs.xdmf: got true with outputs.hdf5 false"});
  EXPECT_FALSE(fs::exists(file_dir.File("out")));
}

// strain.window 99 on the sample's 18 x 10 grid: the fit of every subset spanned the whole grid
// (compacted area 95,060 mm^2 against 57,265 with window 3). Refused naming strain.window, its
// value and the grid; the scene file is named, and nothing is written.
TEST(StrainOutputsFaults, StrainWindowLargerThanTheGridIsRefused) {
  TestDir dir("StrainWindowTooLarge");
  const std::string scene = SampleScene(dir, {kFitGradient});
  const std::string output =
      ExpectCliFailure("run " + scene + " --strain.window 99 -o " + dir.File("out"),
                       {scene, "strain.window", "99", "18 columns x 10 rows", "at most 9"});
  EXPECT_FALSE(fs::exists(dir.File("out/summary.json"))) << output;
}

// --dic.min_zncc 0.99999: no subset correlates after the reference, so no strain is finite
// there. The compacted zone is not measured: null in summary.json, with the strain stage's
// failure saying why (and an error without --allow-partial), not 0 mm^2 and 0 mm.
TEST(StrainOutputsFaults, NoFiniteStrainGivesNullCompactedZoneWithTheReason) {
  TestDir dir("NoFiniteStrain");
  const std::string scene = SampleScene(dir, {});
  const CliResult r =
      RunCli("run " + scene + " --dic.min_zncc 0.99999 --allow-partial -o " + dir.File("out"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string json = ReadBytes(dir.File("out/summary.json"));
  EXPECT_TRUE(Contains(json, "\"compacted_area_end_mm2\": null")) << json;
  EXPECT_TRUE(Contains(json, "\"compacted_depth_end_mm\": null")) << json;
  EXPECT_TRUE(Contains(json, "\"compacted_area_te_mm2\": null")) << json;
  EXPECT_TRUE(Contains(json, "\"compacted_depth_te_mm\": null")) << json;
  EXPECT_TRUE(Contains(json, "\"strain\": \"no finite strain after the reference frame")) << json;
  EXPECT_TRUE(Contains(json, "\"usable\": false")) << json;
}

}  // namespace
}  // namespace impactdic
