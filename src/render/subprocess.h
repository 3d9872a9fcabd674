// Running a helper program (gnuplot) without a shell, capturing what it prints. Internal to render.
#ifndef IMPACTDIC_SRC_RENDER_SUBPROCESS_H_
#define IMPACTDIC_SRC_RENDER_SUBPROCESS_H_

#include <optional>
#include <string>
#include <vector>

#include "impactdic/core/interrupt.h"

namespace impactdic::render_internal {

struct ProcessResult {
  bool started = false;  // false: the program could not be executed at all
  int start_errno = 0;   // errno of the failed start
  int exit_code = -1;    // exit status; -1 if killed by a signal
  std::string output;    // stdout and stderr together
};

// Runs `program` (a path, or a name looked up in PATH) with `arguments`, stdin from /dev/null.
ProcessResult RunProcess(const std::string& program, const std::vector<std::string>& arguments);

// A file in the system temporary folder, created empty with a unique name
// "impactdic-<pid>-<hex><suffix>" and deleted by the destructor (or by the interrupt cleanup, see
// core/interrupt.h). The first one a process makes removes those of dead processes
// (RemoveStaleSystemTemporaries), e.g. what a SIGKILL during a gnuplot figure left.
class TempFile {
 public:
  explicit TempFile(const std::string& suffix);
  ~TempFile();
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  const std::string& path() const { return path_; }
  // Replaces the file's contents with `text`. Never makes the file again: after a signal's cleanup
  // removed it, waits for the process to end (core/interrupt.h). Throws WriteError on a failed
  // write (full disk).
  void Write(const std::string& text) const;

 private:
  std::string path_;
  std::optional<RemoveOnInterrupt> interrupt_guard_;
};

// A unique temporary path ".<stem>.tmp-<pid>-<hex><extension>" in the folder of `final_path`
// (extension e.g. ".mp4", so programs that choose the format from the extension still work);
// nothing is created. The caller registers it with RemoveOnInterrupt while it exists.
std::string TempSiblingPath(const std::string& final_path, const std::string& extension);

}  // namespace impactdic::render_internal

#endif  // IMPACTDIC_SRC_RENDER_SUBPROCESS_H_
