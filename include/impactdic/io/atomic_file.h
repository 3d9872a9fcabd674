// Writes an output under a temporary name in the same folder and renames it to the final name
// only on Commit(), so an interrupted run never leaves a file that looks finished.
//
//   AtomicFile out("results/summary.json");
//   WriteStuff(out.temp_path());
//   out.Commit();            // rename(temp, final); without it the destructor deletes temp
//
// The temporary is named ".<name>.tmp-<pid>-<hex>": SIGINT/SIGTERM remove it (core/interrupt.h),
// and the first AtomicFile a process makes in a folder removes those of dead processes there
// (RemoveStaleTemporaries in io/output_generation.h), e.g. what a SIGKILL left.
#ifndef IMPACTDIC_IO_ATOMIC_FILE_H_
#define IMPACTDIC_IO_ATOMIC_FILE_H_

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/interrupt.h"

namespace impactdic {

class RemoveOnInterrupt;

class AtomicFile {
 public:
  // Checks that the folder of `final_path` exists and is writable (Error kIo otherwise).
  explicit AtomicFile(std::string final_path);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  const std::string& temp_path() const { return temp_path_; }
  const std::string& final_path() const { return final_path_; }
  // Renames the temporary file to the final name (replacing an older file of that name).
  void Commit();
  bool committed() const { return committed_; }

 private:
  std::string final_path_, temp_path_;
  bool committed_ = false;
  std::unique_ptr<RemoveOnInterrupt> interrupt_guard_;
};

// What AtomicFile(path) checks, without writing anything: Error kIo naming `path` unless its
// folder exists and is writable. For commands that check their outputs before any work.
void CheckOutputLocation(const std::string& path);

// What a command promises about one output file, checked before any work.
struct OutputRules {
  std::string option;                   // the option naming the output ("-o"), for the messages
  std::vector<std::string> extensions;  // allowed endings, lower case with the dot; empty = any
  std::vector<std::string> inputs;      // files the command reads: the output is none of them
  // How the text files this command writes begin (a CSV header "t_s,z_m,...", the calibration's
  // "# impactdic camera calibration"): an existing .csv/.json/.yaml/.yml output whose first line
  // begins with none of them was not written by it (an accelerometer record, a scene) and is kept.
  std::vector<std::string> own_first_lines;
};

// Error kInvalidValue naming `option` and `output` if `output` is one of `inputs` (the same
// file under any name: std::filesystem::equivalent). A missing output is none of them.
void CheckNotAnInput(const std::string& output, const std::string& option,
                     const std::vector<std::string>& inputs);

// CheckOutputLocation(path), then the rules, each an Error kInvalidValue naming the option and
// the path: the extension (case-insensitive) is one of rules.extensions; the output is not one
// of rules.inputs (the same file under any name: std::filesystem::equivalent); an existing
// .h5/.hdf5 output is an HDF5 file (its other groups will be kept, see H5Writer), and an existing
// text output (.csv, .json, .yaml, .yml) begins with one of rules.own_first_lines: never a file
// of another kind that writing would destroy.
void CheckOutputLocation(const std::string& path, const OutputRules& rules);

// Writes a file atomically in pieces, for outputs built while they are written (a CSV of every
// subset of every frame) rather than held whole in memory first: Write() collects the bytes and
// passes them on in blocks of kBlockBytes with checked POSIX writes to a temporary sibling;
// Commit() writes the rest, syncs it to the disk and renames it to `path`. Any failure (a full
// disk, a quota, an I/O error) throws WriteError(path, errno); the temporary is removed when the
// writer is destroyed uncommitted, and an existing file of that name is kept.
//
//   AtomicStreamWriter out("rows.csv");
//   for (...) out.Write(line);
//   out.Commit();
class AtomicStreamWriter {
 public:
  static constexpr std::size_t kBlockBytes = std::size_t{1} << 20;
  explicit AtomicStreamWriter(const std::string& path);
  ~AtomicStreamWriter();
  AtomicStreamWriter(const AtomicStreamWriter&) = delete;
  AtomicStreamWriter& operator=(const AtomicStreamWriter&) = delete;

  void Write(const void* data, std::size_t size);
  void Write(const std::string& text) { Write(text.data(), text.size()); }
  void Commit();

 private:
  void Flush();
  AtomicFile file_;
  int fd_ = -1;
  std::string buffer_;
};

// Writes `size` bytes to `path` atomically (AtomicStreamWriter, in one piece): a temporary
// sibling is written with checked POSIX writes, synced to the disk and renamed. Any failure (a
// full disk, a quota, an I/O error) throws WriteError(path, errno) and removes the temporary
// file; an existing file of that name is kept.
void WriteFileAtomic(const std::string& path, const void* data, std::size_t size);

// Writes `text` to `path` atomically (WriteFileAtomic).
void WriteTextFileAtomic(const std::string& path, const std::string& text);

// The one message for a failed write of `path` with the system's error number: Error kIo naming
// the file, e.g. "out/results.h5: cannot write: no space left on device; free space there or
// choose another output folder". For writers that get errno from elsewhere (a helper program).
Error WriteError(const std::string& path, int error_number);

// True when the file system holding `path` has no block left for this process (root may use
// the reserved blocks): how a failed write of a helper program or library that does not report
// its errors (gnuplot, the video writer) is told apart from other failures.
bool DiskFull(const std::string& path);

// Reads a whole text file (io/input_file.h: a regular file of at most kMaxTextFileBytes); Error
// naming the file otherwise.
std::string ReadTextFile(const std::string& path);

}  // namespace impactdic

#endif  // IMPACTDIC_IO_ATOMIC_FILE_H_
