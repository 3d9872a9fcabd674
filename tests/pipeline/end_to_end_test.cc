// End to end: `impactdic synth` renders a small impact scene with known truth, `impactdic run`
// processes it, and the results are compared with the truth (tolerances stated at each check); the
// same for the committed sample (sample_frames/, what the quick start's first command runs) and its
// committed truth, and the sample's summary.json against a committed reference ("behaviour
// unchanged").
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "../cli/cli_runner.h"
#include "../core/test_paths.h"
#include "../io/test_dir.h"
#include "../render/test_util.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/results_layout.h"
#include "impactdic/io/yaml.h"
#include "impactdic/render/animation.h"
#include "impactdic/synth/impact_scene.h"
#include "impactdic/synth/speckle.h"
#include "small_scene_spec.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

// What the tests compare: the generated scene above, or the committed sample (the scene the
// quick start's first command runs; its truth is committed with it).
enum class Source { kGenerated, kCommittedSample };

struct Prepared {
  std::unique_ptr<TestDir> dir;  // Holds the outputs (and the generated scene).
  std::string truth;             // truth.h5 of the scene.
  std::string run_output;        // What `impactdic run` printed.
  bool ok = false;
  std::string Out(const std::string& name) const { return dir->File("out/" + name); }
};

// Renders (for kGenerated) and runs each scene once per process; every test of it reads the
// results.
const Prepared& Prepare(Source source) {
  static std::map<Source, Prepared> cache;
  if (auto it = cache.find(source); it != cache.end()) return it->second;
  Prepared p;
  const bool generated = source == Source::kGenerated;
  p.dir = std::make_unique<TestDir>(generated ? "EndToEnd" : "EndToEndSample");
  std::string scene;
  if (generated) {
    const std::string spec = p.dir->Write("spec.yaml", kSmallSceneSpec);
    const CliResult synth = RunCli("synth " + spec + " -o " + p.dir->File("scene"));
    p.run_output = synth.output;
    scene = p.dir->File("scene/scene.yaml");
    p.truth = p.dir->File("scene/truth.h5");
    if (synth.exit_code != 0) return cache.emplace(source, std::move(p)).first->second;
  } else {
    scene = std::string(impactdic::SourceDir()) + "/sample_frames/scene.yaml";
    p.truth = std::string(impactdic::SourceDir()) + "/sample_frames/truth.h5";
  }
  const CliResult run = RunCli("run " + scene + " -o " + p.dir->File("out"));
  p.run_output += run.output;
  p.ok = run.exit_code == 0;
  return cache.emplace(source, std::move(p)).first->second;
}

class EndToEnd : public ::testing::TestWithParam<Source> {
 protected:
  void SetUp() override {
    p_ = &Prepare(GetParam());
    ASSERT_TRUE(p_->ok) << p_->run_output;
  }
  const Prepared* p_ = nullptr;
};

std::string SourceName(const ::testing::TestParamInfo<Source>& param) {
  return param.param == Source::kGenerated ? "GeneratedScene" : "CommittedSample";
}

INSTANTIATE_TEST_SUITE_P(Scenes, EndToEnd,
                         ::testing::Values(Source::kGenerated, Source::kCommittedSample),
                         SourceName);

// The correlated displacement against the synth field itself (ImpactScene::SoilFieldPx, the
// model truth.h5 samples) averaged over each subset's square: what an affine subset measures where
// the field curves within it. Points the pounder covers (truth.h5 /soil/occluded) are left out.
// RMS error at most 0.05 px on the generated scene (its halo is 1.5 D wide: measured 0.009 px);
// 0.2 px on the committed sample, whose punched cone has a 40 mm halo (soil.decay_length_mm,
// docs/synth.md "The soil field") that takes up the crater's 57 mm (76 px) between the core and
// the still soil: at the end the field departs from a plane by up to u'' (s/2)^2 / 2 = 3.8 px
// at a 25 px subset's edge (u'' = 2 W / L^2), which an affine subset cannot follow. Measured
// 0.149 px RMS over every subset and frame (0.056 px with a 60 mm halo; 1.97 px with 20 mm, where
// subsets lose the speckle).
TEST_P(EndToEnd, SoilDisplacementMatchesTruth) {
  H5Reader results(p_->Out("results.h5"));
  H5Reader truth(p_->truth);
  Dims rd;
  const auto x = results.ReadDouble("/dic/x_px");
  const auto y = results.ReadDouble("/dic/y_px");
  const auto u = results.ReadDouble("/dic/u_px", &rd);
  const auto v = results.ReadDouble("/dic/v_px");
  const auto frame_index = results.ReadDouble("/time/frame_index");
  const auto gx = truth.ReadDouble("/soil/grid_x_px");
  const auto gy = truth.ReadDouble("/soil/grid_y_px");
  const auto t_frames = truth.ReadDouble("/frames/time_s");
  const auto occluded = truth.ReadDouble("/soil/occluded");
  const std::size_t F = rd[0], N = rd[1], T = gx.size();
  const fs::path scene_folder = fs::path(p_->truth).parent_path();
  const ImpactScene scene(LoadImpactSceneSpec((scene_folder / "spec.yaml").string()));
  const double half = 0.5 * (scene.spec().subset_size - 1);
  // The mean of the field over a subset: 7 x 7 points spread evenly over its square.
  const auto subset_mean = [&](const DisplacementField& field, double cx, double cy) {
    cv::Vec2d sum(0, 0);
    for (int a = 0; a < 7; ++a)
      for (int b = 0; b < 7; ++b)
        sum += field.u(cx + half * (a / 3.0 - 1), cy + half * (b / 3.0 - 1));
    return sum / 49.0;
  };
  std::vector<DisplacementField> fields;
  for (std::size_t f = 0; f < F; ++f)
    fields.push_back(scene.SoilFieldPx(t_frames[static_cast<std::size_t>(frame_index[f])]));
  double sum_sq = 0;
  std::size_t count = 0, matched = 0;
  for (std::size_t i = 0; i < N; ++i) {
    // The same subset in the truth grid (same ROI and step: positions agree to rounding).
    std::size_t j = T;
    for (std::size_t k = 0; k < T; ++k)
      if (std::abs(gx[k] - x[i]) < 0.5 && std::abs(gy[k] - y[i]) < 0.5) j = k;
    if (j == T) continue;
    ++matched;
    const cv::Vec2d at_ref = subset_mean(fields[0], x[i], y[i]);
    for (std::size_t f = 1; f < F; ++f) {
      const std::size_t tf = static_cast<std::size_t>(frame_index[f]);
      if (!std::isfinite(u[f * N + i]) || occluded[tf * T + j] != 0) continue;
      const cv::Vec2d d = subset_mean(fields[f], x[i], y[i]) - at_ref;
      const double du = u[f * N + i] - d[0], dv = v[f * N + i] - d[1];
      sum_sq += du * du + dv * dv;
      ++count;
    }
  }
  ASSERT_GT(matched, N * 9 / 10) << "the correlated grid does not match the truth grid";
  ASSERT_GT(count, (F - 1) * N * 8 / 10);
  // RMS of the displacement error vector (as in the dic tests; per component it is 1/sqrt(2) of
  // this).
  const double rms = std::sqrt(sum_sq / count);
  std::printf("soil displacement: RMS error %.4f px over %zu valid samples of %zu subsets\n", rms,
              count, matched);
  const double tolerance = GetParam() == Source::kCommittedSample ? 0.2 : 0.05;
  EXPECT_LE(rms, tolerance) << "displacement RMS error [px] over " << count << " samples";
}

TEST_P(EndToEnd, MomentumAddedMassAndCraterDepthMatchTruth) {
  H5Reader results(p_->Out("results.h5"));
  H5Reader truth(p_->truth);
  const double t_e = truth.ReadDouble("/momentum/t_e_s")[0];
  const double m_add_max = truth.ReadDouble("/momentum/m_add_max_kg")[0];
  const double conservation = truth.ReadDouble("/momentum/conservation_error")[0];
  const double crater = truth.ReadDouble("/pounder/crater_depth_m")[0];
  // Granular momentum over the peak stage, at the analysed frames: within 5 % of its value at
  // the end of the peak stage (where it is largest; early on it is near zero, so a relative
  // error per frame would be meaningless).
  const auto t_frames = truth.ReadDouble("/frames/time_s");
  const auto p_truth = truth.ReadDouble("/momentum/p_gran_Ns");
  const auto frame_index = results.ReadDouble("/time/frame_index");
  const auto p_gran = results.ReadDouble("/momentum/p_gran");
  ASSERT_EQ(p_gran.size(), frame_index.size());
  double p_te = 0;
  for (std::size_t k = 0; k < t_frames.size(); ++k)
    if (t_frames[k] <= t_e) p_te = p_truth[k];
  ASSERT_GT(p_te, 0);
  int compared = 0;
  for (std::size_t f = 0; f < frame_index.size(); ++f) {
    const auto k = static_cast<std::size_t>(frame_index[f]);
    if (t_frames[k] < 0 || t_frames[k] > t_e || !std::isfinite(p_gran[f])) continue;
    EXPECT_NEAR(p_gran[f], p_truth[k], 0.05 * p_te) << "frame " << k << " t = " << t_frames[k];
    ++compared;
  }
  EXPECT_GE(compared, 3);
  EXPECT_NEAR(results.ReadNumberAttribute("/summary", "momentum_conservation_error"), conservation,
              0.02);
  EXPECT_NEAR(results.ReadNumberAttribute("/summary", "added_mass_max_kg"), m_add_max,
              0.05 * m_add_max);
  EXPECT_NEAR(results.ReadNumberAttribute("/summary", "crater_depth_measured_m"), crater,
              0.01 * crater);
  // The one DIC layout (io/results_layout.h), as `impactdic correlate` writes it: versioned, the
  // status codes under one name, /dic/frame the index in the input sequence (= /time/frame_index).
  EXPECT_EQ(results.ReadNumberAttribute("/dic", "layout_version"), 2);
  EXPECT_NE(results.ReadStringAttribute("/dic/status", "codes").find("0=converged"),
            std::string::npos);
  EXPECT_FALSE(results.HasAttribute("/dic/status", "status_names"));
  const std::vector<std::int32_t> dic_frame = results.ReadInt("/dic/frame");
  ASSERT_EQ(dic_frame.size(), frame_index.size());
  for (std::size_t f = 0; f < dic_frame.size(); ++f)
    EXPECT_EQ(dic_frame[f], static_cast<std::int32_t>(frame_index[f]));
}

TEST_P(EndToEnd, FiguresAndAnimationAreComplete) {
  H5Reader results(p_->Out("results.h5"));
  const std::size_t analysed = results.ReadDouble("/time/frame_index").size();
  std::string video = p_->Out("velocity.mp4");
  if (!fs::exists(video)) video = p_->Out("velocity.avi");
  ASSERT_TRUE(fs::exists(video)) << p_->run_output;
  EXPECT_EQ(CountVideoFrames(video), analysed);
  for (const char* name :
       {"momentum.png", "deceleration.png", "added_mass.png", "velocity_field_te.png"}) {
    const cv::Mat png = cv::imread(p_->Out(name), cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(png.empty()) << name << " is not a readable PNG";
    EXPECT_GE(png.cols, 640) << name;
    EXPECT_GE(png.rows, 400) << name;
  }
  EXPECT_TRUE(fs::exists(p_->Out("summary.json")));
  EXPECT_TRUE(fs::exists(p_->Out("summary.csv")));
  // The strain maps and animation: the committed sample asks for the strain
  // (strain.enabled), the generated scene does not, and gets neither them nor /strain.
  const bool strain = GetParam() == Source::kCommittedSample;
  EXPECT_EQ(results.Exists(results_layout::kStrainGroup), strain);
  EXPECT_EQ(fs::exists(p_->Out("strain.csv")), strain);
  for (const char* name : {results_layout::kStrainTePng, results_layout::kStrainEndPng}) {
    EXPECT_EQ(fs::exists(p_->Out(name)), strain) << name;
    if (!strain) continue;
    const cv::Mat png = cv::imread(p_->Out(name), cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(png.empty()) << name << " is not a readable PNG";
    EXPECT_GE(png.cols, 640) << name;
  }
  std::string strain_video = p_->Out(results_layout::kStrainAnimationName);
  if (!fs::exists(strain_video)) strain_video = p_->Out(results_layout::kStrainAnimationAviName);
  EXPECT_EQ(fs::exists(strain_video), strain);
  if (strain) {
    EXPECT_EQ(CountVideoFrames(strain_video), analysed);
    EXPECT_EQ(results.ReadStringAttribute(results_layout::kStrainGroup,
                                          results_layout::kStrainGradientAttr),
              "warp");
  }
  // Nothing temporary is left behind.
  for (const auto& entry : fs::directory_iterator(p_->dir->File("out")))
    EXPECT_EQ(entry.path().filename().string().find(".tmp-"), std::string::npos) << entry.path();
}

// "Behaviour unchanged": the committed sample's summary.json equals a committed
// reference (tests/pipeline/data/sample_summary_reference.json, `impactdic -q run
// sample_frames/scene.yaml` on main before the architecture redesign; changes listed in
// docs/development.md, "Behaviour preserved"). summary.json holds nothing that varies from run
// to run (no path, version, time or rate: the correlation's wall-time rate is in timing.json).
// Same keys at every level, same strings, nulls and booleans; numbers equal to a relative 1e-6, not
// exactly. Measured on the sample: Eigen's LLT (which replaced a hand-written SPD inversion) moved
// three figures at ~1e-14; the ASan preset (-O1) differs from the release build (-O3) by up to
// 4.5e-8 (momentum_conservation_error, a small difference of two momenta; t_end_peak_s 6.9e-9,
// added_mass_max_kg 3.2e-9: floating-point differences of ~1e-15 change where an iteration stops
// and are amplified), the figures from the sensor and the model not at all. Small changes of
// behaviour move figures by 1e-5 or more (measured: dic.convergence_px 0.001 -> 0.002 moves five
// figures by 1e-5 to 5e-5, sensor.cutoff_hz 1500 -> 1499 eight, up to 1.2e-4).
constexpr double kRelativeTolerance = 1e-6;
// The `uncertainty` object (docs/analysis.md) to a relative 1e-3: its u are standard deviations of
// 200 Monte Carlo draws driven by the subsets' sigma, a residual-based estimate that the ASan
// preset (-O1) moves by 1.0e-4 against the release build (measured: uncertainty.inputs.
// dic_sigma_median_mm; the u by up to 8e-6). A change of the method or its inputs moves the u by
// percents (the draws' own sampling error is 1 / sqrt(2 x 200) = 5 %).
constexpr double kUncertaintyTolerance = 1e-3;
// The DIC half of the reflection check (`wave.channels.*.reflection_dic`, docs/wave.md) to a
// relative 1e-4: its threshold is 3 standard deviations of the near-surface velocity in the few
// frames before the impact, where the soil is still and the subsets' displacements are noise of
// ~0.01 px whose last IC-GN step the ASan preset (-O1) moves (measured: threshold_mm_s 6.73420459
// against 6.73422336 in the release build, 2.8e-6).
constexpr double kReflectionDicTolerance = 1e-4;

// The relative tolerance of the figure at `path` (above).
double ToleranceFor(const std::string& path) {
  if (path.rfind("uncertainty.", 0) == 0) return kUncertaintyTolerance;
  if (path.find(".reflection_dic.") != std::string::npos) return kReflectionDicTolerance;
  return kRelativeTolerance;
}

// JSON read as YAML (JSON is YAML's flow style) by the project's one YAML loader. A plain
// (unquoted) scalar that reads as a number is a number; a quoted one (tag "!") is a string.
bool AsNumber(const YAML::Node& node, double* value) {
  return node.IsScalar() && node.Tag() != "!" && YAML::convert<double>::decode(node, *value);
}

// The differences between `run` and `reference` (empty: equal), each naming the key path.
void CompareJson(const YAML::Node& run, const YAML::Node& reference, const std::string& path,
                 std::vector<std::string>* differences) {
  const std::string at = path.empty() ? "(top)" : path;
  if (run.Type() != reference.Type()) {
    differences->push_back(at + ": a " + DescribeYaml(run) + " where the reference has " +
                           DescribeYaml(reference));
    return;
  }
  if (reference.IsMap()) {
    for (const auto& entry : reference) {
      const std::string key = entry.first.as<std::string>();
      const std::string sub = path.empty() ? key : path + "." + key;
      if (!run[key]) {
        differences->push_back(sub + ": missing");
      } else {
        CompareJson(run[key], entry.second, sub, differences);
      }
    }
    for (const auto& entry : run)
      if (!reference[entry.first.as<std::string>()])
        differences->push_back((path.empty() ? "" : path + ".") + entry.first.as<std::string>() +
                               ": not in the reference");
  } else if (reference.IsSequence()) {
    if (run.size() != reference.size()) {
      differences->push_back(at + ": " + std::to_string(run.size()) + " entries, the reference " +
                             std::to_string(reference.size()));
      return;
    }
    for (std::size_t i = 0; i < reference.size(); ++i)
      CompareJson(run[i], reference[i], path + "[" + std::to_string(i) + "]", differences);
  } else if (reference.IsScalar()) {
    double a = 0, b = 0;
    if (AsNumber(run, &a) && AsNumber(reference, &b)) {
      const double tolerance = ToleranceFor(path);
      if (!(std::abs(a - b) <= tolerance * std::max(std::abs(a), std::abs(b))))
        differences->push_back(at + ": " + run.Scalar() + ", the reference " + reference.Scalar());
    } else if (run.Scalar() != reference.Scalar() || run.Tag() != reference.Tag()) {
      differences->push_back(at + ": '" + run.Scalar() + "', the reference '" + reference.Scalar() +
                             "'");
    }
  }
}

std::vector<std::string> JsonDifferences(const YAML::Node& run, const YAML::Node& reference) {
  std::vector<std::string> differences;
  CompareJson(run, reference, "", &differences);
  return differences;
}

std::string Lines(const std::vector<std::string>& lines) {
  std::string text;
  for (const std::string& line : lines) text += "  " + line + "\n";
  return text;
}

// The committed sample shows the paper's wave physics (docs/wave.md, "The sample"): a cone of soil
// punched under the pounder, not the whole bed, and a compression wave that the base sensors and
// the DIC front both time. Against the sample's truth (truth.h5 /base_sensors): each base
// sensor's wave speed within 5 % and its stress ratio within 10 % (the bounds), the DIC
// front's speed within 5 % of the field's wave speed; neither half of the reflection check finds
// a local maximum (the synth wave is not reflected); the space-time figure shows the front
// running down (its pixels, as tests/render/wave_figures_test.cc reads them); at t_e the soil
// at the bottom of the field moves at under a tenth of the core's speed.
TEST(EndToEndSample, ShowsTheConeAndTheWave) {
  const Prepared& p = Prepare(Source::kCommittedSample);
  ASSERT_TRUE(p.ok) << p.run_output;
  H5Reader results(p.Out("results.h5"));
  H5Reader truth(p.truth);
  const double c = truth.ReadNumberAttribute("/base_sensors", "wave_speed_m_s");
  const std::vector<double> speed = results.ReadDouble("/wave/speed_peak_m_s");
  const std::vector<double> ratio = results.ReadDouble("/wave/stress_ratio");
  const std::vector<double> true_ratio = truth.ReadDouble("/base_sensors/stress_ratio");
  ASSERT_EQ(speed.size(), 2u);
  ASSERT_EQ(true_ratio.size(), 2u);
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_NEAR(speed[k], c, 0.05 * c) << "base channel " << k;
    EXPECT_NEAR(ratio[k], true_ratio[k], 0.10 * true_ratio[k]) << "base channel " << k;
  }
  const double front = results.ReadDouble("/wave/front/speed_m_s")[0];
  EXPECT_NEAR(front, c, 0.05 * c);
  // The synth wave has no reflection: neither half of the check finds one, and both are checked.
  for (const char* path : {"/wave/reflection_local_maximum", "/wave/reflection_dic_local_maximum"})
    for (double v : results.ReadDouble(path)) EXPECT_EQ(v, 0) << path;

  // Below the cone (the deeper half of the rows the colour reaches), where the front, not the
  // pounder's push, sets the arrival.
  int rows = 0;
  const double rank =
      test::FrontRankCorrelation(p.Out(results_layout::kWaveSpaceTimePng), &rows, 0.5);
  std::printf("space-time figure: rank correlation %.3f over the deeper %d rows\n", rank, rows);
  EXPECT_GT(rank, 0.8) << rows << " rows with a red pixel";
  EXPECT_GT(rows, 50);

  // The velocity at the analysed frame nearest t_e: the core (the centre line's top subsets) and
  // the deepest row of the field.
  const std::vector<double> t_ms = results.ReadDouble("/time/t_ms");
  const double t_e_ms = 1e3 * results.ReadNumberAttribute("/summary", "t_end_peak_s");
  std::size_t f = 0;
  for (std::size_t k = 0; k < t_ms.size(); ++k)
    if (std::abs(t_ms[k] - t_e_ms) < std::abs(t_ms[f] - t_e_ms)) f = k;
  const std::vector<double> x = results.ReadDouble("/kinematics/x_mm");
  const std::vector<double> y = results.ReadDouble("/kinematics/y_mm");
  const std::vector<double> vy = results.ReadDouble("/kinematics/vy_mm_s");
  const std::size_t n = x.size();
  const double y_bottom = *std::max_element(y.begin(), y.end());
  double core = 0, bottom = 0;
  for (std::size_t s = 0; s < n; ++s) {
    const double v = vy[f * n + s];
    if (!std::isfinite(v)) continue;
    core = std::max(core, v);
    if (y[s] > y_bottom - 1) bottom = std::max(bottom, std::abs(v));
  }
  EXPECT_GT(core, 2000);  // mm/s: the pounder's ~3 m/s near t_e.
  EXPECT_LT(bottom, 0.1 * core) << "the whole bed moves: " << bottom << " of " << core << " mm/s";
}

TEST(EndToEndSample, SummaryEqualsTheCommittedReference) {
  const Prepared& p = Prepare(Source::kCommittedSample);  // The run of the EndToEnd tests.
  ASSERT_TRUE(p.ok) << p.run_output;
  const YAML::Node run = LoadYamlFile(p.Out("summary.json"), "summary.json");
  const YAML::Node reference = LoadYamlFile(
      std::string(impactdic::SourceDir()) + "/tests/pipeline/data/sample_summary_reference.json",
      "the reference summary");
  ASSERT_TRUE(reference.IsMap());
  ASSERT_GE(reference.size(), 20u);
  const std::vector<std::string> differences = JsonDifferences(run, reference);
  EXPECT_TRUE(differences.empty()) << "summary.json differs from the reference:\n"
                                   << Lines(differences);

  // The comparison ignores a figure within the tolerance, and catches one off by 10x the
  // tolerance, a key missing or added, a list changed.
  YAML::Node moved = YAML::Clone(reference);
  const double m_add = reference["added_mass_max_kg"].as<double>();
  moved["added_mass_max_kg"] = m_add * (1 + 0.1 * kRelativeTolerance);
  EXPECT_TRUE(JsonDifferences(run, moved).empty()) << Lines(JsonDifferences(run, moved));
  moved["added_mass_max_kg"] = m_add * (1 + 10 * kRelativeTolerance);
  const std::vector<std::string> one = JsonDifferences(run, moved);
  ASSERT_EQ(one.size(), 1u) << Lines(one);
  EXPECT_EQ(one[0].rfind("added_mass_max_kg: ", 0), 0u) << one[0];
  YAML::Node fewer = YAML::Clone(reference);
  fewer.remove("t_end_model_s");
  fewer["warnings"].push_back("a warning");
  EXPECT_EQ(JsonDifferences(run, fewer).size(), 2u) << Lines(JsonDifferences(run, fewer));
}

}  // namespace
}  // namespace impactdic
