// Interrupted runs (docs/reliability.md). `impactdic run` of a 12 kg scene over
// a folder holding the results of the 10 kg scene, ended by SIGKILL, SIGTERM or SIGINT at many
// points (when its staging folder appears, when results.h5, the first figure or summary.json is
// complete in it, and at delays spread over a whole run): the folder is always entirely the old
// run or entirely the new one (no file of one beside a file of the other; results.h5,
// summary.json and summary.csv agree). SIGTERM and SIGINT remove every temporary (staging folder,
// gnuplot's files in TMPDIR) and exit with 128 + signal; what a SIGKILL leaves is removed by the
// next run. The same for `synth -o`, `campaign -o` and `render`.
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "../io/test_dir.h"
#include "cli_process.h"
#include "impactdic/core/error.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/csv.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/output_generation.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

// A tiny synthetic scene (160x120 px, 8 frames: a run takes about half a second) and two scene
// files for it: a10 (m_p = 10 kg) and b12 (m_p = 12 kg, so p_max = m_p v_max is 1.2x larger).
struct Prepared {
  std::unique_ptr<TestDir> dir;
  std::string scene_a, scene_b;
  double p_max_a = NAN, p_max_b = NAN;
  double seconds_b = 0;  // Wall time of an uninterrupted run of b12.
  std::string error;     // Why preparing failed (empty = fine).
};

std::string ReplaceLine(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

double NumberAfter(const std::string& text, const std::string& key) {
  const std::size_t at = text.find("\"" + key + "\":");
  return at == std::string::npos ? NAN : std::strtod(text.c_str() + at + key.size() + 3, nullptr);
}

ChildExit RunToEnd(const std::vector<std::string>& args, const std::string& tmpdir,
                   const std::string& log) {
  CliProcess p(args, tmpdir, log);
  return p.Wait();
}

const Prepared& Prepare() {
  static Prepared p = [] {
    Prepared q;
    q.dir = std::make_unique<TestDir>("InterruptedRunScene");
    const std::string tmp = q.dir->File("tmp");
    fs::create_directories(tmp);
    const ChildExit synth =
        RunToEnd({"-q", "synth", "--preset", "tiny", "-o", q.dir->File("scene")}, tmp,
                 q.dir->File("synth.log"));
    if (!synth.exited || synth.code != 0) {
      q.error = "synth failed: " + synth.Describe();
      return q;
    }
    const std::string text = ReadTextFile(q.dir->File("scene/scene.yaml"));
    q.scene_a =
        q.dir->Write("scene/a10.yaml", ReplaceLine(text, "name: synthetic_impact", "name: a10"));
    q.scene_b = q.dir->Write("scene/b12.yaml",
                             ReplaceLine(ReplaceLine(text, "name: synthetic_impact", "name: b12"),
                                         "mass_kg: 10", "mass_kg: 12"));
    for (const bool b : {false, true}) {
      const std::string out = q.dir->File(b ? "ref_b" : "ref_a");
      const auto start = std::chrono::steady_clock::now();
      const ChildExit run = RunToEnd({"-q", "run", b ? q.scene_b : q.scene_a, "-o", out}, tmp,
                                     q.dir->File("ref.log"));
      if (!run.exited || run.code != 0) {
        q.error = "reference run failed: " + run.Describe();
        return q;
      }
      const double p_max = NumberAfter(ReadTextFile(out + "/summary.json"), "p_max_kg_m_s");
      (b ? q.p_max_b : q.p_max_a) = p_max;
      if (b)
        q.seconds_b =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    return q;
  }();
  return p;
}

// "old" if `out` is exactly `old_generation` (every file untouched), "new" if it is wholly the
// 12 kg run (the same files, none of them from the old run, and results.h5, summary.json and
// summary.csv all say p_max = new_p_max), otherwise what mixes them.
std::string Generation(const fs::path& out, const std::map<std::string, FileId>& old_generation,
                       double new_p_max) {
  const auto now = Fingerprint(out);
  if (now == old_generation) return "old";
  std::string why;
  for (const auto& [name, id] : now) {
    const auto it = old_generation.find(name);
    if (it == old_generation.end()) why += name + " is not in the old generation; ";
    if (it != old_generation.end() && it->second == id) why += name + " is from the old run; ";
  }
  for (const auto& [name, id] : old_generation)
    if (now.count(name) == 0) why += name + " is missing; ";
  auto agrees = [&](double value, const std::string& where) {
    if (!(std::abs(value - new_p_max) <= 1e-9 * new_p_max))
      why += where + " says p_max " + std::to_string(value) + "; ";
  };
  try {
    agrees(NumberAfter(ReadTextFile((out / "summary.json").string()), "p_max_kg_m_s"),
           "summary.json");
    CsvReadOptions csv;  // A figure the run could not measure is nan (the wave's, here).
    csv.allow_non_finite = true;
    agrees(ReadCsv((out / "summary.csv").string(), csv).Column("p_max_kg_m_s").at(0),
           "summary.csv");
    const H5Reader h5((out / "results.h5").string());
    agrees(h5.ReadNumberAttribute("/summary", "p_max_kg_m_s"), "results.h5");
    if (h5.ReadStringAttribute("/provenance", "scene_yaml").find("mass_kg: 12") ==
        std::string::npos)
      why += "results.h5 is not of the 12 kg scene; ";
  } catch (const Error& e) {
    why += std::string("unreadable: ") + e.what();
  }
  return why.empty() ? "new" : "mixed: " + why;
}

// Where a run is ended: when a file appears in its staging folder, or after a delay.
struct KillPoint {
  std::string name;      // What the staging folder holds ("" = the folder itself), or "delay".
  double delay_s = 0.0;  // For "delay".
};

std::vector<KillPoint> KillPoints(double run_seconds) {
  std::vector<KillPoint> points = {
      {"", 0}, {"results.h5", 0}, {"momentum.png", 0}, {"summary.json", 0}};
  for (double f : {0.2, 0.45, 0.7, 0.95}) points.push_back({"delay", f * run_seconds});
  return points;
}

class InterruptedRun : public ::testing::TestWithParam<int> {};

// SIGINT goes to the whole process group (a terminal's Ctrl-C: gnuplot gets it too), SIGTERM to
// the process alone (kill PID), SIGKILL to the group (nothing of the run survives).
TEST_P(InterruptedRun, FolderIsAlwaysEntirelyOldOrEntirelyNew) {
  const Prepared& p = Prepare();
  ASSERT_TRUE(p.error.empty()) << p.error;
  ASSERT_NEAR(p.p_max_b / p.p_max_a, 1.2, 1e-6);  // The two runs are told apart by p_max.
  const int sig = GetParam();
  const bool group = sig != SIGTERM;
  TestDir dir;
  const std::string tmp = dir.File("tmp"), out = dir.File("out");
  fs::create_directories(tmp);
  auto run_old = [&] {
    const ChildExit a = RunToEnd({"-q", "run", p.scene_a, "-o", out}, tmp, dir.File("a.log"));
    EXPECT_EQ(a.code, 0) << a.Describe();
    return Fingerprint(out);
  };
  auto old_generation = run_old();
  for (const char* name :
       {"results.h5", "summary.json", "summary.csv", "momentum.png", "velocity.mp4"})
    ASSERT_EQ(old_generation.count(name), 1u) << name;

  std::vector<long> killed;  // SIGKILLed runs (their temporaries stay until the next run).
  int interrupted_in_outputs = 0;
  for (const KillPoint& point : KillPoints(p.seconds_b)) {
    SCOPED_TRACE("killed at " + (point.name == "delay"
                                     ? std::to_string(point.delay_s) + " s"
                                     : "staging folder holding '" + point.name + "'"));
    if (Generation(out, old_generation, p.p_max_b) != "old") old_generation = run_old();
    CliProcess run({"-q", "run", p.scene_b, "-o", out}, tmp, dir.File("b.log"));
    ASSERT_GT(run.pid(), 0);
    const auto start = std::chrono::steady_clock::now();
    const ChildExit e = run.SignalWhen(
        [&] {
          if (point.name == "delay")
            return std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
                       .count() >= point.delay_s;
          const auto staging = TemporariesOf(dir.path(), "out", run.pid());
          if (staging.empty()) return false;
          return point.name.empty() || fs::exists(dir.path() / *staging.begin() / point.name);
        },
        sig, group);
    const std::string generation = Generation(out, old_generation, p.p_max_b);
    EXPECT_TRUE(generation == "old" || generation == "new") << generation << "\n" << e.Describe();
    if (e.exited && e.code == 0) {
      EXPECT_EQ(generation, "new") << e.Describe();  // It finished before the signal.
      continue;
    }
    if (sig == SIGKILL) {  // Old, or new if it came between the swap and the exit.
      EXPECT_EQ(e.signal, SIGKILL) << e.Describe();
      killed.push_back(run.pid());
      if (point.name != "delay" && generation == "old") ++interrupted_in_outputs;
      continue;
    }
    // A handled signal after the swap (the process was about to exit) leaves the new outputs and
    // says so; before it, the old ones.
    const bool swapped =
        e.output.find("whose new outputs were complete and stay") != std::string::npos;
    EXPECT_EQ(generation, swapped ? "new" : "old") << e.Describe();
    if (point.name != "delay" && !swapped) ++interrupted_in_outputs;
    // Handled: exit 128 + signal, nothing left behind. (A signal before main installed the
    // handlers takes its default action; the run had written nothing then.)
    if (e.exited) {
      EXPECT_EQ(e.code, 128 + sig) << e.Describe();
      EXPECT_NE(e.output.find(sig == SIGINT ? "interrupted by SIGINT" : "interrupted by SIGTERM"),
                std::string::npos)
          << e.Describe();
    } else {
      EXPECT_EQ(e.signal, sig) << e.Describe();
    }
    EXPECT_TRUE(TemporariesOf(dir.path(), "out").empty()) << e.Describe();
    EXPECT_TRUE(SystemTemporariesOf(tmp, run.pid()).empty()) << e.Describe();
  }
  // The four staging-folder points fall into the outputs stage; the last may race the swap.
  EXPECT_GE(interrupted_in_outputs, 3);
  if (sig != SIGKILL) return;

  // A run SIGKILLed with results.h5 in its staging folder leaves that folder; the next run removes
  // it, and what the SIGKILLed runs left in TMPDIR (gnuplot's files; also a planted one of a dead
  // process, while a live process's stays).
  CliProcess last({"-q", "run", p.scene_b, "-o", out}, tmp, dir.File("b.log"));
  const ChildExit e = last.SignalWhen(
      [&] {
        const auto staging = TemporariesOf(dir.path(), "out", last.pid());
        return !staging.empty() && fs::exists(dir.path() / *staging.begin() / "results.h5");
      },
      SIGKILL, /*whole_group=*/true);
  ASSERT_TRUE(e.signalled_by_us && e.signal == SIGKILL) << e.Describe();
  const auto stale = TemporariesOf(dir.path(), "out", last.pid());
  ASSERT_EQ(stale.size(), 1u);
  const std::string dead_gnuplot = "impactdic-" + std::to_string(DeadPid()) + "-0123abcd.gp";
  const std::string live_gnuplot = "impactdic-" + std::to_string(getpid()) + "-0123abcd.gp";
  std::ofstream(fs::path(tmp) / dead_gnuplot) << "plot 1\n";
  std::ofstream(fs::path(tmp) / live_gnuplot) << "plot 1\n";
  const ChildExit next = RunToEnd({"-q", "run", p.scene_b, "-o", out}, tmp, dir.File("next.log"));
  ASSERT_EQ(next.code, 0) << next.Describe();
  EXPECT_FALSE(fs::exists(dir.path() / *stale.begin()));
  EXPECT_TRUE(TemporariesOf(dir.path(), "out").empty());
  EXPECT_FALSE(fs::exists(fs::path(tmp) / dead_gnuplot));
  for (long pid : killed) EXPECT_TRUE(SystemTemporariesOf(tmp, pid).empty()) << pid;
  EXPECT_TRUE(fs::exists(fs::path(tmp) / live_gnuplot));
  EXPECT_EQ(Generation(out, old_generation, p.p_max_b), "new");
}

INSTANTIATE_TEST_SUITE_P(Signals, InterruptedRun, ::testing::Values(SIGKILL, SIGTERM, SIGINT),
                         [](const ::testing::TestParamInfo<int>& param_info) {
                           return std::string(param_info.param == SIGKILL   ? "SIGKILL"
                                              : param_info.param == SIGTERM ? "SIGTERM"
                                                                            : "SIGINT");
                         });

// `synth -o DIR` over an earlier scene, SIGKILLed and SIGTERMed while writing frames: DIR keeps
// the earlier scene whole (8 frames with its truth.h5); the next synth removes the stale staging
// folder and replaces the scene whole (16 frames).
TEST(InterruptedSynth, FolderKeepsTheEarlierSceneWhole) {
  TestDir dir;
  const std::string tmp = dir.File("tmp"), scene = dir.File("scene");
  fs::create_directories(tmp);
  ASSERT_EQ(RunToEnd({"-q", "synth", "--preset", "tiny", "-o", scene}, tmp, dir.File("a.log")).code,
            0);
  const auto old_generation = Fingerprint(scene);
  ASSERT_TRUE(old_generation.count("frames/frame_0007.png") == 1 &&
              old_generation.count("frames/frame_0008.png") == 0);
  for (const int sig : {SIGKILL, SIGTERM}) {
    SCOPED_TRACE(sig == SIGKILL ? "SIGKILL" : "SIGTERM");
    CliProcess synth({"-q", "synth", "--preset", "tiny", "--frames", "16", "-o", scene}, tmp,
                     dir.File("b.log"));
    const ChildExit e = synth.SignalWhen(
        [&] {
          const auto staging = TemporariesOf(dir.path(), "scene", synth.pid());
          return !staging.empty() &&
                 fs::exists(dir.path() / *staging.begin() / "frames" / "frame_0003.png");
        },
        sig, /*whole_group=*/sig == SIGKILL);
    ASSERT_TRUE(e.signalled_by_us) << e.Describe();
    EXPECT_EQ(Fingerprint(scene), old_generation) << e.Describe();
    if (sig == SIGKILL) {
      EXPECT_EQ(TemporariesOf(dir.path(), "scene", synth.pid()).size(), 1u);
    } else {
      EXPECT_EQ(e.code, 128 + SIGTERM) << e.Describe();
      EXPECT_TRUE(TemporariesOf(dir.path(), "scene").empty()) << e.Describe();
    }
  }
  ASSERT_EQ(RunToEnd({"-q", "synth", "--preset", "tiny", "--frames", "16", "-o", scene}, tmp,
                     dir.File("c.log"))
                .code,
            0);
  EXPECT_TRUE(TemporariesOf(dir.path(), "scene").empty());
  const auto new_generation = Fingerprint(scene);
  EXPECT_EQ(new_generation.count("frames/frame_0015.png"), 1u);
  for (const auto& [name, id] : new_generation) {
    const auto it = old_generation.find(name);
    EXPECT_TRUE(it == old_generation.end() || !(it->second == id)) << name << " is from before";
  }
}

// `campaign -o DIR --force` over an earlier campaign, ended while its second test runs: DIR keeps
// the earlier campaign's files (its test folder a10, campaign.csv, regression.json) untouched, and
// the test that completed before the signal (b12, a generation of its own) is kept; SIGTERM also
// removes the staging folders (docs/campaign.md, "Resuming").
TEST(InterruptedCampaign, FolderKeepsTheEarlierCampaignAndTheCompletedTests) {
  const Prepared& p = Prepare();
  ASSERT_TRUE(p.error.empty()) << p.error;
  TestDir dir;
  const std::string tmp = dir.File("tmp"), out = dir.File("campaign");
  fs::create_directories(tmp);
  ASSERT_EQ(RunToEnd({"-q", "campaign", p.scene_a, "-o", out}, tmp, dir.File("a.log")).code, 0);
  const auto old_generation = Fingerprint(out);
  ASSERT_EQ(old_generation.count("a10/results/summary.json"), 1u);
  ASSERT_EQ(old_generation.count("campaign.csv"), 1u);
  for (const int sig : {SIGKILL, SIGTERM}) {
    SCOPED_TRACE(sig == SIGKILL ? "SIGKILL" : "SIGTERM");
    fs::remove_all(out + "/b12");
    CliProcess campaign({"-q", "campaign", p.scene_b, p.scene_a, "-o", out, "--force"}, tmp,
                        dir.File("b.log"));
    const ChildExit e = campaign.SignalWhen(
        [&] {  // b12 is complete (swapped in); a10 runs.
          return fs::exists(out + "/b12/" + kOutputMarkerName) &&
                 !TemporariesOf(out, "a10", campaign.pid()).empty();
        },
        sig, /*whole_group=*/sig == SIGKILL);
    ASSERT_TRUE(e.signalled_by_us) << e.Describe();
    const auto now = Fingerprint(out);
    for (const auto& [name, id] : old_generation) {
      const auto it = now.find(name);
      EXPECT_TRUE(it != now.end() && it->second == id) << name << " changed; " << e.Describe();
    }
    EXPECT_EQ(now.count("b12/results/summary.json"), 1u) << e.Describe();
    EXPECT_EQ(now.count("b12/campaign_row.csv"), 1u) << e.Describe();
    if (sig == SIGTERM) {
      EXPECT_EQ(e.code, 128 + SIGTERM) << e.Describe();
      EXPECT_TRUE(TemporariesOf(dir.path(), "campaign").empty()) << e.Describe();
      EXPECT_TRUE(TemporariesOf(out, "a10").empty()) << e.Describe();
    }
  }
  // The next campaign resumes b12 and writes the campaign-level files for its tests only.
  const ChildExit last = RunToEnd({"campaign", p.scene_b, "-o", out}, tmp, dir.File("c.log"));
  ASSERT_EQ(last.code, 0) << last.Describe();
  EXPECT_NE(last.output.find("(1 resumed, 0 failed"), std::string::npos) << last.Describe();
  EXPECT_TRUE(TemporariesOf(dir.path(), "campaign").empty());
  EXPECT_TRUE(TemporariesOf(out, "a10").empty());
  const std::string csv = ReadTextFile(out + "/campaign.csv");
  EXPECT_NE(csv.find("\nb12,"), std::string::npos) << csv;
  EXPECT_EQ(csv.find("\na10,"), std::string::npos) << csv;  // Not part of the new campaign.
}

// Commands refuse an output folder holding files impactdic did not write (and delete nothing);
// render replaces its figures and keeps the run's results.h5 and summaries (the same files).
TEST(OutputFolders, UserFilesAreNeverReplaced) {
  const Prepared& p = Prepare();
  ASSERT_TRUE(p.error.empty()) << p.error;
  TestDir dir;
  const std::string tmp = dir.File("tmp"), out = dir.File("out");
  fs::create_directories(tmp);
  fs::create_directories(out);
  dir.Write("out/notes.txt", "the user's notes");
  const ChildExit run = RunToEnd({"-q", "run", p.scene_a, "-o", out}, tmp, dir.File("run.log"));
  EXPECT_EQ(run.code, 1) << run.Describe();
  EXPECT_NE(run.output.find("1 entry impactdic did not write: 'notes.txt'"), std::string::npos)
      << run.Describe();
  EXPECT_EQ(ReadTextFile(dir.File("out/notes.txt")), "the user's notes");
  EXPECT_EQ(Fingerprint(out).size(), 1u);
  EXPECT_TRUE(TemporariesOf(dir.path(), "out").empty());
  const ChildExit synth =
      RunToEnd({"-q", "synth", "--preset", "tiny", "-o", out}, tmp, dir.File("synth.log"));
  EXPECT_EQ(synth.code, 1) << synth.Describe();
  EXPECT_NE(synth.output.find("'notes.txt'"), std::string::npos) << synth.Describe();
  EXPECT_EQ(Fingerprint(out).size(), 1u);
}

TEST(OutputFolders, RenderReplacesItsFiguresAndKeepsTheRunsFiles) {
  const Prepared& p = Prepare();
  ASSERT_TRUE(p.error.empty()) << p.error;
  TestDir dir;
  const std::string tmp = dir.File("tmp"), out = dir.File("out");
  fs::create_directories(tmp);
  ASSERT_EQ(RunToEnd({"-q", "run", p.scene_a, "-o", out}, tmp, dir.File("run.log")).code, 0);
  const auto run_files = Fingerprint(out);
  const ChildExit render = RunToEnd({"-q", "render", out + "/results.h5", "--no-animation"}, tmp,
                                    dir.File("render.log"));
  ASSERT_EQ(render.code, 0) << render.Describe();
  const auto rendered = Fingerprint(out);
  for (const char* kept : {"results.h5", "summary.json", "summary.csv"})
    EXPECT_EQ(rendered.at(kept), run_files.at(kept)) << kept;
  for (const char* redrawn : {"momentum.png", "deceleration.png", "added_mass.png"})
    EXPECT_FALSE(rendered.at(redrawn) == run_files.at(redrawn)) << redrawn;
  // The render generation has no animation: the run's video does not stay beside new figures.
  EXPECT_EQ(rendered.count("velocity.mp4"), 0u);
  EXPECT_TRUE(TemporariesOf(dir.path(), "out").empty());

  // A folder holding another results.h5 is refused (the figures would not match it).
  fs::create_directories(dir.path() / "other");
  fs::copy_file(out + "/results.h5", dir.File("other/results.h5"));
  const ChildExit other = RunToEnd({"-q", "render", out + "/results.h5", "-o", dir.File("other")},
                                   tmp, dir.File("other.log"));
  EXPECT_EQ(other.code, 1) << other.Describe();
  EXPECT_NE(other.output.find("another results file"), std::string::npos) << other.Describe();
  EXPECT_EQ(Fingerprint(dir.path() / "other").size(), 1u);
}

}  // namespace
}  // namespace impactdic
