// impactdic validate-dem TRUTH.h5 RESULTS.h5 [--figures DIR]
// Compares a run on footage filmed from a DEM simulation (impactdic synth --dem) with the truth
// measured on the grains (render/dem_validation.h, docs/validation.md) and prints the table.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "commands.h"
#include "impactdic/core/error.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/csv.h"
#include "impactdic/render/dem_validation.h"

namespace impactdic::cli {
namespace {

struct ValidateDemArgs {
  std::string truth, results, figures, csv;
};

void RunValidateDem(const ValidateDemArgs& args) {
  namespace fs = std::filesystem;
  for (const auto& [name, path] : {std::pair{"TRUTH", args.truth}, {"RESULTS", args.results}}) {
    std::error_code ec;
    if (!fs::is_regular_file(path, ec))
      throw Error(ErrorKind::kFileNotFound, name, path, "an existing HDF5 file");
  }
  // Before any work: the table is never written over an input (io/atomic_file.h).
  const std::vector<std::string> columns = {
      "t_s",           "p_pounder_tool_Ns", "p_pounder_dem_Ns", "p_gran_tool_Ns",
      "p_gran_dem_Ns", "p_gran_dem_fd_Ns",  "v_sand_tool_m_s",  "v_sand_dem_m_s",
      "m_add_tool_kg", "m_add_dem_kg"};
  if (!args.csv.empty()) {
    CheckOutputLocation(args.csv,
                        {"--csv", {".csv"}, {args.truth, args.results}, {CsvHeaderLine(columns)}});
  }
  const DemValidation v = [&] {
    try {
      return ValidateDemRun(args.truth, args.results, args.figures);
    } catch (const Error& e) {
      RethrowWithFlagNames(e, {{"figures folder", "--figures"}});
    }
  }();
  std::cout << v.Report();
  if (!args.csv.empty()) {
    WriteCsv(args.csv, columns,
             {v.t_s, v.p_pounder_tool_Ns, v.p_pounder_truth_Ns, v.p_gran_tool_Ns, v.p_gran_truth_Ns,
              v.p_gran_fd_truth_Ns, v.v_sand_tool_m_s, v.v_sand_truth_m_s, v.m_add_tool_kg,
              v.m_add_truth_kg},
             8);
  }
}

}  // namespace

void RegisterValidateDemCommand(CLI::App& app) {
  auto args = std::make_shared<ValidateDemArgs>();
  auto* cmd = app.add_subcommand(
      "validate-dem",
      "Compare a run on DEM footage (synth --dem) with the grains' truth (docs/validation.md)");
  cmd->add_option("TRUTH", args->truth, "truth.h5 of impactdic synth --dem")->required();
  cmd->add_option("RESULTS", args->results, "results.h5 of impactdic run")->required();
  cmd->add_option("--figures", args->figures,
                  "Folder for velocity_field_compare.png, momentum_compare.png and "
                  "deceleration_compare.png");
  cmd->add_option("--csv", args->csv, "Write the per-frame series (tool and grains) as CSV");
  cmd->callback([args] { RunValidateDem(*args); });
}

}  // namespace impactdic::cli
