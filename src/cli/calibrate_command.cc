#include "commands.h"

namespace impactdic::cli {

void RegisterCalibrateCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("calibrate", "calibrate (not implemented yet)");
  cmd->allow_extras();
  cmd->callback([] { NotImplemented("calibrate"); });
}

}  // namespace impactdic::cli
