#include "impactdic/core/interrupt.h"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstddef>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <iterator>
#include <map>
#include <mutex>
#include <random>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

namespace impactdic {
namespace fs = std::filesystem;
namespace {

std::atomic<bool> g_interrupted{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler needs a lock-free flag");
int g_pipe[2] = {-1, -1};  // The handler writes the signal number into g_pipe[1].

// The cleanup thread may wake while the process exits (after main returned), so what it uses is
// never destroyed: these are allocated once and left to the operating system.
std::mutex& RegistryMutex() {
  static auto* m = new std::mutex;
  return *m;
}
std::map<std::uint64_t, std::string>& Registry() {
  static auto* paths = new std::map<std::uint64_t, std::string>;
  return *paths;
}
std::uint64_t g_next_id = 1;             // Guarded by RegistryMutex().
std::vector<std::string>& Completed() {  // Guarded by RegistryMutex().
  static auto* paths = new std::vector<std::string>;
  return *paths;
}

std::mutex& DeferMutex() {
  static auto* m = new std::mutex;
  return *m;
}

[[noreturn]] void ParkForever() {
  for (;;) std::this_thread::sleep_for(std::chrono::hours(1));
}

extern "C" void OnSignal(int signal_number) {
  const int saved_errno = errno;
  g_interrupted.store(true);
  const unsigned char byte = static_cast<unsigned char>(signal_number);
  // Nothing to do if the pipe is full: one byte is enough to start the cleanup.
  [[maybe_unused]] const ssize_t written = write(g_pipe[1], &byte, 1);
  errno = saved_errno;
}

void WriteStderr(const std::string& text) {
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = write(STDERR_FILENO, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;
    done += static_cast<std::size_t>(n);
  }
}

// Removes `path`; a file another thread or a child process (gnuplot) creates in a folder while it
// is being removed makes the first attempt fail, so try a few times.
bool RemoveWithRetries(const std::string& path) {
  for (int attempt = 0; attempt < 5; ++attempt) {
    std::error_code ec;
    fs::remove_all(path, ec);
    if (!fs::exists(fs::symlink_status(path, ec))) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

[[noreturn]] void CleanupAfterSignal(int read_fd) {
  unsigned char byte = 0;
  while (read(read_fd, &byte, 1) != 1) {
    if (errno != EINTR) ParkForever();  // The pipe broke: behave as if no handler existed.
  }
  const int signal_number = byte;
  // A swap in progress ends first; then nothing swaps any more (the lock is never released).
  DeferMutex().lock();
  std::vector<std::string> paths, completed;
  {
    std::lock_guard<std::mutex> lock(RegistryMutex());
    for (auto it = Registry().rbegin(); it != Registry().rend(); ++it) paths.push_back(it->second);
    completed = Completed();
  }
  std::size_t removed = 0;
  std::string left;
  for (const auto& p : paths) {
    if (RemoveWithRetries(p))
      ++removed;
    else
      left += "\n  could not remove " + p;
  }
  const char* name = signal_number == SIGINT    ? "SIGINT"
                     : signal_number == SIGTERM ? "SIGTERM"
                     : signal_number == SIGHUP  ? "SIGHUP"
                                                : "a signal";
  std::string state = "the output folders hold their earlier contents";
  if (!completed.empty()) {
    std::string list;
    for (const auto& c : completed) list += (list.empty() ? "" : ", ") + c;
    state += ", except " + list + ", whose new outputs were complete and stay";
  }
  WriteStderr("\nimpactdic: interrupted by " + std::string(name) + ": removed " +
              std::to_string(removed) + " temporary output(s); " + state + left + "\n");
  _exit(128 + signal_number);
}

std::terminate_handler g_previous_terminate = nullptr;

// std::terminate (an exception nothing caught: a library that could not start a thread, a
// noexcept function that threw) ends the process without unwinding, so no destructor removes the
// temporaries: remove the registered ones here, then let the previous handler report the error
// and abort. A swap in progress (DeferInterrupts held, maybe by the failing thread itself) is
// never torn apart: then nothing is removed (the next impactdic removes what a dead process
// left, by its pid).
[[noreturn]] void RemoveTemporariesOnTerminate() {
  static std::atomic<bool> entered{false};
  if (!entered.exchange(true) && DeferMutex().try_lock()) {
    std::vector<std::string> paths;
    for (int attempt = 0; attempt < 50 && paths.empty(); ++attempt) {
      if (RegistryMutex().try_lock()) {
        for (auto it = Registry().rbegin(); it != Registry().rend(); ++it)
          paths.push_back(it->second);
        RegistryMutex().unlock();
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    std::size_t removed = 0;
    for (const auto& p : paths) removed += RemoveWithRetries(p);
    WriteStderr("impactdic: internal error: removed " + std::to_string(removed) +
                " temporary output(s)\n");
  }
  if (g_previous_terminate != nullptr) g_previous_terminate();
  std::abort();
}

}  // namespace

void InstallInterruptCleanup() {
  static std::once_flag once;
  std::call_once(once, [] {
    // Without the pipe or the thread, signals keep their default action.
    if (pipe2(g_pipe, O_CLOEXEC) != 0) return;
    try {
      std::thread(CleanupAfterSignal, g_pipe[0]).detach();
    } catch (const std::system_error&) {
      return;
    }
    for (int signal_number : {SIGINT, SIGTERM, SIGHUP}) {
      struct sigaction old {};
      if (sigaction(signal_number, nullptr, &old) != 0 || old.sa_handler == SIG_IGN) continue;
      struct sigaction action {};
      action.sa_handler = OnSignal;
      sigemptyset(&action.sa_mask);
      action.sa_flags = SA_RESTART;  // Interrupted system calls resume; no EINTR failures.
      sigaction(signal_number, &action, nullptr);
    }
    g_previous_terminate = std::set_terminate(RemoveTemporariesOnTerminate);
  });
}

bool Interrupted() { return g_interrupted.load(); }

void WaitIfInterrupted() {
  if (Interrupted()) ParkForever();
}

RemoveOnInterrupt::RemoveOnInterrupt(std::string path) {
  WaitIfInterrupted();
  std::lock_guard<std::mutex> lock(RegistryMutex());
  id_ = g_next_id++;
  Registry().emplace(id_, std::move(path));
}

void MakeFolders(const std::string& path, std::error_code& ec) {
  {
    const DeferInterrupts making;
    if (!Interrupted()) {
      fs::create_directories(path, ec);
      return;
    }
  }
  WaitIfInterrupted();
}

RemoveOnInterrupt::RemoveOnInterrupt(std::string path, const DeferInterrupts& /*held*/) {
  std::lock_guard<std::mutex> lock(RegistryMutex());
  id_ = g_next_id++;
  Registry().emplace(id_, std::move(path));
}

RemoveOnInterrupt::~RemoveOnInterrupt() { Release(); }

void RemoveOnInterrupt::Release() {
  if (id_ == 0) return;
  std::lock_guard<std::mutex> lock(RegistryMutex());
  Registry().erase(id_);
  id_ = 0;
}

void NoteOutputsComplete(const std::string& path) {
  std::lock_guard<std::mutex> lock(RegistryMutex());
  for (const auto& [id, temporary] : Registry()) {
    if (path != temporary && IsSameOrInside(path, temporary)) return;
  }
  Completed().push_back(path);
}

DeferInterrupts::DeferInterrupts() { DeferMutex().lock(); }
DeferInterrupts::~DeferInterrupts() { DeferMutex().unlock(); }

std::string TemporaryTag() {
  static std::mutex mutex;
  static std::mt19937_64 random{std::random_device{}()};
  std::uint64_t r = 0;
  {
    std::lock_guard<std::mutex> lock(mutex);
    r = random();
  }
  char hex[17];
  static const char* digits = "0123456789abcdef";
  for (int i = 15; i >= 0; --i, r >>= 4) hex[i] = digits[r & 0xF];
  hex[16] = '\0';
  return std::to_string(static_cast<long>(getpid())) + "-" + hex;
}

long TemporaryTagPid(std::string_view name, std::string_view prefix) {
  if (name.size() <= prefix.size() || name.substr(0, prefix.size()) != prefix) return 0;
  const std::string_view rest = name.substr(prefix.size());
  long pid = 0;
  std::size_t i = 0;
  for (; i < rest.size() && i < 10 && rest[i] >= '0' && rest[i] <= '9'; ++i)
    pid = pid * 10 + (rest[i] - '0');
  if (i == 0 || i + 1 >= rest.size() || rest[i] != '-' || pid <= 0) return 0;
  const char next = rest[i + 1];  // At least one hex digit after the dash.
  const bool hex = (next >= '0' && next <= '9') || (next >= 'a' && next <= 'f');
  return hex ? pid : 0;
}

bool IsSameOrInside(std::string_view path, std::string_view folder) {
  return path.substr(0, folder.size()) == folder &&
         (path.size() == folder.size() || path[folder.size()] == '/');
}

bool ProcessIsGone(long pid) {
  if (pid <= 0) return false;
  return kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH;
}

}  // namespace impactdic
