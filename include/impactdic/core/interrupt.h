// Interrupted processes remove their temporaries, and a later process can tell a dead process's
// temporary from a live one's by the process id in its name.
//
//   int main() { InstallInterruptCleanup(); ... }          // once, first thing in main
//   RemoveOnInterrupt guard(staging_folder);               // removed (recursively) on a signal
//   { DeferInterrupts swap; rename(a, b); rename(c, a); }  // a signal waits for the block's end
//   std::string name = ".results.h5.tmp-" + TemporaryTag();  // "<pid>-<hex>": whose it is
//
// SIGINT, SIGTERM and SIGHUP: the handler only writes the signal number into a pipe (async-signal
// safe); a thread started by InstallInterruptCleanup reads it, waits for a DeferInterrupts block
// to end, removes every registered path (newest first) and ends the process with exit status
// 128 + signal (130 for SIGINT, 143 for SIGTERM, 129 for SIGHUP) without running destructors. A
// signal that was ignored when the process started (nohup, `cmd &` in a script) stays ignored.
// SIGKILL cannot be caught: what it leaves is recognised by the pid in the name and removed by the
// next process that writes there (io/output_generation.h, RemoveStaleTemporaries).
// std::terminate (an error nothing caught) removes the registered paths too, unless a swap is in
// progress, then reports and aborts as before (exit by SIGABRT).
#ifndef IMPACTDIC_CORE_INTERRUPT_H_
#define IMPACTDIC_CORE_INTERRUPT_H_

#include <cstdint>
#include <string>
#include <string_view>
#include <system_error>

namespace impactdic {

// Installs the handlers (signals, std::terminate) and starts the cleanup thread (idempotent).
// Without it (library use, tests) signals keep their default action and the registrations below
// only cost a map entry.
void InstallInterruptCleanup();

// True once a handled signal arrived: the cleanup thread is about to end the process.
bool Interrupted();

// Blocks the calling thread for good if a signal arrived (the cleanup thread ends the process);
// returns at once otherwise. main calls it before returning, so that an error caused by the
// interruption never races the cleanup with its own exit.
void WaitIfInterrupted();

// std::filesystem::create_directories as one step for a signal's cleanup (which waits for it):
// after a signal it makes nothing and waits for the exit, so a folder inside a temporary the
// cleanup removed (a staging folder's frames/ or results/) is never made again. Every folder made
// inside outputs goes through it.
void MakeFolders(const std::string& path, std::error_code& ec);

// Registers `path` (a file or a folder) for removal if the process is interrupted, until Release()
// or destruction. Does not remove anything itself: the owner removes its temporary as usual. A
// thread registering a path after a signal arrived waits for the process to end instead.
class DeferInterrupts;

class RemoveOnInterrupt {
 public:
  explicit RemoveOnInterrupt(std::string path);
  // Registers without waiting: the caller holds `held`, so no cleanup can run before it ends and
  // the path can be registered and made as one step (the cleanup removes it, or it never exists).
  RemoveOnInterrupt(std::string path, const DeferInterrupts& held);
  ~RemoveOnInterrupt();
  RemoveOnInterrupt(const RemoveOnInterrupt&) = delete;
  RemoveOnInterrupt& operator=(const RemoveOnInterrupt&) = delete;
  // Stops watching the path (it was renamed into place, or removed).
  void Release();

 private:
  std::uint64_t id_ = 0;
};

// While one exists, a signal's cleanup waits: for the few renames that swap a new generation of
// outputs in, which must not be torn apart by removing one of their halves.
class DeferInterrupts {
 public:
  DeferInterrupts();
  ~DeferInterrupts();
  DeferInterrupts(const DeferInterrupts&) = delete;
  DeferInterrupts& operator=(const DeferInterrupts&) = delete;
};

// Records that the outputs at `path` are complete and in place (a generation swapped in), so that
// an interruption's message can say which output folders hold new outputs. Ignored for a path
// inside a registered temporary (e.g. a campaign's scene folder inside the campaign's staging
// folder). Never waits (may be called inside a DeferInterrupts block).
void NoteOutputsComplete(const std::string& path);

// "<pid>-<16 hex digits>": the part of a temporary name that says which process made it.
std::string TemporaryTag();

// The pid of a temporary name that is `prefix` followed by a tag ("<pid>-<hex>", then anything),
// or 0 if `name` has no such form.
long TemporaryTagPid(std::string_view name, std::string_view prefix);

// True if `path` is `folder` or lies below it, comparing the strings ("a/b" is inside "a", "ab"
// is not): for paths made the same way (absolute and normal, or both as given).
bool IsSameOrInside(std::string_view path, std::string_view folder);

// True if no process with this pid exists on this machine (kill(pid, 0) fails with ESRCH). A pid
// that was reused by a new process counts as alive: its temporaries stay (never wrongly removed).
bool ProcessIsGone(long pid);

}  // namespace impactdic

#endif  // IMPACTDIC_CORE_INTERRUPT_H_
