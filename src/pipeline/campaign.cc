// Running a campaign: each test (synthesised first if it is a spec) through the pipeline into its
// own folder, one generation each; complete tests of an earlier run are resumed; tests run in
// parallel (bounded), each in its own TBB arena; then the campaign-level files.
#include "impactdic/pipeline/campaign.h"

#include <fmt/format.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <exception>
#include <filesystem>
#include <mutex>
#include <optional>
#include <system_error>
#include <thread>

#include "campaign_internal.h"
#include "impactdic/core/error.h"
#include "impactdic/core/interrupt.h"
#include "impactdic/core/log.h"
#include "impactdic/core/progress.h"
#include "impactdic/core/threads.h"
#include "impactdic/core/timer.h"
#include "impactdic/io/output_generation.h"
#include "impactdic/model/impact_model.h"
#include "impactdic/pipeline/scene.h"

namespace impactdic {
namespace fs = std::filesystem;
using namespace campaign_internal;
namespace {

// The row's inputs, known before the test runs.
CampaignRow RowSkeleton(const CampaignTest& t) {
  CampaignRow r;
  r.index = t.index;
  r.name = t.name;
  r.source = t.source;
  r.scene_hash = t.hash_hex;
  r.tool_version = ToolVersion();
  if (t.synthesise) {
    r.mass_kg = t.spec.pounder_mass_kg;
    r.drop_height_m = t.spec.drop_height_m;
    r.velocity_m_s = t.spec.ImpactVelocity();
    r.width_m = t.spec.width_m;
    r.area_m2 = t.spec.width_m * t.spec.depth_m;
    r.added_mass_given_kg = t.spec.added_mass_kg;
  } else {
    const Scene scene = LoadScene(t.scene_path);
    r.mass_kg = scene.model.pounder_mass_kg;
    // A scene giving v0 directly has no drop height.
    r.drop_height_m = scene.test.impact_velocity_m_s ? CampaignRow::kNaN : scene.test.drop_height_m;
    r.velocity_m_s = scene.ImpactVelocity();
    r.width_m = scene.model.width_m;
    r.area_m2 = scene.model.ContactArea_m2();
  }
  return r;
}

// The row of a complete earlier result of this test (same scene hash and tool version), if any.
std::optional<CampaignRow> CompleteRow(const CampaignTest& t, const std::string& folder) {
  const fs::path dir = fs::path(folder) / t.name;
  std::error_code ec;
  if (!fs::is_regular_file(dir / kRowCsv, ec) || !fs::exists(dir / kOutputMarkerName, ec))
    return std::nullopt;
  try {
    std::vector<CampaignRow> rows = ReadRows((dir / kRowCsv).string());
    if (rows.size() != 1 || rows[0].scene_hash != t.hash_hex ||
        rows[0].tool_version != ToolVersion() || rows[0].status == "failed") {
      return std::nullopt;
    }
    rows[0].index = t.index;  // The plan may have changed around it.
    rows[0].source = t.source;
    return rows[0];
  } catch (const Error& e) {
    LogWarning("campaign: {}: earlier results not reusable ({}); processing it again", t.name,
               e.what());
    return std::nullopt;
  }
}

// Synthesises (if needed) and runs one test into its folder (a generation of its own, complete or
// absent). `threads`: PipelineOptions::threads. Never throws for the test's own errors: they
// become status "failed" with the message.
CampaignRow ProcessTest(const CampaignTest& t, const std::string& folder, int threads, bool force) {
  WallTimer timer;
  CampaignRow row;
  row.index = t.index;
  row.name = t.name;
  row.source = t.source;
  try {
    row = RowSkeleton(t);  // Loads the scene file again: it may have gone meanwhile.
    OutputGenerationOptions go;
    go.command = "impactdic campaign (test " + t.name + ")";
    go.own_names = {"results", "synth", kRowCsv};
    go.force = force;
    OutputGeneration generation((fs::path(folder) / t.name).string(), go);
    std::string scene_path = t.scene_path;
    if (t.synthesise) {
      const ImpactScene synthetic(t.spec);
      scene_path = WriteImpactScene(synthetic, generation.Path("synth")).scene_yaml;
    }
    Scene scene = LoadScene(scene_path);
    if (t.animation) scene.outputs.animation = *t.animation;
    if (t.figures) scene.outputs.figures = *t.figures;
    PipelineOptions p;
    p.output_folder = generation.Path("results");
    p.threads = threads;
    p.allow_partial = true;  // Its outputs are written; it stays out of the fit (FitEq4).
    const PipelineSummary run = RunScene(scene, p);
    row.figures = run.figures.CsvValues();
    if (std::isfinite(run.figures.impact_velocity_m_s))
      row.velocity_m_s = run.figures.impact_velocity_m_s;
    row.status = run.IsUsable() ? "ok" : "unusable";
    if (!run.IsUsable()) row.excluded = "a stage produced nothing usable: " + run.FailureText();
    row.wall_time_s = timer.ElapsedSeconds();
    WriteRows(generation.Path(kRowCsv), {row});
    generation.Commit();
  } catch (const std::exception& e) {
    WaitIfInterrupted();  // An error caused by an interruption: the cleanup ends the process.
    row.status = "failed";
    row.error = e.what();
    row.wall_time_s = timer.ElapsedSeconds();
    LogWarning("campaign: test {} failed: {}", t.name, e.what());
  }
  return row;
}

struct Parallelism {
  int jobs = 1;           // Tests at the same time.
  int test_threads = -1;  // Threads of each test: an arena's size, or -1 (the scene's dic.threads).
};

// Both counts follow the one thread rule (core ThreadsToUse: at most the machine's cores).
Parallelism SplitThreads(const CampaignOptions& o, std::size_t tests) {
  Parallelism p;
  const int n = static_cast<int>(std::max<std::size_t>(tests, 1));
  const int jobs = o.jobs > 0 ? ThreadsToUse(o.jobs, "campaign jobs") : 0;
  if (o.threads < 0) {
    p.jobs = std::min(jobs > 0 ? jobs : 1, n);
    return p;
  }
  const int total = ThreadsToUse(o.threads, "campaign threads");
  p.jobs = std::min(jobs > 0 ? jobs : total, n);
  p.test_threads = std::max(1, total / p.jobs);
  return p;
}

// Runs the selected tests with `par.jobs` workers; rows in `rows` (by position in `todo`).
void RunTests(const std::vector<const CampaignTest*>& todo, const std::string& folder,
              const Parallelism& par, bool force, std::vector<CampaignRow>* rows) {
  rows->resize(todo.size());
  ProgressBar bar("campaign", todo.size());
  std::mutex mutex;
  std::atomic<std::size_t> next{0};
  const auto worker = [&] {
    for (std::size_t i = next++; i < todo.size(); i = next++) {
      LogInfo("campaign: test {} ({} of {}) -> {}", todo[i]->name, i + 1, todo.size(),
              (fs::path(folder) / todo[i]->name).string());
      CampaignRow row;
      if (par.test_threads > 0) {
        tbb::task_arena arena(par.test_threads);
        arena.execute([&] { row = ProcessTest(*todo[i], folder, /*threads=*/0, force); });
      } else {
        row = ProcessTest(*todo[i], folder, /*threads=*/-1, force);
      }
      const std::lock_guard<std::mutex> lock(mutex);
      (*rows)[i] = std::move(row);
      bar.Advance();
    }
  };
  // A worker that cannot be started, or an error outside a test (the log, the progress bar),
  // stops the others at their next test; the error is rethrown once all are joined, so the
  // callers' temporaries are removed as for any error (never std::terminate on a joinable thread).
  std::exception_ptr error;
  const auto guarded = [&] {
    try {
      worker();
    } catch (...) {
      next = todo.size();
      const std::lock_guard<std::mutex> lock(mutex);
      if (!error) error = std::current_exception();
    }
  };
  std::vector<std::thread> threads;
  try {
    for (int j = 1; j < par.jobs; ++j) threads.emplace_back(guarded);
  } catch (...) {
    next = todo.size();
    const std::lock_guard<std::mutex> lock(mutex);
    error = std::current_exception();
  }
  if (next < todo.size()) guarded();
  for (auto& t : threads) t.join();
  if (error) std::rethrow_exception(error);
  bar.Finish();
}

}  // namespace

void CampaignOptions::Check() const {
  CheckValue(!output_folder.empty(), "output_folder", "an empty path", "a folder");
  CheckValue(threads == -1 || IsValidThreadCount(threads), "threads", std::to_string(threads),
             std::string("-1 (each scene's dic.threads) or ") + kThreadCountExpected);
  CheckValue(jobs >= 0, "jobs", std::to_string(jobs), "0 (auto) or a number of tests >= 1");
  CheckValue(confidence > 0 && confidence < 1, "confidence", fmt::format("{}", confidence),
             "a level in (0, 1)");
  CheckValue(shard.count >= 1 && shard.index >= 1 && shard.index <= shard.count, "shard",
             shard.ToString(), "I/N with 1 <= I <= N");
}

CampaignSummary RunCampaignPlan(const CampaignPlan& plan, const CampaignOptions& options) {
  options.Check();
  WallTimer timer;
  std::vector<const CampaignTest*> todo;
  CampaignSummary summary;
  summary.tests_total = static_cast<int>(plan.tests.size());
  // The selected tests, each with the hash resuming compares: a scene file's hash with its
  // inputs' (SceneInputsHash), so a replaced frame or sensor record re-runs the test.
  std::vector<CampaignTest> selected;
  selected.reserve(plan.tests.size());  // `todo` points into it.
  for (const CampaignTest& planned : plan.tests) {
    if (!options.shard.Selects(planned.index)) continue;
    CampaignTest& t = selected.emplace_back(planned);
    if (!t.synthesise) {
      const Scene scene = LoadScene(t.scene_path);
      // The campaign folder's generation keeps what it holds: still, no input may lie in it.
      CheckOutputFolderHoldsNoInput(scene, options.output_folder, "-o");
      t.hash_hex = ContentHash(t.hash_hex + " inputs " + SceneInputsHash(scene));
    }
    std::optional<CampaignRow> done =
        options.force ? std::nullopt : CompleteRow(t, options.output_folder);
    if (done) {
      LogInfo("campaign: test {} is complete in {} (same scene, inputs and tool): not run again",
              t.name, (fs::path(options.output_folder) / t.name).string());
      summary.rows.push_back(std::move(*done));
      ++summary.resumed;
    } else {
      todo.push_back(&t);
    }
  }
  // Checks the folder before any work; written at the end (the tests' folders commit on their own).
  OutputGeneration generation(options.output_folder,
                              CampaignLevelGeneration("impactdic campaign", options.force));
  const Parallelism par = SplitThreads(options, todo.size());
  std::optional<ThreadLimit> limit;
  if (options.threads >= 0) limit.emplace(options.threads, "campaign threads");
  LogInfo("campaign: {} tests to run ({} resumed, shard {}), {} at a time, {} threads each",
          todo.size(), summary.resumed, options.shard.ToString(), par.jobs,
          par.test_threads > 0 ? std::to_string(par.test_threads) : "scene's dic.threads");
  std::vector<CampaignRow> rows;
  RunTests(todo, options.output_folder, par, options.force, &rows);
  for (auto& r : rows) {
    summary.failed += r.status == "failed";
    summary.rows.push_back(std::move(r));
  }
  FitAndWrite(&summary, options, generation.staging_folder(),
              plan.yaml_text.empty() ? "# scene files\n" : plan.yaml_text);
  generation.Commit();
  for (auto& o : summary.outputs) o = generation.FinalPath(o);
  summary.seconds = timer.ElapsedSeconds();
  return summary;
}

CampaignSummary RunCampaign(const std::vector<std::string>& scene_paths,
                            const CampaignOptions& options) {
  options.Check();
  if (scene_paths.size() == 1 && IsCampaignFile(scene_paths[0]))
    return RunCampaignPlan(LoadCampaignFile(scene_paths[0]), options);
  for (const std::string& f : scene_paths) {
    if (IsCampaignFile(f)) {
      throw Error(ErrorKind::kInvalidValue, "files", f + " is a campaign file",
                  "one campaign file alone, or scene files");
    }
  }
  return RunCampaignPlan(PlanFromSceneFiles(scene_paths), options);
}

void CampaignSummary::ThrowIfEveryTestFailed(const std::string& folder) const {
  // A shard holds part of the campaign: its failures are rows the merge reports.
  if (rows.empty() || failed < static_cast<int>(rows.size()) ||
      static_cast<int>(rows.size()) < tests_total) {
    return;
  }
  throw Error(ErrorKind::kNumerical,
              fmt::format("campaign: all {} tests failed, none has results (each test's error is "
                          "in {}/campaign.csv); the first, {}: {}",
                          failed, folder, rows.front().name, rows.front().error));
}

CampaignSummary RunCampaignRequest(CampaignRequest request) {
  const int modes = !request.files.empty() + !request.table.empty() + !request.merge.empty();
  CheckValue(modes == 1, "files / table / merge", modes == 0 ? "none" : "more than one",
             "a campaign file or scene files, a table, or merge folders: one of them");
  CampaignOptions& options = request.options;
  if (request.threads) CheckThreadCount(*request.threads, "threads");
  options.threads = request.threads.value_or(-1);
  if (!request.shard.empty()) options.shard = ParseShard(request.shard, "shard");
  options.Check();
  CheckValue(request.RunsTests() || request.shard.empty(), "shard", "with a table or merge folders",
             "a shard only when running tests");
  if (!request.table.empty()) return RegressCampaignTable(request.table, options);
  if (!request.merge.empty()) return MergeCampaigns(request.merge, options);
  return RunCampaign(request.files, options);
}

}  // namespace impactdic
