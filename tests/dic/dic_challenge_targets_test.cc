// The accuracy targets with DEFAULT settings, on the public benchmark images
// (../shared/data) and a synthetic noise scene: the fast subset of bench/dic_challenge.py
// (--quick; docs/dic_real_images.md). Each test runs the bench on one
// section with no extra correlate flag and asserts the target on the figure it prints in its
// "Targets" table:
//   Sample 3 (11 shifts 0..1 px, bicubic and biquintic, pairs, subset 25, step 10): max |bias|
//     <= 0.001 px, and the reported sigma within +-30 % of the sd of u and of v at every shift;
//   Sample 14 L1 (pairs, subset 25, step 5): reported sigma within +-30 % of the observed RMS
//     error of u and of v;
//   real sand test48 (IMG_31..40 against IMG_30 in sequence, the sand below its surface
//     0,1400,4096,3000, subset 25, step 50): >= 98 % valid subsets in every frame;
//   real static sand (IMG_1 against each of IMG_2..5 of real-sand/static, pairs, the sand
//     below its surface, subset 25, step 50): the reported sigma within +-30 % of the scatter of
//     u and of v about a quadratic surface, over all subsets and within each quartile of sigma;
//   synthetic noise (512x512 band-limited speckle, 3 exact shifts, 2 grey levels of noise):
//     reported sigma within +-30 % of the observed sd of u and of v.
// About 15 s in Release on 2 cores.
// The real-data tests skip when ../shared/data is absent, and fail then under
// IMPACTDIC_REQUIRE_SHARED_DATA=1 (scripts/test.sh; tests/core/shared_data.h).
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "../core/shared_data.h"
#include "bench_script.h"

namespace impactdic {
namespace {

constexpr double kMaxBiasPx = 0.001;       // bias target
constexpr double kSigmaTolerance = 0.30;   // sigma within +-30 % of the measured scatter
constexpr double kMinValidPercent = 98.0;  // real sand with defaults

class DicChallengeTargets : public ::testing::Test {
 protected:
  // The "Targets" table of a --quick --check run of `section` with default settings: target name
  // -> measured value (NaN for n/a).
  std::map<std::string, double> Run(const std::string& section, const std::string& data) {
    const BenchTempDir work("dic_targets_" + section);
    const CliResult run =
        RunDicChallengeBench("--quick --check --only " + section + " --data " + ShellQuote(data) +
                             " --work " + ShellQuote(work.path()));
    output_ = run.output;
    EXPECT_EQ(run.exit_code, 0) << "the bench could not measure everything (notes below)";
    std::map<std::string, double> targets;
    for (const auto& row : TableRows(run.output, "## Targets")) {
      if (row.size() == 4) targets[row[0]] = CellNumbers(row[1])[0];
    }
    EXPECT_FALSE(targets.empty()) << "no Targets table";
    return targets;
  }

  // The bench's tables once, after the failures.
  void TearDown() override {
    if (HasFailure()) std::cerr << "bench/dic_challenge.py printed:\n" << output_ << std::endl;
  }

  static void ExpectSigmaRatio(const std::string& name, double ratio) {
    EXPECT_TRUE(std::isfinite(ratio)) << name << " n/a";
    EXPECT_GE(ratio, 1 - kSigmaTolerance) << name << ": reported sigma too small";
    EXPECT_LE(ratio, 1 + kSigmaTolerance) << name << ": reported sigma too large";
  }

  std::string output_;
};

TEST_F(DicChallengeTargets, Sample3MaxBiasAtMostAThousandthPixelWithDefaults) {
  IMPACTDIC_SHARED_DATA_OR_SKIP(data, "dic-challenge/sample3");
  const auto targets = Run("s3", SharedDataRoot().string());
  for (const std::string interp : {"bicubic", "biquintic"}) {
    const std::string name = "s3_" + interp + "_max_abs_bias_px";
    ASSERT_TRUE(targets.count(name)) << name << " missing (" << data << ")";
    EXPECT_TRUE(std::isfinite(targets.at(name))) << name;
    EXPECT_LE(targets.at(name), kMaxBiasPx) << name << ": Sample 3 sub-pixel bias";
    // The extreme ratios over the shifts and components.
    for (const std::string bound : {"_sigma_ratio_min", "_sigma_ratio_max"}) {
      ASSERT_TRUE(targets.count("s3_" + interp + bound)) << interp << bound;
      ExpectSigmaRatio("s3_" + interp + bound, targets.at("s3_" + interp + bound));
    }
  }
}

TEST_F(DicChallengeTargets, Sample14SigmaWithin30PercentOfTheObservedErrorWithDefaults) {
  IMPACTDIC_SHARED_DATA_OR_SKIP(data, "dic-challenge/sample14");
  const auto targets = Run("s14", SharedDataRoot().string());
  for (const std::string name : {"s14_L1_sigma_over_error_u", "s14_L1_sigma_over_error_v"}) {
    ASSERT_TRUE(targets.count(name)) << name << " missing (" << data << ")";
    ExpectSigmaRatio(name, targets.at(name));
  }
}

TEST_F(DicChallengeTargets, RealSandAtLeast98PercentValidInEveryFrameWithDefaults) {
  IMPACTDIC_SHARED_DATA_OR_SKIP(data, "real-sand/test48");
  const auto targets = Run("sand", SharedDataRoot().string());
  int frames = 0;
  for (const auto& [name, value] : targets) {
    if (name.rfind("sand_", 0) != 0) continue;
    ++frames;
    EXPECT_TRUE(std::isfinite(value)) << name;
    EXPECT_GE(value, kMinValidPercent) << name;
  }
  EXPECT_EQ(frames, 10) << "frames IMG_31..40 of " << data;
}

// JPEG frames of a camera and sand at rest: the sigma matches the observed scatter over all
// subsets and within each quartile of the reported sigma (the sigma varies 4x over the field).
TEST_F(DicChallengeTargets, RealStaticSandSigmaWithin30PercentOfTheScatterWithDefaults) {
  IMPACTDIC_SHARED_DATA_OR_SKIP(data, "real-sand/static");
  const auto targets = Run("static", SharedDataRoot().string());
  int checked = 0;
  for (const auto& [name, value] : targets) {
    if (name.rfind("static_", 0) != 0) continue;
    ++checked;
    ExpectSigmaRatio(name, value);
  }
  EXPECT_EQ(checked, 16) << "4 pairs x u, v x the least and largest ratio, of " << data;
}

TEST_F(DicChallengeTargets, SyntheticNoiseSigmaWithin30PercentOfTheObservedSdWithDefaults) {
  // The synthetic section makes its own images: no shared data needed.
  const auto targets = Run("synth", "/nonexistent");
  int checked = 0;
  for (const auto& [name, value] : targets) {
    if (name.rfind("synth_", 0) != 0) continue;
    ++checked;
    ExpectSigmaRatio(name, value);
  }
  EXPECT_EQ(checked, 6);  // u and v of 3 shifts
}

}  // namespace
}  // namespace impactdic
