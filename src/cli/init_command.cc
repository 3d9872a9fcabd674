// impactdic init [DIR]: writes DIR/scene.yaml, the commented scene template (pipeline
// SceneTemplate: every key with its default, unit, range and meaning; the required inputs marked).
#include <CLI/CLI.hpp>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <system_error>

#include "commands.h"
#include "impactdic/core/error.h"
#include "impactdic/core/interrupt.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/pipeline/scene_template.h"

namespace impactdic::cli {
namespace {

namespace fs = std::filesystem;

struct InitArgs {
  std::string folder = ".";
  bool force = false;
};

void RunInit(const InitArgs& args) {
  std::error_code ec;
  MakeFolders(args.folder, ec);
  if (ec) throw Error(ErrorKind::kIo, args.folder + ": cannot create the folder: " + ec.message());
  const std::string path = (fs::path(args.folder) / "scene.yaml").string();
  if (!args.force && fs::exists(path)) {
    throw Error(ErrorKind::kInvalidValue,
                path + " exists; `impactdic init --force` overwrites it, or give another folder");
  }
  WriteTextFileAtomic(path, SceneTemplate());
  std::cout << "wrote " << path << ": fill in the lines marked REQUIRED, then run\n"
            << "  impactdic run " << path << "\n";
}

}  // namespace

void RegisterInitCommand(CLI::App& app) {
  auto args = std::make_shared<InitArgs>();
  auto* cmd = app.add_subcommand(
      "init", "Write DIR/scene.yaml: a commented scene template with every key's default");
  cmd->add_option("folder", args->folder, "Folder of the new scene file (created if missing)")
      ->capture_default_str();
  cmd->add_flag("--force", args->force, "Overwrite an existing scene.yaml");
  cmd->callback([args] { RunInit(*args); });
}

}  // namespace impactdic::cli
