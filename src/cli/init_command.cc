// impactdic init [DIR]: writes DIR/scene.yaml, the commented scene template (pipeline
// SceneTemplate: every key with its default, unit, range and meaning; the required inputs marked).
#include <CLI/CLI.hpp>
#include <iostream>
#include <memory>
#include <string>

#include "commands.h"
#include "impactdic/pipeline/scene_template.h"

namespace impactdic::cli {

void RegisterInitCommand(CLI::App& app) {
  struct Args {
    std::string folder = ".";
    bool force = false;
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "init", "Write DIR/scene.yaml: a commented scene template with every key's default");
  cmd->add_option("folder", args->folder, "Folder of the new scene file (created if missing)")
      ->capture_default_str();
  cmd->add_flag("--force", args->force, "Overwrite an existing scene.yaml");
  cmd->callback([args] {
    const std::string path = WriteSceneTemplate(args->folder, args->force);
    std::cout << "wrote " << path << ": fill in the lines marked REQUIRED, then run\n"
              << "  impactdic run " << path << "\n";
  });
}

}  // namespace impactdic::cli
