// The strain validation against the synthetic truth (docs/validation_strain.md, "Strain"):
// `impactdic synth validation/strain/synth_spec.yaml` (the analytic soil field, its Jacobian in
// truth.h5), `impactdic run`, and the strain module on the run's displacements against the truth,
// under bounds measured with this scene (docs/validation_strain.md gives the figures and the
// commands). The scene's shear is large enough that a flipped gradient sign or a Green-Lagrange
// strain without its H^T H term misses the bounds by far: the test checks that too.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "../cli/cli_runner.h"
#include "../core/test_paths.h"
#include "../io/test_dir.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/strain/strain.h"
#include "strain_compare.h"

namespace impactdic {
namespace {

using strain_validation::ErrorStats;
using strain_validation::Minus;
using strain_validation::Named;
using strain_validation::NamedFields;
using strain_validation::RunDic;
using strain_validation::StrainTruth;

constexpr double kFps = 1600;  // the tiny preset

// Synthesises the validation scene into dir/scene and runs it (no figures, no animation);
// returns the results.h5 path.
std::string SynthAndRun(const TestDir& dir) {
  const std::string spec =
      std::string(impactdic::SourceDir()) + "/validation/strain/synth_spec.yaml";
  const std::string scene = dir.File("scene");
  const CliResult synth = RunCli("-q synth '" + spec + "' --no-calibrate -o '" + scene + "'");
  EXPECT_EQ(synth.exit_code, 0) << synth.output;
  std::ifstream in(scene + "/scene.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::string yaml = text.str();
  for (const std::string key : {"figures", "animation"}) {
    const std::string on = key + ": true";
    const auto at = yaml.find(on);
    if (at != std::string::npos) yaml.replace(at, on.size(), key + ": false");
  }
  // The pipeline's strain stage too: /strain in results.h5 (fit, window 3).
  yaml += "strain:\n  enabled: true\n  gradient: fit\n  window: 3\n";
  std::ofstream(scene + "/scene.yaml") << yaml;
  const CliResult run = RunCli("-q run '" + scene + "/scene.yaml' -o '" + dir.File("run") + "'");
  EXPECT_EQ(run.exit_code, 0) << run.output;
  return dir.File("run") + "/results.h5";
}

void Print(const char* what, const ErrorStats& e) {
  std::printf("  %-28s RMS %.2e  max %.2e  (%zu samples)\n", what, e.rms, e.max, e.samples);
}

// The bounds of one gradient source: RMS error of the gradient's components (the largest), eps_v,
// gamma_max, the Green-Lagrange components (the largest) and the quadratic term H^T H / 2.
struct Bounds {
  double gradient, eps_v, gamma_max, green_lagrange, quadratic;
};

struct Measured {
  double gradient = 0, eps_v = 0, gamma_max = 0, green_lagrange = 0, quadratic = 0;
  double gradient_flipped = 0, green_lagrange_linear = 0, quadratic_truth = 0;
};

// The errors of the strain `tool` against `ref` (Named fields), printed under `label`.
Measured Measure(const StrainTruth& truth, const NamedFields& tool, const NamedFields& ref,
                 const std::string& label) {
  Measured m;
  std::printf("%s\n", label.c_str());
  for (const char* name : {"dudx", "dudy", "dvdx", "dvdy"}) {
    const ErrorStats e = truth.Compare(tool.at(name), ref.at(name));
    Print(name, e);
    m.gradient = std::max(m.gradient, e.rms);
    std::vector<double> flipped = tool.at(name);
    for (double& x : flipped) x = -x;
    m.gradient_flipped = std::max(m.gradient_flipped, truth.Compare(flipped, ref.at(name)).rms);
  }
  const ErrorStats ev = truth.Compare(tool.at("eps_v"), ref.at("eps_v"));
  const ErrorStats gm = truth.Compare(tool.at("gamma_max"), ref.at("gamma_max"));
  Print("eps_v", ev);
  Print("gamma_max", gm);
  m.eps_v = ev.rms, m.gamma_max = gm.rms;
  for (const char* c : {"xx", "yy", "xy"}) {
    const std::string gl = std::string("green_lagrange_") + c, small = std::string("e") + c;
    const ErrorStats e = truth.Compare(tool.at(gl), ref.at(gl));
    Print(gl.c_str(), e);
    m.green_lagrange = std::max(m.green_lagrange, e.rms);
    // Without the H^T H term the Green-Lagrange strain would be the small strain.
    m.green_lagrange_linear =
        std::max(m.green_lagrange_linear, truth.Compare(tool.at(small), ref.at(gl)).rms);
    const std::vector<double> q_ref = Minus(ref.at(gl), ref.at(small));
    m.quadratic =
        std::max(m.quadratic, truth.Compare(Minus(tool.at(gl), tool.at(small)), q_ref).rms);
    m.quadratic_truth = std::max(m.quadratic_truth,
                                 truth.Compare(std::vector<double>(q_ref.size(), 0.0), q_ref).rms);
  }
  std::printf(
      "  quadratic term H^T H / 2: error RMS %.2e, its own RMS %.2e; with the gradient "
      "flipped the gradient error would be %.2e, without H^T H the GL error %.2e\n",
      m.quadratic, m.quadratic_truth, m.gradient_flipped, m.green_lagrange_linear);
  return m;
}

void ExpectWithin(const Measured& m, const Bounds& b, bool sensitive) {
  EXPECT_LE(m.gradient, b.gradient);
  EXPECT_LE(m.eps_v, b.eps_v);
  EXPECT_LE(m.gamma_max, b.gamma_max);
  EXPECT_LE(m.green_lagrange, b.green_lagrange);
  EXPECT_LE(m.quadratic, b.quadratic);
  // The test catches a flipped gradient and a missing H^T H term: each would miss its bound
  // twice over (the quadratic term's own RMS is its error without it).
  EXPECT_GT(m.gradient_flipped, 2 * b.gradient);
  if (sensitive) {
    EXPECT_GT(m.quadratic_truth, 2 * b.quadratic);
  }
}

// The truth itself, independently of the code that wrote it: its gradient matches central
// differences of its displacements along the grid rows (the sign and the pixel scale, to the
// differences' truncation), and its strains follow strain/strain.h's formulas.
void ExpectTruthConsistent(const StrainTruth& truth, const RunDic& run) {
  const NamedFields t = Named(truth);
  const std::vector<double> u = truth.Field("u_px"), v = truth.Field("v_px");
  const CorrelationSeries& s = run.series;
  const double step = s.x_px[1] - s.x_px[0];
  double worst = 0;
  for (std::size_t f = 1; f < s.frames; ++f)
    for (std::size_t i = 1; i + 1 < s.subsets; ++i) {
      const std::size_t j = f * s.subsets + i;
      if (s.y_px[i - 1] != s.y_px[i] || s.y_px[i + 1] != s.y_px[i]) continue;  // a row's ends
      worst = std::max(worst, std::abs((v[j + 1] - v[j - 1]) / (2 * step) - t.at("dvdx")[j]));
      worst = std::max(worst, std::abs((u[j + 1] - u[j - 1]) / (2 * step) - t.at("dudx")[j]));
    }
  std::printf("truth gradient against central differences of the truth u, v: max %.2e\n", worst);
  EXPECT_LT(worst, 0.05);  // |dv/dX| reaches 0.23 here: a flipped sign errs by 0.46
  for (std::size_t j = 0; j < u.size(); ++j) {
    const double a = t.at("dudx")[j], b = t.at("dudy")[j], c = t.at("dvdx")[j], d = t.at("dvdy")[j];
    ASSERT_NEAR(t.at("exx")[j], a, 1e-9);
    ASSERT_NEAR(t.at("exy")[j], (b + c) / 2, 1e-9);
    ASSERT_NEAR(t.at("green_lagrange_xx")[j], a + (a * a + c * c) / 2, 1e-9);
    ASSERT_NEAR(t.at("green_lagrange_yy")[j], d + (b * b + d * d) / 2, 1e-9);
    ASSERT_NEAR(t.at("green_lagrange_xy")[j], (b + c + a * b + c * d) / 2, 1e-9);
    ASSERT_NEAR(t.at("eps_v")[j], -(a + d), 1e-9);  // compression positive
  }
}

TEST(StrainSynthTruth, FitGradientMatchesTheAnalyticStrain) {
  TestDir dir;
  const std::string results = SynthAndRun(dir);
  const RunDic run = strain_validation::ReadRunDic(results);
  const StrainTruth truth(dir.File("scene") + "/truth.h5", run);
  ExpectTruthConsistent(truth, run);
  const NamedFields analytic = Named(truth);
  // RMS bounds (gradient, eps_v, gamma_max, Green-Lagrange, H^T H / 2): 1.5 x what this scene
  // gives (docs/validation_strain.md, "Strain"). Against the analytic strain the window's smoothing
  // of the steep shear beside the pounder dominates; against the same fit of the truth
  // displacements (a perfect correlation) what is left is the correlation's own error.
  const Bounds analytic_bounds[] = {{1.05e-2, 9.5e-3, 1.3e-2, 8.7e-3, 1.2e-3},
                                    {1.8e-2, 1.5e-2, 2.2e-2, 1.4e-2, 2.0e-3},
                                    {2.5e-2, 2.1e-2, 3.1e-2, 1.9e-2, 2.7e-3}};
  const Bounds perfect_bounds[] = {{4.8e-3, 4.0e-3, 5.7e-3, 3.5e-3, 5.3e-4},
                                   {2.8e-3, 2.1e-3, 3.4e-3, 2.0e-3, 2.8e-4},
                                   {1.7e-3, 1.3e-3, 2.1e-3, 1.2e-3, 1.4e-4}};
  // The run's /strain (the pipeline's stage, fit, window 3) within the window-3 bounds.
  const Measured stage = Measure(truth, strain_validation::ReadStrainGroup(results), analytic,
                                 "the run's /strain (fit, window 3), against the analytic strain");
  ExpectWithin(stage, analytic_bounds[0], /*sensitive=*/true);
  for (int k = 0; k < 3; ++k) {
    const int window = 3 + 2 * k;
    const DisplacementGradient g = FitDisplacementGradient(run.series, window);
    const std::string w = std::to_string(window);
    const NamedFields tool = Named(g, ComputeStrain(g, kFps));
    const Measured a =
        Measure(truth, tool, analytic, "fit, window " + w + ", against the analytic strain");
    ExpectWithin(a, analytic_bounds[k], /*sensitive=*/window == 3);
    const DisplacementGradient perfect = FitDisplacementGradient(truth.PerfectSeries(), window);
    const Measured p = Measure(truth, tool, Named(perfect, ComputeStrain(perfect, kFps)),
                               "fit, window " + w + ", against the same fit of the truth");
    ExpectWithin(p, perfect_bounds[k], /*sensitive=*/true);
  }
}

// The subset warp's gradient (`correlate --warp-gradient` on the same frames and grid, /dic/*_warp)
// against the analytic strain. Its bounds are 1.5 x what this scene gives.
TEST(StrainSynthTruth, WarpGradientMatchesTheAnalyticStrain) {
  TestDir dir;
  SynthAndRun(dir);
  const std::string scene = dir.File("scene");
  const H5Reader attrs(scene + "/truth.h5");
  std::ostringstream roi;
  for (const char* key : {"roi_x0_px", "roi_y0_px", "roi_x1_px", "roi_y1_px"})
    roi << (roi.tellp() > 0 ? "," : "") << std::lround(attrs.ReadNumberAttribute("soil", key));
  const std::string out = dir.File("warp.h5");
  const CliResult r = RunCli(
      "-q correlate --frames '" + scene + "/frames/frame_*.png' --subset " +
      std::to_string(std::lround(attrs.ReadNumberAttribute("soil", "subset_size_px"))) +
      " --step " + std::to_string(std::lround(attrs.ReadNumberAttribute("soil", "step_px"))) +
      " --roi " + roi.str() + " --warp-gradient -o '" + out + "'");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const RunDic run = strain_validation::ReadRunDic(out);
  const StrainTruth truth(scene + "/truth.h5", run);
  const H5Reader in(out);
  DisplacementGradient g;
  g.frames = run.series.frames, g.subsets = run.series.subsets;
  g.dudx = in.ReadDouble("/dic/dudx_warp");
  g.dudy = in.ReadDouble("/dic/dudy_warp");
  g.dvdx = in.ReadDouble("/dic/dvdx_warp");
  g.dvdy = in.ReadDouble("/dic/dvdy_warp");
  const Measured m = Measure(truth, Named(g, ComputeStrain(g, kFps)), Named(truth),
                             "warp, against the analytic strain");
  ExpectWithin(m, Bounds{7.3e-3, 9.2e-3, 9.6e-3, 6.3e-3, 7.0e-4}, /*sensitive=*/true);
}

}  // namespace
}  // namespace impactdic
