#include "impactdic/pipeline/campaign.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <string>
#include <tuple>
#include <vector>

#include "../cli/cli_runner.h"
#include "../cli/expect_flag_error.h"
#include "../io/test_dir.h"
#include "impactdic/core/error.h"

namespace impactdic {
namespace {

// The paper's 27 combinations with m_add,max exactly from Eq. 4 (c = 425, a = 0.1, b = 0.2,
// g = 1.3): the regression must return the coefficients to rounding and R^2 = 1.
std::string WriteEq4Table(const TestDir& dir) {
  std::string text = "scene,mass_kg,velocity_m_s,area_m2,added_mass_max_kg\n";
  int k = 0;
  for (double m : {7.0, 10.0, 13.0}) {
    for (double h : {0.2, 0.7, 1.2}) {
      for (double d : {0.10, 0.15, 0.20}) {
        const double v = std::sqrt(2 * 9.81 * h), a = d * 0.192;
        const double madd = 425 * std::pow(m, 0.1) * std::pow(v, 0.2) * std::pow(a, 1.3);
        text += fmt::format("t{},{:.6f},{:.6f},{:.6f},{:.6f}\n", ++k, m, v, a, madd);
      }
    }
  }
  return dir.Write("table.csv", text);
}

TEST(Campaign, RegressionFromTableRecoversEq4) {
  TestDir dir;
  CampaignOptions options;
  options.output_folder = dir.File("out");
  const CampaignSummary s = RegressCampaignTable(WriteEq4Table(dir), options);
  ASSERT_TRUE(s.fitted);
  EXPECT_EQ(s.rows.size(), 27u);
  EXPECT_EQ(s.rows[3].name, "t4");
  // The table keeps 6 decimals, so the inputs carry ~1e-6 relative rounding.
  EXPECT_NEAR(s.fit.c, 425, 425 * 1e-3);
  EXPECT_NEAR(s.fit.a, 0.1, 1e-4);
  EXPECT_NEAR(s.fit.b, 0.2, 1e-4);
  EXPECT_NEAR(s.fit.g, 1.3, 1e-4);
  EXPECT_GT(s.fit.r_squared, 0.999999);
  EXPECT_TRUE(std::filesystem::exists(dir.File("out/campaign.csv")));
  EXPECT_TRUE(std::filesystem::exists(dir.File("out/regression.json")));
  // campaign.csv can be fed back in.
  const CampaignSummary again = RegressCampaignTable(dir.File("out/campaign.csv"), options);
  EXPECT_NEAR(again.fit.g, 1.3, 1e-4);
}

TEST(Campaign, TooFewScenesGiveANoteNotAFit) {
  TestDir dir;
  const std::string path = dir.Write(
      "few.csv", "mass_kg,velocity_m_s,area_m2,added_mass_max_kg\n7,2,0.02,1\n10,3,0.03,nan\n");
  CampaignOptions options;
  options.output_folder = dir.File("out");
  const CampaignSummary s = RegressCampaignTable(path, options);
  EXPECT_FALSE(s.fitted);
  EXPECT_NE(s.fit_note.find("1 of 2 tests"), std::string::npos) << s.fit_note;
}

TEST(Campaign, BadTablesAndOptionsAreClearErrors) {
  TestDir dir;
  CampaignOptions options;
  options.output_folder = dir.File("out");
  const std::string negative =
      dir.Write("neg.csv", "mass_kg,velocity_m_s,area_m2,added_mass_max_kg\n-7,2,0.02,1\n");
  try {
    RegressCampaignTable(negative, options);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("neg.csv"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("positive mass_kg"), std::string::npos) << e.what();
  }
  const std::string missing = dir.Write("miss.csv", "mass_kg,velocity_m_s\n7,2\n");
  EXPECT_THROW(RegressCampaignTable(missing, options), Error);
  const CliResult both = RunCli("campaign a.yaml --from-table " + negative);
  EXPECT_EQ(both.exit_code, 1);
  EXPECT_NE(both.output.find("one of them"), std::string::npos) << both.output;
  const CliResult conf = RunCli("campaign --from-table " + negative + " --confidence 1.5");
  EXPECT_EQ(conf.exit_code, 1);
  EXPECT_NE(conf.output.find("--confidence"), std::string::npos) << conf.output;
  // The flags are checked by CampaignOptions::Check() (the one definition), naming the flag.
  for (const auto& [flags, flag, set] :
       std::vector<std::tuple<std::string, std::string, std::function<void(CampaignOptions&)>>>{
           {"--confidence 1.5", "--confidence", [](CampaignOptions& o) { o.confidence = 1.5; }},
           {"--jobs -2", "--jobs", [](CampaignOptions& o) { o.jobs = -2; }}}) {
    ExpectFlagRefusedAsTheLibraryDoes(
        RunCli("campaign --from-table " + WriteEq4Table(dir) + " " + flags), flag, [&set = set] {
          CampaignOptions o;
          o.output_folder = "out";
          set(o);
          o.Check();
        });
  }
  const CliResult json = RunCli("campaign --from-table " + WriteEq4Table(dir) + " -o " +
                                dir.File("o2") + " --format json");
  EXPECT_EQ(json.exit_code, 0) << json.output;
  EXPECT_NE(json.output.find("\"r_squared\""), std::string::npos) << json.output;
}

}  // namespace
}  // namespace impactdic
