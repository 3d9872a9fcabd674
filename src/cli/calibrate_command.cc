// impactdic calibrate --board COLSxROWS --square SIZE_MM [--plane IMAGE] IMAGES... -o OUT.yaml
// Checkerboard calibration (calib module): prints the RMS, intrinsics, distortion and plane
// scale, and writes the calibration YAML (keys in docs/calibration.md).
#include <CLI/CLI.hpp>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "impactdic/calib/calibration.h"
#include "impactdic/core/error.h"
#include "impactdic/io/yaml.h"
#include "impactdic/pipeline/scene_flags.h"

namespace impactdic::cli {

void RegisterCalibrateCommand(CLI::App& app) {
  struct Args {
    std::string board, plane, output, format = "text";
    double square_mm = 0;
    std::vector<std::string> images;
    CalibrationOptions options;  // Defaults: the calib library's.
    SceneKeyValues keys;         // --calibration.*, --min-views, --max-rms, --fix-k3.
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "calibrate",
      "Lens calibration from checkerboard images: intrinsics, Brown-Conrady distortion "
      "(k1 k2 p1 p2 k3), reprojection RMS and, with --plane, the mm-per-pixel scale of the panel");
  cmd->add_option("--board", args->board,
                  "Board size COLSxROWS counting INNER corners (9x6 for a board of 10x7 squares)")
      ->required();
  cmd->add_option("--square", args->square_mm, "Square side, in " + BoardSpec::kSquareRange.Text())
      ->required();
  cmd->add_option("--plane", args->plane,
                  "Image of the board lying on the panel (measurement plane) for the mm/px scale");
  cmd->add_option("-o,--output", args->output,
                  "Calibration YAML to write (.yaml or .yml; never one of the images)")
      ->required();
  cmd->add_option("--format", args->format, "Output format: text or json")->capture_default_str();
  AddKeyFlags(cmd, OptionTableFlags(CalibrationOptionTables(&args->options)), &args->keys);
  cmd->add_option("images", args->images,
                  "Checkerboard images (files, folders or glob patterns), all the same size");
  cmd->callback([args, cmd] {
    // Every option checked before any work, by the library (the one definition), naming the flags.
    CheckFormat(args->format);
    const FlagNames flags = {{"calibration.max_rms_px", "--max-rms"},
                             {"calibration.min_views", "--min-views"},
                             {"board", "--board"},
                             {"board.square_mm", "--square"},
                             {"calibration images", "IMAGES"},
                             {"output", "-o"}};
    CalibrationOptions& options = args->options;
    const std::vector<YamlOptionTable> tables = CalibrationOptionTables(&options);
    ApplyKeyFlags(*cmd, args->keys, [&](const auto& key, const auto& text, const auto& flag) {
      SetOptionTableKey(tables, key, text, flag);
    });
    CalibrationSummary summary;
    const CameraCalibration calibration = WithFlagNames(flags, [&] {
      options.board = ParseBoard(args->board, args->square_mm);
      return CalibrateToFile(args->images, args->plane, options, args->output, &summary);
    });
    std::cout << (args->format == "json" ? summary.ToJson(calibration, args->output).Dump() + "\n"
                                         : summary.CommandReport(calibration, args->output));
  });
}

}  // namespace impactdic::cli
