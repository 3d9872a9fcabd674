// `impactdic analyze`'s two forms as scenes (pipeline/scene_analysis.h): the sensor form's rules
// are the library's (AnalyzeSensorRecord), its options are scene keys (sensor.offset_reference,
// sensor.release_time_s, sensor.impact_threshold_g), and errors name the flag the user typed.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "../core/test_paths.h"
#include "../io/test_dir.h"
#include "impactdic/core/error.h"
#include "impactdic/io/output_generation.h"
#include "impactdic/pipeline/given_keys.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/pipeline/scene_analysis.h"
#include "impactdic/pipeline/scene_flags.h"
#include "impactdic/sensor/sensor.h"

namespace impactdic {
namespace {

const std::string kSensorCsv = std::string(impactdic::SourceDir()) + "/sample_frames/sensor.csv";

// The sensor form's request with `flags` (flag -> value) set as the command line would.
AnalyzeRequest SensorRequest(const std::vector<std::pair<std::string, std::string>>& flags) {
  AnalyzeRequest r;
  r.scene = AnalyzeCommandScene("", kSensorCsv);
  r.given.command = "analyze";
  r.given.Add("inputs.sensor", "--sensor");
  for (const auto& [flag, value] : flags) {
    const std::string key = SceneKeyOfFlag("analyze", flag);
    SetSceneKey(&r.scene, key, value, flag);
    r.given.Add(key, flag);
  }
  return r;
}

// The Error AnalyzeSensorRecord throws: "WHERE: ...found...".
Error SensorError(const AnalyzeRequest& r) {
  try {
    AnalyzeSensorRecord(r);
  } catch (const Error& e) {
    return e;
  }
  ADD_FAILURE() << "no error";
  return Error(ErrorKind::kInvalidValue, "", "", "");
}

TEST(AnalyzeRequest, SensorFormIntegratesFromExactlyOneStartNamingTheFlags) {
  Error e = SensorError(SensorRequest({}));
  EXPECT_EQ(e.where(), "--from-release / --impact-velocity");
  EXPECT_EQ(e.found(), "neither given");
  e = SensorError(SensorRequest({{"--from-release", "release"}, {"--impact-velocity", "3"}}));
  EXPECT_EQ(e.where(), "--from-release / --impact-velocity");
  EXPECT_EQ(e.found(), "both given");
  // The key's own flag, when that is what was typed.
  e = SensorError(
      SensorRequest({{"--sensor.integrate_from", "release"}, {"--test.impact_velocity_m_s", "3"}}));
  EXPECT_EQ(e.where(), "--sensor.integrate_from / --test.impact_velocity_m_s");
  // A key of the scene form only.
  e = SensorError(SensorRequest({{"--from-release", "release"}, {"--momentum.grid_cols", "3"}}));
  EXPECT_EQ(e.where(), "--momentum.grid_cols");
  EXPECT_EQ(e.expected(), "--momentum.grid_cols only with the SCENE.yaml form");
  // The base force channels: their wave figures need the scene's pounder (test.*).
  e = SensorError(
      SensorRequest({{"--from-release", "release"}, {"--sensor.base_columns", "force_base"}}));
  EXPECT_EQ(e.where(), "--sensor.base_columns");
  AnalyzeRequest partial = SensorRequest({{"--from-release", "release"}});
  partial.allow_partial = true;
  EXPECT_EQ(SensorError(partial).where(), "--allow-partial");
}

TEST(AnalyzeRequest, ReleaseTimeOnlyWhenIntegratingFromTheRelease) {
  SensorOptions o;
  o.integrate_from = IntegrationStart::kImpact;
  o.impact_velocity_m_s = 3.7;
  o.release_time_s = 0.05;
  EXPECT_THROW(o.Check(), Error);
  const Error e =
      SensorError(SensorRequest({{"--impact-velocity", "3.7"}, {"--release-time", "0.05"}}));
  EXPECT_EQ(e.where(), "--release-time");
  EXPECT_NE(e.found().find("integrating from the impact"), std::string::npos) << e.found();
}

TEST(AnalyzeRequest, SensorFormRunsAndNamesTheFlagOfARecordError) {
  const SensorRecordAnalysis a = AnalyzeSensorRecord(
      SensorRequest({{"--from-release", "release"}, {"--offset-reference", "rest"}}));
  EXPECT_EQ(a.options.offset_reference, OffsetReference::kRest);
  EXPECT_EQ(a.options.integrate_from, IntegrationStart::kRelease);
  EXPECT_GT(a.result.summary.impact_velocity_m_s, 3);
  EXPECT_NE(a.FullReport().find("offset from rest"), std::string::npos) << a.FullReport();
  // Outside the record: the record's check, naming the flag typed.
  const Error e =
      SensorError(SensorRequest({{"--from-release", "release"}, {"--release-time", "-5"}}));
  EXPECT_EQ(e.where(), "--release-time");
  // A cut-off above the record's Nyquist frequency, by its key's flag.
  EXPECT_EQ(
      SensorError(SensorRequest({{"--from-release", "release"}, {"--sensor.cutoff_hz", "20000"}}))
          .where(),
      "--sensor.cutoff_hz");
}

// The sensor form's options are scene keys: a scene file sets them too.
TEST(AnalyzeRequest, SensorOptionsAreSceneKeys) {
  const Scene scene = ParseScene(
      "inputs: {frames: f}\n"
      "sensor: {offset_reference: rest, release_time_s: 0.05, impact_threshold_g: 7}\n",
      "x/scene.yaml");
  EXPECT_EQ(scene.sensor.options.offset_reference, OffsetReference::kRest);
  EXPECT_EQ(scene.sensor.options.release_time_s, 0.05);
  EXPECT_EQ(scene.sensor.options.impact_threshold_g, 7);
  EXPECT_TRUE(std::isnan(SensorOptions{}.release_time_s));  // The key unset: detected.
}

TEST(AnalyzeRequest, OneFileIsNeverWrittenIntoAGeneration) {
  TestDir dir;
  CheckNotInAGeneration(dir.File("a.h5"), "--output");
  dir.Write("summary.json", "{}");
  try {
    CheckNotInAGeneration(dir.File("a.h5"), "--output");
    ADD_FAILURE() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.where(), "--output");
    EXPECT_NE(e.found().find("with its summary.json"), std::string::npos) << e.found();
  }
}

}  // namespace
}  // namespace impactdic
