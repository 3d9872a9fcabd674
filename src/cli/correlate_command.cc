#include "commands.h"

namespace impactdic::cli {

void RegisterCorrelateCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("correlate", "correlate (not implemented yet)");
  cmd->allow_extras();
  cmd->callback([] { NotImplemented("correlate"); });
}

}  // namespace impactdic::cli
