// The correlation options of a scene (`run`) and of `impactdic correlate` share one definition:
// the dic library's IcgnOptions default for the uncertainty limit.
#include <gtest/gtest.h>

#include <array>
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

ContinuityCheckOptions SceneContinuity(const std::string& dic_section) {
  return MakeDicOptions(ParseScene("inputs: {frames: f}\n" + dic_section, "x/scene.yaml").dic)
      .continuity;
}

// The scene's dic.continuity_* keys: the library's defaults, values reach ContinuityCheckOptions,
// none switches a criterion off, bad values are refused naming the key.
TEST(DicOptions, SceneContinuityKeysReachTheLibrary) {
  const ContinuityCheckOptions d, s = SceneContinuity("");
  EXPECT_EQ(s.enabled, d.enabled);
  EXPECT_EQ(s.misfit_ratio, d.misfit_ratio);
  EXPECT_EQ(s.min_misfit, d.min_misfit);
  EXPECT_EQ(s.max_second_difference_px, d.max_second_difference_px);
  EXPECT_EQ(s.max_neighbour_difference_px, d.max_neighbour_difference_px);
  EXPECT_EQ(s.local_ratio, d.local_ratio);
  const ContinuityCheckOptions set = SceneContinuity(
      "dic: {continuity_check: false, continuity_misfit_ratio: 3, continuity_min_misfit: 0.05, "
      "continuity_max_second_difference_px: none, continuity_max_neighbour_difference_px: 0.6, "
      "continuity_local_ratio: 5}");
  EXPECT_FALSE(set.enabled);
  EXPECT_EQ(set.misfit_ratio, 3);
  EXPECT_EQ(set.min_misfit, 0.05);
  EXPECT_TRUE(std::isinf(set.max_second_difference_px));
  EXPECT_EQ(set.max_neighbour_difference_px, 0.6);
  EXPECT_EQ(set.local_ratio, 5);
  for (const std::string bad :
       {"continuity_check: maybe", "continuity_misfit_ratio: 1", "continuity_min_misfit: 1",
        "continuity_max_second_difference_px: 0", "continuity_max_neighbour_difference_px: -1",
        "continuity_local_ratio: 0.5", "continuity_misfit_ratio: x"}) {
    const std::string key = "dic." + bad.substr(0, bad.find(':'));
    try {
      SceneContinuity("dic: {" + bad + "}");
      ADD_FAILURE() << "no error for " << bad;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  }
}

// Each continuity threshold is defined once (kContinuityLimits): the library's check and the
// scene refuse the value at its bound with the same expected text, and "none" is +inf in both.
TEST(DicOptions, ContinuityThresholdsAreDefinedOnceForTheLibraryAndTheScene) {
  ASSERT_EQ(kContinuityLimits.size(), 4u);
  EXPECT_EQ(ContinuityLimitOf(&ContinuityCheckOptions::local_ratio).Expected(),
            "a number > 1, or none (the thresholds alone)");
  EXPECT_EQ(ContinuityLimitOf(&ContinuityCheckOptions::max_second_difference_px).Expected(),
            "a number > 0 px, or none (criterion off)");
  for (const ContinuityLimit& limit : kContinuityLimits) {
    const std::string name = limit.name;
    ContinuityCheckOptions at_bound;
    at_bound.*limit.field = limit.above;
    try {
      at_bound.Check();
      ADD_FAILURE() << "no error for " << name << " = " << limit.above;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("dic.continuity." + name), std::string::npos)
          << e.what();
      EXPECT_NE(std::string(e.what()).find(limit.Expected()), std::string::npos) << e.what();
    }
    try {
      SceneContinuity("dic: {continuity_" + name + ": " + std::to_string(limit.above) + "}");
      ADD_FAILURE() << "no error for the scene's " << name;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("dic.continuity_" + name), std::string::npos)
          << e.what();
      EXPECT_NE(std::string(e.what()).find(limit.Expected()), std::string::npos) << e.what();
    }
    EXPECT_TRUE(std::isinf(SceneContinuity("dic: {continuity_" + name + ": none}").*limit.field))
        << name;
    EXPECT_TRUE(std::isinf(limit.FromString("none", "x")));
    EXPECT_EQ(limit.FromString("7", "x"), 7);
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
