// Campaign files (pipeline/campaign.h): the plan they give, and clear errors for bad ones.
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "../cli/cli_runner.h"
#include "../io/test_dir.h"
#include "impactdic/core/error.h"
#include "impactdic/model/impact_model.h"
#include "impactdic/pipeline/campaign.h"
#include "impactdic/synth/impact_scene.h"

namespace impactdic {
namespace {

// The error message of `f()` (FAIL if it does not throw Error).
template <typename F>
std::string ErrorOf(F f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error";
  return "";
}

TEST(CampaignFile, DefaultMatrixIsTable1WithEq4AddedMassInTheGridMass) {
  TestDir dir;
  const CampaignPlan plan =
      LoadCampaignFile(dir.Write("c.yaml", "synthesise:\n  added_mass_noise: 0\n"));
  ASSERT_EQ(plan.tests.size(), 27u);
  std::set<std::string> names;
  for (const CampaignTest& t : plan.tests) {
    names.insert(t.name);
    EXPECT_TRUE(t.synthesise);
    const ImpactSceneSpec& s = t.spec;
    const double eq4 =
        AddedMassMaxEq4(s.pounder_mass_kg, s.ImpactVelocity(), s.width_m * s.depth_m);
    EXPECT_EQ(s.added_mass, SceneAddedMass::kGiven);
    EXPECT_NEAR(s.added_mass_kg, eq4, 1e-12 * eq4) << t.name;
    // The synthetic soil makes the measured m_add,max equal the momentum grid's soil mass
    // (docs/synth.md): the panel scale is chosen so that this mass is M.
    const double cell_m = s.step * s.mm_per_px * 1e-3;
    const double grid_mass =
        s.density_kg_m3 * s.grid_cols * s.grid_rows * cell_m * cell_m * s.depth_m;
    EXPECT_NEAR(grid_mass, s.added_mass_kg, 1e-9 * s.added_mass_kg) << t.name;
  }
  EXPECT_EQ(names.size(), 27u);
  EXPECT_EQ(plan.tests[0].name, "m7_h0.2_D0.1");
  EXPECT_EQ(plan.tests[26].name, "m13_h1.2_D0.2");
  EXPECT_EQ(plan.tests[26].index, 27);
  // Table 1: v0 = sqrt(2 g h).
  EXPECT_NEAR(plan.tests[26].spec.ImpactVelocity(), std::sqrt(2 * 9.81 * 1.2), 1e-12);
}

TEST(CampaignFile, NoiseIsLogNormalSeededAndReproducible) {
  TestDir dir;
  const std::string text = "synthesise:\n  added_mass_noise: 0.05\n  seed: 7\n";
  const CampaignPlan a = LoadCampaignFile(dir.Write("a.yaml", text));
  const CampaignPlan b = LoadCampaignFile(dir.Write("b.yaml", text));
  const CampaignPlan c =
      LoadCampaignFile(dir.Write("c.yaml", "synthesise:\n  added_mass_noise: 0.05\n  seed: 8\n"));
  double sum = 0, sum2 = 0;
  bool differs = false;
  for (std::size_t i = 0; i < a.tests.size(); ++i) {
    const ImpactSceneSpec& s = a.tests[i].spec;
    EXPECT_EQ(s.added_mass_kg, b.tests[i].spec.added_mass_kg);
    EXPECT_EQ(a.tests[i].hash_hex, b.tests[i].hash_hex);
    differs |= s.added_mass_kg != c.tests[i].spec.added_mass_kg;
    const double z =
        std::log(s.added_mass_kg /
                 AddedMassMaxEq4(s.pounder_mass_kg, s.ImpactVelocity(), s.width_m * s.depth_m));
    sum += z;
    sum2 += z * z;
  }
  EXPECT_TRUE(differs);
  // 27 draws of N(0, 0.05^2): mean within 4 standard errors, sd within 50 %.
  const double mean = sum / 27, sd = std::sqrt(sum2 / 27 - mean * mean);
  EXPECT_LT(std::abs(mean), 4 * 0.05 / std::sqrt(27.0));
  EXPECT_GT(sd, 0.025);
  EXPECT_LT(sd, 0.075);
}

TEST(CampaignFile, SpecKeysAndOutputsOverrideTheDefaults) {
  TestDir dir;
  const CampaignPlan plan = LoadCampaignFile(
      dir.Write("c.yaml",
                "synthesise:\n  mass_kg: [10]\n  drop_height_m: [0.7]\n  width_m: [0.15, 0.2]\n"
                "  spec:\n    frames:\n      count: 9\n    momentum:\n      grid_rows: 5\n"
                "outputs:\n  animation: false\n"));
  ASSERT_EQ(plan.tests.size(), 2u);
  for (const CampaignTest& t : plan.tests) {
    EXPECT_EQ(t.spec.frames, 9);
    EXPECT_EQ(t.spec.grid_rows, 5);
    EXPECT_EQ(t.spec.grid_cols, 4);  // The campaign default.
    EXPECT_EQ(t.spec.width, 160);    // tiny
    ASSERT_TRUE(t.animation.has_value());
    EXPECT_FALSE(*t.animation);
    EXPECT_FALSE(t.figures.has_value());
  }
  const std::string m = ErrorOf([&] {
    LoadCampaignFile(dir.Write("u.yaml", "synthesise:\n  spec:\n    frames:\n      cnt: 9\n"));
  });
  EXPECT_NE(m.find("frames.cnt"), std::string::npos) << m;
}

TEST(CampaignFile, BadFilesNameTheKey) {
  TestDir dir;
  std::string m =
      ErrorOf([&] { LoadCampaignFile(dir.Write("u.yaml", "synthesise:\n  mass: [7]\n")); });
  EXPECT_NE(m.find("synthesise.mass"), std::string::npos) << m;
  EXPECT_NE(m.find("mass_kg"), std::string::npos) << m;  // did you mean
  EXPECT_NE(m.find("u.yaml"), std::string::npos) << m;
  m = ErrorOf([&] { LoadCampaignFile(dir.Write("t.yaml", "scene: [a.yaml]\n")); });
  EXPECT_NE(m.find("scene"), std::string::npos) << m;
  EXPECT_NE(m.find("unknown key"), std::string::npos) << m;
  m = ErrorOf([&] { LoadCampaignFile(dir.Write("m.yaml", "scenes: [nothere/scene.yaml]\n")); });
  EXPECT_NE(m.find("scenes[0]"), std::string::npos) << m;
  EXPECT_NE(m.find("nothere/scene.yaml"), std::string::npos) << m;
  m = ErrorOf(
      [&] { LoadCampaignFile(dir.Write("g.yaml", "scene_glob: \"none/*/scene.yaml\"\n")); });
  EXPECT_NE(m.find("matches no file"), std::string::npos) << m;
  m = ErrorOf(
      [&] { LoadCampaignFile(dir.Write("d.yaml", "synthesise:\n  seed: 1\n  seed: 2\n")); });
  EXPECT_NE(m.find("seed"), std::string::npos) << m;
  EXPECT_NE(m.find("line 3"), std::string::npos) << m;
  m = ErrorOf(
      [&] { LoadCampaignFile(dir.Write("h.yaml", "synthesise:\n  drop_height_m: [0.2, -1]\n")); });
  EXPECT_NE(m.find("synthesise.drop_height_m[1]"), std::string::npos) << m;
  m = ErrorOf([&] {
    LoadCampaignFile(dir.Write("s.yaml", "synthesise:\n  spec:\n    frames:\n      bits: 12\n"));
  });
  EXPECT_NE(m.find("synthesise.spec"), std::string::npos) << m;
  EXPECT_NE(m.find("frames.bits"), std::string::npos) << m;
  m = ErrorOf([&] { LoadCampaignFile(dir.Write("e.yaml", "outputs:\n  animation: false\n")); });
  EXPECT_NE(m.find("at least one"), std::string::npos) << m;
  m = ErrorOf(
      [&] { LoadCampaignFile(dir.Write("o.yaml", "synthesise: {}\noutputs:\n  video: 1\n")); });
  EXPECT_NE(m.find("outputs.video"), std::string::npos) << m;
}

TEST(CampaignFile, ShardsAreParsedAndPartitionThePlan) {
  const CampaignShard s = ParseShard("2/3", "--shard");
  EXPECT_EQ(s.index, 2);
  EXPECT_EQ(s.count, 3);
  std::vector<int> chosen;
  for (int k = 1; k <= 7; ++k)
    if (s.Selects(k)) chosen.push_back(k);
  EXPECT_EQ(chosen, (std::vector<int>{2, 5}));
  for (const char* bad : {"4/3", "0/3", "1/0", "3", "1/3x", "a/b", "-1/2"}) {
    const std::string m = ErrorOf([&] { ParseShard(bad, "--shard"); });
    EXPECT_NE(m.find("--shard"), std::string::npos) << bad << ": " << m;
    EXPECT_NE(m.find("1 <= I <= N"), std::string::npos) << bad << ": " << m;
  }
  const CliResult cli = RunCli("campaign x.yaml --shard 4/3");
  EXPECT_EQ(cli.exit_code, 1);
  EXPECT_NE(cli.output.find("--shard"), std::string::npos) << cli.output;
}

TEST(CampaignFile, CliRefusesMixedModes) {
  TestDir dir;
  const std::string file = dir.Write("c.yaml", "synthesise: {}\n");
  CliResult r = RunCli("campaign " + file + " --merge " + dir.File("a"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("one of them"), std::string::npos) << r.output;
  r = RunCli("campaign --merge " + dir.File("a") + " --shard 1/2");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("--shard"), std::string::npos) << r.output;
  r = RunCli("campaign --merge " + dir.File("nothing") + " -o " + dir.File("m"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("nothing"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace impactdic
