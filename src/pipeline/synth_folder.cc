#include "impactdic/pipeline/synth_folder.h"

#include <fmt/format.h>

#include <filesystem>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "impactdic/calib/calibration.h"
#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/output_generation.h"
#include "impactdic/synth/checkerboard.h"
#include "impactdic/synth/dem_scene.h"
#include "impactdic/synth/impact_scene.h"
#include "impactdic/synth/realistic.h"

namespace impactdic {
namespace {

// The scene points at calibration/camera.yaml: make it from the rendered images in `staging` (the
// generation's folder; messages name `output`, where they will be).
void CalibrateRendered(const ImpactSceneSpec& spec, const std::string& staging,
                       const std::string& output, bool calibrate) {
  namespace fs = std::filesystem;
  if (!spec.render_calibration || !spec.calibration_yaml.empty()) return;
  const fs::path dir = fs::path(staging) / "calibration";
  const std::string yaml = (dir / "camera.yaml").string();
  if (calibrate) {
    CalibrationOptions options;  // The rendered board: 9x6 inner corners, 25 mm squares.
    // The scene's lens is Brown-Conrady by construction: no model choice (~1.5 s).
    options.model = LensModel::kBrown;
    CalibrationSummary summary;
    CameraCalibration calibration = CalibrateFromFiles(
        {(dir / "view_*.png").string()}, (dir / "plane.png").string(), options, &summary);
    SaveCalibration(calibration, yaml);
    LogInfo("calibration: {}", summary.BriefReport());
  } else {
    const fs::path final_dir = fs::path(output) / "calibration";
    const std::string final_yaml = (final_dir / "camera.yaml").string();
    LogWarning(
        "--no-calibrate: the scene points at {} which does not exist yet; make it with "
        "impactdic calibrate --board 9x6 --square 25 --plane {} {} -o {}",
        final_yaml, (final_dir / "plane.png").string(), (final_dir / "view_*.png").string(),
        final_yaml);
  }
}

// impactdic synth --dem DIR: films a DEM run (synth/dem_scene.h, docs/validation.md).
std::string RunSynthDem(const SynthFolderOptions& args, const ImpactSceneSpec& spec,
                        OutputGeneration& generation) {
  if (args.frames)
    throw Error(ErrorKind::kInvalidValue, "--frames", std::to_string(*args.frames),
                "no --frames with --dem (the frames are the DEM's snapshots)");
  DemRecord record = ReadDemRecord(args.dem_dir);
  DemScene scene(std::move(record), spec);
  const DemTruth& t = scene.truth();
  LogInfo(
      "DEM scene: {} frames, {} grains, bulk density {:.1f} kg/m^3, grid mass {:.4g} kg (bulk "
      "estimate {:.4g} kg), p_max {:.4g} N s, t_e {:.4g} ms, m_add,max {:.4g} kg, conservation "
      "error at t_e {:.2f} % (max {:.2f} % in the peak stage)",
      scene.frame_count(), scene.record().frames[0].grains.size(), t.bulk_density_kg_m3,
      t.grid_mass_kg, t.grid_mass_bulk_kg, t.p_max_Ns, t.t_e_s * 1e3, t.m_add_max_kg,
      100 * t.conservation_error_te, 100 * t.conservation_error_peak);
  for (const auto& note : t.notes) LogWarning("DEM truth: {}", note);
  DemSceneReport report = WriteDemScene(scene, generation.staging_folder());
  CalibrateRendered(scene.base().spec(), generation.staging_folder(), args.output, args.calibrate);
  generation.Commit();
  for (std::string* path : {&report.out_dir, &report.scene_yaml, &report.truth_h5,
                            &report.sensor_csv, &report.calibration_yaml})
    *path = generation.FinalPath(*path);
  return report.BriefReport() + "\nscene: " + report.scene_yaml + "\n";
}

// impactdic synth --realistic SPEC -o DIR: realistic footage (synth/realistic.h, docs/synth.md).
std::string RunSynthRealistic(const SynthFolderOptions& args) {
  if (!args.spec_path.empty() || !args.preset.empty() || !args.dem_dir.empty() || args.frames)
    throw Error(ErrorKind::kInvalidValue, "--realistic", args.realistic_spec,
                "no SCENE_SPEC, --preset, --dem or --frames with --realistic (the realistic "
                "spec has its own `realistic.frames`)");
  const RealisticSceneSpec spec = LoadRealisticSceneSpec(args.realistic_spec);
  CheckNotAnInput((std::filesystem::path(args.output) / "spec.yaml").string(), "-o",
                  {args.realistic_spec});
  OutputGenerationOptions generation_options;
  generation_options.command = "impactdic synth --realistic";
  generation_options.own_names = {"frames", "spec.yaml", "truth.h5"};
  generation_options.force = args.force;
  generation_options.nested_kinds = {"run", "render"};  // Runs of the scene it replaces.
  OutputGeneration generation(args.output, generation_options);
  const RealisticScene scene(spec);
  const RealisticSceneReport report = WriteRealisticScene(scene, generation.staging_folder());
  generation.Commit();
  return fmt::format("realistic scene: {} frames of {}x{} px in {:.1f} s; truth {}\n",
                     report.frames, spec.width, spec.height, report.render_seconds,
                     generation.FinalPath(report.truth_h5));
}

// impactdic synth --calibration-set NAME -o DIR: a calibration set with known truth
// (synth/checkerboard.h, docs/calibration.md).
std::string RunSynthCalibrationSet(const SynthFolderOptions& args) {
  if (!args.spec_path.empty() || !args.preset.empty() || !args.dem_dir.empty() ||
      !args.realistic_spec.empty() || args.frames)
    throw Error(ErrorKind::kInvalidValue, "--calibration-set", args.calibration_set,
                "no SCENE_SPEC, --preset, --dem, --realistic or --frames with --calibration-set");
  const CalibrationPreset preset = CalibrationPresetNamed(args.calibration_set);
  OutputGenerationOptions generation_options;
  generation_options.command = "impactdic synth --calibration-set";
  generation_options.own_names = {"plane.png", "soil.png", "board.yaml"};
  for (int k = 0; k < preset.options.views; ++k)
    generation_options.own_names.push_back(fmt::format("view_{:02d}.png", k));
  generation_options.force = args.force;
  OutputGeneration generation(args.output, generation_options);
  const CalibrationSet set = RenderCalibrationPreset(preset, generation.staging_folder());
  generation.Commit();
  std::string report =
      fmt::format("calibration set {}: {} views, plane view {}{}; truth {}\n", args.calibration_set,
                  set.view_paths.size(), generation.FinalPath(set.plane_path),
                  set.soil_path.empty() ? "" : ", soil view " + generation.FinalPath(set.soil_path),
                  generation.FinalPath(set.board_path));
  return report;
}

}  // namespace

std::string WriteSynthFolder(const SynthFolderOptions& args) {
  if (!args.calibration_set.empty()) {
    CheckValue(!args.output.empty(), "-o", "nothing", "an output folder");
    return RunSynthCalibrationSet(args);
  }
  // Named as `impactdic synth` names them.
  if (args.realistic_spec.empty()) {
    CheckValue(!args.spec_path.empty() || !args.preset.empty(), "SCENE_SPEC", "nothing",
               "a scene spec YAML file or --preset small|full|tiny");
    CheckValue(args.preset.empty() || args.spec_path.empty(), "--preset", args.preset,
               "no --preset together with a spec file (write `preset:` in the spec)");
  }
  CheckValue(!args.output.empty(), "-o", "nothing", "an output folder");
  if (!args.realistic_spec.empty()) return RunSynthRealistic(args);
  ImpactSceneSpec spec =
      args.spec_path.empty() ? ImpactScenePreset(args.preset) : LoadImpactSceneSpec(args.spec_path);
  if (args.frames) spec.frames = *args.frames;
  // The spec's check (the allowed counts are defined there), naming --frames for the override.
  try {
    spec.Check();
  } catch (const Error& e) {
    if (!args.frames) throw;
    if (e.where() != "frames.count") throw;
    throw Error(e.kind(), "--frames", e.found(), e.expected());
  }
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::exists(args.output, ec) && !fs::is_directory(args.output, ec))
    throw Error(ErrorKind::kInvalidValue, "-o", args.output, "a folder, not a file");
  // The files synth replaces in DIR must not include the spec it reads.
  for (const char* name : {"scene.yaml", "spec.yaml", "sensor.csv", "truth.h5"})
    CheckNotAnInput((fs::path(args.output) / name).string(), "-o", {args.spec_path});
  // The folder's files are one generation (io/output_generation.h): made in a staging folder and
  // swapped in when complete, replacing an earlier scene (and the runs nested in it) whole.
  OutputGenerationOptions generation_options;
  generation_options.command = "impactdic synth";
  for (const char* name : kImpactSceneOutputNames) generation_options.own_names.emplace_back(name);
  generation_options.known_names = {"results"};  // The scene's outputs.folder, run by an older
                                                 // impactdic (newer runs leave a marker in it).
  generation_options.force = args.force;
  generation_options.nested_kinds = {"run", "render"};  // Runs of the scene it replaces.
  OutputGeneration generation(args.output, generation_options);

  if (!args.dem_dir.empty()) return RunSynthDem(args, spec, generation);
  ImpactScene scene(spec);
  LogInfo("model: {}", scene.model_run().summary.BriefReport());
  LogInfo("scene: {} frames of {}x{} px, t_e = {:.4g} ms, m_grid = {:.4g} kg, ROI [{}, {}, {}, {}]",
          scene.frame_count(), spec.width, spec.height, scene.momentum().t_e_s * 1e3,
          scene.momentum().m_grid_kg, scene.dic_grid().roi[0], scene.dic_grid().roi[1],
          scene.dic_grid().roi[2], scene.dic_grid().roi[3]);
  ImpactSceneReport report = WriteImpactScene(scene, generation.staging_folder());

  CalibrateRendered(spec, generation.staging_folder(), args.output, args.calibrate);
  generation.Commit();
  for (std::string* path : {&report.out_dir, &report.scene_yaml, &report.truth_h5,
                            &report.sensor_csv, &report.spec_yaml, &report.calibration_dir})
    *path = generation.FinalPath(*path);
  return report.BriefReport() + "\nscene: " + report.scene_yaml + "\n";
}

}  // namespace impactdic
