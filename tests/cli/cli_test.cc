// Runs the built impactdic binary and checks exit codes and messages.
#include <gtest/gtest.h>

#include <filesystem>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "../core/test_paths.h"
#include "cli_runner.h"

namespace impactdic {
namespace {

TEST(Cli, VersionPrintsVersionAndRevision) {
  const CliResult r = RunCli("version");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.output.find("impactdic 0."), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("git "), std::string::npos) << r.output;
  // Built from a git checkout, the revision is a commit hash (not "unknown").
  if (std::filesystem::exists(std::string(impactdic::SourceDir()) + "/.git")) {
    EXPECT_TRUE(std::regex_search(r.output, std::regex("\\(git [0-9a-f]{7,}(-dirty)?\\)")))
        << r.output;
  }
}

// `--version`, `-V` and `version` print the same: the version, the commit the build was configured
// from (its short form a prefix of the full hash) and the IC-GN kernels.
TEST(Cli, VersionFlagsPrintVersionCommitAndKernels) {
  const CliResult command = RunCli("version");
  ASSERT_EQ(command.exit_code, 0) << command.output;
  for (const char* flag : {"--version", "-V"}) {
    const CliResult r = RunCli(flag);
    EXPECT_EQ(r.exit_code, 0) << flag << ": " << r.output;
    EXPECT_EQ(r.output, command.output) << flag;
  }
  std::smatch m;
  ASSERT_TRUE(std::regex_search(command.output, m,
                                std::regex("^impactdic 0\\.[0-9.]+ \\(git ([0-9a-f]{7,}|unknown)")))
      << command.output;
  const std::string revision = m[1];
  std::smatch c;
  ASSERT_TRUE(std::regex_search(command.output, c,
                                std::regex("\ngit commit: ([0-9a-f]{40}|unknown \\(built outside a "
                                           "git checkout\\))\n")))
      << command.output;
  if (revision == "unknown") {
    EXPECT_EQ(c[1].str().rfind("unknown", 0), 0u) << command.output;
  } else {
    EXPECT_EQ(c[1].str().rfind(revision, 0), 0u) << "the short revision is not the commit's prefix";
  }
  // Every build holds the scalar kernel; the one in use is one this CPU runs.
  std::smatch k;
  ASSERT_TRUE(std::regex_search(
      command.output, k,
      std::regex("\nSIMD kernels \\(IC-GN\\): built scalar[a-z0-9, ]*; this CPU runs "
                 "([a-z0-9, ]+); in use (scalar|avx2|avx512) ")))
      << command.output;
  EXPECT_NE(k[1].str().find(k[2].str()), std::string::npos) << command.output;
  // IMPACTDIC_DIC_KERNEL forces the kernel reported, and a bad one is said, not hidden.
  const CliResult scalar = RunCli("--version", "IMPACTDIC_DIC_KERNEL=scalar");
  EXPECT_EQ(scalar.exit_code, 0) << scalar.output;
  EXPECT_NE(scalar.output.find("; in use scalar "), std::string::npos) << scalar.output;
  const CliResult bad = RunCli("-V", "IMPACTDIC_DIC_KERNEL=sse9");
  EXPECT_NE(bad.output.find("; in use none: "), std::string::npos) << bad.output;
  EXPECT_NE(bad.output.find("sse9"), std::string::npos) << bad.output;
}

// `impactdic` alone is not an error: it lists every command with its one line.
TEST(Cli, NoArgumentsPrintsTheCommandTable) {
  const CliResult r = RunCli("");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("error"), std::string::npos) << r.output;
  for (const char* sub : {"run", "synth", "calibrate", "correlate", "analyze", "model", "render",
                          "campaign", "validate-dem", "version", "init"}) {
    EXPECT_TRUE(std::regex_search(r.output, std::regex(std::string("\n  ") + sub + " +\\S")))
        << sub << " has no line in:\n"
        << r.output;
  }
  EXPECT_NE(r.output.find("--help"), std::string::npos) << r.output;
}

TEST(Cli, EverySubcommandHasHelp) {
  for (const char* sub : {"run", "synth", "calibrate", "correlate", "analyze", "model", "render",
                          "campaign", "version", "init"}) {
    const CliResult r = RunCli(std::string(sub) + " --help");
    EXPECT_EQ(r.exit_code, 0) << sub << ": " << r.output;
    EXPECT_NE(r.output.find(sub), std::string::npos) << r.output;
  }
}

TEST(Cli, ANonNumberForANumericOptionSaysWhatIsExpected) {
  const CliResult mass = RunCli("model --mass abc --height 0.7 --width 0.15");
  EXPECT_EQ(mass.exit_code, 1);
  EXPECT_NE(mass.output.find("--mass (got 'abc'); expected a number"), std::string::npos)
      << mass.output;
  const CliResult subset = RunCli("correlate --subset 2.5 --frames x -o y.csv");
  EXPECT_EQ(subset.exit_code, 1);
  // The scene key's own message (--subset is dic.subset_size, read by the key's parser).
  EXPECT_NE(subset.output.find("--subset: invalid value (got 2.5); expected an odd integer"),
            std::string::npos)
      << subset.output;
}

TEST(Cli, UnknownSubcommandFails) {
  const CliResult r = RunCli("frobnicate");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("frobnicate"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace impactdic
