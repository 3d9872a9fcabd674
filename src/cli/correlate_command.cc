// impactdic correlate: subset DIC of images, a video or a camera file. The flags make a scene (the
// dic.* and preprocess.* keys, pipeline/scene_flags.h); the library's CorrelateScene runs its
// frames and correlate stages (pipeline/correlate_scene.h).
#include <CLI/CLI.hpp>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "impactdic/core/error.h"
#include "impactdic/pipeline/correlate_scene.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/pipeline/scene_flags.h"
#include "impactdic/preprocess/preprocess.h"

namespace impactdic::cli {
namespace {

struct CorrelateArgs {
  std::string reference, frames, roi, gaussian, output;
  std::vector<std::string> deformed;
  bool allow_partial = false;
  SceneKeyValues keys;  // --dic.*, --preprocess.*, --inputs.fps/calibration and their aliases.
};

// The scene of the flags, run; its stages' errors name the flags (SceneFlagAliases).
void Run(const CLI::App& cmd, const CorrelateArgs& a) {
  Scene scene;
  ApplySceneKeyFlags(cmd, a.keys, &scene);
  const auto given = [&cmd](const char* name) { return cmd.count(name) > 0; };
  scene.inputs.frames = a.frames;
  if (!a.reference.empty() || !a.deformed.empty()) scene.inputs.frame_files = {a.reference};
  for (const std::string& d : a.deformed) scene.inputs.frame_files.push_back(d);
  if (!a.roi.empty()) SetSceneKey(&scene, "dic.roi", a.roi, given("--roi") ? "--roi" : "--dic.roi");
  if (given("--gaussian")) scene.preprocess.gaussian = GaussianFromString(a.gaussian, "--gaussian");
  FlagNames flags = {{"dic.first_frame_number..last_frame_number", "--first/--last"}};
  for (const SceneFlagAlias& alias : SceneFlagAliases())
    if (cmd.get_name() == alias.command) flags.emplace_back(alias.key, alias.alias);
  WithFlagNames(flags, [&] {
    try {
      CorrelateScene(scene, a.output, a.allow_partial);
    } catch (const PartialResultsError& e) {
      RethrowWithPartialFlag(e, "correlate");
    }
  });
}

}  // namespace

void RegisterCorrelateCommand(CLI::App& app) {
  auto a = std::make_shared<CorrelateArgs>();
  auto* cmd = app.add_subcommand("correlate",
                                 "correlate: subset DIC of a sequence (a scene's "
                                 "frames and correlate stages)");
  cmd->add_option("--reference", a->reference, "Reference image (first frame)");
  cmd->add_option("--deformed", a->deformed, "Deformed image(s), in order");
  AddSceneKeyOption(cmd, "inputs.frames", &a->frames,
                    SceneKeyFlags({"inputs"}).front().help + " (the first is the reference)");
  AddSceneKeyOption(cmd, "dic.roi", &a->roi,
                    "Region of interest X0,Y0,X1,Y1 [px] (default: image)");
  SetsKeys(cmd->add_option("--gaussian", a->gaussian,
                           "auto | none | on | SIGMA[,KERNEL]: short for the "
                           "--preprocess.gaussian.* flags")
               ->default_str(ToString(GaussianBlurOptions{}.mode)),
           {"preprocess.gaussian"});
  cmd->add_option("-o,--output", a->output, "Output file (.csv or .h5)");
  cmd->add_flag(kAllowPartialFlag, a->allow_partial,
                "Write the output (exit 0) even when no subset is valid in any deformed image");
  AddSceneKeyFlags(cmd, {"dic", "preprocess", "inputs.fps", "inputs.calibration"}, &a->keys);
  cmd->callback([a, cmd] { Run(*cmd, *a); });
}

}  // namespace impactdic::cli
