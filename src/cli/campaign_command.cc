// impactdic campaign CAMPAIGN.yaml | SCENE.yaml... [-o OUTDIR] [--shard I/N] [--jobs N] [--force]
// | --merge DIR... | --from-table CSV: many tests, then the Eq. 4 power-law regression and the
// comparison figures (pipeline/campaign.h, docs/campaign.md).
#include <CLI/CLI.hpp>
#include <iostream>
#include <memory>
#include <string>

#include "commands.h"
#include "impactdic/core/threads.h"
#include "impactdic/io/json.h"
#include "impactdic/pipeline/campaign.h"

namespace impactdic::cli {

void RegisterCampaignCommand(CLI::App& app) {
  auto r = std::make_shared<CampaignRequest>();  // Defaults: the library's CampaignOptions.
  auto format = std::make_shared<std::string>("text");
  auto* cmd = app.add_subcommand(
      "campaign",
      "Run many tests (a campaign file: scene list, glob or synthesised parameter matrix; or "
      "scene files), fit Eq. 4 m_add,max = c m_p^a v0^b A^g with confidence intervals, and draw "
      "the comparison figures (docs/campaign.md)");
  cmd->add_option("files", r->files, "A campaign file (YAML), or scene files");
  cmd->add_option("--from-table", r->table,
                  "Fit Eq. 4 from a CSV with mass_kg, velocity_m_s, area_m2, added_mass_max_kg "
                  "(e.g. a campaign.csv) instead of running tests");
  cmd->add_option("--merge", r->merge,
                  "Combine the output folders of shard runs (--shard I/N) into -o")
      ->expected(1, -1);
  cmd->add_option("-o,--output", r->options.output_folder, "Output folder")->capture_default_str();
  cmd->add_option("--shard", r->shard,
                  "Run only shard I of N: tests I, I+N, I+2N, ... in plan order (e.g. 2/3)");
  cmd->add_option("--jobs", r->options.jobs,
                  "Tests at the same time: 0 = auto (one per thread), N >= 1")
      ->capture_default_str();
  cmd->add_option("--threads", r->threads,
                  std::string("Threads of the whole campaign: ") + kThreadCountExpected +
                      " (default: each scene's dic.threads, one test at a time)");
  cmd->add_flag("--force", r->options.force,
                "Reprocess tests whose complete results exist, and replace an output folder "
                "another command wrote (a run, a synth scene); files impactdic did not write "
                "are never replaced");
  cmd->add_flag("!--no-figures", r->options.figures, "Skip the comparison figures");
  cmd->add_option("--confidence", r->options.confidence, "Confidence level of the intervals")
      ->capture_default_str();
  cmd->add_option("--format", *format, "Report on stdout: text or json (the regression)");
  cmd->callback([r, format] {
    CheckFormat(*format);
    const FlagNames flags = {{"output_folder", "-o"},
                             {"threads", "--threads"},
                             {"jobs", "--jobs"},
                             {"confidence", "--confidence"},
                             {"shard", "--shard"},
                             {"merge folders", "--merge"},
                             {"files / table / merge", "files / --from-table / --merge"}};
    const CampaignSummary summary = WithFlagNames(flags, [&] { return RunCampaignRequest(*r); });
    std::cout << (*format == "json" ? summary.RegressionJson().Dump() + "\n"
                                    : summary.FullReport());
    if (r->table.empty()) summary.ThrowIfEveryTestFailed(r->options.output_folder);
  });
}

}  // namespace impactdic::cli
