#include "commands.h"

namespace impactdic::cli {

void RegisterSynthCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("synth", "synth (not implemented yet)");
  cmd->allow_extras();
  cmd->callback([] { NotImplemented("synth"); });
}

}  // namespace impactdic::cli
