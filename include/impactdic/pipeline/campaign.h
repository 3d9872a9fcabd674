// A campaign: many impact tests (e.g. the paper's 27 combinations of m_p, h and D, Table 1), each
// run through the whole pipeline, then the paper's Section 5 over all of them: the power-law
// regression of Eq. 4,
//   m_add,max = c m_p^a v0^b A^g   (paper: c = 425, a = 0.1, b = 0.2, g = 1.3),
// with confidence intervals (momentum/fit.h), and the comparison figures of measured against
// modelled values (Figs. 5, 7-10, render/comparison_figures.h). Full description: docs/campaign.md.
//
//   CampaignPlan plan = LoadCampaignFile("docs/campaign/table1_synthetic.yaml");
//   // or PlanFromSceneFiles({"t01/scene.yaml", "t02/scene.yaml"})
//   CampaignOptions options;
//   options.output_folder = "results/campaign";
//   options.shard = ParseShard("2/3", "--shard");   // optional: every third test
//   CampaignSummary s = RunCampaignPlan(plan, options);
//   MergeCampaigns({"out1", "out2", "out3"}, options);  // shards -> one campaign
//
// Output folder (options.output_folder):
//   <test>/            one folder per test, named uniquely (CampaignTest::name), ONE GENERATION
//                      each (io/output_generation.h), swapped in as soon as that test is complete:
//                        results/        the pipeline's outputs (pipeline.h)
//                        synth/          the synthesised scene (synthesised tests only)
//                        campaign_row.csv  the test's campaign.csv row (with scene_hash and
//                                        tool_version: what resuming compares)
//   campaign.csv, campaign.h5, regression.json, fig5_added_mass.png, fig7_peak_deceleration.png,
//   fig8_plateau_deceleration.png, fig9_relative_penetration.png, fig10_momentum_ratio.png:
//                      the campaign-level files, one generation written at the end (it keeps the
//                      test folders, hard-linked).
// So an interrupted campaign keeps every test that was complete; the next run with the same plan
// finds them (same scene hash -- the scene file and every input file it reads -- and tool
// version) and processes only the others (unless options.force).
//
// A test whose pipeline throws is "failed": its error is in its campaign.csv row (status, error)
// and the others go on. A test that ran but whose m_add,max is not usable (a stage produced
// nothing usable, PipelineSummary::failures, or no finite m_add,max) is "unusable" or "ok" with
// eq4_fit = excluded: it never enters the Eq. 4 fit; regression.json says why.
#ifndef IMPACTDIC_PIPELINE_CAMPAIGN_H_
#define IMPACTDIC_PIPELINE_CAMPAIGN_H_

#include <algorithm>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "impactdic/io/json.h"
#include "impactdic/momentum/fit.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/render/comparison_figures.h"
#include "impactdic/synth/impact_scene.h"

namespace impactdic {

// Process test k (1-based index in the plan) if (k - 1) % count == index - 1.
struct CampaignShard {
  int index = 1, count = 1;  // 1 <= index <= count.
  bool Selects(int test_index) const { return (test_index - 1) % count == index - 1; }
  std::string ToString() const;
};
// "I/N" with 1 <= I <= N; Error kInvalidValue naming `where` otherwise.
CampaignShard ParseShard(const std::string& text, const std::string& where);

struct CampaignOptions {
  std::string output_folder = "results/campaign";
  // Total worker threads of the campaign: 0 = all cores, N >= 1 (capped at the cores, core
  // ThreadsToUse, like `jobs`); -1 = each scene's dic.threads for its correlation (scenes one at a
  // time unless `jobs` says otherwise).
  int threads = -1;
  // Tests processed at the same time: 0 = auto (threads / 2, at least 1, at most the number of
  // tests; bounded because each test holds its frames: peak memory ~ jobs x one test's peak,
  // docs/campaign.md), N >= 1. Each test's correlation gets max(1, threads / jobs) threads.
  int jobs = 0;
  double confidence = 0.95;  // Of the regression intervals, in (0, 1).
  // Reprocess tests whose complete results exist; replace an output folder another kind of
  // command wrote (a run, a synth scene: io/output_generation.h).
  bool force = false;
  bool figures = true;  // The comparison figures (Figs. 5, 7-10).
  CampaignShard shard;  // Only the tests of this shard.
  void Check() const;
};

// One test of a campaign: a scene file, or a scene to synthesise first (ImpactSceneSpec).
struct CampaignTest {
  int index = 0;           // 1-based position in the plan (shards select by it).
  std::string name;        // Unique in the plan: its folder in the output.
  std::string scene_path;  // A scene file; empty for a synthesised test.
  bool synthesise = false;
  ImpactSceneSpec spec;  // With synthesise.
  std::string source;    // Scene path, or "synthesised", for messages and the CSV.
  // The campaign file's `outputs:` (applied to the scene's outputs section); unset: the scene's.
  std::optional<bool> animation, figures;
  // Hash of the scene file's bytes or of the spec's YAML (16 hex digits). Resuming compares it
  // combined with the hash of the scene's input files (RunCampaignPlan; docs/campaign.md).
  std::string hash_hex;
};

struct CampaignPlan {
  std::string path;       // The campaign file ("" for a list of scene files).
  std::string yaml_text;  // Its text (provenance in campaign.h5).
  std::vector<CampaignTest> tests;
};

// The plan of a campaign file (docs/campaign.md): `scenes` (files), `scene_glob` (patterns) and/or
// `synthesise` (a parameter matrix, Table 1 by default). Paths are relative to the campaign file.
// Error naming the key path for unknown keys, bad values, duplicate keys, missing scene files, a
// glob matching nothing, or an empty plan.
CampaignPlan LoadCampaignFile(const std::string& path);
// The plan of scene files given on the command line (each loaded, so checked).
CampaignPlan PlanFromSceneFiles(const std::vector<std::string>& scene_paths);
// True if the file is a campaign file (a map with `scenes`, `scene_glob` or `synthesise` and no
// scene keys such as `inputs`), false for a scene file.
bool IsCampaignFile(const std::string& path);

// One row of campaign.csv.
struct CampaignRow {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  int index = 0;
  std::string name, source;
  double mass_kg = kNaN, drop_height_m = kNaN, velocity_m_s = kNaN, width_m = kNaN, area_m2 = kNaN;
  // Synthesised tests: the added mass M the scene was made with (the measured m_add,max should
  // equal it, docs/campaign.md); NaN for scene files.
  double added_mass_given_kg = kNaN;
  // SceneFigures::CsvValues() (names: SceneFigures::CsvNames()) of the test's pipeline run.
  std::vector<double> figures = SceneFigures{}.CsvValues();
  double Figure(const std::string& csv_name) const;  // By SceneFigures::CsvNames() name.
  // "ok", "unusable" (ran; a stage produced nothing usable) or "failed" (error; `error` says).
  std::string status;
  std::string error;
  // Why the test is left out of the Eq. 4 fit; empty: it is in the fit.
  std::string excluded;
  std::string scene_hash, tool_version;
  double wall_time_s = kNaN;  // Of this test's synth + pipeline (the only run-dependent column
                              // besides dic_subsets_per_s).
  double RelativePenetrationMeasured() const;  // Eq. 10: crater depth / D.
  double RelativePenetrationModel() const;
};

struct CampaignSummary {
  std::vector<CampaignRow> rows;  // Plan order (the shard's tests only, for a shard).
  int tests_total = 0;            // In the plan.
  int resumed = 0;                // Rows taken from complete earlier results.
  int failed = 0;
  bool fitted = false;
  std::string fit_note;  // Why there is no fit (too few usable tests), if so.
  PowerLawFit fit;
  std::vector<std::pair<std::string, ComparisonFit>> comparisons;  // Figure name -> fit.
  std::vector<std::string> outputs;
  std::vector<std::string> warnings;
  double seconds = 0;
  JsonObject RegressionJson() const;
  std::string FullReport() const;
  // A campaign none of whose tests has results (every one failed) is a failed command: Error
  // kNumerical naming how many failed, the first error and `folder`/campaign.csv, which lists each
  // test's error. Some failed tests among good ones are not an error (docs/campaign.md), nor is a
  // shard (rows of part of the campaign) whose tests all failed: the merge, which holds every
  // test, reports them, and is the failed command when every test of the campaign failed.
  void ThrowIfEveryTestFailed(const std::string& folder) const;
};

// Runs the plan's tests (those of options.shard) in parallel, resuming complete ones, then writes
// the campaign-level files. Error for bad options or an output folder that cannot be used; a
// failing test is a row with status "failed", not an error.
CampaignSummary RunCampaignPlan(const CampaignPlan& plan, const CampaignOptions& options);
// The same for the command line's files: one campaign file alone, or scene files (Error naming
// "files" for a campaign file among others).
CampaignSummary RunCampaign(const std::vector<std::string>& scene_paths,
                            const CampaignOptions& options);

// Combines the outputs of shard runs (their campaign.csv rows) into options.output_folder:
// the rows sorted by test index give exactly the campaign.csv of one run over all shards
// (wall_time_s and dic_subsets_per_s are those of the shard that ran the test). Error if a
// folder has no campaign.csv, two shards hold the same test, the shards come from different plans
// (total test count) or a test is missing.
CampaignSummary MergeCampaigns(const std::vector<std::string>& folders,
                               const CampaignOptions& options);

// The regression alone, from a CSV with the columns mass_kg, velocity_m_s, area_m2 and
// added_mass_max_kg (e.g. a campaign.csv, or the user's own table); rows whose optional eq4_fit
// column says "excluded" are left out. Writes campaign.csv and regression.json.
CampaignSummary RegressCampaignTable(const std::string& csv_path, const CampaignOptions& options);

// What `impactdic campaign` asks for: exactly one of `files` (a campaign file or scene files:
// RunCampaign), `table` (RegressCampaignTable) or `merge` (MergeCampaigns); `shard` ("I/N") and
// `threads` (unset: each scene's dic.threads) only apply to running tests.
struct CampaignRequest {
  std::vector<std::string> files, merge;
  std::string table, shard;
  std::optional<int> threads;
  CampaignOptions options;
  bool RunsTests() const { return table.empty() && merge.empty(); }
};
// Checks the whole request before any work (Error naming "files / table / merge", "shard",
// "threads" or an option's field) and runs it. ThrowIfEveryTestFailed is the caller's, after its
// report.
CampaignSummary RunCampaignRequest(CampaignRequest request);

}  // namespace impactdic

#endif  // IMPACTDIC_PIPELINE_CAMPAIGN_H_
