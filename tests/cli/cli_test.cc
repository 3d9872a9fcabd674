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
