// The `impactdic calibrate` command: exit codes, messages and outputs (through the built binary).
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <string>
#include <vector>

#include "../cli/cli_runner.h"
#include "../core/test_paths.h"
#include "impactdic/calib/calibration.h"

namespace impactdic {
namespace {

const std::string kSource = impactdic::SourceDir();
const std::string kViews = "'" + kSource + "/calibration/view_*.png'";

bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(CalibrateCli, JsonOutputWithPlaneScale) {
  const std::string out = ::testing::TempDir() + "/impactdic_cli_camera.yaml";
  const CliResult r = RunCli("calibrate --board 9x6 --square 25 --plane " + kSource +
                             "/calibration/plane.png " + kViews + " -o " + out + " --format json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* key : {"\"rms_px\"", "\"fx\"", "\"fy\"", "\"cx\"", "\"cy\"", "\"dist\"",
                          "\"mm_per_px\"", "\"images_used\": 12", "\"images_rejected\": 0"})
    EXPECT_TRUE(Contains(r.output, key)) << key << "\n" << r.output;
  EXPECT_FALSE(Contains(r.output, "\"mm_per_px\": null")) << r.output;
  const CameraCalibration c = LoadCalibration(out);
  ASSERT_TRUE(c.plane);
  EXPECT_NEAR(c.plane->mm_per_px, 0.747786537, 0.002 * 0.747786537);
  EXPECT_EQ(c.views.size(), 12u);
}

TEST(CalibrateCli, TextOutputWithoutPlaneHasNoScale) {
  const std::string out = ::testing::TempDir() + "/impactdic_cli_camera2.yaml";
  CliResult r = RunCli("calibrate --board 9x6 --square 25 " + kViews + " -o " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* part : {"reprojection RMS", "intrinsics: fx", "distortion: k1", "scale: none"})
    EXPECT_TRUE(Contains(r.output, part)) << part << "\n" << r.output;
  r = RunCli("calibrate --board 9x6 --square 25 " + kViews + " -o " + out + " --format json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(Contains(r.output, "\"mm_per_px\": null")) << r.output;
  // Every CalibrationOptions field is a flag: no tangential distortion and k3 held at 0.
  r = RunCli("calibrate --board 9x6 --square 25 " + kViews + " -o " + out +
             " --calibration.zero_tangential true --fix-k3");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const cv::Mat dist = LoadCalibration(out).DistCoeffs();
  EXPECT_NE(dist.at<double>(0), 0.0);                                              // k1 fitted
  for (const int held : {2, 3, 4}) EXPECT_EQ(dist.at<double>(held), 0.0) << held;  // p1 p2 k3
}

TEST(CalibrateCli, BadOptionsAreRefusedBeforeWork) {
  const std::string out = ::testing::TempDir() + "/impactdic_cli_bad.yaml";
  struct Case {
    std::string args, message;
  };
  for (const Case& c : std::vector<Case>{
           {"--board 9-6 --square 25 " + kViews + " -o " + out,
            "--board: invalid value (got '9-6')"},
           {"--board 9x6 --square 0 " + kViews + " -o " + out, "--square"},
           {"--board 9x6 --square 25 -o " + out, "IMAGES"},
           {"--board 9x6 --square 25 " + kViews + " -o " + out + " --format xml", "--format"},
           {"--board 9x6 --square 25 " + kViews, "-o"},
           {"--board 9x6 --square 25 /no/such/image.png -o " + out, "/no/such/image.png"},
           {"--board 9x6 --square 25 --plane /no/such/plane.png " + kViews + " -o " + out,
            "/no/such/plane.png"},
           {"--board 9x6 --square 25 " + kViews + " -o /no/such/folder/out.yaml",
            "/no/such/folder"},
           // CalibrationOptions' ranges decide (the one definition), naming the flag.
           {"--board 9x6 --square 25 --max-rms 0 " + kViews + " -o " + out,
            "--max-rms: invalid value (got 0); expected a reprojection RMS in (0, 1000] px"},
           {"--board 9x6 --square 25 --max-rms nan " + kViews + " -o " + out, "--max-rms"},
           {"--board 9x6 --square 25 --min-views 2 " + kViews + " -o " + out,
            "--min-views: invalid value (got 2); expected an integer view count in [3, 10000]"},
           {"--board 9x6 --square 25 --calibration.detection.subpix_half_window 1 " + kViews +
                " -o " + out,
            "--calibration.detection.subpix_half_window: invalid value (got 1)"},
           {"--board 9x6 --square 25 --calibration.zero_tangential maybe " + kViews + " -o " + out,
            "--calibration.zero_tangential: invalid value (got 'maybe'); expected true or false"},
       }) {
    const CliResult r = RunCli("calibrate " + c.args);
    EXPECT_EQ(r.exit_code, 1) << c.args << "\n" << r.output;
    EXPECT_TRUE(Contains(r.output, c.message)) << c.args << "\n" << r.output;
    // Refused before any work: no calibration was computed.
    EXPECT_FALSE(Contains(r.output, "images used")) << c.args << "\n" << r.output;
  }
}

TEST(CalibrateCli, ImagesWithoutTheBoardAreAClearError) {
  const std::string dir = ::testing::TempDir();
  std::string images;
  for (int k = 0; k < 6; ++k) {
    const std::string path = dir + "/impactdic_blank_" + std::to_string(k) + ".png";
    ASSERT_TRUE(cv::imwrite(path, cv::Mat(120, 160, CV_8U, cv::Scalar(90 + k))));
    images += " " + path;
  }
  const CliResult r =
      RunCli("calibrate --board 9x6 --square 25" + images + " -o " + dir + "/impactdic_x.yaml");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_TRUE(Contains(r.output, "no board found in any of the 6 calibration images")) << r.output;
  // A plane view of another size than the calibration images.
  const std::string small = dir + "/impactdic_small_plane.png";
  ASSERT_TRUE(cv::imwrite(small, cv::Mat(240, 320, CV_8U, cv::Scalar(90))));
  const CliResult p = RunCli("calibrate --board 9x6 --square 25 --plane " + small + " " + kViews +
                             " -o " + dir + "/impactdic_y.yaml");
  EXPECT_EQ(p.exit_code, 1) << p.output;
  EXPECT_TRUE(Contains(p.output, "has size 320x240 but the calibration was made for 640x480"))
      << p.output;
}

TEST(CalibrateCli, ModelChoiceAndPerViewCornersInTextAndJson) {
  const std::string out = ::testing::TempDir() + "/impactdic_cli_model.yaml";
  CliResult r = RunCli("calibrate --board 9x6 --square 25 " + kViews + " -o " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* part :
       {"model: brown (lowest held-out RMS)", "rational held-out RMS", "fisheye  held-out RMS",
        "view_00.png: 54 points, RMS", "residual RMS [px] over the image"})
    EXPECT_TRUE(Contains(r.output, part)) << part << "\n" << r.output;
  r = RunCli("calibrate --board 9x6 --square 25 " + kViews + " -o " + out +
             " --model rational --format json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* part : {"\"model\": \"rational\"", "\"corners\": 54", "\"residual_map_px\"",
                           "\"model_candidates\": {}"})
    EXPECT_TRUE(Contains(r.output, part)) << part << "\n" << r.output;
  EXPECT_EQ(LoadCalibration(out).DistCoeffs().total(), 8u);
}

TEST(CalibrateCli, WindowCarriesThePlaneScaleToTheSoil) {
  // The sample's plane view is 613.93 mm from the camera: behind a 20 mm panel of n = 1.5 the
  // soil's scale is (613.93 + 20 / 1.5) / 613.93 = 1.02172 times the board's (paraxially).
  const std::string out = ::testing::TempDir() + "/impactdic_cli_window.yaml";
  const std::string base = "calibrate --board 9x6 --square 25 --model brown --plane " + kSource +
                           "/calibration/plane.png " + kViews + " -o " + out;
  CliResult r = RunCli(base +
                       " --calibration.window.thickness_mm 20 "
                       "--calibration.window.refractive_index 1.5 --format json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(Contains(r.output, "\"window\": {\"thickness_mm\": 20")) << r.output;
  const CameraCalibration c = LoadCalibration(out);
  ASSERT_TRUE(c.plane);
  EXPECT_NEAR(c.plane->mm_per_px / c.plane->board_mm_per_px, (613.93 + 20 / 1.5) / 613.93, 2e-4);
  EXPECT_EQ(c.plane->window.board_position, BoardPosition::kOuterFace);
  // The board at the soil plane: the scale is the measured one.
  r = RunCli(base +
             " --calibration.window.thickness_mm 20 "
             "--calibration.window.board_position soil");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NEAR(LoadCalibration(out).plane->mm_per_px, 0.747786537, 0.002 * 0.747786537);
}

TEST(CalibrateCli, BoardKindsAreCheckedBeforeWork) {
  const std::string out = ::testing::TempDir() + "/impactdic_cli_kinds.yaml";
  struct Case {
    std::string args, message;
  };
  for (const Case& c : std::vector<Case>{
           {"--charuco 8x6 --square 30 " + kViews + " -o " + out, "--marker"},
           {"--charuco 8x6 --square 30 --marker 40 " + kViews + " -o " + out, "--marker"},
           {"--charuco 8x6 --square 30 --marker 21 --dictionary DICT_9X9 " + kViews + " -o " + out,
            "--dictionary"},
           {"--charuco 8x6 --board 9x6 --square 30 --marker 21 " + kViews + " -o " + out,
            "excludes"},
           {"--circles 7x5 --spacing 0 " + kViews + " -o " + out, "--spacing"},
           {"--square 25 " + kViews + " -o " + out, "one of --board, --charuco or --circles"},
           {"--board 9x6 --square 25 --model wide " + kViews + " -o " + out, "--model"},
           {"--board 9x6 --square 25 --calibration.window.refractive_index 0.5 " + kViews + " -o " +
                out,
            "--calibration.window.refractive_index"},
       }) {
    const CliResult r = RunCli("calibrate " + c.args);
    EXPECT_EQ(r.exit_code, 1) << c.args << "\n" << r.output;
    EXPECT_TRUE(Contains(r.output, c.message)) << c.args << "\n" << r.output;
    EXPECT_FALSE(Contains(r.output, "images used")) << c.args << "\n" << r.output;
  }
}

}  // namespace
}  // namespace impactdic
