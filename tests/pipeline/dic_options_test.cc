// The correlation options of a scene (`run`) and of `impactdic correlate` share one definition:
// the dic library's IcgnOptions default for the uncertainty limit.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>
#include <string>

#include "../cli/cli_runner.h"
#include "../io/test_dir.h"
#include "impactdic/core/error.h"
#include "impactdic/dic/options.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/image_io.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/scene.h"

namespace impactdic {
namespace {

double SceneLimit(const std::string& dic_section) {
  const Scene s = ParseScene("inputs: {frames: f}\n" + dic_section, "x/scene.yaml");
  return MakeDicOptions(s.dic).icgn.max_uncertainty_px;
}

// Fails if the scene, the correlate command or the library drift apart on the default.
TEST(DicOptions, SceneAndCorrelateShareTheUncertaintyLimitDefault) {
  const double library = IcgnOptions{}.max_uncertainty_px;
  EXPECT_EQ(SceneLimit(""), library);
  // `correlate` without --max-uncertainty records the limit it used in its HDF5 file.
  TestDir dir;
  cv::Mat image(60, 60, CV_8U);
  cv::RNG(4).fill(image, cv::RNG::UNIFORM, 0, 255);
  WriteImage(dir.File("a.png"), image);
  WriteImage(dir.File("b.png"), image);
  const std::string out = dir.File("out.h5");
  const CliResult r = RunCli("correlate --reference " + dir.File("a.png") + " --deformed " +
                             dir.File("b.png") + " --subset 21 --step 20 -o " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(H5Reader(out).ReadNumberAttribute("dic", "max_uncertainty_px"), library);
  // Explicit values reach the library options the same way from both.
  EXPECT_EQ(SceneLimit("dic: {max_uncertainty_px: 0.05}"), 0.05);
  EXPECT_EQ(SceneLimit("dic: {max_uncertainty_px: 0}"), 0.0);
  EXPECT_TRUE(std::isinf(SceneLimit("dic: {max_uncertainty_px: none}")));
  try {
    SceneLimit("dic: {max_uncertainty_px: -1}");
    FAIL() << "no error for -1";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("dic.max_uncertainty_px"), std::string::npos) << e.what();
  }
}

// The downstream limit (kinematics ExcludeUncertainSamples) is read from momentum.max_sigma_px.
TEST(DicOptions, MomentumSigmaLimitIsAPositiveNumber) {
  EXPECT_FALSE(ParseScene("inputs: {frames: f}\n", "x/scene.yaml").momentum.max_sigma_px);
  EXPECT_EQ(ParseScene("inputs: {frames: f}\nmomentum: {max_sigma_px: 0.04}\n", "x/scene.yaml")
                .momentum.max_sigma_px,
            0.04);
  try {
    ParseScene("inputs: {frames: f}\nmomentum: {max_sigma_px: 0}\n", "x/scene.yaml");
    FAIL() << "no error for 0";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("momentum.max_sigma_px"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace impactdic
