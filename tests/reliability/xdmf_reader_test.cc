// The sample run's results for other tools (docs/python.md): results.xdmf
// opens in a real XDMF reader (meshio, xdmf_meshio_check.py) that finds results.h5's values at
// every frame and subset, and the h5py example of docs/python.md runs as written on the run.
// The Python modules come from scripts/install_deps.sh; without one a test is skipped, except
// under CI=true or IMPACTDIC_REQUIRE_SHARED_DATA=1 (scripts/test.sh), where it fails.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>

#include "../cli/cli_runner.h"
#include "../core/shared_data.h"
#include "../core/test_paths.h"
#include "../io/test_dir.h"
#include "fault_util.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/results_layout.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;
namespace L = results_layout;

const std::string kPython = "/usr/bin/python3";

// "" when `module` imports in kPython, else why not.
std::string MissingPythonModule(const std::string& module) {
  const CliResult r = RunShell(kPython + " -c 'import " + module + "'");
  return r.exit_code == 0 ? "" : kPython + " cannot import " + module + ": " + r.output;
}

bool ToolsRequired() {
  const char* ci = std::getenv("CI");
  return SharedDataRequired() || (ci && *ci && std::string(ci) != "false");
}

#define IMPACTDIC_PYTHON_MODULE_OR_SKIP(module)                                               \
  do {                                                                                        \
    const std::string missing = MissingPythonModule(module);                                  \
    if (!missing.empty()) {                                                                   \
      if (ToolsRequired()) FAIL() << missing << " (required under CI / REQUIRE_SHARED_DATA)"; \
      GTEST_SKIP() << missing << " (scripts/install_deps.sh installs it)";                    \
    }                                                                                         \
  } while (false)

// One run of the sample scene (figures and animation off) into DIR/results/sample, shared by the
// tests of this program.
class SampleRun : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = std::make_unique<TestDir>("xdmf_sample_run");
    const std::string scene = SampleScene(*dir_, {});
    const CliResult r = RunCli("-q run " + scene + " -o " + Folder());
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  static void TearDownTestSuite() { dir_.reset(); }
  static std::string Folder() { return dir_->File("results/sample"); }
  static std::unique_ptr<TestDir> dir_;
};
std::unique_ptr<TestDir> SampleRun::dir_;

using XdmfReader = SampleRun;
using PythonDocs = SampleRun;

// meshio's TimeSeriesReader opens results.xdmf: 53 frames at /time/t_ms, the 180 subsets at
// (x_px, y_px), and every frame's status, zncc, sigma and displacement, velocity, acceleration
// vectors equal to results.h5's rows (exactly: the same bytes through HDF5 virtual datasets);
// every DataItem refers to results.h5 and no field is copied (xdmf_meshio_check.py).
TEST_F(XdmfReader, MeshioReadsTheSampleRunsFieldsAtEveryFrame) {
  IMPACTDIC_PYTHON_MODULE_OR_SKIP("meshio, h5py");
  ASSERT_TRUE(fs::exists(Folder() + "/" + L::kXdmfFile));
  const CliResult r = RunShell(kPython + " " + impactdic::SourceDir() +
                               "/tests/reliability/xdmf_meshio_check.py " + Folder());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("xdmf-ok 53 frames 180 subsets"), std::string::npos) << r.output;
}

// outputs.xdmf: false writes neither results.xdmf nor the /xdmf views; results.h5 is otherwise
// the same run's (its /dic is there).
TEST(XdmfOutput, OutputsXdmfFalseWritesNeither) {
  TestDir dir;
  const std::string scene = SampleScene(dir, {{"xdmf: true", "xdmf: false"}});
  const CliResult r = RunCli("-q run " + scene + " -o " + dir.File("out"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_FALSE(fs::exists(dir.File("out/") + L::kXdmfFile));
  const H5Reader in(dir.File("out/") + L::kResultsFile);
  EXPECT_TRUE(in.Exists(L::kDicU));
  EXPECT_FALSE(in.Exists(L::kXdmfGroup));
}

// The Python block of docs/python.md, extracted from the doc so the two cannot drift, run as it
// is from the folder holding results/sample: it prints the frame it plots and writes the PNG.
TEST_F(PythonDocs, H5pyExampleRunsOnTheSampleRun) {
  IMPACTDIC_PYTHON_MODULE_OR_SKIP("h5py, numpy, matplotlib");
  const std::string doc = ReadBytes(std::string(impactdic::SourceDir()) + "/docs/python.md");
  const std::string open = "```python\n";
  const std::size_t begin = doc.find(open);
  ASSERT_NE(begin, std::string::npos) << "no ```python block in docs/python.md";
  const std::size_t end = doc.find("\n```", begin + open.size());
  ASSERT_NE(end, std::string::npos);
  const fs::path work = fs::path(Folder()).parent_path().parent_path();
  const std::string script =
      dir_->Write("doc_example.py", doc.substr(begin + open.size(), end - begin - open.size()));
  fs::remove(work / "velocity_frame.png");
  const CliResult r = RunShell("cd " + work.string() + " && " + kPython + " " + script);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("frame 12 at 4.74 ms: 180 of 180 subsets valid"), std::string::npos)
      << r.output;
  ASSERT_TRUE(fs::exists(work / "velocity_frame.png"));
  EXPECT_GT(fs::file_size(work / "velocity_frame.png"), 20000u);  // A drawn plot, not a blank.
}

}  // namespace
}  // namespace impactdic
