// The lint step of CI remembers clean files (scripts/clang_tidy_files.py, docs/development.md
// "Building and testing"): a file is skipped only when nothing it is made of changed. Each test
// lints a one-file project of its own, with a copy of the script, one clang-tidy check and its own
// cache folder.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "../cli/cli_runner.h"
#include "../core/test_paths.h"
#include "../io/test_dir.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

constexpr char kCleanHeader[] = "#include <vector>\ninline int Probe() { return 1; }\n";

// ROOT/scripts/clang_tidy_files.py, ROOT/.clang-tidy, ROOT/src/{probe.h,a.cc} and
// ROOT/build/compile_commands.json; `header` is probe.h's text.
void WriteProject(const fs::path& root, const std::string& header) {
  fs::create_directories(root / "scripts");
  fs::create_directories(root / "src");
  fs::create_directories(root / "build");
  fs::copy_file(fs::path(SourceDir()) / "scripts" / "clang_tidy_files.py",
                root / "scripts" / "clang_tidy_files.py", fs::copy_options::overwrite_existing);
  std::ofstream(root / ".clang-tidy") << "Checks: '-*,performance-unnecessary-value-param'\n"
                                         "HeaderFilterRegex: '.*'\n";
  std::ofstream(root / "src" / "probe.h") << header;
  std::ofstream(root / "src" / "a.cc") << "#include \"probe.h\"\nint A() { return Probe(); }\n";
  const std::string src = (root / "src").string();
  std::ofstream(root / "build" / "compile_commands.json")
      << "[{\"directory\": \"" << (root / "build").string()
      << "\", \"command\": \"c++ -std=c++20 -I" << src << " -o a.o -c " << src
      << "/a.cc\", \"file\": \"" << src << "/a.cc\"}]\n";
}

CliResult Lint(const fs::path& root, const fs::path& cache) {
  return RunShell("python3 '" + (root / "scripts" / "clang_tidy_files.py").string() + "' '" +
                  (root / "build").string() + "' 1 '" + cache.string() + "'");
}

bool Says(const CliResult& r, const std::string& text) {
  return r.output.find(text) != std::string::npos;
}

TEST(ClangTidyCache, ACleanFileIsRememberedAndLintedAgainWhenAHeaderChanges) {
  const TestDir dir;
  const fs::path root = dir.path() / "clone1";
  const fs::path cache = dir.path() / "cache";
  WriteProject(root, kCleanHeader);
  CliResult r = Lint(root, cache);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(Says(r, "1 files, 0 clean by their remembered fingerprint, 1 linted now"))
      << r.output;

  r = Lint(root, cache);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(Says(r, "1 files, 1 clean by their remembered fingerprint, 0 linted now"))
      << r.output;

  // Another clone of the same tree, in another folder, shares the entry.
  const fs::path other = dir.path() / "clone2";
  WriteProject(other, kCleanHeader);
  r = Lint(other, cache);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(Says(r, "1 clean by their remembered fingerprint, 0 linted now")) << r.output;

  // A change in the included header, not in a.cc itself, lints a.cc again.
  WriteProject(root, std::string(kCleanHeader) + "inline int Probe2() { return 2; }\n");
  r = Lint(root, cache);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(Says(r, "0 clean by their remembered fingerprint, 1 linted now")) << r.output;
}

TEST(ClangTidyCache, AFindingFailsAndIsNeverRemembered) {
  const TestDir dir;
  const fs::path root = dir.path() / "clone";
  const fs::path cache = dir.path() / "cache";
  WriteProject(root, std::string(kCleanHeader) +
                         "inline std::size_t Size(const std::vector<double> v) { return v.size(); "
                         "}\n");
  for (int run = 0; run < 2; ++run) {
    const CliResult r = Lint(root, cache);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_TRUE(Says(r, "performance-unnecessary-value-param")) << r.output;
    EXPECT_TRUE(Says(r, "0 clean by their remembered fingerprint, 1 linted now")) << r.output;
    EXPECT_TRUE(Says(r, "FAILED in 1 files")) << r.output;
  }
  // A changed .clang-tidy is a new fingerprint too: without the check the file is clean.
  std::ofstream(root / ".clang-tidy") << "Checks: '-*,bugprone-use-after-move'\n";
  CliResult r = Lint(root, cache);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = Lint(root, cache);
  EXPECT_TRUE(Says(r, "1 clean by their remembered fingerprint, 0 linted now")) << r.output;
}

}  // namespace
}  // namespace impactdic
