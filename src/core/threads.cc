#include "impactdic/core/threads.h"

#include <tbb/global_control.h>

#include <cstddef>
#include <filesystem>
#include <iterator>
#include <memory>
#include <new>
#include <opencv2/core.hpp>
#include <system_error>

#include "impactdic/core/error.h"
#include "impactdic/core/log.h"

namespace impactdic {

void CheckThreadCount(int threads, const std::string& where) {
  CheckValue(IsValidThreadCount(threads), where, std::to_string(threads), kThreadCountExpected);
}

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
