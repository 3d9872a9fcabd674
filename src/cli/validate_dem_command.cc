// impactdic validate-dem TRUTH.h5 RESULTS.h5 [--figures DIR] [--csv TABLE.csv]
//   [--wave-csv WAVE.csv]
// Compares a run on footage filmed from a DEM simulation (impactdic synth --dem) with the truth
// measured on the grains (render/dem_validation.h, docs/validation.md) and prints the table.
#include <CLI/CLI.hpp>
#include <iostream>
#include <memory>
#include <string>

#include "commands.h"
#include "impactdic/render/dem_validation.h"

namespace impactdic::cli {

void RegisterValidateDemCommand(CLI::App& app) {
  struct Args {
    std::string truth, results, figures, csv, wave_csv;
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "validate-dem",
      "Compare a run on DEM footage (synth --dem) with the grains' truth (docs/validation.md)");
  cmd->add_option("TRUTH", args->truth, "truth.h5 of impactdic synth --dem")->required();
  cmd->add_option("RESULTS", args->results, "results.h5 of impactdic run")->required();
  cmd->add_option("--figures", args->figures,
                  "Folder for velocity_field_compare.png, momentum_compare.png and "
                  "deceleration_compare.png");
  cmd->add_option("--csv", args->csv, "Write the per-frame series (tool and grains) as CSV");
  cmd->add_option("--wave-csv", args->wave_csv,
                  "Write the wave figures per base sensor (tool and grains) as CSV");
  cmd->callback([args] {
    const Args& a = *args;
    std::cout << WithFlagNames({{"figures folder", "--figures"}}, [&] {
                   return ValidateDemFiles(a.truth, a.results, a.figures, a.csv, a.wave_csv);
                 }).Report();
  });
}

}  // namespace impactdic::cli
