// GeoPIV-RG's scheme names through `impactdic correlate`: listed by --help,
// accepted by --reference-update, recorded as written in the HDF5 results.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "../cli/cli_runner.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/image_io.h"
#include "impactdic/synth/speckle.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

class GeopivSchemesCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("impactdic_geopiv_cli_test_" + std::to_string(getpid()));
    fs::create_directories(dir_);
    SpeckleOptions speckle;
    speckle.blob_radius_px = 2.0;
    SpecklePattern pattern(speckle, 120, 100);
    RenderOptions render;
    render.noise_sigma = 2;
    render.supersampling = 2;
    WriteImage(Path("ref.png"), RenderImage(pattern, 120, 100, ZeroField(), render));
    render.noise_seed = 8;
    WriteImage(Path("def1.png"), RenderImage(pattern, 120, 100, Translation(0.4, -0.3), render));
    render.noise_seed = 9;
    WriteImage(Path("def2.png"), RenderImage(pattern, 120, 100, Translation(0.8, -0.6), render));
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static std::string Path(const std::string& name) { return (dir_ / name).string(); }
  static std::string Sequence() {
    return "correlate --reference " + Path("ref.png") + " --deformed " + Path("def1.png") + " " +
           Path("def2.png");
  }
  static fs::path dir_;
};
fs::path GeopivSchemesCli::dir_;

TEST_F(GeopivSchemesCli, HelpListsTheSchemes) {
  const CliResult r = RunCli("correlate --help");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* name : {"sequential", "leapfrog[:Z]", "preconditioned"})
    EXPECT_NE(r.output.find(name), std::string::npos) << name << "\n" << r.output;
}

TEST_F(GeopivSchemesCli, EachSchemeRunsAndIsRecordedAsWritten) {
  const struct {
    const char* scheme;
    const char* updates;  // Of the two deformed frames.
  } cases[] = {{"sequential", "2 reference updates"},
               {"leapfrog:0.75", "0 reference updates"},
               {"preconditioned", "0 reference updates"}};
  for (const auto& c : cases) {
    const std::string out = Path(std::string(c.scheme).substr(0, 8) + ".h5");
    const CliResult r = RunCli(Sequence() + " --reference-update " + c.scheme + " -o " + out);
    ASSERT_EQ(r.exit_code, 0) << c.scheme << "\n" << r.output;
    EXPECT_NE(r.output.find(c.updates), std::string::npos) << c.scheme << "\n" << r.output;
    EXPECT_EQ(H5Reader(out).ReadStringAttribute("dic", "reference_update"), c.scheme);
  }
}

TEST_F(GeopivSchemesCli, ABadThresholdNamesTheTextAndTheSchemes) {
  const CliResult r = RunCli(Sequence() + " --reference-update leapfrog:1.5 -o " + Path("bad.csv"));
  EXPECT_NE(r.exit_code, 0) << r.output;
  for (const char* needle : {"leapfrog:1.5", "sequential", "preconditioned"})
    EXPECT_NE(r.output.find(needle), std::string::npos) << needle << "\n" << r.output;
}

}  // namespace
}  // namespace impactdic
