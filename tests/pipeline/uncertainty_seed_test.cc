// Issue 42 item 4: the momentum figures' reported standard uncertainty (momentum/uncertainty.h)
// against their actual scatter. The small synthesised scene (small_scene_spec.h, rendered without
// supersampling so that 48 seeds cost what 16 supersampled ones did; on 48 supersampled seeds
// every ratio lay within 0.08 of these) is rendered with kSeeds noise seeds (the top-level
// `seed`: image noise and accelerometer noise; the speckle's own seed is fixed, so the
// correlation's bias is the same in every one) and run; the standard deviation of each figure
// over the seeds must match the mean reported u within +-30 %. With N seeds the sample SD has a
// relative standard error of 1 / sqrt(2 (N - 1)): 48 seeds give 10 %, so the tolerance holds the
// ratio to ~3 standard errors (measured ratios in docs/analysis.md, "Uncertainty of the
// figures"). Held to it: every figure but the sigmoid's T, which is printed: its scatter over
// the seeds is heavy-tailed (the onset's change-point fit puts the onset a whole DAQ sample early
// in ~1 % of records, and T's time origin is the onset): one of the 48 seeds lies 5.4 SD out and
// makes the SD; without it the ratio is 0.54, with it 0.87, so the SD over seeds checks nothing.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <future>
#include <string>
#include <vector>

#include "../cli/cli_runner.h"
#include "../io/test_dir.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/momentum/momentum_results.h"
#include "small_scene_spec.h"

namespace impactdic {
namespace {

constexpr int kSeeds = 48;

struct SeedRun {
  MomentumSummary summary;
  std::string problem;  // Empty when the run succeeded.
};

// Renders and runs the small scene with noise seed `seed` in `folder`.
SeedRun RunSeed(const TestDir& dir, int seed) {
  const std::string folder = dir.File(fmt::format("seed{}", seed));
  const std::string spec =
      dir.Write(fmt::format("spec{}.yaml", seed),
                fmt::format("seed: {}\n", seed) + SmallSceneSpec({.supersampling = 1}));
  SeedRun r;
  const CliResult synth = RunCli("-q synth " + spec + " -o " + folder + "/scene");
  if (synth.exit_code != 0) {
    r.problem = synth.output;
    return r;
  }
  // The figures and the video are not needed: the run's numbers only.
  const CliResult run = RunCli("-q run " + folder + "/scene/scene.yaml -o " + folder +
                               "/out --outputs.figures false --outputs.animation false");
  if (run.exit_code != 0) {
    r.problem = run.output;
    return r;
  }
  const std::string h5 = folder + "/out/results.h5";
  r.summary = ReadMomentumResults(H5Reader(h5), h5).momentum.summary;
  return r;
}

double Mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return s / static_cast<double>(v.size());
}

double Sd(const std::vector<double>& v) {
  const double m = Mean(v);
  double s = 0;
  for (double x : v) s += (x - m) * (x - m);
  return std::sqrt(s / static_cast<double>(v.size() - 1));
}

TEST(UncertaintySeeds, SpreadOverNoiseSeedsMatchesTheReportedUncertainty) {
  TestDir dir;
  // Two at a time (CI has two cores); each run's correlation on one thread.
  std::vector<SeedRun> runs;
  for (int seed = 1; seed <= kSeeds; seed += 2) {
    auto a = std::async(std::launch::async, [&] { return RunSeed(dir, seed); });
    SeedRun b = RunSeed(dir, seed + 1);
    runs.push_back(a.get());
    runs.push_back(std::move(b));
  }
  for (const SeedRun& r : runs) ASSERT_TRUE(r.problem.empty()) << r.problem;
  const std::vector<std::string> not_held = {"sigmoid_T_s"};
  std::string table =
      "figure                        mean          SD over seeds  mean u      SD/u\n";
  const std::size_t figures = UncertainFigures(runs[0].summary).size();
  for (std::size_t j = 0; j < figures; ++j) {
    std::vector<double> values, us;
    std::string name;
    for (SeedRun& r : runs) {
      const auto f = UncertainFigures(r.summary)[j];
      name = f.name;
      values.push_back(*f.value);
      us.push_back(*f.u);
    }
    const double sd = Sd(values), u = Mean(us), ratio = sd / u;
    table += fmt::format("{:<29} {:<13.6g} {:<14.4g} {:<11.4g} {:.3f}\n", name, Mean(values), sd, u,
                         ratio);
    if (std::find(not_held.begin(), not_held.end(), name) != not_held.end()) continue;
    EXPECT_TRUE(std::isfinite(ratio)) << name;
    EXPECT_NEAR(ratio, 1.0, 0.3) << name << ": SD over " << kSeeds << " seeds " << sd
                                 << ", mean reported u " << u;
  }
  std::cout << table;
}

}  // namespace
}  // namespace impactdic
