#include "commands.h"

namespace impactdic::cli {

void RegisterModelCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("model", "model (not implemented yet)");
  cmd->allow_extras();
  cmd->callback([] { NotImplemented("model"); });
}

}  // namespace impactdic::cli
