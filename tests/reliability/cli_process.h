// Test helpers for fault injection: start the built `impactdic` (impactdic::CliPath()) as a child
// process in its own process group with its own TMPDIR, signal it when a condition holds, and
// fingerprint the files of a folder to tell two generations of outputs apart.
#ifndef IMPACTDIC_TESTS_RELIABILITY_CLI_PROCESS_H_
#define IMPACTDIC_TESTS_RELIABILITY_CLI_PROCESS_H_

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

#include "../core/test_paths.h"

extern char** environ;

namespace impactdic {

// How a child ended.
struct ChildExit {
  bool exited = false;           // Exited (code) rather than killed by a signal.
  int code = -1;                 // Exit status if `exited`.
  int signal = 0;                // The signal that ended it otherwise.
  bool signalled_by_us = false;  // The condition held and the signal was sent.
  std::string output;            // stdout + stderr.
  std::string Describe() const {
    return (exited ? "exit " + std::to_string(code)
                   : "killed by signal " + std::to_string(signal)) +
           (signalled_by_us ? " (signalled)" : " (finished before the signal)") + "; output:\n" +
           output;
  }
};

// A running `impactdic ARGS...` (stdin /dev/null, stdout + stderr into `log`, TMPDIR = `tmpdir`,
// SIGINT/SIGTERM/SIGHUP at their default action and unblocked, own process group).
class CliProcess {
 public:
  CliProcess(const std::vector<std::string>& args, const std::string& tmpdir, std::string log)
      : log_(std::move(log)) {
    std::vector<std::string> env;
    for (char** e = environ; *e != nullptr; ++e)
      if (std::strncmp(*e, "TMPDIR=", 7) != 0) env.emplace_back(*e);
    env.push_back("TMPDIR=" + tmpdir);
    std::vector<std::string> argv_storage = {impactdic::CliPath()};
    argv_storage.insert(argv_storage.end(), args.begin(), args.end());
    std::vector<char*> argv, envp;
    for (auto& a : argv_storage) argv.push_back(a.data());
    argv.push_back(nullptr);
    for (auto& e : env) envp.push_back(e.data());
    envp.push_back(nullptr);

    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log_.c_str(),
                                     O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
    posix_spawnattr_t attr;
    posix_spawnattr_init(&attr);
    sigset_t defaults, empty;
    sigemptyset(&defaults);
    for (int s : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&defaults, s);
    sigemptyset(&empty);
    posix_spawnattr_setsigdefault(&attr, &defaults);
    posix_spawnattr_setsigmask(&attr, &empty);
    posix_spawnattr_setpgroup(&attr, 0);
    posix_spawnattr_setflags(
        &attr, POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETPGROUP);
    if (posix_spawn(&pid_, argv[0], &actions, &attr, argv.data(), envp.data()) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&actions);
    posix_spawnattr_destroy(&attr);
  }
  ~CliProcess() {
    if (pid_ > 0 && !reaped_) {
      kill(-pid_, SIGKILL);
      int status = 0;
      waitpid(pid_, &status, 0);
    }
  }
  CliProcess(const CliProcess&) = delete;
  CliProcess& operator=(const CliProcess&) = delete;

  pid_t pid() const { return pid_; }

  // Polls `condition` (every 0.2 ms, up to `timeout_s`) while the child runs; when it holds, sends
  // `signal_number` to the child (or, if `whole_group`, to its process group, as a terminal's
  // Ctrl-C does), then waits for the child's end.
  ChildExit SignalWhen(const std::function<bool()>& condition, int signal_number, bool whole_group,
                       double timeout_s = 60) {
    ChildExit result;
    const auto start = std::chrono::steady_clock::now();
    int status = 0;
    for (;;) {
      if (waitpid(pid_, &status, WNOHANG) == pid_) return Finish(status, result);
      const double elapsed =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      if (condition() || elapsed > timeout_s) break;
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    kill(whole_group ? -pid_ : pid_, signal_number);
    result.signalled_by_us = true;
    waitpid(pid_, &status, 0);
    return Finish(status, result);
  }

  ChildExit Wait() {
    int status = 0;
    waitpid(pid_, &status, 0);
    ChildExit result;
    return Finish(status, result);
  }

 private:
  ChildExit& Finish(int status, ChildExit& result) {
    reaped_ = true;
    result.exited = WIFEXITED(status);
    result.code = result.exited ? WEXITSTATUS(status) : -1;
    result.signal = WIFSIGNALED(status) ? WTERMSIG(status) : 0;
    std::ifstream in(log_);
    std::ostringstream text;
    text << in.rdbuf();
    result.output = text.str();
    return result;
  }

  std::string log_;
  pid_t pid_ = -1;
  bool reaped_ = false;
};

// Identity of a file: the same inode, size and modification time means the same, untouched file.
struct FileId {
  std::uintmax_t inode = 0, size = 0;
  std::int64_t mtime_ns = 0;
  bool operator==(const FileId&) const = default;
};

// Every file below `folder` (relative path -> identity).
inline std::map<std::string, FileId> Fingerprint(const std::filesystem::path& folder) {
  std::map<std::string, FileId> files;
  std::error_code ec;
  for (auto it = std::filesystem::recursive_directory_iterator(folder, ec);
       !ec && it != std::filesystem::recursive_directory_iterator(); it.increment(ec)) {
    struct stat st {};
    if (lstat(it->path().c_str(), &st) != 0 || !S_ISREG(st.st_mode)) continue;
    files[std::filesystem::relative(it->path(), folder).string()] = {
        static_cast<std::uintmax_t>(st.st_ino), static_cast<std::uintmax_t>(st.st_size),
        static_cast<std::int64_t>(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec};
  }
  return files;
}

// Entries of `parent` that are impactdic temporaries of `name` (".<name>.tmp-...", ".bak-"), made
// by process `pid` if given.
inline std::set<std::string> TemporariesOf(const std::filesystem::path& parent,
                                           const std::string& name, long pid = 0) {
  std::set<std::string> found;
  std::error_code ec;
  const std::string suffix = pid > 0 ? std::to_string(pid) + "-" : "";
  for (const auto& e : std::filesystem::directory_iterator(parent, ec)) {
    const std::string n = e.path().filename().string();
    if (n.rfind("." + name + ".tmp-" + suffix, 0) == 0 ||
        n.rfind("." + name + ".bak-" + suffix, 0) == 0)
      found.insert(n);
  }
  return found;
}

// Files "impactdic-<pid>-..." (gnuplot scripts, data, logs) in a temporary folder.
inline std::set<std::string> SystemTemporariesOf(const std::filesystem::path& tmpdir, long pid) {
  std::set<std::string> found;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(tmpdir, ec)) {
    const std::string n = e.path().filename().string();
    if (n.rfind("impactdic-" + std::to_string(pid) + "-", 0) == 0) found.insert(n);
  }
  return found;
}

// The pid of a process that has just ended (and was reaped): no process has it now.
inline long DeadPid() {
  const pid_t child = fork();
  if (child == 0) _exit(0);
  int status = 0;
  waitpid(child, &status, 0);
  return child;
}

}  // namespace impactdic

#endif  // IMPACTDIC_TESTS_RELIABILITY_CLI_PROCESS_H_
