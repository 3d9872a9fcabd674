// `impactdic analyze --sensor CSV ...`: the JSON contract and option validation, through the
// built binary on a CSV this test writes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <functional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "../cli/cli_runner.h"
#include "../cli/expect_flag_error.h"
#include "../io/test_dir.h"
#include "impactdic/sensor/sensor.h"
#include "synthetic_record.h"

namespace impactdic {
namespace {

using testing::MakeRecord;
using testing::PulseMotion;
using testing::SyntheticRecord;
using testing::WriteRecordCsv;

// The value of a numeric key in a flat JSON object (test helper; NaN if absent or null).
double JsonNumberOf(const std::string& json, const std::string& key) {
  const std::string needle = "\"" + key + "\":";
  const auto pos = json.find(needle);
  if (pos == std::string::npos) return std::nan("");
  return std::strtod(json.c_str() + pos + needle.size(), nullptr);
}

class AnalyzeCli : public ::testing::Test {
 protected:
  void SetUp() override {
    motion_.a_pk = 40 * motion_.g;
    const SyntheticRecord rec =
        MakeRecord(motion_, 25000, motion_.t_impact() + 0.05, 0.05, 0.02, /*seed=*/21);
    csv_ = dir_.File("daq.csv");
    WriteRecordCsv(csv_, rec);
  }
  TestDir dir_;
  PulseMotion motion_;
  std::string csv_;
};

TEST_F(AnalyzeCli, JsonContract) {
  const CliResult r = RunCli("-q analyze --sensor " + csv_ + " --from-release --format json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // One JSON object whose keys start with exactly these, in this order.
  const std::string keys[] = {"impact_time_s",
                              "impact_velocity_m_s",
                              "final_penetration_m",
                              "peak_deceleration_g",
                              "t_peak_s",
                              "sample_rate_hz",
                              "warnings"};
  std::size_t last = 0;
  for (const auto& k : keys) {
    const auto pos = r.output.find("\"" + k + "\":");
    ASSERT_NE(pos, std::string::npos) << k << "\n" << r.output;
    EXPECT_GT(pos, last) << k;
    last = pos;
  }
  EXPECT_EQ(r.output.find_first_not_of(" \n"), r.output.find('{'));
  EXPECT_EQ(r.output.find_last_not_of(" \n"), r.output.rfind('}'));
  EXPECT_NEAR(JsonNumberOf(r.output, "impact_time_s"), motion_.t_impact(), 1 / 25000.0);
  EXPECT_NEAR(JsonNumberOf(r.output, "impact_velocity_m_s"), motion_.v0, 0.005 * motion_.v0);
  EXPECT_NEAR(JsonNumberOf(r.output, "final_penetration_m"), motion_.CraterDepth(),
              0.01 * motion_.CraterDepth());
  EXPECT_NEAR(JsonNumberOf(r.output, "peak_deceleration_g"), 39, 0.3);
  EXPECT_NEAR(JsonNumberOf(r.output, "t_peak_s"), motion_.t_d / 2, 5e-4);
  EXPECT_NEAR(JsonNumberOf(r.output, "sample_rate_hz"), 25000, 1e-3);

  // From the impact with the true velocity, a lower cut-off, text output.
  const CliResult t = RunCli("analyze --sensor " + csv_ + " --impact-velocity 3.7 --cutoff 1000");
  ASSERT_EQ(t.exit_code, 0) << t.output;
  EXPECT_NE(t.output.find("final penetration"), std::string::npos) << t.output;
  EXPECT_NE(t.output.find("1000.0 Hz"), std::string::npos) << t.output;
}

// The sensor flags are checked by SensorOptions::Check() (the one definition of their ranges),
// the error naming the flag: the CLI's expected text is the library's.
TEST_F(AnalyzeCli, SensorFlagsAreCheckedByTheLibraryNamingTheFlag) {
  const std::vector<std::tuple<std::string, std::string, std::function<void(SensorOptions&)>>>
      cases = {
          {"--cutoff 0", "--cutoff", [](SensorOptions& o) { o.cutoff_hz = 0; }},
          {"--quiet-window -1", "--quiet-window", [](SensorOptions& o) { o.quiet_window_s = -1; }},
          {"--impact-threshold 1", "--impact-threshold",
           [](SensorOptions& o) { o.impact_threshold_g = 1; }},
      };
  for (const auto& [flags, flag, set] : cases) {
    ExpectFlagRefusedAsTheLibraryDoes(
        RunCli("analyze --sensor " + csv_ + " --from-release " + flags), flag, [&set = set] {
          SensorOptions o;
          set(o);
          o.Check();
        });
  }
}

TEST_F(AnalyzeCli, OptionsValidatedFirst) {
  struct Case {
    std::string args, expect;
  };
  const Case cases[] = {
      {"--sensor " + csv_ + " --format json", "--from-release / --impact-velocity"},
      {"--sensor " + csv_ + " --from-release --impact-velocity 3", "both given"},
      {"--sensor " + csv_ + " --impact-velocity -2", "--impact-velocity"},
      {"--sensor " + csv_ + " --from-release --cutoff 0", "--cutoff"},
      {"--sensor " + csv_ + " --from-release --cutoff 20000", "--cutoff"},
      {"--sensor " + csv_ + " --from-release --format yaml", "--format"},
      {"--sensor " + csv_ + " --from-release --accel-unit furlong", "--accel-unit"},
      {"--sensor " + csv_ + " --from-release --offset-reference sky", "--offset-reference"},
      {"--sensor " + dir_.File("missing.csv") + " --from-release", "missing.csv"},
      {"--from-release", "SCENE / --sensor"},
      {"--sensor " + csv_ + " --from-release --accel-column acc", "'acc'"},
  };
  for (const auto& c : cases) {
    const CliResult r = RunCli("analyze " + c.args);
    EXPECT_EQ(r.exit_code, 1) << c.args << "\n" << r.output;
    EXPECT_NE(r.output.find(c.expect), std::string::npos) << c.args << "\n" << r.output;
  }
}

}  // namespace
}  // namespace impactdic
