#include "commands.h"

namespace impactdic::cli {

void RegisterCampaignCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("campaign", "campaign (not implemented yet)");
  cmd->allow_extras();
  cmd->callback([] { NotImplemented("campaign"); });
}

}  // namespace impactdic::cli
