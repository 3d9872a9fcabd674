// The DIC Challenge scripts without network (issue 13, items 1-2): bench/dic_challenge.py runs on
// small stand-ins of Samples 3 and 14 written with the challenge archives' file names and layout
// (known rigid shifts 0..1 px; a sinusoidal u), and its tables must give the known truth; and
// scripts/fetch_dic_challenge.sh fails cleanly when its download host cannot be resolved.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "../cli/cli_runner.h"
#include "impactdic/synth/fields.h"
#include "impactdic/synth/speckle.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

std::string Quote(const fs::path& p) {
  std::string quoted(1, '\'');
  quoted.append(p.string());
  quoted.push_back('\'');
  return quoted;
}

constexpr double kNoise = 2.0;  // grey levels (8-bit), as the challenge's "N2" images

SpecklePattern Pattern(int w, int h) {
  SpeckleOptions o;
  o.seed = 13;
  o.blob_radius_px = 2.0;
  return SpecklePattern(o, w, h);
}

cv::Mat Render(const SpecklePattern& pattern, int w, int h, const DisplacementField& f,
               std::uint64_t noise_seed) {
  RenderOptions r;
  r.noise_sigma = kNoise;
  r.noise_seed = noise_seed;
  r.supersampling = 2;
  return RenderImage(pattern, w, h, f, r);
}

// Sample 3 stand-in: "Sample3 Reference.tif" and the 11 shifted images X0.00 Y0.00 .. X1.00
// Y1.00, each with its own noise (written by OpenCV's TIFF encoder, LZW-compressed).
void WriteSample3(const fs::path& dir) {
  fs::create_directories(dir);
  const int w = 160, h = 160;
  const SpecklePattern pattern = Pattern(w, h);
  cv::imwrite((dir / "Sample3 Reference.tif").string(),
              Render(pattern, w, h, Translation(0, 0), 1));
  for (int k = 0; k <= 10; ++k) {
    char name[64];
    std::snprintf(name, sizeof name, "Sample3-%03d X%.2f Y%.2f N2 C0 R0.tif", k, 0.1 * k, 0.1 * k);
    cv::imwrite((dir / name).string(),
                Render(pattern, w, h, Translation(0.1 * k, 0.1 * k), 100 + k));
  }
}

// Sample 14 stand-in: level L1 has u = 0.1 sin(2 pi X / 200 px), v = 0, and its truth in the
// table Sample14_command.csv (x, u_L1, exx_L1, u_L3, exx_L3, u_L5, exx_L5 per pixel column, as
// the real one); L2 (no column in the table, as in the real one) has the same field. The deformed
// images are 3 x 2 px larger than the reference (the bench crops them to the common size);
// uncompressed TIFF.
constexpr double kAmplitude = 0.1, kPeriod = 200.0;
void WriteSample14(const fs::path& dir, const fs::path& truth_csv) {
  fs::create_directories(dir);
  const int w = 400, h = 90;
  const SpecklePattern pattern = Pattern(w + 3, h + 2);
  const std::vector<int> uncompressed = {cv::IMWRITE_TIFF_COMPRESSION, 1};
  const cv::Mat reference = Render(pattern, w + 3, h + 2, Translation(0, 0), 1);
  cv::imwrite((dir / "Sample14 Reference.tif").string(), reference(cv::Rect(0, 0, w, h)),
              uncompressed);
  const DisplacementField field = Sinusoidal(kAmplitude, 0, kPeriod);
  cv::imwrite((dir / "Sample14 L1 Amp0.1.tif").string(), Render(pattern, w + 3, h + 2, field, 2),
              uncompressed);
  cv::imwrite((dir / "Sample14 L2 Amp0.1.tif").string(), Render(pattern, w + 3, h + 2, field, 3),
              uncompressed);
  std::FILE* f = std::fopen(truth_csv.string().c_str(), "w");
  ASSERT_NE(f, nullptr);
  for (int x = 0; x < 2048; ++x) {
    const double u = field.u(x, 0)[0];
    const double exx = 1e6 * kAmplitude * 2 * M_PI / kPeriod * std::cos(2 * M_PI * x / kPeriod);
    std::fprintf(f, "%d,%.9g,%.9g,0,0,0,0\n", x, u, exx);
  }
  std::fclose(f);
}

// Table rows "| a | b | ... |" of the section that starts with `heading`.
std::vector<std::vector<std::string>> Rows(const std::string& out, const std::string& heading) {
  std::vector<std::vector<std::string>> rows;
  const std::size_t start = out.find(heading);
  if (start == std::string::npos) return rows;
  std::istringstream in(out.substr(start));
  std::string line;
  bool in_table = false;
  while (std::getline(in, line)) {
    if (line.rfind("|", 0) != 0) {
      if (in_table) break;
      continue;
    }
    in_table = true;
    if (line.find("---") != std::string::npos || line.find("[px]") != std::string::npos) continue;
    std::vector<std::string> cells;
    std::istringstream cs(line.substr(1));
    std::string cell;
    while (std::getline(cs, cell, '|')) {
      cell = std::regex_replace(cell, std::regex("^ +| +$"), "");
      cells.push_back(cell);
    }
    if (!cells.empty() && cells.back().empty()) cells.pop_back();
    rows.push_back(cells);
  }
  return rows;
}

// "a, b" -> {a, b}
std::vector<double> Numbers(const std::string& cell) {
  std::vector<double> v;
  std::istringstream in(cell);
  std::string part;
  while (std::getline(in, part, ',')) v.push_back(std::stod(part));
  return v;
}

class DicChallengeScripts : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("impactdic_dic_challenge_test_" + std::to_string(getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
  const fs::path source_ = IMPACTDIC_SOURCE_DIR;
};

TEST_F(DicChallengeScripts, BenchTablesGiveTheKnownTruthOfStandInSamples) {
  // The archives unpack into a sub-folder in some layouts: the bench searches below SampleN/.
  WriteSample3(dir_ / "data" / "Sample3" / "Sample3");
  WriteSample14(dir_ / "data" / "Sample14", dir_ / "data" / "Sample14_command.csv");
  const CliResult run = RunShell("python3 " + Quote(source_ / "bench" / "dic_challenge.py") + " " +
                                 Quote(dir_ / "data") + " --binary " + Quote(IMPACTDIC_CLI_PATH) +
                                 " --threads 2 --work " + Quote(dir_ / "work"));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  SCOPED_TRACE(run.output);

  // The noise estimate from the zero-shift image: the images' noise is 2 grey levels.
  std::smatch m;
  ASSERT_TRUE(std::regex_search(run.output, m, std::regex("sigma_n = ([0-9.]+) grey levels")));
  EXPECT_NEAR(std::stod(m[1]), kNoise, 0.15);

  for (const std::string interp : {"bicubic", "biquintic"}) {
    const auto rows = Rows(run.output, "### " + interp);
    ASSERT_EQ(rows.size(), 11u) << interp;
    for (std::size_t k = 0; k < rows.size(); ++k) {
      const auto& r = rows[k];
      ASSERT_EQ(r.size(), 8u);
      const std::vector<double> shift = Numbers(r[0]);
      EXPECT_NEAR(shift[0], 0.1 * k, 1e-9);
      EXPECT_NEAR(shift[1], 0.1 * k, 1e-9);
      EXPECT_LT(std::abs(std::stod(r[1])), 0.01) << interp << " shift " << r[0];  // bias u
      EXPECT_LT(std::abs(std::stod(r[2])), 0.01) << interp << " shift " << r[0];  // bias v
      const double sd_u = std::stod(r[3]);
      const double sd_v = std::stod(r[4]);
      const std::vector<double> limit = Numbers(r[5]);
      // sd at the noise limit: the limit predicts the scatter within a factor 1.6.
      EXPECT_GT(limit[0], 0.0);
      EXPECT_NEAR(std::log(sd_u / limit[0]), 0.0, std::log(1.6)) << interp << " " << r[0];
      EXPECT_NEAR(std::log(sd_v / limit[1]), 0.0, std::log(1.6)) << interp << " " << r[0];
      const std::vector<double> sigma = Numbers(r[6]);
      EXPECT_GT(sigma[0], 0.0);
      EXPECT_LT(sigma[0], 2 * limit[0]);
      // Every subset of the grid converged: "n/n".
      const std::size_t slash = r[7].find('/');
      ASSERT_NE(slash, std::string::npos);
      EXPECT_EQ(r[7].substr(0, slash), r[7].substr(slash + 1));
      EXPECT_GE(std::stoi(r[7].substr(0, slash)), 100);
    }
  }
  // Sample 3: one correlate per interpolator with all shifted images; Sample 14: one per image.
  EXPECT_NE(run.output.find("command: "), std::string::npos);
  EXPECT_NE(run.output.find("X0.50 Y0.50 N2 C0 R0.tif' '"), std::string::npos);
  EXPECT_NE(run.output.find("command (per image): "), std::string::npos);
  EXPECT_NE(run.output.find("--mode pairs"), std::string::npos);
  EXPECT_NE(run.output.find("--interp biquintic"), std::string::npos);
  // --prefilter SIGMA passes correlate's Gaussian pre-filter (docs/dic.md, "Sub-pixel bias").
  const CliResult filtered = RunShell(
      "python3 " + Quote(source_ / "bench" / "dic_challenge.py") + " " + Quote(dir_ / "data") +
      " --binary " + Quote(IMPACTDIC_CLI_PATH) + " --threads 2 --only 3 --prefilter 0.8");
  ASSERT_EQ(filtered.exit_code, 0) << filtered.output;
  EXPECT_NE(filtered.output.find("--gaussian 0.8"), std::string::npos) << filtered.output;
  EXPECT_EQ(Rows(filtered.output, "### bicubic").size(), 11u) << filtered.output;

  const auto s14 = Rows(run.output, "## DIC Challenge 1.0 Sample 14");
  ASSERT_EQ(s14.size(), 2u);
  const auto& r = s14[0];
  ASSERT_EQ(r.size(), 8u);
  EXPECT_EQ(r[0], "Sample14 L1 Amp0.1.tif");
  const std::size_t slash = r[1].find('/');
  EXPECT_EQ(r[1].substr(0, slash), r[1].substr(slash + 1));  // --max-uncertainty none: all
  EXPECT_GE(std::stoi(r[1].substr(0, slash)), 500);
  // RMS errors against the table's truth: at the noise level (reported sigma ~0.0065 px) plus the
  // affine subset's attenuation of the sinusoid (~2.5 % of 0.1 px).
  EXPECT_LT(std::stod(r[2]), 0.012);
  EXPECT_GT(std::stod(r[2]), 0.003);
  EXPECT_LT(std::stod(r[3]), 0.012);  // v, truth 0
  EXPECT_TRUE(std::regex_match(r[5], std::regex("[0-9]+\\.[0-9]{2} %"))) << r[5];
  const std::vector<double> sigma = Numbers(r[6]);
  EXPECT_NEAR(sigma[0], 0.0065, 0.003);
  EXPECT_EQ(r[7], "L1 of Sample14_command.csv");
  // L2 has no column in the table: no error figure, and a note says why.
  EXPECT_EQ(s14[1][0], "Sample14 L2 Amp0.1.tif");
  EXPECT_EQ(s14[1][2], "nan");
  EXPECT_EQ(s14[1][7], "none");
  EXPECT_NE(run.output.find("no commanded displacement for level L2"), std::string::npos);
  EXPECT_NE(run.output.find("cropped to the common top-left 400x90"), std::string::npos);
  EXPECT_NE(run.output.find("--max-uncertainty none"), std::string::npos);

  // The fetch script, given these stand-ins as archives (file:// URLs), unpacks and checks them,
  // records their SHA-256, and refuses a different archive under the same name later.
  const fs::path zips = dir_ / "zips";
  fs::create_directories(zips);
  const std::string zip = "cd " + Quote(dir_ / "data") + " && python3 -m zipfile -c ";
  ASSERT_EQ(RunShell(zip + Quote(zips / "Sample3.zip") + " Sample3/Sample3").exit_code, 0);
  ASSERT_EQ(RunShell(zip + Quote(zips / "Sample14.zip") + " Sample14").exit_code, 0);
  const std::string fetch =
      "DIC_CHALLENGE_SAMPLE3_URL=file://" + (zips / "Sample3.zip").string() +
      " DIC_CHALLENGE_SAMPLE14_URL=file://" + (zips / "Sample14.zip").string() +
      " DIC_CHALLENGE_SAMPLE14_TRUTH_URL=file://" +
      (dir_ / "data" / "Sample14_command.csv").string() + " " +
      Quote(source_ / "scripts" / "fetch_dic_challenge.sh") + " " + Quote(dir_ / "cache");
  const CliResult fetched = RunShell(fetch);
  ASSERT_EQ(fetched.exit_code, 0) << fetched.output;
  EXPECT_TRUE(fs::exists(dir_ / "cache" / "Sample3" / "Sample3" / "Sample3 Reference.tif"));
  EXPECT_TRUE(fs::exists(dir_ / "cache" / "Sample14" / "Sample14" / "Sample14 L1 Amp0.1.tif"));
  EXPECT_TRUE(fs::exists(dir_ / "cache" / "Sample14_command.csv"));
  EXPECT_NE(fetched.output.find("1 reference + 11 deformed images"), std::string::npos);
  EXPECT_NE(fetched.output.find("1 reference + 2 deformed images"), std::string::npos);
  // A different archive under the same name (one file more).
  ASSERT_EQ(RunShell(zip + Quote(dir_ / "cache" / "Sample3.zip") +
                     " Sample3/Sample3 Sample14_command.csv")
                .exit_code,
            0);
  const CliResult refetched = RunShell(fetch);
  EXPECT_EQ(refetched.exit_code, 1) << refetched.output;
  EXPECT_NE(refetched.output.find("differs from the"), std::string::npos) << refetched.output;
}

TEST_F(DicChallengeScripts, BenchNamesTheMissingFolder) {
  const CliResult run =
      RunShell("python3 " + Quote(source_ / "bench" / "dic_challenge.py") + " " +
               Quote(dir_ / "nothing") + " --binary " + Quote(IMPACTDIC_CLI_PATH));
  EXPECT_EQ(run.exit_code, 2) << run.output;
  EXPECT_NE(run.output.find((dir_ / "nothing" / "Sample3").string()), std::string::npos)
      << run.output;
  EXPECT_NE(run.output.find("fetch_dic_challenge.sh"), std::string::npos) << run.output;
}

TEST_F(DicChallengeScripts, FetchFailsCleanlyWhenTheHostCannotBeResolved) {
  const std::string url = "https://impactdic-no-such-host.invalid/Sample14.zip";
  const CliResult run =
      RunShell("DIC_CHALLENGE_SAMPLE14_URL=" + url +
               " DIC_CHALLENGE_SAMPLE3_URL=https://impactdic-no-such-host.invalid/"
               "Sample3.zip " +
               Quote(source_ / "scripts" / "fetch_dic_challenge.sh") + " " + Quote(dir_ / "cache"));
  EXPECT_NE(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find(url), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("network"), std::string::npos) << run.output;
  // Nothing half-downloaded is left under the archive's name.
  EXPECT_FALSE(fs::exists(dir_ / "cache" / "Sample14.zip"));
}

}  // namespace
}  // namespace impactdic
