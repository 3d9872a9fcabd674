// The number of worker threads: one rule for every command, option and scene key.
//   0      all cores (the default)
//   N >= 1 at most N threads
// Anything else (e.g. -1) is an error naming the option.
#ifndef IMPACTDIC_CORE_THREADS_H_
#define IMPACTDIC_CORE_THREADS_H_

#include <memory>
#include <string>

namespace impactdic {

// What a thread count may be, for messages and help texts.
inline constexpr const char* kThreadCountExpected = "0 (all cores) or a number of threads >= 1";

inline bool IsValidThreadCount(int threads) { return threads >= 0; }

// Error(kInvalidValue, where, threads, kThreadCountExpected) unless IsValidThreadCount(threads).
void CheckThreadCount(int threads, const std::string& where);

// The cores this process may run on (oneTBB's default concurrency: the CPU affinity mask), >= 1.
int MachineCores();

// The one rule of every command, option and scene key that asks for threads (`--threads`,
// `dic.threads`, `campaign --jobs`): 0 gives MachineCores(); N gives min(N, MachineCores()). A
// request above the cores is capped (more threads than cores only cost memory and switching, and
// 100000 of them exhaust the process table), logged once per `where` and count at info level:
// "WHERE: 100000 threads requested; this machine has 2 cores: using 2". `threads` must be valid
// (asserted; CheckThreadCount first).
int ThreadsToUse(int threads, const std::string& where);

// While it lives, oneTBB runs at most ThreadsToUse(threads, where) threads (a
// tbb::global_control); with threads 0 (all cores) it sets nothing. Use it wherever a command
// limits its parallelism: the only place a thread count reaches oneTBB.
class ThreadLimit {
 public:
  ThreadLimit(int threads, const std::string& where);
  ~ThreadLimit();
  ThreadLimit(const ThreadLimit&) = delete;
  ThreadLimit& operator=(const ThreadLimit&) = delete;
  int threads() const { return threads_; }  // The threads allowed (MachineCores() with 0).

 private:
  struct Control;  // oneTBB's global_control (its header stays out of ours).
  std::unique_ptr<Control> control_;
  int threads_ = 0;
};

// Holds oneTBB's worker threads (ours and OpenCV's) for its lifetime and joins them when
// destroyed, so that none is still exiting when exit-time code runs (a process's main, a test
// program's environment). Otherwise only a static destructor tells them to stop, and at exit:
//  - LeakSanitizer's stop-the-world can read the stack of a worker being unmapped and crash
//    (a failure of the sanitizer, not of the program);
//  - what a library keeps in a worker's thread-specific data is lost: libsrt (FFmpeg's, loaded
//    with the OpenCV video plugin) keeps a 120-byte error object there for the thread that
//    loaded it and frees it only when that thread exits, so a worker left running leaks it.
// OpenCV's own task_arena is terminated first (cv::setNumThreads(0)): OpenCV must not be used
// after Join. At debug level it logs whether the workers were joined and how many threads are
// still alive afterwards (from /proc; -1 without it).
class WorkerThreadsJoinedAtExit {
 public:
  WorkerThreadsJoinedAtExit();
  ~WorkerThreadsJoinedAtExit();
  WorkerThreadsJoinedAtExit(const WorkerThreadsJoinedAtExit&) = delete;
  WorkerThreadsJoinedAtExit& operator=(const WorkerThreadsJoinedAtExit&) = delete;

  // Joins the workers now (once); false when oneTBB could not (a thread or an arena of another
  // library is still attached to it: the workers are then left to the library).
  bool Join();

 private:
  struct Handle;  // oneTBB's task_scheduler_handle (its header stays out of ours).
  std::unique_ptr<Handle> handle_;
};

}  // namespace impactdic

#endif  // IMPACTDIC_CORE_THREADS_H_
