// The `impactdic model` command line: the JSON contract, the outputs and the exit codes.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <functional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "../cli/cli_runner.h"
#include "../cli/expect_flag_error.h"
#include "impactdic/model/impact_model.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

fs::path TempDir() {
  const fs::path dir =
      fs::temp_directory_path() / ("impactdic_model_cli_test_" + std::to_string(getpid()));
  fs::create_directories(dir);
  return dir;
}

TEST(ModelCli, JsonHasEveryContractKey) {
  const CliResult r = RunCli("model --mass 10 --height 0.7 --width 0.15 --format json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* key : {"t_end_s", "crater_depth_m", "relative_penetration", "added_mass_max_kg",
                          "peak_deceleration_g", "t_peak_s", "plateau_deceleration_g",
                          "momentum_ratio", "solver", "steps", "rejected_steps", "rhs_evals",
                          "jacobian_evals", "error_estimate", "wall_time_s", "warnings"})
    EXPECT_NE(r.output.find(std::string("\"") + key + "\":"), std::string::npos) << key;
  EXPECT_NE(r.output.find("\"solver\": \"auto(dopri5)\""), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("\"warnings\": []"), std::string::npos) << r.output;
}

TEST(ModelCli, NoPeakIsNullInJsonWithAWarning) {
  const CliResult r = RunCli("model --mass 10 --velocity 0.01 --width 0.15 --format json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("\"peak_deceleration_g\": null"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("no distinct peak"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("stopped only by the v^-n damping term"), std::string::npos);
}

TEST(ModelCli, EveryOptionIsAcceptedAndSeriesAreWritten) {
  const fs::path dir = TempDir();
  const std::string csv = (dir / "series.csv").string(), h5 = (dir / "series.h5").string();
  CliResult r = RunCli(
      "model --mass 10 --velocity 3.7 --width 0.15 --depth 0.192 --added-mass 6.9 --K 50 --n 0.2 "
      "--u 1.9 --T 0.002 --b 2500 --rho 1550 --g 9.81 --solver stiff --rtol 1e-7 --atol 1e-10 "
      "-o " +
      csv);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("rodas3"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(csv));
  r = RunCli("model --mass 10 --height 0.7 --width 0.15 --ode45-defaults -o " + h5);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("ode45(dopri5)"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(h5));
  fs::remove_all(dir);
}

TEST(ModelCli, Table1AndWorkPrecisionWriteTheirTables) {
  const fs::path dir = TempDir();
  const std::string t1 = (dir / "table1.csv").string(), wp = (dir / "wp.csv").string(),
                    png = (dir / "wp.png").string();
  CliResult r = RunCli("model --table1 --rtol 1e-6 -o " + t1);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(t1));
  EXPECT_NE(r.output.find("13.0"), std::string::npos);
  r = RunCli("model --work-precision --wp-cases exact --wp-solvers dopri5,stiff -o " + wp +
             " --plot " + png);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("harmonic-exact"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(wp));
  EXPECT_TRUE(fs::exists(png));
  EXPECT_GT(fs::file_size(png), 1000u);
  fs::remove_all(dir);
}

// (The remaining option checks are the library's Check(), tested in impact_model_test.cc; each
// CLI start costs ~0.3 s of library loading, so only a representative set runs here.)
TEST(ModelCli, BadInputFailsWithExitCode1AndNamesTheOption) {
  struct Case {
    std::string args, needle;
  };
  const std::vector<Case> cases = {
      {"model --mass 0 --height 0.7 --width 0.15", "--mass"},
      {"model --mass nan --height 0.7 --width 0.15", "--mass"},
      {"model --mass 10 --height 0.7 --width 0", "--width"},
      {"model --mass 10 --velocity -1 --width 0.15", "--velocity"},
      {"model --mass 10 --height 0.7 --velocity 3 --width 0.15", "--height/--velocity"},
      {"model --mass 10 --width 0.15", "--height/--velocity"},
      {"model --mass 10 --height 0.7 --width 0.15 --rtol 0", "--rtol"},
      {"model --mass 10 --height 0.7 --width 0.15 --rtol -1e-6", "--rtol"},
      {"model --mass 10 --height 0.7 --width 0.15 --solver rk4",
       "--solver: invalid value (got 'rk4'); expected one of auto, dopri5, stiff"},
      {"model --mass 10 --height 0.7 --width 0.15 --error-estimate x", "--error-estimate"},
      {"model --mass 10 --height 0.7 --width 0.15 -o out.txt", "-o"},
      {"model --mass 10 --height 0.7 --width 0.15 --ode45-defaults --solver stiff",
       "--ode45-defaults"},
      {"model --table1 --mass 10", "--mass"},
      {"model --mass 10 --height 0.7 --width 0.15 -o /no/such/folder/s.csv", "/no/such/folder"},
      {"model --work-precision --plot /no/such/folder/wp.png", "/no/such/folder"},
      {"model --table1 -o /no/such/folder/t1.csv", "/no/such/folder"},
  };
  for (const Case& c : cases) {
    const CliResult r = RunCli(c.args);
    EXPECT_EQ(r.exit_code, 1) << c.args << "\n" << r.output;
    EXPECT_NE(r.output.find(c.needle), std::string::npos) << c.args << "\n" << r.output;
  }
}

// The solver flags are checked by ImpactSolverOptions::Check() (the one definition of their
// ranges), the error naming the flag: the CLI's expected text is the library's.
TEST(ModelCli, SolverFlagsAreCheckedByTheLibraryNamingTheFlag) {
  const std::vector<std::tuple<std::string, std::string, std::function<void(ImpactSolverOptions&)>>>
      cases = {
          {"--rtol 0", "--rtol", [](ImpactSolverOptions& o) { o.rtol = 0; }},
          {"--atol -1", "--atol", [](ImpactSolverOptions& o) { o.atol = -1; }},
          {"--t-max 0", "--t-max", [](ImpactSolverOptions& o) { o.t_max_s = 0; }},
      };
  for (const auto& [flags, flag, set] : cases) {
    ExpectFlagRefusedAsTheLibraryDoes(RunCli("model --mass 10 --height 0.7 --width 0.15 " + flags),
                                      flag, [&set = set] {
                                        ImpactSolverOptions o;
                                        set(o);
                                        o.Check();
                                      });
  }
  // NaN would mean "unset" to the library: a given NaN is refused.
  const CliResult nan = RunCli("model --mass 10 --height 0.7 --width 0.15 --rtol nan");
  EXPECT_EQ(nan.exit_code, 1) << nan.output;
  EXPECT_NE(nan.output.find("--rtol"), std::string::npos) << nan.output;
}

}  // namespace
}  // namespace impactdic
