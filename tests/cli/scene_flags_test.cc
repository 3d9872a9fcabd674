// Every scene key is a command-line flag named as the key (pipeline/scene_flags.h): the keys of
// dic.* and preprocess.* in `correlate`, of test.* and model.* in `model`, and each command's short
// aliases; a key flag's value is the key's, and it reaches the library (dic.max_iterations,
// dic.convergence_px change the correlation).
#include "impactdic/pipeline/scene_flags.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <string>
#include <vector>

#include "../core/test_paths.h"
#include "../io/test_dir.h"
#include "../reliability/fault_util.h"
#include "cli_runner.h"
#include "impactdic/core/error.h"
#include "impactdic/io/csv.h"
#include "impactdic/io/image_io.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/synth/speckle.h"

namespace impactdic {
namespace {

// The help text of `command` names every key of `sections` as "--KEY", and each alias.
void ExpectEveryKeyInHelp(const std::string& command, const std::vector<std::string>& sections) {
  const CliResult help = RunCli(command + " --help");
  ASSERT_EQ(help.exit_code, 0) << help.output;
  const std::vector<SceneKeyFlag> flags = SceneKeyFlags(sections);
  ASSERT_FALSE(flags.empty());
  for (const SceneKeyFlag& f : flags)
    EXPECT_NE(help.output.find("--" + f.key + " "), std::string::npos)
        << "--" << f.key << " not in `impactdic " << command << " --help`";
  for (const SceneFlagAlias& a : SceneFlagAliases()) {
    if (command == a.command) {
      EXPECT_NE(help.output.find(std::string(a.alias) + " "), std::string::npos) << a.alias;
    }
  }
}

TEST(SceneFlags, EveryKeyOfTheTablesIsAFlagOfItsCommand) {
  // The sections of the keys each command runs on (run and analyze take a scene file).
  ExpectEveryKeyInHelp("correlate", {"dic", "preprocess"});
  ExpectEveryKeyInHelp("model", {"test", "model"});
  ExpectEveryKeyInHelp("analyze", {"sensor", "momentum"});
  ExpectEveryKeyInHelp("run", {"sensor", "momentum", "outputs"});
  // Every section of the table: the lists above are checked against it.
  Scene scene;
  std::vector<std::string> keys;
  for (const YamlOptionTable& t : SceneOptionTables(&scene))
    for (const auto& e : t.entries()) keys.push_back(t.section() + "." + e.key);
  for (const char* key : {"dic.max_iterations", "dic.convergence_px", "model.K", "test.mass_kg",
                          "preprocess.gaussian.sigma", "preprocess.clahe.enabled",
                          "sensor.cutoff_hz", "momentum.grid_cols", "outputs.figures"})
    EXPECT_NE(std::find(keys.begin(), keys.end(), key), keys.end()) << key;
}

TEST(SceneFlags, AFlagIsReadAsItsKeyInASceneFile) {
  Scene scene;
  SetSceneKey(&scene, "dic.max_iterations", "7", "--dic.max_iterations");
  SetSceneKey(&scene, "dic.convergence_px", "0.01", "--dic.convergence_px");
  SetSceneKey(&scene, "dic.continuity_check", "on", "--continuity-check");
  EXPECT_EQ(scene.dic.options.icgn.max_iterations, 7);
  EXPECT_EQ(scene.dic.options.icgn.convergence_px, 0.01);
  EXPECT_TRUE(scene.dic.options.continuity.enabled);
  // Refused with the scene key's expected text, naming the flag as given.
  try {
    SetSceneKey(&scene, "dic.subset_size", "24", "--dic.subset_size");
    FAIL() << "an even subset was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.where(), "--dic.subset_size");
    EXPECT_NE(e.expected().find("an odd integer"), std::string::npos) << e.what();
  }
  EXPECT_EQ(SceneFlagNames("correlate", "dic.subset_size"), "--dic.subset_size,--subset");
  EXPECT_EQ(SceneFlagNames("correlate", "dic.max_iterations"), "--dic.max_iterations");
}

class SceneFlagsCorrelate : public ::testing::Test {
 protected:
  void SetUp() override {
    SpeckleOptions speckle;
    speckle.blob_radius_px = 2.0;
    SpecklePattern pattern(speckle, 100, 80);
    RenderOptions render;
    render.noise_sigma = 2;
    render.supersampling = 2;
    WriteImage(dir_.File("ref.png"), RenderImage(pattern, 100, 80, ZeroField(), render));
    render.noise_seed = 8;
    WriteImage(dir_.File("def.png"), RenderImage(pattern, 100, 80, Translation(1.4, -0.7), render));
  }
  // The iterations and u of `correlate` with `flags`.
  CsvTable Correlate(const std::string& flags, const std::string& name) {
    const std::string out = dir_.File(name + ".csv");
    const CliResult r =
        RunCli("-q correlate --reference " + dir_.File("ref.png") + " --deformed " +
               dir_.File("def.png") + " --threads 1 --subset 21 --step 20 " + flags + " -o " + out);
    EXPECT_EQ(r.exit_code, 0) << flags << "\n" << r.output;
    CsvReadOptions options;
    options.text_columns = {"status"};
    options.allow_non_finite = true;  // A subset that did not converge has no u, v.
    return ReadCsv(out, options);
  }
  TestDir dir_{"scene_flags_correlate"};
};

double Sum(const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0); }

TEST_F(SceneFlagsCorrelate, MaxIterationsAndConvergenceChangeTheCorrelation) {
  const CsvTable base = Correlate("", "base");
  // One iteration converges no subset (status max_iterations): written with --allow-partial.
  const CsvTable capped = Correlate("--dic.max_iterations 1 --allow-partial", "capped");
  const CsvTable loose = Correlate("--dic.convergence_px 0.9", "loose");
  ASSERT_GT(base.rows(), 0u);
  ASSERT_EQ(capped.rows(), base.rows());
  ASSERT_EQ(loose.rows(), base.rows());
  const auto& it = capped.Column("iterations");
  EXPECT_EQ(*std::max_element(it.begin(), it.end()), 1);
  EXPECT_GT(*std::max_element(base.Column("iterations").begin(), base.Column("iterations").end()),
            1);
  EXPECT_NE(capped.TextColumn("status"), base.TextColumn("status"));
  EXPECT_LT(Sum(loose.Column("iterations")), Sum(base.Column("iterations")));
  EXPECT_NE(loose.Column("u_px"), base.Column("u_px"));
}

TEST_F(SceneFlagsCorrelate, AKeyFlagIsRefusedAsTheKeyAndTwoNamesOfOneKeyAreRefused) {
  const std::string pair = "correlate --reference " + dir_.File("ref.png") + " --deformed " +
                           dir_.File("def.png") + " -o " + dir_.File("x.csv");
  CliResult r = RunCli(pair + " --dic.max_iterations 0");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("--dic.max_iterations: invalid value (got 0); expected an integer "
                          "iteration cap in [1, 200]"),
            std::string::npos)
      << r.output;
  r = RunCli(pair + " --min-zncc 0.5 --dic.min_zncc 0.6");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("both given"), std::string::npos) << r.output;
}

// `run SCENE --KEY VALUE` and `analyze SCENE --KEY VALUE`: the flag overrides the scene file's
// key (sensor.*, momentum.*, outputs.*); a momentum key is refused with `analyze --sensor`.
TEST(SceneFlags, RunAndAnalyzeFlagsOverrideTheSceneFile) {
  TestDir dir("scene_flags_run");
  const std::string scene = SampleScene(dir, {});  // outputs.folder: results; xdmf, csv: true.
  const std::string out = dir.File("from_flag");
  CliResult r = RunCli("-q run " + scene + " --outputs.folder " + out +
                       " --outputs.xdmf off --outputs.csv false");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(std::filesystem::exists(out + "/results.h5"));
  EXPECT_FALSE(std::filesystem::exists(out + "/results.xdmf"));
  EXPECT_FALSE(std::filesystem::exists(out + "/summary.csv"));
  EXPECT_FALSE(std::filesystem::exists(dir.File("results")));
  r = RunCli("run " + scene + " --outputs.frames some");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("--outputs.frames: invalid value (got 'some')"), std::string::npos)
      << r.output;

  // analyze SCENE: --cutoff (alias of sensor.cutoff_hz) and the momentum keys reach the analysis.
  const std::string analyze = "analyze " + scene + " --results " + out + "/results.h5";
  r = RunCli(analyze + " --output " + dir.File("a.h5") + " --cutoff 1000");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("1000.0 Hz"), std::string::npos) << r.output;
  r = RunCli(analyze + " --output " + dir.File("b.h5") + " --momentum.grid_cols 0");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("--momentum.grid_cols: invalid value (got 0)"), std::string::npos)
      << r.output;
  r = RunCli("analyze --sensor " + std::string(impactdic::SourceDir()) +
             "/sample_frames/sensor.csv --from-release --momentum.grid_cols 3");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("--momentum.grid_cols only with the SCENE.yaml form"), std::string::npos)
      << r.output;
}

}  // namespace
}  // namespace impactdic
