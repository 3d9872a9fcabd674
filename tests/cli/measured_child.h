// Test helper: runs the built `impactdic` binary (impactdic::CliPath()) as a child process and
// returns its exit code and its own peak resident set size (wait4's ru_maxrss), for tests that
// bound memory (never time, so they do not depend on the load of the machine).
#ifndef IMPACTDIC_TESTS_CLI_MEASURED_CHILD_H_
#define IMPACTDIC_TESTS_CLI_MEASURED_CHILD_H_

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <string>
#include <vector>

#include "../core/test_paths.h"

extern char** environ;

namespace impactdic {

struct MeasuredChild {
  int exit_code = -1;
  long peak_rss_kb = 0;  // ru_maxrss of the child alone.
};

// Runs `impactdic ARGS...` (output discarded). Under AddressSanitizer (the asan preset) freed
// blocks stay in its quarantine (256 MB), so the resident set would grow with everything ever
// allocated: the child runs without it.
inline MeasuredChild RunMeasured(const std::vector<std::string>& args) {
  std::vector<std::string> all = {impactdic::CliPath()};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::vector<std::string> env;
  bool asan_set = false;
  for (char** e = environ; *e; ++e) {
    std::string entry = *e;
    if (entry.rfind("ASAN_OPTIONS=", 0) == 0) {
      entry += ":quarantine_size_mb=0";
      asan_set = true;
    }
    env.push_back(entry);
  }
  if (!asan_set) env.push_back("ASAN_OPTIONS=quarantine_size_mb=0");
  std::vector<char*> envp;
  for (auto& e : env) envp.push_back(e.data());
  envp.push_back(nullptr);
  const pid_t pid = fork();
  if (pid == 0) {
    std::freopen("/dev/null", "w", stdout);
    std::freopen("/dev/null", "w", stderr);
    execve(argv[0], argv.data(), envp.data());
    _exit(127);
  }
  MeasuredChild child;
  int status = 0;
  rusage usage{};
  if (pid > 0 && wait4(pid, &status, 0, &usage) == pid) {
    child.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    child.peak_rss_kb = usage.ru_maxrss;
  }
  return child;
}

}  // namespace impactdic

#endif  // IMPACTDIC_TESTS_CLI_MEASURED_CHILD_H_
