// Test helper: runs bench/dic_challenge.py (with Debian's /usr/bin/python3, which has numpy) on the
// built `impactdic` and reads the markdown tables it prints.
#ifndef IMPACTDIC_TESTS_DIC_BENCH_SCRIPT_H_
#define IMPACTDIC_TESTS_DIC_BENCH_SCRIPT_H_

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "../cli/cli_runner.h"
#include "../core/test_paths.h"

namespace impactdic {

inline std::string ShellQuote(const std::filesystem::path& p) {
  std::string quoted(1, '\'');
  for (const char c : p.string()) {
    if (c == '\'') {
      quoted += "'\\''";
    } else {
      quoted.push_back(c);
    }
  }
  quoted.push_back('\'');
  return quoted;
}

// `bench/dic_challenge.py --binary IMPACTDIC --threads 2 ARGUMENTS` (ARGUMENTS already quoted).
inline CliResult RunDicChallengeBench(const std::string& arguments) {
  const std::filesystem::path script =
      std::filesystem::path(impactdic::SourceDir()) / "bench" / "dic_challenge.py";
  return RunShell("/usr/bin/python3 " + ShellQuote(script) + " --binary " +
                  ShellQuote(impactdic::CliPath()) + " --threads 2 " + arguments);
}

// The cells of the table rows "| a | b | ... |" of the first table after the line starting with
// `heading` (header and separator rows left out).
inline std::vector<std::vector<std::string>> TableRows(const std::string& out,
                                                       const std::string& heading) {
  std::vector<std::vector<std::string>> rows;
  const std::size_t start = out.rfind(heading, 0) == 0 ? 0 : out.find("\n" + heading);
  if (start == std::string::npos) return rows;
  std::istringstream in(out.substr(start));
  std::string line;
  bool in_table = false, header = true;
  while (std::getline(in, line)) {
    if (line.rfind('|', 0) != 0) {
      if (in_table) break;
      continue;
    }
    in_table = true;
    if (header || line.rfind("|---", 0) == 0) {
      header = false;
      continue;
    }
    std::vector<std::string> cells;
    std::istringstream cs(line.substr(1));
    std::string cell;
    while (std::getline(cs, cell, '|')) {
      cells.push_back(std::regex_replace(cell, std::regex("^ +| +$"), ""));
    }
    if (!cells.empty() && cells.back().empty()) cells.pop_back();
    rows.push_back(cells);
  }
  return rows;
}

// "a, b" -> {a, b}; "n/a" -> NaN.
inline std::vector<double> CellNumbers(const std::string& cell) {
  std::vector<double> v;
  std::istringstream in(cell);
  std::string part;
  while (std::getline(in, part, ',')) {
    part = std::regex_replace(part, std::regex("^ +| +$| %$"), "");
    v.push_back(part == "n/a" ? std::nan("") : std::stod(part));
  }
  return v;
}

// A fresh temporary folder named after the test and the process, removed by the destructor.
class BenchTempDir {
 public:
  explicit BenchTempDir(const std::string& name)
      : path_(std::filesystem::temp_directory_path() /
              ("impactdic_" + name + "_" + std::to_string(getpid()))) {
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~BenchTempDir() { std::filesystem::remove_all(path_); }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace impactdic

#endif  // IMPACTDIC_TESTS_DIC_BENCH_SCRIPT_H_
