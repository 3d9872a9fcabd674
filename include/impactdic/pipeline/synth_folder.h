// A synthetic scene folder, as `impactdic synth` writes it (docs/synth.md): frames, sensor CSV,
// calibration images (calibrated here through the calib module into calibration/camera.yaml),
// the scene YAML that processes it and the ground-truth HDF5; or, with `dem_dir`, a DEM run filmed
// (synth/dem_scene.h); or, with `realistic_spec`, realistic footage (synth/realistic.h).
//
//   SynthFolderOptions o;
//   o.preset = "tiny";
//   o.output = "scene";
//   std::cout << WriteSynthFolder(o);   // "... \nscene: scene/scene.yaml\n"
//
// The folder's files are one generation (io/output_generation.h): made in a staging folder and
// swapped in when complete, replacing an earlier scene (and the runs nested in it) whole.
#ifndef IMPACTDIC_PIPELINE_SYNTH_FOLDER_H_
#define IMPACTDIC_PIPELINE_SYNTH_FOLDER_H_

#include <optional>
#include <string>

namespace impactdic {

struct SynthFolderOptions {
  std::string spec_path;        // Scene spec YAML (docs/synth.md); empty: `preset`.
  std::string preset;           // small, full or tiny (ImpactScenePreset) when no spec.
  std::string output;           // The folder (created).
  std::string dem_dir;          // Film this DEM run instead (validation/dem/run_case.sh's folder).
  std::string realistic_spec;   // Render realistic footage from this spec instead.
  std::string calibration_set;  // Render this calibration set instead (kCalibrationSetNames).
  std::optional<int> frames;    // Overrides the spec's frames.count (not with dem_dir).
  bool calibrate = true;        // Calibrate the rendered checkerboard images.
  bool force = false;           // Replace a folder another command wrote.
};

// Writes the folder and returns the report to print (the scene's brief report and its YAML's
// path). Errors name the options of `impactdic synth`: no spec nor preset ("SCENE_SPEC"), both
// ("--preset"), no output folder ("-o"). The spec's errors are Error(kInvalidValue) naming its
// keys; an override of frames.count out of range names "frames.count".
std::string WriteSynthFolder(const SynthFolderOptions& options);

}  // namespace impactdic

#endif  // IMPACTDIC_PIPELINE_SYNTH_FOLDER_H_
