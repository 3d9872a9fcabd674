// `impactdic correlate` through the binary: outputs and clear errors for bad input.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "../cli/cli_runner.h"
#include "impactdic/dic/correlator.h"
#include "impactdic/dic/options.h"
#include "impactdic/io/csv.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/image_io.h"
#include "impactdic/preprocess/preprocess.h"
#include "impactdic/synth/speckle.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

class CorrelateCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("impactdic_correlate_cli_test_" + std::to_string(getpid()));
    fs::create_directories(dir_);
    SpeckleOptions speckle;
    speckle.blob_radius_px = 2.0;
    SpecklePattern pattern(speckle, 120, 100);
    RenderOptions render;
    render.noise_sigma = 2;
    render.supersampling = 2;
    WriteImage(Path("ref.png"), RenderImage(pattern, 120, 100, ZeroField(), render));
    render.noise_seed = 8;
    WriteImage(Path("def1.png"), RenderImage(pattern, 120, 100, Translation(0.4, -0.3), render));
    render.noise_seed = 9;
    WriteImage(Path("def2.png"), RenderImage(pattern, 120, 100, Translation(0.8, -0.6), render));
    WriteImage(Path("small.png"), RenderImage(pattern, 80, 100, ZeroField(), render));
    std::ofstream(Path("corrupt.png")) << "this is not a PNG file";
  }
  static std::string Path(const std::string& name) { return (dir_ / name).string(); }
  static std::string Pair() {
    return "correlate --reference " + Path("ref.png") + " --deformed " + Path("def1.png") + " " +
           Path("def2.png");
  }
  static void ExpectError(const std::string& args, const std::string& needle) {
    const CliResult r = RunCli(args);
    EXPECT_NE(r.exit_code, 0) << args << "\n" << r.output;
    EXPECT_NE(r.output.find(needle), std::string::npos) << args << "\n" << r.output;
  }
  static fs::path dir_;
};
fs::path CorrelateCli::dir_;

TEST_F(CorrelateCli, WritesTheCsvContract) {
  const std::string out = Path("out.csv");
  const CliResult r = RunCli(Pair() + " --subset 25 --step 10 -o " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // Summary on stderr: subsets, valid fraction, mean iterations, reference updates, wall time,
  // POIs per second.
  for (const char* item : {"63 subsets x 2 frames", "% valid", "iterations/subset",
                           "reference updates", "wall time", "POIs/s"})
    EXPECT_NE(r.output.find(item), std::string::npos) << item << "\n" << r.output;
  std::ifstream in(out);
  std::string header;
  std::getline(in, header);
  // The first eight columns are a contract; the sigma columns were added after them.
  EXPECT_EQ(header, "frame,x_px,y_px,u_px,v_px,zncc,iterations,status,sigma_u_px,sigma_v_px");
  int rows = 0, converged = 0;
  std::string line;
  while (std::getline(in, line)) {
    ++rows;
    std::vector<std::string> fields;
    std::stringstream ss(line);
    for (std::string field; std::getline(ss, field, ',');) fields.push_back(field);
    ASSERT_EQ(fields.size(), 10u) << line;
    const bool ok = fields[7] == "converged";
    converged += ok;
    // Converged rows carry finite sigmas within the default limit, the others "nan".
    const double su = std::stod(fields[8]), sv = std::stod(fields[9]);
    if (ok) {
      EXPECT_TRUE(su > 0 && su <= 0.025 && sv > 0 && sv <= 0.025) << line;
    } else {
      EXPECT_TRUE(std::isnan(su) && std::isnan(sv)) << line;
    }
  }
  // (120 - 8 - 25) / 10 + 1 = 9 columns, (100 - 8 - 25) / 10 + 1 = 7 rows, 2 frames.
  EXPECT_EQ(rows, 2 * 9 * 7);
  EXPECT_GT(converged, rows / 2);
}

TEST_F(CorrelateCli, WritesHdf5WithFramesAndStatusCodes) {
  const std::string out = Path("out.h5");
  const CliResult r = RunCli("correlate --frames '" + Path("def*.png") +
                             "' --interp biquintic --shape quadratic --reference-update every:1 "
                             "--threads 2 --roi 10,10,110,90 -o " +
                             out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  H5Reader h5(out);
  Dims dims;
  h5.ReadDouble("dic/u_px", &dims);
  ASSERT_EQ(dims.size(), 2u);
  // The results layout of `impactdic run` (io/results_layout.h): row 0 is the reference (def1),
  // row 1 the only deformed frame (def2); /dic/frame their index in the sequence.
  EXPECT_EQ(dims[0], 2u);
  EXPECT_EQ(dims[1], h5.Dimensions("dic/x_px")[0]);
  EXPECT_EQ(h5.ReadNumberAttribute("dic", "layout_version"), 2);
  EXPECT_EQ(h5.ReadInt("dic/frame"), (std::vector<std::int32_t>{0, 1}));
  EXPECT_NE(h5.ReadStringAttribute("dic/status", "codes").find("0=converged"), std::string::npos);
  EXPECT_FALSE(h5.HasAttribute("dic/status", "status_names"));     // One name per attribute.
  EXPECT_EQ(h5.ReadStringAttribute("dic", "shape"), "quadratic");  // --shape quadratic above
  for (const char* name : {"dic/sigma_u_px", "dic/sigma_v_px"}) {
    Dims sigma_dims;
    h5.ReadFloat(name, &sigma_dims);
    EXPECT_EQ(sigma_dims, dims) << name;
    EXPECT_EQ(h5.ReadStringAttribute(name, "units"), "px") << name;
  }
  EXPECT_EQ(h5.ReadStringAttribute("dic", "mode"), "sequence");
}

TEST_F(CorrelateCli, PairsModeAndUncertaintyLimit) {
  const std::string out = Path("pairs.h5");
  const CliResult r =
      RunCli(Pair() + " --mode pairs --max-uncertainty none --subset 25 --step 10 -o " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  H5Reader h5(out);
  EXPECT_EQ(h5.ReadStringAttribute("dic", "mode"), "pairs");
  EXPECT_TRUE(std::isinf(h5.ReadNumberAttribute("dic", "max_uncertainty_px")));
  const std::vector<std::int32_t> reference = h5.ReadInt("dic/reference_frame");
  EXPECT_EQ(reference, (std::vector<std::int32_t>{0, 0, 0}));  // Row 0: the reference itself.
  // Both deformed images (rows 1, 2) against the reference: 0.4/-0.3 and 0.8/-0.6 px.
  Dims dims;
  const std::vector<double> u = h5.ReadDouble("dic/u_px", &dims);
  const std::vector<std::int32_t> status = h5.ReadInt("dic/status");
  const std::vector<float> sigma_u = h5.ReadFloat("dic/sigma_u_px");
  int converged = 0;
  for (std::size_t k = 1; k < dims[0]; ++k) {
    for (std::size_t i = 0; i < dims[1]; ++i) {
      if (status[k * dims[1] + i] != 0) continue;
      ++converged;
      EXPECT_NEAR(u[k * dims[1] + i], 0.4 * k, 0.05);
      EXPECT_GT(sigma_u[k * dims[1] + i], 0);
    }
  }
  EXPECT_GT(converged, static_cast<int>((dims[0] - 1) * dims[1]) / 2);
  ExpectError(Pair() + " --mode pair -o " + Path("x.csv"), "--mode");
  ExpectError(Pair() + " --mode pairs --reference-update incremental -o " + Path("x.csv"),
              "--reference-update");
  ExpectError(Pair() + " --max-uncertainty -1 -o " + Path("x.csv"), "--max-uncertainty");
  ExpectError(Pair() + " --max-uncertainty lots -o " + Path("x.csv"), "--max-uncertainty");
  // --help names the modes, the default and the uncertainty default.
  const CliResult help = RunCli("correlate --help");
  for (const char* item :
       {"--mode TEXT=sequence", "sequence | pairs", "--max-uncertainty TEXT=none"})
    EXPECT_NE(help.output.find(item), std::string::npos) << item << "\n" << help.output;
}

TEST_F(CorrelateCli, GaussianPrefilterBlursEveryImageAndBadValuesAreNamed) {
  const std::string out = Path("prefiltered.h5");
  const CliResult r =
      RunCli(Pair() + " --mode pairs --max-uncertainty none --gaussian 0.8,5 -o " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("pre-filter gaussian: sigma 0.8 px, kernel 5x5"), std::string::npos)
      << r.output;
  H5Reader h5(out);
  EXPECT_NE(h5.ReadStringAttribute("dic", "preprocess").find("sigma 0.8 px"), std::string::npos);
  // The same as the library on the three images blurred by the preprocess module: the reference
  // is filtered as well as the deformed images (filtering one side only gives other results).
  PreprocessOptions pre_options;
  pre_options.gaussian.mode = GaussianMode::kOn;
  pre_options.gaussian.sigma_px = 0.8;
  std::vector<cv::Mat> images;
  for (const char* name : {"ref.png", "def1.png", "def2.png"}) {
    const cv::Mat image = ReadGreyImage(Path(name));
    images.push_back(Preprocessor(pre_options, nullptr, image.size()).Apply(image));
  }
  DicOptions options;
  options.mode = SequenceMode::kPairs;
  options.icgn.max_uncertainty_px = 0;
  const DicResult both = CorrelateSequence(images, options);
  images[0] = ReadGreyImage(Path("ref.png"));
  const DicResult deformed_only = CorrelateSequence(images, options);
  Dims dims;
  const std::vector<double> u = h5.ReadDouble("dic/u_px", &dims);
  ASSERT_EQ(dims[0], 3u);
  int compared = 0, differ = 0;
  for (std::size_t k = 1; k < 3; ++k) {
    for (std::size_t i = 0; i < dims[1]; ++i) {
      const double cli = u[k * dims[1] + i], lib = both.frames[k - 1].u_px[i];
      if (std::isnan(lib)) {
        EXPECT_TRUE(std::isnan(cli));
        continue;
      }
      ++compared;
      EXPECT_NEAR(cli, lib, 1e-12);
      differ += std::abs(cli - deformed_only.frames[k - 1].u_px[i]) > 1e-6;
    }
  }
  EXPECT_GT(compared, 0);
  EXPECT_GT(differ, compared / 2);
  for (const char* bad : {"0", "-1", "25", "abc", "0.8,4", "0.8,2", "0.8,x", "0.8,", ",5"})
    ExpectError(Pair() + " --gaussian " + bad + " -o " + Path("x.csv"), "--gaussian");
  ExpectError(Pair() + " --gaussian 0.8,4 -o " + Path("x.csv"), "kernel an odd size");
  EXPECT_FALSE(fs::exists(Path("x.csv")));
  const CliResult help = RunCli("correlate --help");
  EXPECT_NE(help.output.find("--gaussian"), std::string::npos) << help.output;
}

TEST_F(CorrelateCli, BadInputGivesClearErrors) {
  ExpectError("correlate --reference " + Path("missing.png") + " --deformed " + Path("def1.png") +
                  " -o " + Path("x.csv"),
              "missing.png");
  ExpectError("correlate --reference " + Path("ref.png") + " --deformed " + Path("corrupt.png") +
                  " -o " + Path("x.csv"),
              "corrupt.png");
  ExpectError("correlate --reference " + Path("ref.png") + " --deformed " + Path("small.png") +
                  " -o " + Path("x.csv"),
              "small.png");
  ExpectError(Pair() + " --subset 24 -o " + Path("x.csv"), "--subset");
  ExpectError(Pair() + " --subset 151 -o " + Path("x.csv"), "subset");
  ExpectError(Pair() + " --roi 50,50,300,90 -o " + Path("x.csv"), "ROI");
  ExpectError(Pair() + " --roi 5,5,2 -o " + Path("x.csv"), "--roi");
  ExpectError(Pair() + " --interp bilinear -o " + Path("x.csv"),
              "--interp: invalid value (got 'bilinear'); expected one of bicubic, biquintic");
  ExpectError(Pair() + " --shape cubic -o " + Path("x.csv"),
              "--shape: invalid value (got 'cubic')");
  ExpectError(Pair() + " --reference-update every:0 -o " + Path("x.csv"), "every:0");
  ExpectError(Pair() + " --threads -1 -o " + Path("x.csv"), "--threads");
  ExpectError(Pair() + " -o " + Path("x.txt"), ".csv, .h5 or .hdf5");
  ExpectError(Pair() + " -o /no/such/folder/x.csv", "/no/such/folder");
  ExpectError("correlate -o " + Path("x.csv"), "--frames");
}

TEST_F(CorrelateCli, MaskLimitsTheSubsetsAndAWrongSizedMaskIsNamed) {
  // 120x100 images; the mask opens only the right half (x >= 60).
  cv::Mat mask(100, 120, CV_8U, cv::Scalar(0));
  mask(cv::Rect(60, 0, 60, 100)).setTo(255);
  WriteImage(Path("mask.png"), mask);
  WriteImage(Path("mask_small.png"), cv::Mat(50, 60, CV_8U, cv::Scalar(255)));
  const std::string out = Path("masked.csv");
  const CliResult r =
      RunCli(Pair() + " --subset 25 --step 10 --mask " + Path("mask.png") + " -o " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  CsvReadOptions read;
  read.allow_non_finite = true;
  read.text_columns = {"status"};
  const CsvTable t = ReadCsv(out, read);
  const std::vector<double>& xs = t.Column("x_px");
  const std::vector<double>& us = t.Column("u_px");
  const std::vector<std::string>& statuses = t.TextColumn("status");
  int masked = 0, correlated = 0;
  for (std::size_t i = 0; i < t.rows(); ++i) {
    const double x = xs[i];
    const std::string& status = statuses[i];
    if (x < 60) {
      EXPECT_EQ(status, "masked") << "x = " << x;
      EXPECT_TRUE(std::isnan(us[i]));
      ++masked;
    } else {
      EXPECT_EQ(status, "converged") << "x = " << x;
      ++correlated;
    }
  }
  EXPECT_GT(masked, 0);
  EXPECT_GT(correlated, 0);
  ExpectError(Pair() + " --mask " + Path("mask_small.png") + " -o " + out, "mask_small.png");
  ExpectError(Pair() + " --mask " + Path("no_mask.png") + " -o " + out, "no_mask.png");
}

// Images are decoded while the previous frame is correlated: a bad image late in the sequence
// still stops the run with its name, and no output file is left behind.
TEST_F(CorrelateCli, BadImageLateInTheSequenceIsNamedAndNothingIsWritten) {
  const std::string out = Path("late.h5");
  // A third deformed image: a copy (the same file twice is refused, CorrelateInputs).
  fs::copy_file(Path("def1.png"), Path("def3.png"), fs::copy_options::overwrite_existing);
  for (const char* bad : {"corrupt.png", "small.png", "missing.png"}) {
    ExpectError(Pair() + " " + Path("def3.png") + " " + Path(bad) + " -o " + out, bad);
    EXPECT_FALSE(fs::exists(out)) << bad;
  }
  const CliResult ok = RunCli(Pair() + " " + Path("def3.png") + " -o " + out);
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
  EXPECT_TRUE(fs::exists(out));
}

}  // namespace
}  // namespace impactdic
