#include "commands.h"

namespace impactdic::cli {

void RegisterAnalyzeCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("analyze", "analyze (not implemented yet)");
  cmd->allow_extras();
  cmd->callback([] { NotImplemented("analyze"); });
}

}  // namespace impactdic::cli
