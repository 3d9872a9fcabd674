// No command destroys another's outputs (docs/reliability.md): a
// folder written by another kind of command (a campaign, a synth scene, a run) is refused unless
// --force, naming what is there; a second writer of a folder is refused naming the first one's
// pid; an existing CSV or YAML the command did not write is kept; a folder whose earlier outputs
// cannot be removed is refused before any work; render keeps a run's full animation; and the
// messages about output names say what is wrong.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <system_error>
#include <vector>

#include "../core/expect_error.h"
#include "../core/test_paths.h"
#include "cli_process.h"
#include "fault_util.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/output_generation.h"
#include "impactdic/render/animation.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

const std::string kSource = impactdic::SourceDir();

std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

// A tiny synthetic scene, made once per process: 8 frames; quick.yaml without figures and
// animation (a run takes a fraction of a second).
struct Scenes {
  std::unique_ptr<TestDir> dir;
  std::string quick, error;
};

const Scenes& Prepare() {
  static const Scenes s = [] {
    Scenes q;
    q.dir = std::make_unique<TestDir>("OutputOwnershipScenes");
    const CliResult a = RunCli("-q synth --preset tiny -o " + q.dir->File("scene"));
    if (a.exit_code != 0) {
      q.error = "synth failed:\n" + a.output;
      return q;
    }
    const std::string text = ReadTextFile(q.dir->File("scene/scene.yaml"));
    q.quick =
        q.dir->Write("scene/quick.yaml", Replace(Replace(text, "figures: true", "figures: false"),
                                                 "animation: true", "animation: false"));
    return q;
  }();
  return s;
}

void ExpectRefused(const CliResult& r, const std::vector<std::string>& words) {
  EXPECT_EQ(r.exit_code, 1) << r.output;
  for (const std::string& w : words)
    EXPECT_NE(r.output.find(w), std::string::npos) << "'" << w << "' missing:\n" << r.output;
}

// Item 1: every command refuses a folder another kind of command wrote, naming it and some of its
// entries, and leaves it untouched; --force replaces it.
TEST(OutputOwnership, AnotherCommandsFolderIsRefusedUnlessForce) {
  const Scenes& s = Prepare();
  ASSERT_TRUE(s.error.empty()) << s.error;
  TestDir dir;
  const std::string camp = dir.File("camp"), run = dir.File("run"), synth = dir.File("synth");
  ASSERT_EQ(RunCli("-q campaign " + s.quick + " --no-figures -o " + camp).exit_code, 0);
  ASSERT_EQ(RunCli("-q run " + s.quick + " -o " + run).exit_code, 0);
  ASSERT_EQ(RunCli("-q synth --preset tiny --frames 6 -o " + synth).exit_code, 0);
  const auto camp_files = Fingerprint(camp), run_files = Fingerprint(run),
             synth_files = Fingerprint(synth);

  // The cases: a run over a campaign and over a synth scene (another scene's inputs),
  // synth over a run, a campaign into a run's folder.
  ExpectRefused(
      RunCli("-q run " + s.quick + " -o " + camp),
      {camp, "a campaign folder, written by `impactdic campaign`", "'campaign.csv'", "--force"});
  ExpectRefused(RunCli("-q run " + s.quick + " -o " + synth),
                {"a synth folder, written by `impactdic synth`", "'frames'", "'sensor.csv'"});
  ExpectRefused(RunCli("-q synth --preset tiny -o " + run),
                {"a run folder, written by `impactdic run`", "'results.h5'", "--force"});
  ExpectRefused(RunCli("-q campaign " + s.quick + " -o " + run), {"a run folder", "--force"});
  EXPECT_EQ(Fingerprint(camp), camp_files);
  EXPECT_EQ(Fingerprint(run), run_files);
  EXPECT_EQ(Fingerprint(synth), synth_files);

  // A run above other runs' folders (results/t10 under `run -o results`) would delete them.
  const std::string nested = dir.File("results");
  ASSERT_EQ(RunCli("-q run " + s.quick + " -o " + nested + "/t10").exit_code, 0);
  ExpectRefused(RunCli("-q run " + s.quick + " -o " + nested),
                {"the outputs of other commands: 't10' (a run folder"});
  EXPECT_TRUE(fs::exists(nested + "/t10/results.h5"));

  // --force replaces the folder whole: nothing of the campaign stays beside the run, nothing of
  // the run beside the campaign.
  ASSERT_EQ(RunCli("-q run " + s.quick + " -o " + camp + " --force").exit_code, 0);
  EXPECT_FALSE(fs::exists(camp + "/campaign.csv"));
  EXPECT_TRUE(fs::exists(camp + "/results.h5"));
  ASSERT_EQ(RunCli("-q campaign " + s.quick + " --no-figures -o " + run + " --force").exit_code, 0);
  EXPECT_FALSE(fs::exists(run + "/results.h5"));
  EXPECT_TRUE(fs::exists(run + "/campaign.csv"));
  EXPECT_NE(ReadTextFile(run + "/" + kOutputMarkerName).find("# kind: campaign\n"),
            std::string::npos);
  // The same kind is replaced as before, without --force.
  EXPECT_EQ(RunCli("-q run " + s.quick + " -o " + camp).exit_code, 0);
}

// Item 1: a folder without a marker holding only names the command writes (an impactdic older
// than the marker) is still replaced, but never silently: a warning names what goes.
TEST(OutputOwnership, AnUnmarkedFolderIsReplacedWithAWarningNamingWhatGoes) {
  const Scenes& s = Prepare();
  ASSERT_TRUE(s.error.empty()) << s.error;
  TestDir dir;
  fs::create_directories(dir.path() / "out");
  dir.Write("out/summary.json", "{}\n");
  const CliResult r = RunCli("-q run " + s.quick + " -o " + dir.File("out"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("has no .impactdic-output"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("'summary.json' taken for impactdic's outputs and replaced"),
            std::string::npos)
      << r.output;
}

// Item 2: a second writer of a folder is refused, naming the first one's pid. The test process
// holds the lock itself (as a running command does), so nothing depends on timing.
TEST(OutputOwnership, ASecondWriterIsRefusedNamingTheFirstOnesPid) {
  const Scenes& s = Prepare();
  ASSERT_TRUE(s.error.empty()) << s.error;
  TestDir dir;
  const std::string out = dir.File("out");
  ASSERT_EQ(RunCli("-q run " + s.quick + " -o " + out).exit_code, 0);
  const auto before = Fingerprint(out);
  const std::string lock_path = OutputLockPath(out);
  EXPECT_FALSE(fs::exists(lock_path)) << "a finished command leaves its lock file";
  {
    const int fd = open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(flock(fd, LOCK_EX | LOCK_NB), 0);
    const std::string holder = "process " + std::to_string(getpid()) + " (`impactdic run`)\n";
    ASSERT_EQ(write(fd, holder.data(), holder.size()), static_cast<ssize_t>(holder.size()));
    const std::string pid = "process " + std::to_string(getpid());
    ExpectRefused(RunCli("-q run " + s.quick + " -o " + out), {out, "being written", pid});
    ExpectRefused(RunCli("-q campaign " + s.quick + " -o " + out), {"being written", pid});
    ExpectRefused(RunCli("-q render " + out + "/results.h5"), {"being written", pid});
    EXPECT_EQ(Fingerprint(out), before);
    EXPECT_TRUE(TemporariesOf(dir.path(), "out").empty());
    close(fd);
  }
  fs::remove(lock_path);
  // Within one process too (two generations of one folder at once), and the lock goes with the
  // generation that held it.
  OutputGenerationOptions o;
  o.command = "impactdic run";
  o.own_names = {"results.h5"};
  {
    const OutputGeneration first(dir.File("lib"), o);
    ExpectErrorContaining([&] { const OutputGeneration second(dir.File("lib"), o); },
                          "being written by another command: process " + std::to_string(getpid()));
  }
  EXPECT_FALSE(fs::exists(OutputLockPath(dir.File("lib"))));
  const OutputGeneration again(dir.File("lib"), o);
}

// Item 4: an existing CSV or YAML under an output name is replaced only if the command wrote it.
TEST(OutputOwnership, ExistingTextFilesTheCommandDidNotWriteAreKept) {
  TestDir dir;
  const std::string victim = dir.File("victim.csv");
  fs::copy_file(kSource + "/sample_frames/sensor.csv", victim);
  const std::string record = ReadBytes(victim);
  const std::string model = "-q model --mass 10 --height 0.7 --width 0.15 --format json -o ";
  ExpectRefused(RunCli(model + victim),
                {"-o", victim, "an existing file this command did not write", "kept"});
  const std::string frames = "--reference " + kSource + "/sample_frames/frames/frame_0000.png" +
                             " --deformed " + kSource + "/sample_frames/frames/frame_0001.png";
  ExpectRefused(RunCli("-q correlate " + frames + " --subset 21 --step 60 -o " + victim),
                {"-o/--output", victim, "did not write"});
  EXPECT_EQ(ReadBytes(victim), record);
  // calibrate -o over a scene file.
  const std::string scene = dir.Write("scene.yaml", "name: my_test\n");
  ExpectRefused(RunCli("-q calibrate --board 9x6 --square 25 " + kSource +
                       "/calibration/view_00.png -o " + scene),
                {"-o", scene, "did not write"});
  EXPECT_EQ(ReadBytes(scene), "name: my_test\n");
  // The command's own earlier output is replaced as before.
  const std::string series = dir.File("series.csv");
  ASSERT_EQ(RunCli(model + series).exit_code, 0);
  const CliResult again = RunCli(model + series);
  EXPECT_EQ(again.exit_code, 0) << again.output;
}

// Item 4: a folder whose earlier outputs the user may not remove is refused before any work; it
// used to be swapped out and left behind under a hidden name, silently.
TEST(OutputOwnership, AFolderWhoseOutputsCannotBeRemovedIsRefusedBeforeAnyWork) {
  const Scenes& s = Prepare();
  ASSERT_TRUE(s.error.empty()) << s.error;
  TestDir dir;
  fs::permissions(dir.path(), fs::perms::all);
  const std::string out = dir.File("out");
  ASSERT_EQ(RunCli("-q run " + s.quick + " -o " + out).exit_code, 0);
  // A folder of the run holding a file the user may not remove: as root, the run is made as
  // nobody; otherwise the folder is read-only.
  fs::create_directories(out + "/kept");
  dir.Write("out/kept/file", "x");
  std::string as_user;
  if (geteuid() == 0) {
    as_user = "setpriv --reuid=65534 --regid=65534 --clear-groups ";
    for (const auto& e : fs::recursive_directory_iterator(out)) {
      if (e.path().filename() != "kept" && e.path().filename() != "file") {
        ASSERT_EQ(chown(e.path().c_str(), 65534, 65534), 0);
      }
    }
    ASSERT_EQ(chown(out.c_str(), 65534, 65534), 0);
  } else {
    fs::permissions(out + "/kept", fs::perms::owner_read | fs::perms::owner_exec);
  }
  // The marker lists it: impactdic wrote it (e.g. an earlier version's folder).
  WriteBytes(out + "/" + kOutputMarkerName,
             ReadBytes(out + "/" + kOutputMarkerName) + std::string("kept\n"));
  const CliResult r =
      RunShell(as_user + impactdic::CliPath() + " -q run " + s.quick + " -o " + out);
  std::error_code ec;  // (Gone if the folder was replaced.)
  fs::permissions(out + "/kept", fs::perms::owner_all, ec);
  ExpectRefused(r, {out, "cannot replace it", "kept"});
  EXPECT_TRUE(TemporariesOf(dir.path(), "out").empty());
  EXPECT_TRUE(fs::exists(out + "/results.h5"));
}

// Item 10: `render RUN/results.h5` draws from the preview results.h5 stores (at most 16 of the
// 20 frames): it writes its animation under its own name and keeps the run's, drawn from every
// frame.
TEST(OutputOwnership, RenderOfAPreviewKeepsTheRunsAnimation) {
  TestDir dir;
  // 20 frames: more than the 16 a results.h5 stores by default; with its animation.
  const CliResult synth = RunCli("-q synth --preset tiny --frames 20 -o " + dir.File("scene"));
  ASSERT_EQ(synth.exit_code, 0) << synth.output;
  const std::string run = dir.File("run");
  ASSERT_EQ(RunCli("-q run " + dir.File("scene/scene.yaml") + " -o " + run).exit_code, 0);
  const auto before = Fingerprint(run);
  ASSERT_EQ(before.count("velocity.mp4"), 1u);
  const CliResult r = RunCli("render " + run + "/results.h5 --no-figures");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto after = Fingerprint(run);
  EXPECT_EQ(after.at("velocity.mp4"), before.at("velocity.mp4"));
  EXPECT_EQ(after.at("velocity_field_te.png"), before.at("velocity_field_te.png"));
  EXPECT_EQ(after.count("velocity_preview.mp4"), 1u);
  EXPECT_NE(r.output.find(" of 20, downsampled"), std::string::npos) << r.output;
  EXPECT_EQ(CountVideoFrames(run + "/velocity.mp4"), 20u);
  EXPECT_LT(CountVideoFrames(run + "/velocity_preview.mp4"), 20u);
}

// A preview that stores every 4th frame has no frame at the sample's t_e (3.33 ms, analysed frame
// 6): the snapshot and the strain map are drawn at the nearest stored frame and say so, not
// "t_e = 3.33 ms" over the 2.22 ms frame.
TEST(OutputOwnership, RenderOfAPreviewSaysWhichFrameItDrawsForTe) {
  TestDir dir;
  const std::string run = dir.File("run");
  const CliResult ran = RunCli("-q run " + kSource +
                               "/sample_frames/scene.yaml --outputs.frames preview "
                               "--outputs.animation false --outputs.figures false -o " +
                               run);
  ASSERT_EQ(ran.exit_code, 0) << ran.output;
  const CliResult r = RunCli("render " + run + "/results.h5 --no-figures");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const std::string what : {"velocity field", "strain"}) {
    EXPECT_NE(r.output.find("no stored frame at t_e = 3.12 ms: the " + what +
                            " is drawn at the nearest, t = 2.22 ms"),
              std::string::npos)
        << r.output;
  }
  EXPECT_TRUE(fs::exists(run + "/velocity_field_te_preview.png"));
}

// Messages: an over-long output name, an empty -o, and info lines naming the staging folder.
TEST(OutputOwnership, OutputNameMessagesSayWhatIsWrong) {
  const Scenes& s = Prepare();
  ASSERT_TRUE(s.error.empty()) << s.error;
  TestDir dir;
  const std::string long_name = dir.File(std::string(240, 'x'));
  const std::string message =
      ExpectCliFailure("-q run " + s.quick + " -o " + long_name,
                       {"-o", "240 bytes", "at most 225 bytes", "the file system allows 255"});
  EXPECT_EQ(message.find("holds the input"), std::string::npos) << message;
  ExpectCliFailure("-q run " + s.quick + " -o ''", {"-o", "an empty name"});
  ExpectCliFailure("-q render " + dir.File("none.h5") + " -o ''", {"-o", "an empty name"});
  EXPECT_FALSE(fs::exists(s.dir->File("scene/results")));
  // The animation's info line names the folder the user asked for.
  const CliResult r = RunCli("run " + s.dir->File("scene/scene.yaml") + " -o " + dir.File("o"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("animation: " + dir.File("o") + "/velocity.mp4"), std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find(".tmp-"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace impactdic
