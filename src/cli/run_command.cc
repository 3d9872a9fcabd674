#include "commands.h"

namespace impactdic::cli {

void RegisterRunCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("run", "run (not implemented yet)");
  cmd->allow_extras();
  cmd->callback([] { NotImplemented("run"); });
}

}  // namespace impactdic::cli
