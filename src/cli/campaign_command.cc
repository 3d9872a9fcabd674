// impactdic campaign SCENE.yaml... [-o OUTDIR] | --from-table CSV: many scenes, then the Eq. 4
// power-law regression over their measured m_add,max (pipeline/campaign.h).
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "commands.h"
#include "impactdic/core/error.h"
#include "impactdic/core/threads.h"
#include "impactdic/pipeline/campaign.h"

namespace impactdic::cli {

void RegisterCampaignCommand(CLI::App& app) {
  struct Args {
    std::vector<std::string> scenes;
    std::string table, output = "results/campaign", format = "text";
    std::optional<int> threads;  // Unset: each scene's dic.threads.
    double confidence = 0.95;
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "campaign",
      "Run many scenes and fit Eq. 4, m_add,max = c m_p^a v0^b A^g, with confidence intervals");
  cmd->add_option("scenes", args->scenes, "Scene files (YAML)");
  cmd->add_option("--from-table", args->table,
                  "Fit Eq. 4 from a CSV with mass_kg, velocity_m_s, area_m2, added_mass_max_kg "
                  "(e.g. a campaign.csv) instead of running scenes");
  cmd->add_option("-o,--output", args->output, "Output folder (default results/campaign)");
  cmd->add_option("--threads", args->threads,
                  std::string("Correlation threads: ") + kThreadCountExpected +
                      " (default: each scene's dic.threads)");
  cmd->add_option("--confidence", args->confidence,
                  "Confidence level of the intervals (default 0.95)");
  cmd->add_option("--format", args->format, "Report on stdout: text or json (the regression)");
  cmd->callback([args] {
    if (args->scenes.empty() == args->table.empty()) {
      throw Error(ErrorKind::kInvalidValue, "scenes / --from-table",
                  args->scenes.empty() ? "neither" : "both",
                  "scene files or --from-table CSV, not both");
    }
    if (args->format != "text" && args->format != "json") {
      throw Error(ErrorKind::kInvalidValue, "--format", args->format, "text or json");
    }
    if (args->threads) CheckThreadCount(*args->threads, "--threads");
    CampaignOptions options;
    options.output_folder = args->output;
    options.threads = args->threads.value_or(-1);
    options.confidence = args->confidence;
    if (!(args->confidence > 0 && args->confidence < 1)) {
      throw Error(ErrorKind::kInvalidValue, "--confidence", std::to_string(args->confidence),
                  "a level in (0, 1)");
    }
    const CampaignSummary summary = args->table.empty()
                                        ? RunCampaign(args->scenes, options)
                                        : RegressCampaignTable(args->table, options);
    if (args->format == "json") {
      std::cout << summary.RegressionJson().Dump() << "\n";
    } else {
      std::cout << summary.FullReport();
    }
  });
}

}  // namespace impactdic::cli
