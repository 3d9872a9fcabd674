#include <CLI/CLI.hpp>
#include <iostream>
#include <memory>

#include "commands.h"
#include "impactdic/core/version.h"

namespace impactdic::cli {

void RegisterVersionCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("version", "Print the tool version and git revision");
  cmd->callback(
      [] { std::cout << "impactdic " << Version() << " (git " << GitRevision() << ")\n"; });
}

}  // namespace impactdic::cli
