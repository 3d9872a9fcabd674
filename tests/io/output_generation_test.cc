// OutputGeneration: a command's outputs replace the previous ones as one set, and only in folders
// impactdic wrote; stale temporaries of dead processes are removed or (a swap's backup) restored.
#include "impactdic/io/output_generation.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <map>
#include <set>
#include <string>

#include "../core/expect_error.h"
#include "impactdic/core/interrupt.h"
#include "impactdic/io/atomic_file.h"
#include "test_dir.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

// The pid of a process that has just ended (and was reaped): no process has it now.
long DeadPid() {
  const pid_t child = fork();
  if (child == 0) _exit(0);
  int status = 0;
  waitpid(child, &status, 0);
  return child;
}

std::set<std::string> Entries(const fs::path& folder) {
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(folder)) names.insert(e.path().filename().string());
  return names;
}

std::string Read(const fs::path& file) { return ReadTextFile(file.string()); }

OutputGenerationOptions RunLike() {
  OutputGenerationOptions o;
  o.command = "test";
  o.own_names = {"a.txt", "b.txt", "figs"};
  return o;
}

// Writes a generation holding `files` (name -> text) into `folder`.
void WriteGeneration(const std::string& folder, const std::map<std::string, std::string>& files,
                     OutputGenerationOptions options = RunLike()) {
  OutputGeneration g(folder, options);
  for (const auto& [name, text] : files) WriteTextFileAtomic(g.Path(name), text);
  g.Commit();
}

// Entries of `parent` that are temporaries (staging folders, backups) of `name`.
std::set<std::string> TemporariesOf(const fs::path& parent, const std::string& name) {
  std::set<std::string> found;
  for (const auto& e : Entries(parent)) {
    if (e.rfind("." + name + ".tmp-", 0) == 0 || e.rfind("." + name + ".bak-", 0) == 0)
      found.insert(e);
  }
  return found;
}

TEST(OutputGeneration, CommitReplacesThePreviousGenerationWhole) {
  TestDir dir;
  const std::string out = dir.File("out");
  WriteGeneration(out, {{"a.txt", "old a"}, {"b.txt", "old b"}});
  EXPECT_EQ(Entries(out), (std::set<std::string>{".impactdic-output", "a.txt", "b.txt"}));
  // The new generation has no b.txt: the old one must not stay beside the new a.txt.
  WriteGeneration(out, {{"a.txt", "new a"}});
  EXPECT_EQ(Entries(out), (std::set<std::string>{".impactdic-output", "a.txt"}));
  EXPECT_EQ(Read(fs::path(out) / "a.txt"), "new a");
  const std::string marker = Read(fs::path(out) / ".impactdic-output");
  EXPECT_NE(marker.find("\na.txt\n"), std::string::npos) << marker;
  EXPECT_EQ(marker.find("b.txt"), std::string::npos) << marker;
  EXPECT_TRUE(TemporariesOf(dir.path(), "out").empty());
}

TEST(OutputGeneration, WithoutCommitThePreviousGenerationStaysAndStagingGoes) {
  TestDir dir;
  const std::string out = dir.File("out");
  WriteGeneration(out, {{"a.txt", "old a"}, {"b.txt", "old b"}});
  std::string staging;
  {
    OutputGeneration g(out, RunLike());
    staging = g.staging_folder();
    WriteTextFileAtomic(g.Path("a.txt"), "new a");
    EXPECT_TRUE(fs::is_directory(staging));
    EXPECT_EQ(fs::path(staging).parent_path(), dir.path());
    EXPECT_EQ(Read(fs::path(out) / "a.txt"), "old a");  // Nothing visible before the commit.
  }
  EXPECT_FALSE(fs::exists(staging));
  EXPECT_EQ(Read(fs::path(out) / "a.txt"), "old a");
  EXPECT_EQ(Read(fs::path(out) / "b.txt"), "old b");
  EXPECT_TRUE(TemporariesOf(dir.path(), "out").empty());
}

TEST(OutputGeneration, ANewFolderIsCreatedWithItsParents) {
  TestDir dir;
  const std::string out = dir.File("x/y/out");
  OutputGeneration g(out, RunLike());
  WriteTextFileAtomic(g.Path("a.txt"), "a");
  EXPECT_FALSE(fs::exists(out));
  g.Commit();
  EXPECT_EQ(Read(fs::path(out) / "a.txt"), "a");
  EXPECT_EQ(g.FinalPath(g.Path("a.txt")), (fs::path(out) / "a.txt").string());
  EXPECT_EQ(g.FinalPath("/elsewhere/a.txt"), "/elsewhere/a.txt");
}

TEST(OutputGeneration, RefusesAFolderHoldingFilesItDidNotWrite) {
  TestDir dir;
  const std::string out = dir.File("out");
  fs::create_directories(out);
  dir.Write("out/notes.txt", "the user's notes");
  dir.Write("out/a.txt", "a file named like an output");
  ExpectErrorContaining([&] { const OutputGeneration g(out, RunLike()); },
                        "1 entry impactdic did not write: 'notes.txt'");
  EXPECT_EQ(Read(fs::path(out) / "notes.txt"), "the user's notes");
  EXPECT_EQ(Read(fs::path(out) / "a.txt"), "a file named like an output");
  EXPECT_TRUE(TemporariesOf(dir.path(), "out").empty());
}

TEST(OutputGeneration, AcceptsEmptyOlderAndNestedOutputFolders) {
  TestDir dir;
  // Empty.
  fs::create_directories(dir.path() / "empty");
  WriteGeneration(dir.File("empty"), {{"a.txt", "a"}});
  EXPECT_EQ(Read(dir.path() / "empty" / "a.txt"), "a");
  // Written by an older impactdic (no marker): only the command's own names.
  fs::create_directories(dir.path() / "older");
  dir.Write("older/a.txt", "old");
  dir.Write("older/b.txt", "old");
  WriteGeneration(dir.File("older"), {{"a.txt", "new"}});
  EXPECT_EQ(Entries(dir.path() / "older"), (std::set<std::string>{".impactdic-output", "a.txt"}));
  // A folder holding a generation of a kind it nests (e.g. a campaign's test folders).
  WriteGeneration(dir.File("outer"), {{"a.txt", "outer"}});
  WriteGeneration(dir.File("outer/inner"), {{"a.txt", "inner"}});
  OutputGenerationOptions nesting = RunLike();
  nesting.nested_kinds = {"test"};
  WriteGeneration(dir.File("outer"), {{"b.txt", "outer 2"}}, nesting);
  EXPECT_EQ(Entries(dir.path() / "outer"), (std::set<std::string>{".impactdic-output", "b.txt"}));
}

TEST(OutputGeneration, RefusesAFile) {
  TestDir dir;
  dir.Write("file", "x");
  ExpectErrorContaining([&] { const OutputGeneration g(dir.File("file"), RunLike()); }, "a file");
}

TEST(OutputGeneration, KeepOtherEntriesCarriesThemOverAsHardLinks) {
  TestDir dir;
  const std::string out = dir.File("out");
  OutputGenerationOptions run = RunLike();
  run.own_names.push_back("results.h5");
  WriteGeneration(out, {{"results.h5", "data"}, {"a.txt", "old figure"}}, run);
  struct stat before {};
  ASSERT_EQ(stat((fs::path(out) / "results.h5").c_str(), &before), 0);
  OutputGenerationOptions render;
  render.command = "render";
  render.own_names = {"a.txt", "b.txt"};
  render.keep_other_entries = true;
  render.replaces_kinds = {"test"};  // Into the folder of a "test" command.
  WriteGeneration(out, {{"b.txt", "new figure"}}, render);
  // a.txt is render's own: not carried over (it was not drawn this time).
  EXPECT_EQ(Entries(out), (std::set<std::string>{".impactdic-output", "b.txt", "results.h5"}));
  struct stat after {};
  ASSERT_EQ(stat((fs::path(out) / "results.h5").c_str(), &after), 0);
  EXPECT_EQ(after.st_ino, before.st_ino);  // The same file, not a copy.
  EXPECT_EQ(Read(fs::path(out) / "results.h5"), "data");
  const std::string marker = Read(fs::path(out) / ".impactdic-output");
  EXPECT_NE(marker.find("\nresults.h5\n"), std::string::npos) << marker;
  EXPECT_NE(marker.find("\n# kind: test\n"), std::string::npos) << marker;  // Still its kind.
}

TEST(OutputGeneration, SwapByTwoRenamesWhereTheFileSystemCannotExchange) {
  TestDir dir;
  const std::string out = dir.File("out");
  OutputGenerationOptions o = RunLike();
  o.atomic_exchange = false;
  WriteGeneration(out, {{"a.txt", "old"}, {"b.txt", "old"}}, o);
  WriteGeneration(out, {{"a.txt", "new"}}, o);
  EXPECT_EQ(Entries(out), (std::set<std::string>{".impactdic-output", "a.txt"}));
  EXPECT_EQ(Read(fs::path(out) / "a.txt"), "new");
  EXPECT_TRUE(TemporariesOf(dir.path(), "out").empty());
}

TEST(OutputGeneration, AForeignFileAppearingDuringTheRunStopsTheSwap) {
  TestDir dir;
  const std::string out = dir.File("out");
  WriteGeneration(out, {{"a.txt", "old"}});
  OutputGeneration g(out, RunLike());
  WriteTextFileAtomic(g.Path("a.txt"), "new");
  dir.Write("out/notes.txt", "written by the user meanwhile");
  ExpectErrorContaining([&] { g.Commit(); }, "'notes.txt' appeared in it during the run");
  EXPECT_EQ(Read(fs::path(out) / "a.txt"), "old");
  EXPECT_EQ(Read(fs::path(out) / "notes.txt"), "written by the user meanwhile");
}

// What a SIGKILL leaves: a staging folder (any time before the swap) or, on a file system without
// atomic exchange, a backup of the previous generation with the destination missing or replaced.
TEST(OutputGeneration, TheNextProcessRemovesOrRestoresWhatADeadOneLeft) {
  TestDir dir;
  const long dead = DeadPid();
  const std::string tag = std::to_string(dead) + "-00000000deadbeef";
  const std::string live_tag = std::to_string(getpid()) + "-00000000deadbeef";
  // Stale staging folder of "out" and a live one.
  fs::create_directories(dir.path() / (".out.tmp-" + tag) / "sub");
  fs::create_directories(dir.path() / (".out.tmp-" + live_tag));
  // A dead swap between its two renames: "gone" is missing, its backup holds the old generation.
  fs::create_directories(dir.path() / (".gone.bak-" + tag));
  dir.Write(".gone.bak-" + tag + "/a.txt", "previous generation");
  // A dead swap after its second rename: "done" is the new generation, the backup is stale.
  fs::create_directories(dir.path() / "done");
  fs::create_directories(dir.path() / (".done.bak-" + tag));
  // A stale AtomicFile temporary and something that only looks like one (no pid tag).
  dir.Write(".summary.json.tmp-" + tag, "half written");
  dir.Write(".notes.tmp-keep", "user file");

  OutputGeneration g(dir.File("out"), RunLike());
  EXPECT_FALSE(fs::exists(dir.path() / (".out.tmp-" + tag)));
  EXPECT_TRUE(fs::exists(dir.path() / (".out.tmp-" + live_tag)));  // Its process runs (us).
  EXPECT_EQ(Read(dir.path() / "gone" / "a.txt"), "previous generation");
  EXPECT_FALSE(fs::exists(dir.path() / (".gone.bak-" + tag)));
  EXPECT_TRUE(fs::is_directory(dir.path() / "done"));
  EXPECT_FALSE(fs::exists(dir.path() / (".done.bak-" + tag)));
  EXPECT_FALSE(fs::exists(dir.path() / (".summary.json.tmp-" + tag)));
  EXPECT_TRUE(fs::exists(dir.path() / ".notes.tmp-keep"));
}

// Errors about a file being written into a generation name it where the user will look for it,
// never the staging folder that is gone when the message is read.
TEST(OutputGeneration, WritersNameFilesByTheirFinalPath) {
  TestDir dir;
  const std::string out = dir.File("out");
  OutputGeneration g(out, RunLike());
  const std::string text = ErrorText([&] { WriteTextFileAtomic(g.Path("figs/a.txt"), "x"); });
  EXPECT_NE(text.find(out + "/figs/a.txt"), std::string::npos) << text;
  EXPECT_EQ(text.find(".tmp-"), std::string::npos) << text;
}

TEST(OutputGeneration, TemporaryNamesCarryTheirProcess) {
  EXPECT_TRUE(IsTemporaryName(TemporaryName("results.h5")));
  EXPECT_TRUE(IsTemporaryName(TemporaryName("out", ".bak-")));
  const std::string tag = TemporaryTag();
  EXPECT_EQ(TemporaryTagPid(".x.tmp-" + tag, ".x.tmp-"), getpid());
  EXPECT_EQ(TemporaryTagPid(".x.tmp-" + tag + ".png", ".x.tmp-"), getpid());
  EXPECT_EQ(TemporaryTagPid(".x.tmp-keep", ".x.tmp-"), 0);
  EXPECT_EQ(TemporaryTagPid(".x.tmp-12-", ".x.tmp-"), 0);
  EXPECT_TRUE(IsTemporaryName(".results.h5.tmp-" + tag));
  EXPECT_TRUE(IsTemporaryName(".out.bak-" + tag));
  EXPECT_FALSE(IsTemporaryName("results.h5"));
  EXPECT_FALSE(IsTemporaryName(".tmp-" + tag));  // No name before the marker.
  EXPECT_FALSE(ProcessIsGone(getpid()));
  EXPECT_TRUE(ProcessIsGone(DeadPid()));
}

}  // namespace
}  // namespace impactdic
