// One command's outputs in a folder are one generation: whatever happens to a run (an error,
// SIGINT, SIGTERM, SIGKILL), the folder holds either all files of the previous generation or all
// files of the new one, never a mix. Used by every command that writes a set of files into a
// folder (run, render, synth -o DIR, campaign -o DIR).
//
//   OutputGenerationOptions o;
//   o.command = "impactdic run";
//   o.own_names = {"results.h5", "summary.json"};
//   OutputGeneration out("results/t10", o);   // checks the folder, makes
//   results/.t10.tmp-<pid>-<hex>/ WriteResults(out.Path("results.h5"));      // everything goes
//   into that staging folder out.Commit();                              // swaps it in; without
//   Commit the destructor removes it
//
// The swap: the staging folder and the destination are exchanged in one atomic step
// (renameat2 RENAME_EXCHANGE), then the previous generation (now under the staging name) is
// removed. Where the file system cannot exchange, the destination is renamed to
// ".<name>.bak-<pid>-<hex>", the staging folder renamed in and the backup removed; if the second
// rename fails the backup is renamed back, and after a SIGKILL between the two renames the next
// process writing there renames it back (RemoveStaleTemporaries). SIGINT/SIGTERM during the swap
// wait for it to end (core/interrupt.h).
//
// Ownership: the tool replaces only folders it wrote. The destination may be missing or empty, or
// hold only what impactdic writes: entries listed in its marker file `.impactdic-output` (written
// last into every generation), the command's own names (folders of an older impactdic, which wrote
// no marker), folders holding a marker (nested outputs, e.g. a run's results inside a synth
// folder, or a campaign's scene folders) and impactdic temporaries. Anything else (a user's file)
// makes the command fail before any work, naming the entries; nothing is deleted.
//
// Kinds: the marker records which command wrote the folder and its kind ("run", "synth",
// "campaign", "campaign test", "render"). A folder of another kind (a campaign under `run -o`, a
// synth scene under `run -o` or `campaign -o`, a run under `synth -o`), or one holding nested
// outputs of a kind the command does not nest (`run -o results` over results/t10/, a run of its
// own), is refused before any work, naming the command that wrote it and some of its entries,
// unless `force` (the CLI's --force). A user's files are never replaced, even with `force`.
//
// One writer at a time: the generation holds an flock on ".<name>.lock" beside the folder from
// its construction to its destruction (the file holds the writer's pid and command, and is
// removed again); a second writer of the same folder, in this process or another, is refused
// naming the first one's pid.
#ifndef IMPACTDIC_IO_OUTPUT_GENERATION_H_
#define IMPACTDIC_IO_OUTPUT_GENERATION_H_

#include <optional>
#include <string>
#include <vector>

#include "impactdic/core/interrupt.h"

namespace impactdic {

// The marker file in every generation: what wrote it and when, and the entries it holds.
inline constexpr const char* kOutputMarkerName = ".impactdic-output";

struct OutputGenerationOptions {
  std::string command;  // What writes the folder, e.g. "impactdic run" (recorded in the marker).
  // The top-level entries this command writes (file or folder names).
  std::vector<std::string> own_names;
  // More names that count as impactdic's in a folder without a marker (e.g. render into a run's
  // folder written by an older impactdic: results.h5, summary.json).
  std::vector<std::string> known_names;
  // false: the new generation is exactly what the command wrote; the previous one goes whole.
  // true: it also keeps the previous generation's entries that are not among own_names (as hard
  // links, else copies), for commands that redo part of a folder (render, campaign --from-table).
  bool keep_other_entries = false;
  // false: swap by two renames and a backup even where the file system can exchange atomically
  // (what file systems without RENAME_EXCHANGE get; tests use it to cover that path).
  bool atomic_exchange = true;
  // The kind of folder this command makes, recorded in the marker; empty: derived from `command`
  // (KindOfCommand: "impactdic campaign (test t1)" -> "campaign test").
  std::string kind;
  // Other kinds of folder it replaces without `force` (render: "run", run: "render"). A command
  // that keeps other entries and replaces such a folder keeps its kind (render into a run's
  // folder: still a run).
  std::vector<std::string> replaces_kinds;
  // Kinds of generation that may sit in the folder as entries of their own without being listed
  // by its marker (campaign: "campaign test", its tests' folders).
  std::vector<std::string> nested_kinds;
  // Replace a folder of another kind, or holding nested outputs of other kinds, too (--force).
  bool force = false;
};

// The kind of folder a command writes: "impactdic run" -> "run", "impactdic synth --realistic" ->
// "synth", "impactdic campaign (merge)" -> "campaign", "impactdic campaign (test t1)" ->
// "campaign test"; a command without the "impactdic " prefix is its own kind.
std::string KindOfCommand(const std::string& command);

// What `.impactdic-output` in `folder` says: whether there is one, the kind and command that
// wrote the folder, when (UTC) and the entries it lists.
struct OutputMarker {
  bool present = false;
  std::string kind, command, written_utc;
  std::vector<std::string> entries;
};
OutputMarker ReadOutputMarker(const std::string& folder);

// Error kInvalidValue naming `option` unless `path` can name an output folder: not empty, and
// each part of it short enough for the file system (NAME_MAX, 255 bytes on Linux), its last
// part short enough to stage it as ".NAME.tmp-<pid>-<hex>" beside it (NAME_MAX - 30 bytes).
void CheckOutputFolderName(const std::string& path, const std::string& option);

// The lock file of an output folder "<parent>/.<name>.lock" (the generation's flock).
std::string OutputLockPath(const std::string& folder);

// An flock on the lock file of an output folder (OutputLockPath), held while this exists: the
// file holds "process <pid> (`<command>`, since <UTC>)" and is removed again at the end. Error
// kIo naming `folder` and the holder if another writer (process or object) holds it.
class OutputFolderLock {
 public:
  OutputFolderLock(const std::string& folder, const std::string& command);
  ~OutputFolderLock();
  OutputFolderLock(const OutputFolderLock&) = delete;
  OutputFolderLock& operator=(const OutputFolderLock&) = delete;

 private:
  std::string path_;
  int fd_ = -1;  // Holds the flock while >= 0.
  std::optional<RemoveOnInterrupt> guard_;
};

class OutputGeneration {
 public:
  // Creates the parent folders if needed, removes stale temporaries of dead processes beside the
  // destination and in TMPDIR, checks that the destination may be replaced and makes the staging
  // folder.
  // Error kInvalidValue for a destination that is a file or holds entries impactdic did not
  // write (named), kIo for a parent folder that cannot be created or written.
  OutputGeneration(const std::string& folder, OutputGenerationOptions options);
  // Without Commit(): removes the staging folder; the previous generation stays as it was.
  ~OutputGeneration();
  OutputGeneration(const OutputGeneration&) = delete;
  OutputGeneration& operator=(const OutputGeneration&) = delete;

  const std::string& folder() const { return folder_; }           // The destination, as given.
  const std::string& staging_folder() const { return staging_; }  // Where the outputs go.
  std::string Path(const std::string& name) const;                // staging_folder()/name
  // A path inside the staging folder as it is named once committed (other paths unchanged).
  std::string FinalPath(const std::string& path) const;

  // Writes the marker, then swaps the new generation in and removes the previous one. Error kIo
  // (the previous generation intact) if the swap fails or foreign entries appeared meanwhile.
  void Commit();
  bool committed() const { return committed_; }

 private:
  std::vector<std::string> ForeignEntries() const;
  std::string OwnKind() const;
  void CheckReplaceable();
  void CheckKinds(const OutputMarker& marker) const;
  void CheckRemovable() const;
  void WarnOfUnmarkedEntries() const;
  void CarryOverPrevious() const;
  void WriteMarker() const;
  void SwapIn(bool had_previous);

  std::string folder_;       // As given (for messages and FinalPath).
  std::string destination_;  // Absolute.
  std::string staging_;      // Absolute: <parent>/.<name>.tmp-<pid>-<hex>
  OutputGenerationOptions options_;
  std::optional<RemoveOnInterrupt> staging_guard_;
  std::string kind_;  // Written into the marker.
  // --force over a folder of another kind: its entries, which keep_other_entries does not keep.
  std::vector<std::string> dropped_entries_;
  std::optional<OutputFolderLock> lock_;  // From the checks to the end: one writer at a time.
  bool committed_ = false;
};

// A path inside the staging folder of a generation alive in this process, named as it will be
// once committed (nested generations too); other paths unchanged. Error messages name files so:
// the user looks for DIR/truth.h5, not for the staging folder that is gone by then.
std::string OutputPathForMessages(std::string path);

// Removes, in `folder`, the temporaries of processes that no longer exist (ProcessIsGone):
// entries named ".<name>.tmp-<pid>-<hex>..." (AtomicFile, staging folders, files being rendered),
// and a backup ".<name>.bak-<pid>-<hex>" of an interrupted swap, which is renamed back to <name>
// if that is missing (the previous generation returns) and removed otherwise. Done once per folder
// and process; never fails (what cannot be removed stays). Returns the entries it removed or
// restored.
std::vector<std::string> RemoveStaleTemporaries(const std::string& folder);

// The same for the system temporary folder (TMPDIR, else /tmp): files "impactdic-<pid>-<hex>..."
// (gnuplot scripts, data and logs) of processes that no longer exist.
std::vector<std::string> RemoveStaleSystemTemporaries();

// The one way an impactdic temporary is named: ".<base><kind><pid>-<hex>", kind ".tmp-" (a file or
// folder being written) or ".bak-" (the previous generation during a swap). The pid tells a later
// process whether its maker still runs (RemoveStaleTemporaries).
std::string TemporaryName(const std::string& base, const char* kind = ".tmp-");

// A folder of outputs written as one generation (`run`'s, a campaign test's results/: its
// summary.json, figures and results.h5 describe one analysis) is never changed file by file: a
// command that writes one file (`analyze`) writes its own file instead. Error kInvalidValue naming
// `option` if `path` (the file it would write) lies in such a folder (one with a summary.json or
// a kOutputMarkerName).
void CheckNotInAGeneration(const std::string& path, const std::string& option);

// True for the name of an impactdic temporary (".<name>.tmp-<pid>-<hex>...",
// ".<name>.bak-<pid>-<hex>") or an output folder's lock file (".<name>.lock"), whoever made it.
bool IsTemporaryName(const std::string& name);

}  // namespace impactdic

#endif  // IMPACTDIC_IO_OUTPUT_GENERATION_H_
