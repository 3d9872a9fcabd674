// impactdic calibrate (--board COLSxROWS --square MM | --charuco COLSxROWS --square MM --marker MM
//   [--dictionary NAME] | --circles COLSxROWS --spacing MM [--asymmetric]) [--plane IMAGE]
//   IMAGES... -o OUT.yaml
// Lens calibration (calib module): prints the RMS, intrinsics, distortion model and plane scale,
// and writes the calibration YAML (keys in docs/calibration.md).
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
    std::string board, charuco, circles, dictionary = "DICT_4X4_50", plane, output, format = "text";
    double square_mm = 0, marker_mm = 0, spacing_mm = 0;
    bool asymmetric = false;
    std::vector<std::string> images;
    CalibrationOptions options;  // Defaults: the calib library's.
    SceneKeyValues keys;         // --calibration.*, --min-views, --max-rms, --fix-k3.
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "calibrate",
      "Lens calibration from views of a chessboard, ChArUco board or circle grid: intrinsics, "
      "the distortion model (Brown-Conrady, rational or fisheye, chosen by the held-out "
      "reprojection RMS), its overall RMS and, with --plane, the mm-per-pixel scale of the "
      "panel (carried to the soil plane through a viewing window)");
  auto* board = cmd->add_option(
      "--board", args->board,
      "Chessboard size COLSxROWS counting INNER corners (9x6 for a board of 10x7 squares)");
  auto* charuco = cmd->add_option("--charuco", args->charuco,
                                  "ChArUco board size COLSxROWS counting SQUARES, as printed "
                                  "(11x8 has 10x7 inner corners); partial views count");
  auto* circles = cmd->add_option("--circles", args->circles,
                                  "Circle grid COLSxROWS counting circles (asymmetric: circles "
                                  "per row x rows); dark circles on a light board");
  board->excludes(charuco)->excludes(circles);
  charuco->excludes(circles);
  cmd->add_option("--square", args->square_mm,
                  "Square side (--board, --charuco), in " + BoardSpec::kSquareRange.Text());
  cmd->add_option("--marker", args->marker_mm, "ArUco marker side (--charuco) [mm]");
  cmd->add_option("--dictionary", args->dictionary,
                  "ArUco dictionary (--charuco), an OpenCV name: DICT_4X4_50 ... DICT_7X7_1000, "
                  "DICT_ARUCO_ORIGINAL, DICT_APRILTAG_*")
      ->capture_default_str();
  cmd->add_option("--spacing", args->spacing_mm,
                  "Circle centre spacing (--circles) [mm]; asymmetric grids: the row pitch, half "
                  "the centre distance within a row");
  cmd->add_flag("--asymmetric", args->asymmetric, "The circle grid is asymmetric (staggered rows)");
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
                             {"calibration.model", "--model"},
                             {"board", "--board"},
                             {"charuco", "--charuco"},
                             {"circles", "--circles"},
                             {"board.square_mm", args->circles.empty() ? "--square" : "--spacing"},
                             {"board.marker_mm", "--marker"},
                             {"board.dictionary", "--dictionary"},
                             {"calibration images", "IMAGES"},
                             {"output", "-o"}};
    CalibrationOptions& options = args->options;
    const std::vector<YamlOptionTable> tables = CalibrationOptionTables(&options);
    ApplyKeyFlags(*cmd, args->keys, [&](const auto& key, const auto& text, const auto& flag) {
      SetOptionTableKey(tables, key, text, flag);
    });
    CalibrationSummary summary;
    const CameraCalibration calibration = WithFlagNames(flags, [&] {
      const CharucoLayout layout = options.board.layout;  // calibration.charuco_layout
      if (!args->charuco.empty()) {
        CheckValue(args->marker_mm > 0, "board.marker_mm", "none",
                   "the ArUco marker side of the ChArUco board");
        options.board =
            ParseCharucoBoard(args->charuco, args->square_mm, args->marker_mm, args->dictionary);
        options.board.layout = layout;
      } else if (!args->circles.empty()) {
        options.board = ParseCircleGrid(args->circles, args->spacing_mm, args->asymmetric);
      } else {
        CheckValue(!args->board.empty(), "board", "none",
                   "one of --board, --charuco or --circles (the calibration target)");
        options.board = ParseBoard(args->board, args->square_mm);
      }
      return CalibrateToFile(args->images, args->plane, options, args->output, &summary);
    });
    std::cout << (args->format == "json" ? summary.ToJson(calibration, args->output).Dump() + "\n"
                                         : summary.CommandReport(calibration, args->output));
  });
}

}  // namespace impactdic::cli
