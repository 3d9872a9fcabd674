// Test helper: runs a shell command (RunShell), or the built `impactdic` binary (path compiled in
// as impactdic::CliPath()) with arguments (RunCli), and captures stdout+stderr and the exit code.
// RunCli's `environment` ("NAME=value ...") is set for the binary only.
#ifndef IMPACTDIC_TESTS_CLI_CLI_RUNNER_H_
#define IMPACTDIC_TESTS_CLI_CLI_RUNNER_H_

#include <sys/wait.h>

#include <cstdio>
#include <string>

#include "../core/test_paths.h"

namespace impactdic {

struct CliResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr interleaved
};

// Runs `command` through the shell; stdout and stderr interleaved, and the exit code (-1 if it
// could not be started or did not exit normally).
inline CliResult RunShell(const std::string& command) {
  CliResult result;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return result;
  char buffer[4096];
  std::size_t n;
  while ((n = fread(buffer, 1, sizeof buffer, pipe)) > 0) result.output.append(buffer, n);
  const int status = pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

inline CliResult RunCli(const std::string& arguments, const std::string& environment = "") {
  return RunShell((environment.empty() ? "" : environment + " ") +
                  std::string(impactdic::CliPath()) + " " + arguments);
}

}  // namespace impactdic

#endif  // IMPACTDIC_TESTS_CLI_CLI_RUNNER_H_
