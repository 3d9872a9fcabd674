// Fault injection (11 and the duplicate --deformed message): thread counts
// beyond the machine, a correlation or a campaign that produced nothing, campaign resume after an
// input changed, and `analyze` of another scene's results or of a run folder's results.h5.
// Scenes are tiny synthesised ones (160 x 120 px, no figures or video: a second or less a run).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "../cli/cli_runner.h"
#include "../core/test_paths.h"
#include "../io/test_dir.h"
#include "fault_util.h"
#include "impactdic/core/interrupt.h"
#include "impactdic/core/threads.h"
#include "impactdic/dic/correlator.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/image_io.h"
#include "impactdic/synth/impact_scene.h"

namespace impactdic {
namespace {
namespace fs = std::filesystem;

bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// A tiny synthesised scene (8 frames) in `folder` without figures or video; returns its file.
std::string TinyScene(const std::string& folder, std::uint64_t seed) {
  ImpactSceneSpec spec = ImpactScenePreset("tiny");
  spec.seed = seed;
  const std::string scene = WriteImpactScene(ImpactScene(spec), folder).scene_yaml;
  std::string text = ReadBytes(scene);
  for (const std::string key : {"figures", "animation"}) {
    const std::size_t at = text.find("  " + key + ": true");
    if (at != std::string::npos) text.replace(at, key.size() + 8, "  " + key + ": false");
  }
  WriteBytes(scene, text);
  return scene;
}

// Entries of `folder` whose name starts with '.' and holds ".tmp-" (temporaries).
std::vector<std::string> Temporaries(const fs::path& folder) {
  std::vector<std::string> found;
  for (const auto& e : fs::directory_iterator(folder)) {
    const std::string name = e.path().filename().string();
    if (name[0] == '.' && Contains(name, ".tmp-")) found.push_back(name);
  }
  return found;
}

// ---- Item 3: thread counts -------------------------------------------------------------------

// One rule: 0 is all cores, N is at most the cores.
TEST(ThreadCap, RequestsAreCappedAtTheMachinesCores) {
  const int cores = MachineCores();
  ASSERT_GE(cores, 1);
  EXPECT_EQ(ThreadsToUse(0, "test"), cores);
  EXPECT_EQ(ThreadsToUse(1, "test"), 1);
  EXPECT_EQ(ThreadsToUse(cores, "test"), cores);
  EXPECT_EQ(ThreadsToUse(100000, "test"), cores);
  const ThreadLimit limit(100000, "test");
  EXPECT_EQ(limit.threads(), cores);
}

// `campaign --threads 100000` made a oneTBB arena of 100000 threads: pthread_create failed,
// std::terminate (exit 134) left the staging folder; as root (no process limit) it made threads
// until killed. The child's address space is bounded (4 GiB: ~500 thread stacks) so that the
// old code fails at once instead; not under AddressSanitizer, whose shadow memory needs more.
TEST(ThreadCap, CampaignWithAHugeThreadCountRunsOnTheCoresAndLeavesNoTemporaries) {
  TestDir dir;
  const std::string scene = TinyScene(dir.File("s"), 1);
#if defined(__SANITIZE_ADDRESS__)
  const std::string limit;
#else
  const std::string limit = "ulimit -v 4194304; ";
#endif
  const CliResult r =
      RunShell(limit + impactdic::CliPath() + std::string(" campaign ") + scene + " -o " +
               dir.File("out") + " --threads 100000 --jobs 100000 --no-figures");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string cores = std::to_string(MachineCores());
  EXPECT_TRUE(Contains(r.output, "campaign threads: 100000 threads requested; this machine has " +
                                     cores + " cores: using " + cores))
      << r.output;
  EXPECT_TRUE(Contains(r.output, "campaign jobs: 100000 threads requested")) << r.output;
  EXPECT_TRUE(Temporaries(dir.path()).empty());
  EXPECT_TRUE(fs::exists(dir.File("out/campaign.csv")));
  // `run` and `correlate` follow the same rule (the correlate stage's and the command's limit).
  const CliResult run = RunCli("run " + scene + " -o " + dir.File("run") + " --threads 100000");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_TRUE(Contains(run.output, "threads: 100000 threads requested")) << run.output;
}

// Whatever still ends the process through std::terminate (an exception nothing caught, e.g.
// oneTBB's "pthread_create has failed" above) removes the registered temporaries before it aborts.
TEST(ThreadCap, StdTerminateRemovesTheRegisteredTemporaries) {
  TestDir dir;
  const std::string staging = dir.File(".out.tmp-1-0123456789abcdef");
  const pid_t child = fork();
  if (child == 0) {
    InstallInterruptCleanup();
    fs::create_directories(staging + "/results");
    const RemoveOnInterrupt guard(staging);
    std::thread([] { throw std::runtime_error("an error no code caught"); }).join();
    _exit(0);
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGABRT) << status;
  EXPECT_FALSE(fs::exists(staging));
}

// ---- Item 11: a correlation or a campaign that produced nothing ------------------------------

// `run` fails when no subset is valid in any frame (its correlate stage asks
// DicSummary::NothingUsable); `correlate` asks the same and fails the same way, writing nothing
// unless --allow-partial.
TEST(NothingUsable, CorrelateFailsAsRunDoesWhenNoSubsetIsValid) {
  DicSummary s;
  s.frames = 2;
  s.subsets = 10;
  s.status_counts[static_cast<int>(SubsetStatus::kLowCorrelation)] = 20;
  EXPECT_TRUE(Contains(s.NothingUsable("--min-zncc", 0.8),
                       "no valid subset in any of the 2 frames after the reference"));
  EXPECT_TRUE(Contains(s.NothingUsable("--min-zncc", 0.8), "--min-zncc = 0.8"));
  s.valid_fraction = 0.01;  // One valid subset: usable enough not to fail (a warning says more).
  EXPECT_EQ(s.NothingUsable("--min-zncc", 0.8), "");

  TestDir dir;
  WriteImage(dir.File("flat.png"), cv::Mat(80, 96, CV_8U, cv::Scalar(128)));
  WriteImage(dir.File("def.png"), Speckle(96, 80, 3));
  const std::string args = "-q correlate --reference " + dir.File("flat.png") + " --deformed " +
                           dir.File("def.png") + " --subset 21 --step 20 -o " + dir.File("c.csv");
  const std::string output =
      ExpectCliFailure(args, {"no valid subset in any of the 1 frames after the reference",
                              "--min-zncc", "`impactdic correlate --allow-partial` writes it"});
  EXPECT_FALSE(fs::exists(dir.File("c.csv"))) << output;
  const CliResult partial = RunCli(args + " --allow-partial");
  EXPECT_EQ(partial.exit_code, 0) << partial.output;
  EXPECT_TRUE(fs::exists(dir.File("c.csv")));
}

// A campaign whose every test failed has no results at all: exit 1 naming how many failed (its
// campaign.csv with each error is still written). One failed test among good ones stays exit 0
// (CampaignRun.AFailingTestIsReportedAndTheOthersFinish).
TEST(NothingUsable, CampaignWhoseEveryTestFailedExitsNonZero) {
  TestDir dir;
  const std::string a = TinyScene(dir.File("a"), 1), b = TinyScene(dir.File("b"), 2);
  for (const char* s : {"a/sensor.csv", "b/sensor.csv"}) dir.Write(s, "time_s,accel_g,exposure\n");
  const CliResult r =
      RunCli("-q campaign " + a + " " + b + " -o " + dir.File("out") + " --no-figures");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_TRUE(Contains(r.output, "all 2 tests failed, none has results")) << r.output;
  EXPECT_TRUE(Contains(r.output, "sensor.csv")) << r.output;  // The first error.
  EXPECT_TRUE(fs::exists(dir.File("out/campaign.csv")));
  EXPECT_TRUE(Temporaries(dir.path()).empty());
}

// A shard is part of a campaign: every one of its tests failing is rows for the merge to report
// (exit 0, so a Slurm array task's merge submitted with --dependency=afterok still runs), and the
// merge fails when every test of the whole campaign failed, as one run over all tests does.
TEST(NothingUsable, AShardWhoseTestsAllFailedExitsZeroTheMergeOfAllFailedExitsOne) {
  TestDir dir;
  const std::string a = TinyScene(dir.File("a"), 1), b = TinyScene(dir.File("b"), 2);
  dir.Write("a/sensor.csv", "time_s,accel_g,exposure\n");
  const std::string scenes = " " + a + " " + b + " --no-figures";
  CliResult s1 = RunCli("campaign" + scenes + " --shard 1/2 -o " + dir.File("s1"));
  EXPECT_EQ(s1.exit_code, 0) << s1.output;
  EXPECT_TRUE(Contains(s1.output, "1 failed")) << s1.output;
  CliResult s2 = RunCli("-q campaign" + scenes + " --shard 2/2 -o " + dir.File("s2"));
  ASSERT_EQ(s2.exit_code, 0) << s2.output;
  CliResult merged =
      RunCli("campaign --merge " + dir.File("s1") + " " + dir.File("s2") + " -o " + dir.File("m"));
  EXPECT_EQ(merged.exit_code, 0) << merged.output;
  EXPECT_TRUE(Contains(merged.output, "1 failed")) << merged.output;
  EXPECT_TRUE(Contains(merged.output, "sensor.csv")) << merged.output;  // The failed test's error.

  // Both tests failing: each shard still exits 0; the merge exits 1 naming how many.
  dir.Write("b/sensor.csv", "time_s,accel_g,exposure\n");
  s2 = RunCli("-q campaign" + scenes + " --shard 2/2 -o " + dir.File("s2"));
  EXPECT_EQ(s2.exit_code, 0) << s2.output;
  merged = RunCli("-q campaign --merge " + dir.File("s1") + " " + dir.File("s2") + " -o " +
                  dir.File("m"));
  EXPECT_EQ(merged.exit_code, 1) << merged.output;
  EXPECT_TRUE(Contains(merged.output, "all 2 tests failed, none has results")) << merged.output;
  // The same campaign as one shard of one (the whole campaign) is the run over all tests: exit 1.
  const CliResult whole = RunCli("-q campaign" + scenes + " --shard 1/1 -o " + dir.File("w"));
  EXPECT_EQ(whole.exit_code, 1) << whole.output;
}

// ---- Item 11: campaign resume after an input changed -----------------------------------------

// Resuming compared the scene file's hash only: a replaced sensor record or frame kept the old
// results. Now every input file counts by its bytes (not its mtime).
TEST(CampaignResume, AChangedInputFileRerunsTheTestAndATouchDoesNot) {
  TestDir dir;
  const std::string scene = TinyScene(dir.File("s"), 1);
  const std::string command = "-q campaign " + scene + " -o " + dir.File("out") + " --no-figures";
  const auto resumed = [&] {
    const CliResult r = RunCli(command);
    EXPECT_EQ(r.exit_code, 0) << r.output;
    return Contains(r.output, "(1 resumed");
  };
  ASSERT_FALSE(resumed());
  // The same bytes, newer mtime: still complete.
  const std::string sensor = dir.File("s/sensor.csv");
  const std::string record = ReadBytes(sensor);
  fs::last_write_time(sensor, fs::last_write_time(sensor) + std::chrono::hours(1));
  EXPECT_TRUE(resumed());
  // One sample changed: run again.
  const std::string changed = record.substr(0, record.rfind('\n', record.size() - 2) + 1);
  ASSERT_NE(changed, record);
  WriteBytes(sensor, changed);
  EXPECT_FALSE(resumed());
  // A frame replaced by another: run again.
  fs::copy_file(dir.File("s/frames/frame_0004.png"), dir.File("s/frames/frame_0003.png"),
                fs::copy_options::overwrite_existing);
  EXPECT_FALSE(resumed());
}

// ---- Item 9: analyze and another scene's results, or a run folder's results.h5 ---------------

TEST(AnalyzeResults, AnotherScenesResultsAndARunFoldersFileAreRefused) {
  TestDir dir;
  const std::string scene = TinyScene(dir.File("s"), 1);
  const CliResult run = RunCli("-q run " + scene + " -o " + dir.File("run"));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const std::string results = dir.File("run/results.h5");
  const std::string before = ReadBytes(results);
  const std::string summary = ReadBytes(dir.File("run/summary.json"));

  // Another scene (its own name) given the run's results: refused, naming both scenes.
  std::string other = ReadBytes(scene);
  const std::size_t name = other.find("\nname: ");
  ASSERT_NE(name, std::string::npos) << other;
  other.insert(name + 7, "other_");
  const std::string other_scene = dir.File("s/other.yaml");
  WriteBytes(other_scene, other);
  ExpectCliFailure("analyze " + other_scene + " --results " + results,
                   {"--results", "holds the results of scene 'synthetic_impact'",
                    "expected the results of scene 'other_synthetic_impact'"});
  // Its own scene, in place: the folder's summary.json would no longer describe results.h5.
  ExpectCliFailure("analyze " + scene + " --results " + results,
                   {"--results", "with its summary.json", "--output NEW.h5"});
  ExpectCliFailure(
      "analyze " + scene + " --results " + results + " --output " + dir.File("run/analysis.h5"),
      {"--output", "with its summary.json"});
  EXPECT_TRUE(ReadBytes(results) == before);  // Unchanged.
  EXPECT_TRUE(ReadBytes(dir.File("run/summary.json")) == summary);
  EXPECT_FALSE(fs::exists(dir.File("run/analysis.h5")));

  // Into a file of its own: the analysis with the correlation, without the run's summary.
  const CliResult own = RunCli("-q analyze " + scene + " --results " + results + " --output " +
                               dir.File("analysis.h5") + " --format json");
  ASSERT_EQ(own.exit_code, 0) << own.output;
  const H5Reader in(dir.File("analysis.h5"));
  EXPECT_TRUE(in.Exists("dic/u_px"));
  EXPECT_TRUE(in.Exists("momentum/p_gran"));
  EXPECT_FALSE(in.Exists("summary"));
  EXPECT_EQ(in.ReadStringAttribute("/", "scene_name"), "synthetic_impact");
  // An existing --output of another scene is not replaced by this analysis.
  {
    H5Writer file(dir.File("other.h5"));
    file.SetAttribute("/", "scene_name", std::string("other_synthetic_impact"));
    file.Commit();
  }
  ExpectCliFailure(
      "analyze " + scene + " --results " + results + " --output " + dir.File("other.h5"),
      {"--output", "holds the results of scene 'other_synthetic_impact'"});
  EXPECT_FALSE(H5Reader(dir.File("other.h5")).Exists("momentum"));  // Left as it was.
  EXPECT_TRUE(ReadBytes(results) == before);                        // Unchanged.
}

// ---- Messages: a deformed image given twice ---------------------------------------------------

TEST(CorrelateInputs, AnImageGivenTwiceIsRefusedUnderAnySpelling) {
  TestDir dir;
  WriteImage(dir.File("ref.png"), Speckle(96, 80, 1));
  WriteImage(dir.File("def.png"), Speckle(96, 80, 2));
  fs::create_hard_link(dir.File("def.png"), dir.File("link.png"));
  const std::string ref = " --reference " + dir.File("ref.png");
  const std::string out = " -o " + dir.File("c.csv");
  ExpectCliFailure(
      "correlate" + ref + " --deformed " + dir.File("def.png") + " " + dir.File("def.png") + out,
      {"--deformed", dir.File("def.png") + "', given twice"});
  const std::string dotted = (dir.path() / "." / "def.png").string();
  ExpectCliFailure(
      "correlate" + ref + " --deformed " + dir.File("def.png") + " " + dotted + out,
      {"--deformed", "'" + dotted + "', the same file as '" + dir.File("def.png") + "'"});
  ExpectCliFailure(
      "correlate" + ref + " --deformed " + dir.File("def.png") + " " + dir.File("link.png") + out,
      {"the same file as"});
  ExpectCliFailure("correlate" + ref + " --deformed " + dir.File("ref.png") + out,
                   {"--deformed", "the --reference image"});
  EXPECT_FALSE(fs::exists(dir.File("c.csv")));
}

}  // namespace
}  // namespace impactdic
