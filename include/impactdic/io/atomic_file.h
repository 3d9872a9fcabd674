// Writes an output under a temporary name in the same folder and renames it to the final name
// only on Commit(), so an interrupted run never leaves a file that looks finished.
//
//   AtomicFile out("results/summary.json");
//   WriteStuff(out.temp_path());
//   out.Commit();            // rename(temp, final); without it the destructor deletes temp
#ifndef IMPACTDIC_IO_ATOMIC_FILE_H_
#define IMPACTDIC_IO_ATOMIC_FILE_H_

#include <string>

namespace impactdic {

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
};

// What AtomicFile(path) checks, without writing anything: Error kIo naming `path` unless its
// folder exists and is writable. For commands that check their outputs before any work.
void CheckOutputLocation(const std::string& path);

// Writes `text` to `path` atomically.
void WriteTextFileAtomic(const std::string& path, const std::string& text);

// Reads a whole text file (io/input_file.h: a regular file of at most kMaxTextFileBytes); Error
// naming the file otherwise.
std::string ReadTextFile(const std::string& path);

}  // namespace impactdic

#endif  // IMPACTDIC_IO_ATOMIC_FILE_H_
