// impactdic synth [SCENE_SPEC.yaml] [--preset small|full|tiny] -o DIR [--force]
// Renders a synthetic impact scene (synth/impact_scene.h, docs/synth.md): frames, sensor CSV,
// calibration images through the same lens (calibrated here with the calib module into
// DIR/calibration/camera.yaml), the scene YAML that processes it and the ground truth HDF5.
#include <CLI/CLI.hpp>
#include <iostream>
#include <memory>
#include <string>

#include "commands.h"
#include "impactdic/pipeline/synth_folder.h"

namespace impactdic::cli {

void RegisterSynthCommand(CLI::App& app) {
  auto args = std::make_shared<SynthFolderOptions>();
  auto* cmd = app.add_subcommand(
      "synth",
      "Render a synthetic impact scene (frames, sensor CSV, calibration images, scene YAML, "
      "ground truth HDF5) from a scene spec YAML (docs/synth.md)");
  cmd->add_option("SCENE_SPEC", args->spec_path, "Scene spec YAML (keys in docs/synth.md)");
  cmd->add_option("--preset", args->preset, "Use a preset instead of a spec: small, full, tiny");
  cmd->add_option("-o,--output", args->output,
                  "Output folder (created; an earlier scene in it is replaced when complete)")
      ->required();
  cmd->add_option("--dem", args->dem_dir,
                  "Film a DEM run instead (folder of validation/dem/run_case.sh: meta.txt, "
                  "grains.dump, near.dump, pounder.txt; docs/validation.md); the spec gives the "
                  "camera, noise, sensor and DIC settings");
  cmd->add_option("--realistic", args->realistic_spec,
                  "Render realistic footage instead (sand grains, uneven light, glare, motion "
                  "blur, JPEG; bearing-capacity field with a shear band): a spec YAML with a "
                  "`realistic:` section (docs/synth.md)");
  cmd->add_option("--calibration-set", args->calibration_set,
                  "Render a calibration set with known truth instead: charuco, charuco_legacy, "
                  "circles, asymmetric_circles, wide_angle or window (docs/calibration.md)");
  cmd->add_option("--frames", args->frames,
                  "Override the spec's frames.count (0: auto, or at least before_impact + 2)");
  cmd->add_flag("!--no-calibrate", args->calibrate,
                "Do not calibrate the rendered checkerboard images");
  cmd->add_flag("--force", args->force,
                "Replace an output folder another command wrote (a run, a campaign); files "
                "impactdic did not write are never replaced");
  cmd->callback([args] { std::cout << WriteSynthFolder(*args); });
}

}  // namespace impactdic::cli
