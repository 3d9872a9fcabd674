// Test helper: runs the built `impactdic` binary (path compiled in as IMPACTDIC_CLI_PATH) with
// arguments through the shell and captures stdout+stderr and the exit code. `environment`
// ("NAME=value ...") is set for the binary only.
#ifndef IMPACTDIC_TESTS_CLI_CLI_RUNNER_H_
#define IMPACTDIC_TESTS_CLI_CLI_RUNNER_H_

#include <sys/wait.h>

#include <cstdio>
#include <string>

namespace impactdic {

struct CliResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr interleaved
};

inline CliResult RunCli(const std::string& arguments, const std::string& environment = "") {
  const std::string command = (environment.empty() ? "" : environment + " ") +
                              std::string(IMPACTDIC_CLI_PATH) + " " + arguments + " 2>&1";
  CliResult result;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return result;
  char buffer[4096];
  std::size_t n;
  while ((n = fread(buffer, 1, sizeof buffer, pipe)) > 0) result.output.append(buffer, n);
  const int status = pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

}  // namespace impactdic

#endif  // IMPACTDIC_TESTS_CLI_CLI_RUNNER_H_
