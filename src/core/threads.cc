#include "impactdic/core/threads.h"

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <algorithm>
#include <cassert>
#include <cstddef>
#include <filesystem>
#include <iterator>
#include <memory>
#include <mutex>
#include <new>
#include <opencv2/core.hpp>
#include <set>
#include <system_error>
#include <utility>

#include "impactdic/core/error.h"
#include "impactdic/core/log.h"

namespace impactdic {

void CheckThreadCount(int threads, const std::string& where) {
  CheckValue(IsValidThreadCount(threads), where, std::to_string(threads), kThreadCountExpected);
}

int MachineCores() { return std::max(1, tbb::info::default_concurrency()); }

int ThreadsToUse(int threads, const std::string& where) {
  assert(IsValidThreadCount(threads));
  const int cores = MachineCores();
  if (threads == 0 || threads <= cores) return threads == 0 ? cores : threads;
  static std::mutex mutex;
  static std::set<std::pair<std::string, int>> logged;
  const std::lock_guard<std::mutex> lock(mutex);
  if (logged.emplace(where, threads).second) {
    LogInfo("{}: {} threads requested; this machine has {} cores: using {}", where, threads, cores,
            cores);
  }
  return cores;
}

struct ThreadLimit::Control {
  explicit Control(int threads)
      : control(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads)) {}
  tbb::global_control control;
};

ThreadLimit::ThreadLimit(int threads, const std::string& where)
    : threads_(ThreadsToUse(threads, where)) {
  if (threads > 0) control_ = std::make_unique<Control>(threads_);
}

ThreadLimit::~ThreadLimit() = default;

struct WorkerThreadsJoinedAtExit::Handle {
  tbb::task_scheduler_handle scheduler{tbb::attach{}};
};

WorkerThreadsJoinedAtExit::WorkerThreadsJoinedAtExit() : handle_(std::make_unique<Handle>()) {}

WorkerThreadsJoinedAtExit::~WorkerThreadsJoinedAtExit() { Join(); }

bool WorkerThreadsJoinedAtExit::Join() {
  if (!handle_->scheduler) return true;  // Joined before.
  // OpenCV's parallel_for_ (GaussianBlur, CLAHE, remap, ...) runs in OpenCV's own oneTBB
  // task_arena, kept until OpenCV's static destructor: while it lives, finalize cannot join.
  // Setting OpenCV to no threads terminates that arena (nothing of OpenCV runs after this).
  cv::setNumThreads(0);
  const bool joined = tbb::finalize(handle_->scheduler, std::nothrow);
  if (GetLogLevel() > LogLevel::kDebug) return joined;
  std::error_code error;
  std::ptrdiff_t alive = -1;
  if (const std::filesystem::directory_iterator tasks("/proc/self/task", error); !error) {
    alive = std::distance(tasks, std::filesystem::directory_iterator());
  }
  LogDebug("exit: oneTBB worker threads {}; threads alive: {}",
           joined ? "joined" : "still in use, not joined", alive);
  return joined;
}

}  // namespace impactdic
