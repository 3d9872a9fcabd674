#include "commands.h"

namespace impactdic::cli {

void RegisterRenderCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("render", "render (not implemented yet)");
  cmd->allow_extras();
  cmd->callback([] { NotImplemented("render"); });
}

}  // namespace impactdic::cli
