// Issue 42 item 4: the momentum figures' reported standard uncertainty (momentum/uncertainty.h)
// against their actual scatter. The small synthesised scene (small_scene_spec.h) is rendered with
// kSeeds noise seeds (the top-level `seed`: image noise and accelerometer noise; the speckle's own
// seed is fixed, so the correlation's bias is the same in every one) and run; the standard
// deviation of each figure over the seeds must match the mean reported u within +-30 %.
// With N seeds the sample SD has a relative standard error of 1 / sqrt(2 (N - 1)): 16 seeds give
// 18 %, so the tolerance holds the ratio to ~1.6 standard errors (measured ratios in
// docs/analysis.md, "Uncertainty of the figures"). Held to it: m_add,max, t_e and p_gran at t_e
// (the Done-when); the others are printed.
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

constexpr int kSeeds = 16;

struct SeedRun {
  MomentumSummary summary;
  std::string problem;  // Empty when the run succeeded.
};

// Renders and runs the small scene with noise seed `seed` in `folder`.
SeedRun RunSeed(const TestDir& dir, int seed) {
  const std::string folder = dir.File(fmt::format("seed{}", seed));
  const std::string spec = dir.Write(fmt::format("spec{}.yaml", seed),
                                     fmt::format("seed: {}\n", seed) + kSmallSceneSpec);
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
  const std::vector<std::string> held = {"t_end_peak_s", "added_mass_max_kg", "p_gran_te_kg_m_s"};
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
    if (std::find(held.begin(), held.end(), name) == held.end()) continue;
    EXPECT_TRUE(std::isfinite(ratio)) << name;
    EXPECT_NEAR(ratio, 1.0, 0.3) << name << ": SD over " << kSeeds << " seeds " << sd
                                 << ", mean reported u " << u;
  }
  std::cout << table;
}

}  // namespace
}  // namespace impactdic
