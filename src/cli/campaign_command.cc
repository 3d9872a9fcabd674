// impactdic campaign CAMPAIGN.yaml | SCENE.yaml... [-o OUTDIR] [--shard I/N] [--jobs N] [--force]
// | --merge DIR... | --from-table CSV: many tests, then the Eq. 4 power-law regression and the
// comparison figures (pipeline/campaign.h, docs/campaign.md).
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.h"
#include "impactdic/core/error.h"
#include "impactdic/core/threads.h"
#include "impactdic/io/json.h"
#include "impactdic/pipeline/campaign.h"

namespace impactdic::cli {
namespace {

// Defaults: the library's CampaignOptions (bound in `options`).
struct CampaignArgs {
  std::vector<std::string> files, merge;
  std::string table, format = "text", shard;
  std::optional<int> threads;  // Unset: each scene's dic.threads.
  bool no_figures = false;
  CampaignOptions options;
};

void Run(CampaignArgs a) {
  const int modes = !a.files.empty() + !a.table.empty() + !a.merge.empty();
  if (modes != 1) {
    throw Error(ErrorKind::kInvalidValue, "files / --from-table / --merge",
                modes == 0 ? "none" : "more than one",
                "a campaign file or scene files, --from-table CSV, or --merge DIR...: one of them");
  }
  CheckFormat(a.format);
  if (a.threads) CheckThreadCount(*a.threads, "--threads");
  CampaignOptions& options = a.options;
  options.threads = a.threads.value_or(-1);
  options.figures = !a.no_figures;
  if (!a.shard.empty()) options.shard = ParseShard(a.shard, "--shard");
  // The library's check (the allowed values are defined there), naming the flags.
  const FlagNames flags = {{"output_folder", "-o"}, {"threads", "--threads"},
                           {"jobs", "--jobs"},      {"confidence", "--confidence"},
                           {"shard", "--shard"},    {"merge folders", "--merge"}};
  WithFlagNames(flags, [&] { options.Check(); });
  if ((!a.table.empty() || !a.merge.empty()) && !a.shard.empty()) {
    throw Error(ErrorKind::kInvalidValue, "--shard", "with --from-table or --merge",
                "--shard only when running tests");
  }
  CampaignSummary summary;
  if (!a.table.empty()) {
    summary = RegressCampaignTable(a.table, options);
  } else if (!a.merge.empty()) {
    summary = WithFlagNames(flags, [&] { return MergeCampaigns(a.merge, options); });
  } else {
    summary = RunCampaign(a.files, options);
  }
  if (a.format == "json") {
    std::cout << summary.RegressionJson().Dump() << "\n";
  } else {
    std::cout << summary.FullReport();
  }
  if (a.table.empty() && a.merge.empty()) summary.ThrowIfEveryTestFailed(options.output_folder);
}

}  // namespace

void RegisterCampaignCommand(CLI::App& app) {
  auto args = std::make_shared<CampaignArgs>();
  auto* cmd = app.add_subcommand(
      "campaign",
      "Run many tests (a campaign file: scene list, glob or synthesised parameter matrix; or "
      "scene files), fit Eq. 4 m_add,max = c m_p^a v0^b A^g with confidence intervals, and draw "
      "the comparison figures (docs/campaign.md)");
  cmd->add_option("files", args->files, "A campaign file (YAML), or scene files");
  cmd->add_option("--from-table", args->table,
                  "Fit Eq. 4 from a CSV with mass_kg, velocity_m_s, area_m2, added_mass_max_kg "
                  "(e.g. a campaign.csv) instead of running tests");
  cmd->add_option("--merge", args->merge,
                  "Combine the output folders of shard runs (--shard I/N) into -o")
      ->expected(1, -1);
  cmd->add_option("-o,--output", args->options.output_folder, "Output folder")
      ->capture_default_str();
  cmd->add_option("--shard", args->shard,
                  "Run only shard I of N: tests I, I+N, I+2N, ... in plan order (e.g. 2/3)");
  cmd->add_option("--jobs", args->options.jobs,
                  "Tests at the same time: 0 = auto (one per thread), N >= 1")
      ->capture_default_str();
  cmd->add_option("--threads", args->threads,
                  std::string("Threads of the whole campaign: ") + kThreadCountExpected +
                      " (default: each scene's dic.threads, one test at a time)");
  cmd->add_flag("--force", args->options.force,
                "Reprocess tests whose complete results exist, and replace an output folder "
                "another command wrote (a run, a synth scene); files impactdic did not write "
                "are never replaced");
  cmd->add_flag("--no-figures", args->no_figures, "Skip the comparison figures");
  cmd->add_option("--confidence", args->options.confidence, "Confidence level of the intervals")
      ->capture_default_str();
  cmd->add_option("--format", args->format, "Report on stdout: text or json (the regression)");
  cmd->callback([args] { Run(*args); });
}

}  // namespace impactdic::cli
