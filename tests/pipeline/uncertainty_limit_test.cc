// momentum.max_sigma_px end to end (item 2: "let downstream stages weight or exclude by
// it"): a synthesised scene is run without a limit, the limit is then set between the reported
// sigmas, and `run` and `analyze` must leave out exactly the valid samples above it (counted in the
// warning), keep them in /dic, and still measure the momentum from the others.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "../cli/cli_runner.h"
#include "../io/test_dir.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/results_layout.h"
#include "impactdic/kinematics/kinematics.h"
#include "impactdic/kinematics/kinematics_results.h"
#include "impactdic/momentum/momentum_results.h"
#include "impactdic/momentum/scene_analysis.h"
#include "impactdic/pipeline/scene.h"
#include "small_scene_spec.h"

namespace impactdic {
namespace {

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The scene text with `momentum.max_sigma_px: limit` added to its momentum section.
std::string WithSigmaLimit(const std::string& scene, double limit) {
  const std::string key = "\nmomentum:\n";
  const std::size_t at = scene.find(key);
  EXPECT_NE(at, std::string::npos) << "the synthesised scene has a momentum section";
  std::string out = scene;
  out.insert(at + key.size(), fmt::format("  max_sigma_px: {:.17g}\n", limit));
  return out;
}

// Valid samples whose larger sigma exceeds `limit`.
std::size_t CountAbove(const CorrelationSeries& s, double limit) {
  std::size_t n = 0;
  for (std::size_t j = 0; j < s.frames * s.subsets; ++j)
    n += s.valid[j] && (s.sigma_u_px[j] > limit || s.sigma_v_px[j] > limit);
  return n;
}

std::size_t CountNaN(const std::vector<double>& values) {
  return static_cast<std::size_t>(
      std::count_if(values.begin(), values.end(), [](double v) { return std::isnan(v); }));
}

TEST(SigmaLimit, RunAndAnalyzeLeaveOutExactlyTheSamplesAboveItAndKeepThemInDic) {
  TestDir dir;
  const CliResult synth =
      RunCli("-q synth " + dir.Write("spec.yaml", kSmallSceneSpec) + " -o " + dir.File("scene"));
  ASSERT_EQ(synth.exit_code, 0) << synth.output;
  const std::string scene = dir.File("scene/scene.yaml");
  const CliResult plain = RunCli("-q run " + scene + " -o " + dir.File("plain"));
  ASSERT_EQ(plain.exit_code, 0) << plain.output;

  // The limit: the median of the larger sigma over the valid samples.
  long first = -1;
  const CorrelationSeries all = ReadCorrelationSeries(dir.File("plain/results.h5"), &first);
  ASSERT_FALSE(all.sigma_u_px.empty());
  // Without momentum.max_sigma_px the default rule applied: samples above 50 x their frame's
  // median sigma (momentum.max_sigma_ratio), named in a warning when there are any.
  CorrelationSeries by_default = all;
  const std::size_t left_out_by_default = ExcludeSamplesAboveMedianSigma(
      SceneMomentum::kDefaultMaxSigmaRatio, "momentum.max_sigma_ratio", &by_default);
  EXPECT_EQ(plain.output.find("momentum.max_sigma_px"), std::string::npos) << plain.output;
  if (left_out_by_default == 0) {
    EXPECT_EQ(plain.output.find("left out"), std::string::npos) << plain.output;
  } else {
    EXPECT_NE(plain.output.find(fmt::format("kinematics: {} of", left_out_by_default)),
              std::string::npos)
        << plain.output;
  }
  std::vector<double> sigmas;
  for (std::size_t j = 0; j < all.frames * all.subsets; ++j)
    if (all.valid[j]) sigmas.push_back(std::max(all.sigma_u_px[j], all.sigma_v_px[j]));
  ASSERT_GT(sigmas.size(), 100u);
  std::nth_element(sigmas.begin(), sigmas.begin() + sigmas.size() / 2, sigmas.end());
  const double limit = sigmas[sigmas.size() / 2];
  const std::size_t above = CountAbove(all, limit);
  ASSERT_GT(above, sigmas.size() / 4);
  ASSERT_LT(above, sigmas.size() * 3 / 4);
  const std::string warning =
      fmt::format("kinematics: {} of {} subset samples left out", above, all.frames * all.subsets);

  const std::string limited =
      dir.Write("scene/limited.yaml", WithSigmaLimit(ReadText(scene), limit));
  const CliResult run =
      RunCli("-q run " + limited + " -o " + dir.File("limited") + " --format json");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find(warning), std::string::npos) << warning << "\n" << run.output;
  EXPECT_NE(run.output.find("\"usable\": true"), std::string::npos) << run.output;

  // /dic keeps every sample as correlated; the kinematics leave the ones above the limit out.
  const CorrelationSeries kept = ReadCorrelationSeries(dir.File("limited/results.h5"), &first);
  EXPECT_EQ(kept.valid, all.valid);
  EXPECT_EQ(CountAbove(kept, limit), above);
  const H5Reader plain_h5(dir.File("plain/results.h5"));
  const H5Reader limited_h5(dir.File("limited/results.h5"));
  const std::vector<double> vy_plain = plain_h5.ReadDouble(results_layout::kVy);
  const std::vector<double> vy_limited = limited_h5.ReadDouble(results_layout::kVy);
  ASSERT_EQ(vy_plain.size(), vy_limited.size());
  // The plain run left out its samples above 50 x the median, all of them above the median too.
  EXPECT_GE(CountNaN(vy_limited), CountNaN(vy_plain) + above - left_out_by_default);
  // The momentum is still measured from the other samples, and differs from the unlimited one.
  const std::vector<double> p_plain = plain_h5.ReadDouble(results_layout::kPGran);
  const std::vector<double> p_limited = limited_h5.ReadDouble(results_layout::kPGran);
  ASSERT_EQ(p_plain.size(), p_limited.size());
  EXPECT_LT(CountNaN(p_limited), p_limited.size());
  EXPECT_NE(p_plain, p_limited);

  // `analyze` of the unlimited results with the limited scene leaves out the same samples.
  // Into a file of its own: the run folder's results.h5 stays with its summary.json.
  const CliResult analyze =
      RunCli("-q analyze " + limited + " --results " + dir.File("plain/results.h5") + " --output " +
             dir.File("analysis.h5") + " --format json");
  ASSERT_EQ(analyze.exit_code, 0) << analyze.output;
  EXPECT_NE(analyze.output.find(warning), std::string::npos) << warning << "\n" << analyze.output;
}

}  // namespace
}  // namespace impactdic
