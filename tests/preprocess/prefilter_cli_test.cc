// `impactdic correlate` with the automatic pre-filter (docs/dic_accuracy.md, "Sub-pixel bias"):
// decided from the reference, logged, recorded in /dic, switched by --gaussian auto | none | on |
// SIGMA.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "../cli/cli_runner.h"
#include "impactdic/dic/correlator.h"
#include "impactdic/dic/options.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/image_io.h"
#include "impactdic/preprocess/nyquist_bias.h"
#include "impactdic/preprocess/preprocess.h"
#include "impactdic/synth/fourier_shift.h"
#include "impactdic/synth/speckle.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

class PrefilterCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("impactdic_prefilter_cli_test_" + std::to_string(getpid()));
    fs::create_directories(dir_);
    // Sharp: painted-style dots, band-limited shifts. Smooth: the blob speckle, rendered exactly.
    const cv::Mat dots = SharpSpeckle(160, 140, /*dot_radius_px=*/2.0, /*seed=*/4) * 190 + 30;
    WriteImage(Path("sharp0.png"), QuantiseWithNoise(FourierShift(dots, 0, 0), 2, 8, 1));
    WriteImage(Path("sharp1.png"), QuantiseWithNoise(FourierShift(dots, 0.3, -0.2), 2, 8, 2));
    SpeckleOptions speckle;
    speckle.blob_radius_px = 2.0;
    const SpecklePattern pattern(speckle, 160, 140);
    RenderOptions render;
    render.noise_sigma = 2;
    WriteImage(Path("smooth0.png"), RenderImage(pattern, 160, 140, ZeroField(), render));
    render.noise_seed = 8;
    WriteImage(Path("smooth1.png"), RenderImage(pattern, 160, 140, Translation(0.3, -0.2), render));
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static std::string Path(const std::string& name) { return (dir_ / name).string(); }
  static std::string Pair(const std::string& kind) {
    return "correlate --mode pairs --max-uncertainty none --reference " + Path(kind + "0.png") +
           " --deformed " + Path(kind + "1.png");
  }
  static fs::path dir_;
};
fs::path PrefilterCli::dir_;

TEST_F(PrefilterCli, DefaultFiltersASharpPairAsTheLibraryWouldAndRecordsWhy) {
  const std::string out = Path("sharp.h5");
  const CliResult r = RunCli(Pair("sharp") + " -o " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("pre-filter: auto, Gaussian sigma 0.7 px (kernel 5x5) applied: "
                          "near-Nyquist bias figure "),
            std::string::npos)
      << r.output;
  H5Reader h5(out);
  EXPECT_EQ(h5.ReadNumberAttribute("dic", "prefilter_applied"), 1);
  const double figure = h5.ReadNumberAttribute("dic", "nyquist_bias_px");
  EXPECT_EQ(h5.ReadNumberAttribute("dic", "prefilter_threshold_px"),
            GaussianBlurOptions{}.auto_threshold_px);
  EXPECT_GT(figure, GaussianBlurOptions{}.auto_threshold_px);
  EXPECT_NEAR(figure, MeasureNyquistBias(ReadGreyImage(Path("sharp0.png"))).bias_px, 1e-12);
  EXPECT_NE(h5.ReadStringAttribute("dic", "prefilter").find("auto, Gaussian sigma 0.7 px"),
            std::string::npos);
  EXPECT_NE(h5.ReadStringAttribute("dic", "preprocess").find("sigma 0.7 px"), std::string::npos);
  // The same as the library on both images blurred by the preprocess module.
  const GaussianBlurOptions blur = GaussianFromString("on", "test");
  std::vector<cv::Mat> images;
  for (const char* name : {"sharp0.png", "sharp1.png"})
    images.push_back(GaussianBlurFrame(blur, ReadGreyImage(Path(name))));
  DicOptions options;
  options.mode = SequenceMode::kPairs;
  options.icgn.max_uncertainty_px = 0;
  const DicResult lib = CorrelateSequence(images, options);
  Dims dims;
  const std::vector<double> u = h5.ReadDouble("dic/u_px", &dims);
  ASSERT_EQ(dims[0], 2u);
  int compared = 0;
  for (std::size_t i = 0; i < dims[1]; ++i) {
    if (std::isnan(lib.frames[0].u_px[i])) continue;
    ++compared;
    EXPECT_NEAR(u[dims[1] + i], lib.frames[0].u_px[i], 1e-12);
  }
  EXPECT_GT(compared, 0);
}

TEST_F(PrefilterCli, NoneAndOnWinAndASmoothPairIsLeftAlone) {
  const std::string none = Path("none.h5"), smooth = Path("smooth.h5"), on = Path("on.h5");
  CliResult r = RunCli(Pair("sharp") + " --gaussian none -o " + none);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("pre-filter: off (set), skipped; near-Nyquist bias figure"),
            std::string::npos)
      << r.output;
  H5Reader h5_none(none);
  EXPECT_EQ(h5_none.ReadNumberAttribute("dic", "prefilter_applied"), 0);
  EXPECT_GT(h5_none.ReadNumberAttribute("dic", "nyquist_bias_px"),
            GaussianBlurOptions{}.auto_threshold_px);  // Measured all the same.
  EXPECT_FALSE(h5_none.HasAttribute("dic", "preprocess"));

  r = RunCli(Pair("smooth") + " -o " + smooth);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("pre-filter: auto, skipped: near-Nyquist bias figure"), std::string::npos)
      << r.output;
  H5Reader h5_smooth(smooth);
  EXPECT_EQ(h5_smooth.ReadNumberAttribute("dic", "prefilter_applied"), 0);
  EXPECT_LT(h5_smooth.ReadNumberAttribute("dic", "nyquist_bias_px"),
            GaussianBlurOptions{}.auto_threshold_px);

  r = RunCli(Pair("smooth") + " --gaussian on -o " + on);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  H5Reader h5_on(on);
  EXPECT_EQ(h5_on.ReadNumberAttribute("dic", "prefilter_applied"), 1);
  EXPECT_NE(h5_on.ReadStringAttribute("dic", "prefilter").find("on (set), Gaussian sigma 0.7 px"),
            std::string::npos);

  const CliResult help = RunCli("correlate --help");
  EXPECT_NE(help.output.find("--gaussian TEXT=auto"), std::string::npos) << help.output;
  r = RunCli(Pair("smooth") + " --gaussian sometimes -o " + Path("x.csv"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("--gaussian"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("auto, none"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace impactdic
