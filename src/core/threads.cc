#include "impactdic/core/threads.h"

#include <tbb/global_control.h>

#include <cstddef>
#include <filesystem>
#include <iterator>
#include <memory>
#include <new>
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
