#include "subprocess.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <system_error>

#include "impactdic/core/error.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/output_generation.h"

extern char** environ;

namespace impactdic::render_internal {
namespace fs = std::filesystem;

TempFile::TempFile(const std::string& suffix) {
  RemoveStaleSystemTemporaries();
  std::error_code ec;
  fs::path folder = fs::temp_directory_path(ec);
  if (ec) folder = "/tmp";
  for (int attempt = 0; attempt < 16; ++attempt) {
    std::string name = "impactdic-";
    name.append(TemporaryTag()).append(suffix);
    const std::string candidate = (folder / name).string();
    // Registered and made as one step for a signal's cleanup (which waits for the block): a
    // cleanup between the two would find nothing to remove and leave the file behind.
    const DeferInterrupts making;
    if (Interrupted()) break;
    interrupt_guard_.emplace(candidate, making);
    const int fd = open(candidate.c_str(), O_CREAT | O_EXCL | O_WRONLY | O_CLOEXEC, 0600);
    if (fd >= 0) {
      close(fd);
      path_ = candidate;
      return;
    }
    interrupt_guard_.reset();
  }
  WaitIfInterrupted();
  throw Error(ErrorKind::kIo, "temporary file", "cannot create one in " + folder.string(),
              "a writable temporary folder (TMPDIR)");
}

void TempFile::Write(const std::string& text) const {
  // No O_CREAT: a file the interrupt cleanup removed stays removed.
  const int fd = open(path_.c_str(), O_WRONLY | O_TRUNC | O_CLOEXEC);
  if (fd < 0) {
    WaitIfInterrupted();
    throw WriteError(path_, errno);
  }
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int error = n < 0 ? errno : EIO;
      close(fd);
      throw WriteError(path_, error);
    }
    done += static_cast<std::size_t>(n);
  }
  if (close(fd) != 0) throw WriteError(path_, errno);
}

TempFile::~TempFile() {
  std::error_code ec;
  fs::remove(path_, ec);
}

std::string TempSiblingPath(const std::string& final_path, const std::string& extension) {
  const fs::path final_fs(final_path);
  fs::path folder = final_fs.parent_path();
  if (folder.empty()) folder = ".";
  return (folder / (TemporaryName(final_fs.stem().string()) + extension)).string();
}

ProcessResult RunProcess(const std::string& program, const std::vector<std::string>& arguments) {
  ProcessResult result;
  TempFile capture(".log");

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, capture.path().c_str(),
                                   O_WRONLY | O_TRUNC, 0600);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);

  std::vector<std::string> args_storage;
  args_storage.push_back(program);
  args_storage.insert(args_storage.end(), arguments.begin(), arguments.end());
  std::vector<char*> argv;
  argv.reserve(args_storage.size() + 1);
  for (auto& a : args_storage) argv.push_back(a.data());
  argv.push_back(nullptr);

  pid_t pid = 0;
  const bool has_slash = program.find('/') != std::string::npos;
  const int rc = has_slash
                     ? posix_spawn(&pid, program.c_str(), &actions, nullptr, argv.data(), environ)
                     : posix_spawnp(&pid, program.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) {
    result.start_errno = rc;
    return result;
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) break;
  }
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  // 127: the child could not execute the program (older C libraries report it this way).
  result.started = result.exit_code != 127;
  if (!result.started) result.start_errno = ENOENT;
  std::ifstream in(capture.path(), std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  result.output = text.str();
  return result;
}

}  // namespace impactdic::render_internal
