// Fault injection: a stage that produces nothing usable must never yield
// plausible figures. Frames whose momentum grid has too few valid subsets get a NaN p_gran; when
// t_e cannot be measured, t_e and everything that depends on it is NaN with the reason; `run`
// fails naming the stage (no output written) unless --allow-partial; `campaign` keeps such a
// scene out of the Eq. 4 fit.
//
// Ground truth: the synthetic momentum chain (tests/momentum/synthetic_chain.h: exact p_gran,
// t_e and m_add) for the per-frame rule, and a small scene rendered by `impactdic synth` whose
// healthy run (checked against its truth by pipeline_end_to_end_test) is the reference here.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "../cli/cli_runner.h"
#include "../io/test_dir.h"
#include "../momentum/synthetic_chain.h"
#include "impactdic/core/error.h"
#include "impactdic/io/csv.h"
#include "impactdic/io/json.h"
#include "impactdic/kinematics/kinematics.h"
#include "impactdic/momentum/fit.h"
#include "impactdic/momentum/momentum.h"
#include "impactdic/pipeline/campaign.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/scene.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// ---- The per-frame rule, on the synthetic chain ----------------------------------------------

// The chain's correlation with the grid subsets `ids` (indices into the 12 of the momentum grid)
// failed (NaN) in frames [first, last].
CorrelationSeries ChainWithFailedGridSubsets(const Chain& c, std::size_t first, std::size_t last,
                                             const std::vector<std::size_t>& ids) {
  CorrelationSeries dic = MakeChainCorrelation(c);
  for (std::size_t k = first; k <= last; ++k) {
    for (std::size_t g : ids) {
      const std::size_t subset = (g / 6) * 10 + 2 + g % 6;  // Grid: columns 2..7, rows 0..1.
      dic.u_px[k * dic.subsets + subset] = dic.v_px[k * dic.subsets + subset] = std::nan("");
    }
  }
  return dic;
}

SceneAnalysis AnalyzeChain(const Chain& c, const CorrelationSeries& dic,
                           const MomentumOptions& options) {
  PanelMapping map;
  map.mm_per_px = c.scale;
  return AnalyzeCorrelation(dic, map, {.fps = c.fps, .offset_s = c.offset}, MakeChainSensor(c),
                            options);
}

// 8 of the 12 grid subsets: 4 valid = 33 %, below the default 50 %.
const std::vector<std::size_t> kEightOfTwelve = {0, 1, 2, 3, 6, 7, 8, 9};

TEST(FailedStageMomentum, SparseGridFramesAfterTeGiveNaNPgranButKeepTe) {
  const Chain c;  // Impact at frame 50, t_e at frame 78, stop at frame ~114.
  const SceneAnalysis a =
      AnalyzeChain(c, ChainWithFailedGridSubsets(c, 95, 100, kEightOfTwelve), ChainOptions(c));
  const MomentumResult& m = a.momentum;
  const MomentumSummary& s = m.summary;
  // Velocities are central differences: displacements lost in frames 95..100 leave 4 of 12
  // velocities in frames 94..101.
  std::size_t sparse = 0;
  for (std::size_t k = 0; k < c.frames; ++k) {
    const bool too_few = m.valid_subsets[k] < 6;
    sparse += too_few ? 1 : 0;
    EXPECT_EQ(std::isnan(m.p_gran_kg_m_s[k]), too_few) << "frame " << k;
    EXPECT_EQ(std::isnan(m.p_total_kg_m_s[k]), too_few) << "frame " << k;
  }
  EXPECT_EQ(sparse, 8u);
  EXPECT_EQ(s.unmeasured_frames, 8u);
  for (std::size_t k = 95; k <= 100; ++k) EXPECT_EQ(m.valid_subsets[k], 4) << k;
  bool warned = false;
  for (const auto& w : s.warnings)
    warned = warned || (Contains(w, "8 of 120 frames have fewer than 6 of the 12") &&
                        Contains(w, "frames 94-101") && Contains(w, "min_valid_fraction"));
  EXPECT_TRUE(warned);
  // The peak stage is complete: t_e and m_add,max are measured as without the fault (truth:
  // t_e to one frame, m_add,max to 1 %, as in momentum_chain_test).
  EXPECT_TRUE(s.IsUsable()) << s.t_end_problem;
  EXPECT_NEAR(s.t_end_peak_s, c.tau_e, 1 / c.fps + 1e-12);
  EXPECT_NEAR(s.added_mass_max_kg, c.Ms(), 0.01 * c.Ms());
}

TEST(FailedStageMomentum, SparseGridFramesInThePeakStageMakeTeAndItsDependentsNaN) {
  const Chain c;
  const SceneAnalysis a =
      AnalyzeChain(c, ChainWithFailedGridSubsets(c, 60, 62, kEightOfTwelve), ChainOptions(c));
  const MomentumResult& m = a.momentum;
  const MomentumSummary& s = m.summary;
  EXPECT_FALSE(s.IsUsable());
  EXPECT_TRUE(Contains(s.t_end_problem, "59-63")) << s.t_end_problem;
  EXPECT_TRUE(Contains(s.t_end_problem, "min_valid_fraction")) << s.t_end_problem;
  // Every figure that depends on t_e is NaN; p_max (the sensor alone) is not.
  EXPECT_TRUE(std::isnan(s.t_end_peak_s));
  EXPECT_TRUE(std::isnan(s.momentum_conservation_error));
  EXPECT_TRUE(std::isnan(s.added_mass_max_kg));
  EXPECT_TRUE(std::isnan(s.momentum_ratio));
  EXPECT_TRUE(std::isnan(s.v_sand_max_m_s));
  EXPECT_FALSE(s.sigmoid_fitted);
  EXPECT_FALSE(s.t_end_found);
  for (double madd : m.added_mass_kg) EXPECT_TRUE(std::isnan(madd));
  EXPECT_TRUE(m.added_mass_daq_kg.empty());
  EXPECT_NEAR(s.p_max_kg_m_s, c.PMax(), 1e-9);
  bool warned = false;
  for (const auto& w : s.warnings)
    warned = warned || (Contains(w, "t_e is not measurable") && Contains(w, "m_add,max"));
  EXPECT_TRUE(warned);
  // The analyze command's JSON says so too.
  const std::string json = s.ToJson().Dump();
  EXPECT_TRUE(Contains(json, "\"added_mass_max_kg\": null")) << json;
  EXPECT_TRUE(Contains(json, "\"t_end_problem\": \"frames 59-63")) << json;
}

TEST(FailedStageMomentum, MinValidFractionIsTheThreshold) {
  const Chain c;
  // 4 of 12 valid (33 %) passes a threshold of 0.25: the remaining subsets move exactly like the
  // grid, so t_e and m_add,max are as without the fault.
  MomentumOptions o = ChainOptions(c);
  o.min_valid_fraction = 0.25;
  const MomentumSummary s =
      AnalyzeChain(c, ChainWithFailedGridSubsets(c, 60, 62, kEightOfTwelve), o).momentum.summary;
  EXPECT_TRUE(s.IsUsable()) << s.t_end_problem;
  EXPECT_EQ(s.unmeasured_frames, 0u);
  EXPECT_NEAR(s.t_end_peak_s, c.tau_e, 1 / c.fps + 1e-12);
  EXPECT_NEAR(s.added_mass_max_kg, c.Ms(), 0.01 * c.Ms());
  // Out of range: named.
  for (double bad : {0.0, -0.5, 1.5, std::nan("")}) {
    o.min_valid_fraction = bad;
    try {
      o.Check();
      ADD_FAILURE() << bad;
    } catch (const Error& e) {
      EXPECT_TRUE(Contains(e.what(), "momentum.min_valid_fraction")) << e.what();
    }
  }
}

TEST(FailedStageMomentum, NoValidGridSubsetInAnyFrame) {
  const Chain c;
  std::vector<std::size_t> all(12);
  for (std::size_t i = 0; i < 12; ++i) all[i] = i;
  const MomentumSummary s =
      AnalyzeChain(c, ChainWithFailedGridSubsets(c, 0, c.frames - 1, all), ChainOptions(c))
          .momentum.summary;
  EXPECT_FALSE(s.IsUsable());
  EXPECT_TRUE(Contains(s.t_end_problem, "no frame between the impact and the stop"))
      << s.t_end_problem;
  EXPECT_TRUE(std::isnan(s.t_end_peak_s));
  EXPECT_TRUE(std::isnan(s.added_mass_max_kg));
  EXPECT_EQ(s.unmeasured_frames, c.frames);
}

TEST(FailedStageMomentum, SceneKeyIsReadAndItsDefaultIsTheLibrarys) {
  TestDir dir;
  const std::string base = "inputs: {frames: f/*.png}\nmomentum: {rect_mm: [0, 0, 10, 10]";
  const Scene unset = ParseScene(base + "}\n", dir.File("a.yaml"));
  EXPECT_EQ(MakeMomentumOptions(unset, 1.0).min_valid_fraction,
            MomentumOptions{}.min_valid_fraction);
  const Scene set = ParseScene(base + ", min_valid_fraction: 0.3}\n", dir.File("b.yaml"));
  EXPECT_EQ(MakeMomentumOptions(set, 1.0).min_valid_fraction, 0.3);
  try {
    ParseScene(base + ", min_valid_fraction: 1.5}\n", dir.File("c.yaml"));
    FAIL() << "expected an error for min_valid_fraction 1.5";
  } catch (const Error& e) {
    EXPECT_TRUE(Contains(e.what(), "momentum.min_valid_fraction")) << e.what();
    EXPECT_TRUE(Contains(e.what(), "1.5")) << e.what();
    EXPECT_TRUE(Contains(e.what(), "(0, 1]")) << e.what();
  }
}

// ---- The pipeline on a small rendered scene --------------------------------------------------

constexpr const char* kSpec = R"(
preset: small
name: healthy
camera: {lens: ideal, width: 320, height: 240, mm_per_px: 1.5}
frames: {count: 14, before_impact: 2, supersampling: 1}
sensor: {tail_s: 0.05}
calibration: {render: false}
dic: {subset_size: 21, step: 12}
)";

// One rendered scene per test process; `Variant` writes a copy of its scene file with text
// replaced (relative paths stay valid: same folder).
class FailedStageRun : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TestDir("FailedStageRun");
    const CliResult synth =
        RunCli("synth " + dir_->Write("spec.yaml", kSpec) + " -o " + dir_->File("scene"));
    ASSERT_EQ(synth.exit_code, 0) << synth.output;
    std::string text = ReadText(dir_->File("scene/scene.yaml"));
    for (const char* key : {"figures: true", "animation: true"})
      text.replace(text.find(key), std::string(key).size(),
                   std::string(key).substr(0, std::string(key).find(':')) + ": false");
    scene_text_ = new std::string(text);
  }
  static void TearDownTestSuite() {
    delete dir_;
    delete scene_text_;
  }

  // The scene with `from` replaced by `to` (each must occur), named `name`.
  static std::string Variant(const std::string& name,
                             const std::vector<std::pair<std::string, std::string>>& edits) {
    std::string text = *scene_text_;
    text.replace(text.find("name: healthy"), 13, "name: " + name);
    for (const auto& [from, to] : edits) {
      const std::size_t at = text.find(from);
      EXPECT_NE(at, std::string::npos) << from;
      if (at != std::string::npos) text.replace(at, from.size(), to);
    }
    return dir_->Write("scene/" + name + ".yaml", text);
  }
  static std::string Out(const std::string& name) { return dir_->File("out/" + name); }

  static TestDir* dir_;
  static std::string* scene_text_;
};
TestDir* FailedStageRun::dir_ = nullptr;
std::string* FailedStageRun::scene_text_ = nullptr;

const std::pair<std::string, std::string> kNoValidSubset = {"min_zncc: 0.8", "min_zncc: 0.99999"};

TEST_F(FailedStageRun, EmptyCorrelationFailsNamingTheStagesAndWritesNothing) {
  const Scene scene = LoadScene(Variant("empty", {kNoValidSubset}));
  // An earlier generation in the output folder stays as it was.
  PipelineOptions options;
  options.output_folder = Out("empty");
  fs::create_directories(options.output_folder);
  std::ofstream(options.output_folder + "/summary.json") << "earlier run\n";
  try {
    RunScene(scene, options);
    FAIL() << "expected the run to fail";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kNumerical);
    const std::string m = e.what();
    EXPECT_TRUE(Contains(m, "2 stage(s) produced nothing usable")) << m;
    EXPECT_TRUE(Contains(m, "correlate: no valid subset in any of the")) << m;
    EXPECT_TRUE(Contains(m, "dic.min_zncc = 0.99999")) << m;
    EXPECT_TRUE(Contains(m, "momentum: t_e is not measurable")) << m;
    // The library names its option (PipelineOptions::allow_partial), never a command-line flag;
    // `impactdic run` names its flag (RunCommandExitsNonZeroUnlessAllowPartial).
    EXPECT_TRUE(Contains(m, "; the option `allow_partial` writes them, with the figures")) << m;
    EXPECT_FALSE(Contains(m, "--")) << m;
    EXPECT_TRUE(dynamic_cast<const PartialResultsError*>(&e) != nullptr);
  }
  EXPECT_EQ(ReadText(options.output_folder + "/summary.json"), "earlier run\n");
  EXPECT_FALSE(fs::exists(options.output_folder + "/results.h5"));
  EXPECT_FALSE(fs::exists(options.output_folder + "/summary.csv"));
  // A folder the failed run would have created is not left behind.
  options.output_folder = Out("empty_new");
  EXPECT_THROW(RunScene(scene, options), Error);
  EXPECT_FALSE(fs::exists(options.output_folder));
}

TEST_F(FailedStageRun, AllowPartialWritesNullFiguresWithTheReasons) {
  PipelineOptions options;
  options.output_folder = Out("healthy");
  const PipelineSummary good = RunScene(LoadScene(Variant("healthy", {})), options);
  ASSERT_TRUE(good.IsUsable()) << good.FailureText();
  ASSERT_TRUE(std::isfinite(good.figures.added_mass_max_kg));
  EXPECT_TRUE(Contains(ReadText(Out("healthy/summary.json")), "\"usable\": true"));

  // The figures render too: the added-mass figure has nothing to draw and is skipped, not fatal.
  options.output_folder = Out("partial");
  options.allow_partial = true;
  const Scene scene =
      LoadScene(Variant("partial", {kNoValidSubset, {"figures: false", "figures: true"}}));
  const PipelineSummary bad = RunScene(scene, options);
  ASSERT_EQ(bad.failures.size(), 2u);
  EXPECT_EQ(bad.failures[0].stage, "correlate");
  EXPECT_EQ(bad.failures[1].stage, "momentum");
  const SceneFigures& f = bad.figures;
  EXPECT_EQ(f.dic_valid_fraction, 0.0);
  for (double unmeasured :
       {f.t_end_peak_s, f.momentum_conservation_error, f.added_mass_max_kg, f.sigmoid_M_kg,
        f.sigmoid_b_per_s, f.sigmoid_T_s, f.momentum_ratio_measured, f.v_sand_max_m_s})
    EXPECT_TRUE(std::isnan(unmeasured));
  // What the sensor measures alone is unaffected.
  EXPECT_EQ(f.p_max_kg_m_s, good.figures.p_max_kg_m_s);
  EXPECT_EQ(f.crater_depth_measured_m, good.figures.crater_depth_measured_m);
  // The measured peak deceleration: the issue's run said 2.25 g (the "peak stage" ended at the
  // fallback t_e, the first frame after the impact); with t_e unmeasured the window is T + 4/b,
  // which holds the peak the healthy run finds before its t_e (the sensor's own peak).
  EXPECT_NEAR(f.peak_deceleration_measured_g, good.figures.peak_deceleration_measured_g,
              0.01 * good.figures.peak_deceleration_measured_g);
  EXPECT_GT(f.peak_deceleration_measured_g, 10.0);
  const std::string json = ReadText(Out("partial/summary.json"));
  for (const char* part :
       {"\"added_mass_max_kg\": null", "\"t_end_peak_s\": null", "\"sigmoid_M_kg\": null",
        "\"momentum_ratio_measured\": null", "\"momentum_conservation_error\": null",
        "\"usable\": false", "\"correlate\": \"no valid subset", "t_e is not measurable",
        "peak deceleration (measured): t_e was not measured"})
    EXPECT_TRUE(Contains(json, part)) << part << "\n" << json;
  EXPECT_TRUE(fs::exists(Out("partial/results.h5")));
  EXPECT_TRUE(fs::exists(Out("partial/momentum.png")));
  EXPECT_FALSE(fs::exists(Out("partial/added_mass.png")));
}

TEST_F(FailedStageRun, RunCommandExitsNonZeroUnlessAllowPartial) {
  const std::string scene = Variant("cli", {kNoValidSubset});
  const CliResult failed = RunCli("run " + scene + " -o " + Out("cli"));
  EXPECT_EQ(failed.exit_code, 1) << failed.output;
  EXPECT_TRUE(Contains(failed.output,
                       "impactdic: error: scene cli: 2 stage(s) produced nothing "
                       "usable"))
      << failed.output;
  EXPECT_TRUE(Contains(failed.output, "; `impactdic run --allow-partial` writes them, with the"))
      << failed.output;
  EXPECT_FALSE(Contains(failed.output, "allow_partial")) << failed.output;
  EXPECT_FALSE(fs::exists(Out("cli")));
  const CliResult partial =
      RunCli("run " + scene + " -o " + Out("cli") + " --allow-partial --format json");
  EXPECT_EQ(partial.exit_code, 0) << partial.output;
  EXPECT_TRUE(Contains(partial.output, "\"usable\": false")) << partial.output;
  EXPECT_TRUE(Contains(partial.output, "partial results (--allow-partial)")) << partial.output;
  EXPECT_TRUE(fs::exists(Out("cli/summary.json")));
}

// Frames of the peak stage where the soil under most of the momentum grid is unreadable (a dark
// band over the left two thirds of the grid, as where the pounder's shadow or a smear covers it).
TEST_F(FailedStageRun, UnreadableGridInSomeFramesOfThePeakStage) {
  const fs::path frames = dir_->path() / "scene" / "frames";
  const fs::path painted = dir_->path() / "scene" / "painted";
  fs::create_directories(painted);
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(frames)) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  // Frame 0 is before the impact (reference), frames 3..5 are in the peak stage (t_e ~ 3 ms, 1600
  // fps). The grid: 6 columns centred on x = 160 px, rows just below y = 59.5 px, step 12 px.
  for (std::size_t k = 0; k < files.size(); ++k) {
    cv::Mat image = cv::imread(files[k].string(), cv::IMREAD_UNCHANGED);
    if (k >= 3 && k <= 5)
      cv::rectangle(image, cv::Rect(110, 50, 62, 50), cv::Scalar(0), cv::FILLED);
    cv::imwrite((painted / files[k].filename()).string(), image);
  }
  const Scene scene = LoadScene(Variant("painted", {{"frames/frame_", "painted/frame_"}}));
  PipelineOptions options;
  options.output_folder = Out("painted");
  options.allow_partial = true;
  const PipelineSummary s = RunScene(scene, options);
  ASSERT_EQ(s.failures.size(), 1u) << s.FailureText();
  EXPECT_EQ(s.failures[0].stage, "momentum");
  EXPECT_TRUE(Contains(s.failures[0].reason, "have no measured p_gran")) << s.failures[0].reason;
  EXPECT_TRUE(std::isnan(s.figures.added_mass_max_kg));
  EXPECT_TRUE(std::isnan(s.figures.t_end_peak_s));
  bool counted = false;
  for (const auto& w : s.warnings)
    counted = counted || Contains(w, "momentum-grid subsets valid (momentum.min_valid_fraction");
  EXPECT_TRUE(counted);
}

TEST_F(FailedStageRun, ModelThatDoesNotStopFailsTheRun) {
  // K = 0: no soil resistance, the pounder never stops (the solver gives up at t_max = 10 s).
  const Scene scene = LoadScene(Variant("nostop", {{"K: 50", "K: 0"}}));
  Scene model_only = scene;
  model_only.stages = {"sensor", "model", "outputs"};
  PipelineOptions options;
  options.output_folder = Out("nostop");
  try {
    RunScene(model_only, options);
    FAIL() << "expected the run to fail";
  } catch (const Error& e) {
    EXPECT_TRUE(Contains(e.what(),
                         "model: the solve did not reach v = 0: v did not reach 0 by "
                         "t_max"))
        << e.what();
  }
  EXPECT_FALSE(fs::exists(options.output_folder));
  options.allow_partial = true;
  const PipelineSummary s = RunScene(model_only, options);
  EXPECT_TRUE(std::isnan(s.figures.t_end_model_s));
  EXPECT_TRUE(std::isnan(s.figures.crater_depth_model_m));
  EXPECT_TRUE(std::isnan(s.figures.plateau_deceleration_model_g));
}

TEST_F(FailedStageRun, CampaignLeavesUnusableScenesOutOfTheEq4Fit) {
  CampaignOptions options;
  options.output_folder = Out("campaign");
  const CampaignSummary s =
      RunCampaign({Variant("good", {}), Variant("bad", {kNoValidSubset})}, options);
  ASSERT_EQ(s.rows.size(), 2u);
  EXPECT_TRUE(s.rows[0].excluded.empty()) << s.rows[0].excluded;
  EXPECT_TRUE(Contains(s.rows[1].excluded, "correlate: no valid subset")) << s.rows[1].excluded;
  EXPECT_FALSE(s.fitted);
  EXPECT_TRUE(Contains(s.fit_note, "1 of 2 tests")) << s.fit_note;
  EXPECT_TRUE(Contains(s.FullReport(), "not in the Eq. 4 fit: a stage produced nothing usable"))
      << s.FullReport();
  const std::string regression = ReadText(Out("campaign/regression.json"));
  EXPECT_TRUE(Contains(regression, "\"excluded\": {\"bad\": \"a stage produced nothing usable"))
      << regression;
  CsvReadOptions read;
  read.allow_non_finite = true;
  read.text_columns = {"scene",      "eq4_fit",     "source",
                       "status",     "error",       "eq4_excluded_reason",
                       "scene_hash", "tool_version"};
  const CsvTable table = ReadCsv(Out("campaign/campaign.csv"), read);
  EXPECT_EQ(table.TextColumn("eq4_fit"), (std::vector<std::string>{"used", "excluded"}));
  EXPECT_EQ(table.TextColumn("status"), (std::vector<std::string>{"ok", "unusable"}));
  // The failed scene's own outputs are there (the campaign runs scenes with allow_partial).
  EXPECT_TRUE(Contains(ReadText(Out("campaign/bad/results/summary.json")), "\"usable\": false"));
}

// A campaign table whose rows say "excluded" never enters the fit, even with a finite m_add,max:
// five rows exactly on Eq. 4 and one excluded outlier give Eq. 4's coefficients back.
TEST(FailedStageCampaign, ExcludedTableRowsStayOutOfTheFit) {
  TestDir dir;
  std::string text = "scene,mass_kg,velocity_m_s,area_m2,added_mass_max_kg,eq4_fit\n";
  const double rows[][3] = {{7, 2, 0.0192},   {10, 3.7, 0.0288}, {13, 4.9, 0.0384},
                            {7, 4.9, 0.0288}, {13, 2, 0.0192},   {10, 2, 0.0384}};
  int k = 0;
  for (const auto& r : rows) {
    const double madd = 425 * std::pow(r[0], 0.1) * std::pow(r[1], 0.2) * std::pow(r[2], 1.3);
    text += "t" + std::to_string(++k) + "," + std::to_string(r[0]) + "," + std::to_string(r[1]) +
            "," + std::to_string(r[2]) + "," + std::to_string(madd) + ",used\n";
  }
  text += "outlier,10,3.7,0.0288,100,excluded\n";
  CampaignOptions options;
  options.output_folder = dir.File("out");
  const CampaignSummary s = RegressCampaignTable(dir.Write("t.csv", text), options);
  ASSERT_TRUE(s.fitted) << s.fit_note;
  EXPECT_EQ(s.fit.n, 6u);
  EXPECT_NEAR(s.fit.g, 1.3, 1e-3);
  EXPECT_NEAR(s.fit.c, 425, 425 * 0.02);
  EXPECT_TRUE(Contains(s.rows.back().excluded, "eq4_fit")) << s.rows.back().excluded;
}

}  // namespace
}  // namespace impactdic
