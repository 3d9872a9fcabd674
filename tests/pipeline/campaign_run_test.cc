// Running campaigns end to end (pipeline/campaign.h): unique folders, failing tests, resuming,
// interruption, shards and their merge. Tests are tiny synthesised scenes (160 x 120 px).
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <signal.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "../cli/cli_runner.h"
#include "../io/test_dir.h"
#include "../reliability/cli_process.h"
#include "impactdic/io/csv.h"
#include "impactdic/pipeline/campaign.h"
#include "impactdic/synth/impact_scene.h"

namespace impactdic {
namespace {
namespace fs = std::filesystem;

// A campaign of tiny synthesised tests (10 frames, no per-test figures or video: quick).
std::string QuickCampaign(const TestDir& dir, const std::string& name, const std::string& widths) {
  return dir.Write(name,
                   "synthesise:\n  mass_kg: [10]\n  drop_height_m: [0.7]\n  width_m: " + widths +
                       "\n  spec:\n    frames:\n      count: 10\n"
                       "outputs:\n  animation: false\n  figures: false\n");
}

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// campaign.csv as rows of cells, without the columns that time the run.
std::vector<std::vector<std::string>> CsvWithoutTimings(const std::string& path) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(ReadText(path));
  std::string line;
  std::vector<std::size_t> drop;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream ls(line);
    std::string cell;
    while (std::getline(ls, cell, ',')) cells.push_back(cell);
    if (rows.empty()) {
      for (std::size_t c = 0; c < cells.size(); ++c)
        if (cells[c] == "wall_time_s" || cells[c] == "dic_subsets_per_s") drop.push_back(c);
      EXPECT_EQ(drop.size(), 2u) << line;
    }
    for (auto it = drop.rbegin(); it != drop.rend(); ++it) cells.erase(cells.begin() + *it);
    rows.push_back(cells);
  }
  return rows;
}

CsvTable ReadCampaignCsv(const std::string& path) {
  CsvReadOptions o;
  o.allow_non_finite = true;
  o.text_columns = {"scene",      "eq4_fit",     "source", "status", "error", "eq4_excluded_reason",
                    "scene_hash", "tool_version"};
  return ReadCsv(path, o);
}

// Writes a tiny synthetic scene (8 frames) into `folder`; returns its scene.yaml.
std::string TinyScene(const std::string& folder, std::uint64_t seed) {
  ImpactSceneSpec spec = ImpactScenePreset("tiny");
  spec.seed = seed;
  return WriteImpactScene(ImpactScene(spec), folder).scene_yaml;
}

TEST(CampaignRun, ScenesOfTheSameNameGetTheirOwnFolders) {
  TestDir dir;
  const std::string a = TinyScene(dir.File("a"), 1), b = TinyScene(dir.File("b"), 2);
  const CliResult r = RunCli("-q campaign " + a + " " + b + " -o " + dir.File("out"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const CsvTable t = ReadCampaignCsv(dir.File("out/campaign.csv"));
  ASSERT_EQ(t.rows(), 2u);
  const auto& names = t.TextColumn("scene");
  EXPECT_NE(names[0], names[1]);
  for (const auto& n : names) {
    EXPECT_EQ(n.rfind("synthetic_impact-", 0), 0u) << n;
    EXPECT_TRUE(fs::exists(dir.File("out/" + n + "/results/results.h5"))) << n;
  }
  // Each folder holds the results of its own scene file.
  const auto& sources = t.TextColumn("source");
  EXPECT_EQ(sources[0], a);
  EXPECT_EQ(sources[1], b);
  for (std::size_t i = 0; i < 2; ++i) {
    const std::string row = ReadText(dir.File("out/" + names[i] + "/campaign_row.csv"));
    EXPECT_NE(row.find(sources[i]), std::string::npos) << row;
  }
}

TEST(CampaignRun, AFailingTestIsReportedAndTheOthersFinish) {
  TestDir dir;
  const std::string a = TinyScene(dir.File("a"), 1), b = TinyScene(dir.File("b"), 2),
                    c = TinyScene(dir.File("c"), 3);
  // c's accelerometer record is empty: its pipeline fails (after the scene file loaded).
  dir.Write("c/sensor.csv", "time_s,accel_g,exposure\n");
  const CliResult r = RunCli("-q campaign " + a + " " + b + " " + c + " -o " + dir.File("out"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("failed"), std::string::npos) << r.output;
  const CsvTable t = ReadCampaignCsv(dir.File("out/campaign.csv"));
  ASSERT_EQ(t.rows(), 3u);
  EXPECT_EQ(t.TextColumn("status")[0], "ok");
  EXPECT_EQ(t.TextColumn("status")[1], "ok");
  EXPECT_EQ(t.TextColumn("status")[2], "failed");
  EXPECT_NE(t.TextColumn("error")[2].find("sensor.csv"), std::string::npos)
      << t.TextColumn("error")[2];
  EXPECT_EQ(t.TextColumn("eq4_fit")[2], "excluded");
  EXPECT_TRUE(std::isnan(t.Column("added_mass_max_kg")[2]));
  EXPECT_GT(t.Column("added_mass_max_kg")[0], 0);
  // The failed test has no folder; the others are complete.
  EXPECT_FALSE(fs::exists(dir.File("out/" + t.TextColumn("scene")[2])));
  EXPECT_TRUE(fs::exists(dir.File("out/" + t.TextColumn("scene")[1] + "/campaign_row.csv")));
}

TEST(CampaignRun, CompleteTestsAreResumedChangedOnesRedoneForceRedoesAll) {
  TestDir dir;
  CampaignOptions o;
  o.output_folder = dir.File("out");
  o.threads = 2;
  const CampaignSummary first =
      RunCampaignPlan(LoadCampaignFile(QuickCampaign(dir, "c.yaml", "[0.15, 0.2]")), o);
  ASSERT_EQ(first.rows.size(), 2u);
  EXPECT_EQ(first.resumed, 0);
  const std::string t1 = first.rows[0].name, t2 = first.rows[1].name;
  const auto f1 = Fingerprint(dir.File("out/" + t1)), f2 = Fingerprint(dir.File("out/" + t2));
  const std::string csv = ReadText(dir.File("out/campaign.csv"));

  const CampaignSummary again =
      RunCampaignPlan(LoadCampaignFile(QuickCampaign(dir, "c.yaml", "[0.15, 0.2]")), o);
  EXPECT_EQ(again.resumed, 2);
  EXPECT_EQ(Fingerprint(dir.File("out/" + t1)), f1);
  EXPECT_EQ(Fingerprint(dir.File("out/" + t2)), f2);
  EXPECT_EQ(ReadText(dir.File("out/campaign.csv")), csv);  // Rows read back exactly.

  // A changed test (D 0.2 -> 0.25) is new; the unchanged one is resumed.
  const CampaignSummary changed =
      RunCampaignPlan(LoadCampaignFile(QuickCampaign(dir, "c.yaml", "[0.15, 0.25]")), o);
  EXPECT_EQ(changed.resumed, 1);
  EXPECT_EQ(Fingerprint(dir.File("out/" + t1)), f1);
  ASSERT_EQ(changed.rows.size(), 2u);
  EXPECT_EQ(changed.rows[1].width_m, 0.25);
  EXPECT_EQ(changed.rows[1].status, "ok");

  o.force = true;
  const CampaignSummary forced =
      RunCampaignPlan(LoadCampaignFile(QuickCampaign(dir, "c.yaml", "[0.15, 0.25]")), o);
  EXPECT_EQ(forced.resumed, 0);
  EXPECT_NE(Fingerprint(dir.File("out/" + t1)), f1);
}

// The number of test folders of `out` that are complete (their generation is swapped in).
int CompleteTests(const std::string& out) {
  int n = 0;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(out, ec))
    n += fs::exists(e.path() / "campaign_row.csv") && fs::exists(e.path() / ".impactdic-output");
  return n;
}

TEST(CampaignRun, AnInterruptedCampaignKeepsFinishedTestsAndResumesTheOthers) {
  TestDir dir;
  // Eight tests: on a loaded machine the polling below may see a few finish at once.
  const std::string file =
      QuickCampaign(dir, "c.yaml", "[0.1, 0.125, 0.15, 0.175, 0.2, 0.225, 0.25, 0.275]");
  const std::string out = dir.File("out");
  fs::create_directories(dir.File("tmp"));
  CliProcess child({"campaign", file, "-o", out, "--jobs", "1", "--threads", "1"}, dir.File("tmp"),
                   dir.File("log1"));
  const ChildExit stopped =
      child.SignalWhen([&] { return CompleteTests(out) >= 2; }, SIGINT, /*whole_group=*/false);
  ASSERT_TRUE(stopped.signalled_by_us) << stopped.Describe();
  EXPECT_TRUE(stopped.exited && stopped.code == 130) << stopped.Describe();
  const int kept = CompleteTests(out);
  ASSERT_GE(kept, 2);
  ASSERT_LT(kept, 8) << "the campaign ended before the interrupt";
  EXPECT_FALSE(fs::exists(out + "/campaign.csv"));  // Written only at the end.
  std::map<std::string, std::map<std::string, FileId>> finished;
  for (const auto& e : fs::directory_iterator(out)) {
    const std::string n = e.path().filename().string();
    EXPECT_EQ(n.rfind(".", 0), std::string::npos) << "temporary left: " << n;
    if (fs::exists(e.path() / "campaign_row.csv")) finished[n] = Fingerprint(e.path());
  }
  const CliResult rerun = RunCli("campaign " + file + " -o " + out + " --threads 1");
  ASSERT_EQ(rerun.exit_code, 0) << rerun.output;
  EXPECT_NE(rerun.output.find(fmt::format("({} resumed, 0 failed", kept)), std::string::npos)
      << rerun.output;
  for (const auto& [name, files] : finished)
    EXPECT_EQ(Fingerprint(out + "/" + name), files) << name << " was processed again";
  const CsvTable t = ReadCampaignCsv(out + "/campaign.csv");
  ASSERT_EQ(t.rows(), 8u);
  for (const auto& s : t.TextColumn("status")) EXPECT_EQ(s, "ok");
}

TEST(CampaignRun, ShardsMergedEqualOneRun) {
  TestDir dir;
  const std::string file = QuickCampaign(dir, "c.yaml", "[0.1, 0.125, 0.15, 0.175, 0.2]");
  CliResult r = RunCli("-q campaign " + file + " -o " + dir.File("all") + " --threads 2");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::string shards;
  for (int i = 1; i <= 3; ++i) {
    const std::string out = dir.File(fmt::format("shard{}", i));
    r = RunCli(fmt::format("-q campaign {} -o {} --threads 2 --shard {}/3", file, out, i));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    shards += " " + out;
  }
  // Shard 2 of 3 holds tests 2 and 5.
  const CsvTable s2 = ReadCampaignCsv(dir.File("shard2/campaign.csv"));
  EXPECT_EQ(s2.Column("test_index"), (std::vector<double>{2, 5}));
  r = RunCli("-q campaign --merge" + shards + " -o " + dir.File("merged"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto one = CsvWithoutTimings(dir.File("all/campaign.csv"));
  const auto merged = CsvWithoutTimings(dir.File("merged/campaign.csv"));
  ASSERT_EQ(one.size(), 6u);
  EXPECT_EQ(merged, one);
  EXPECT_EQ(ReadText(dir.File("merged/regression.json")).substr(0, 40),
            ReadText(dir.File("all/regression.json")).substr(0, 40));
  for (const char* fig : {"fig5_added_mass.png", "fig10_momentum_ratio.png"})
    EXPECT_TRUE(fs::exists(dir.File(std::string("merged/") + fig))) << fig;

  // A missing shard, or one given twice, is an error naming the problem.
  r = RunCli("campaign --merge " + dir.File("shard1") + " " + dir.File("shard2") + " -o " +
             dir.File("m2"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("tests 3 of 5 missing"), std::string::npos) << r.output;
  r = RunCli("campaign --merge" + shards + " " + dir.File("shard1") + " -o " + dir.File("m3"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("in both"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace impactdic
