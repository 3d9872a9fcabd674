// Fault injection: inputs that used to give a plausible but wrong
// figure with exit 0 and `usable: true`. Each now gives the right figure, a warning, or an error
// naming the key, the values and what is expected; and summary.json is the same bytes for two
// runs of one scene.
//
// Ground truth: the closed-form sensor record (tests/sensor/synthetic_record.h), the synthetic
// momentum chain (tests/momentum/synthetic_chain.h) and the committed sample scene.
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "../cli/cli_runner.h"
#include "../core/expect_error.h"
#include "../core/test_paths.h"
#include "../io/test_dir.h"
#include "../momentum/synthetic_chain.h"
#include "../sensor/synthetic_record.h"
#include "fault_util.h"
#include "impactdic/core/error.h"
#include "impactdic/io/csv.h"
#include "impactdic/kinematics/kinematics.h"
#include "impactdic/momentum/momentum.h"
#include "impactdic/sensor/sensor.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

const std::string kSample = std::string(impactdic::SourceDir()) + "/sample_frames";

bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// The stages that time the frames without correlating them (quick).
const std::string kNoCorrelation = "stages: [calibrate, sensor, frames, outputs]\n";

// ---- Item 5: integration from the release, v0 against the drop height -------------------------

// A record that starts 10 s before the release and reads 1 % high (gain error): integrated from
// the record's start, the rest period's 1.01 g gave -0.098 m/s^2 for 10 s, v0 2.69 instead of
// 3.70 m/s. From the release, the gain does not enter (the free fall reads 0 g whatever the
// gain): v0 within 0.3 % (the offset's noise, 0.05 g over the 0.38 s fall, leaves ~0.05 %; the
// release and impact are located to a sample, ~0.01 %).
TEST(PhysicsFaults, SensorIsIntegratedFromTheReleaseNotTheRecordStart) {
  testing::PulseMotion m;
  m.a_pk = 40 * m.g;
  m.t_release = 10.0;
  const double fs = 25000, gain = 1.01, offset_g = 0.02;
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0, 0.05);
  SensorRecord record;
  for (std::size_t i = 0; i < static_cast<std::size_t>((m.t_impact() + 0.05) * fs); ++i) {
    const double t = static_cast<double>(i) / fs;
    record.time_s.push_back(t);
    record.accel_g.push_back(gain * m.Reading(t) + offset_g + noise(rng));
  }
  record.sample_rate_hz = fs;
  const SensorResult r = ProcessSensor(record, SensorOptions{});
  const SensorSummary& s = r.summary;
  EXPECT_NEAR(s.release_time_s, m.t_release, 1 / fs);
  EXPECT_NEAR(s.impact_time_s, m.t_impact(), 1 / fs);
  EXPECT_NEAR(s.impact_velocity_m_s, m.v0, 0.003 * m.v0);
  // At rest the pounder does not move: v = 0 before the release.
  EXPECT_EQ(r.velocity_m_s[static_cast<std::size_t>(5 * fs)], 0.0);
}

// The integrated v0 against the scene's sqrt(2 g h): within 5 % silent, beyond it a warning in
// summary.json, beyond a factor 2 an error naming the drop height (the sample's v0 is 3.705 m/s;
// h = 0.8 m gives 3.962 m/s, -6.5 %; h = 5 m gives 9.905 m/s, a factor 2.67).
TEST(PhysicsFaults, ImpactVelocityIsCheckedAgainstTheScenesDropHeight) {
  TestDir dir;
  const std::string warned =
      SampleScene(dir, {{"drop_height_m: 0.7", "drop_height_m: 0.8"}}, kNoCorrelation);
  const CliResult r = RunCli("-q run " + warned + " -o " + dir.File("out"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string summary = ReadBytes(dir.File("out/summary.json"));
  EXPECT_TRUE(Contains(summary,
                       "differs by -6.5 % from the 3.962 m/s of a free fall from "
                       "test.drop_height_m = 0.8 m"))
      << summary;
  const std::string absurd =
      SampleScene(dir, {{"drop_height_m: 0.7", "drop_height_m: 5"}}, kNoCorrelation);
  ExpectCliFailure("-q run " + absurd + " -o " + dir.File("out2"),
                   {kSample + "/sensor.csv", "an impact velocity of 3.705 m/s",
                    "within a factor 2 of the 9.905 m/s", "test.drop_height_m = 5 m"});
  EXPECT_FALSE(fs::exists(dir.File("out2")));
  // The sample itself: no warning (v0 -0.02 % from sqrt(2 g h)).
  const std::string sample = SampleScene(dir, {}, kNoCorrelation);
  const CliResult ok = RunCli("-q run " + sample + " -o " + dir.File("out3"));
  ASSERT_EQ(ok.exit_code, 0) << ok.output;
  EXPECT_TRUE(Contains(ReadBytes(dir.File("out3/summary.json")), "\"warnings\": []"));
}

// ---- Item 11: a release time outside the record -----------------------------------------------

// `--release-time -5` assumed 5.05 s of free fall before the record (v0 52.8 m/s, exit 0).
TEST(PhysicsFaults, ReleaseTimeOutsideTheRecordNamesItsSpan) {
  const std::string csv = kSample + "/sensor.csv";
  for (const char* time : {"-5", "0.9", "0.43"}) {
    ExpectCliFailure("-q analyze --sensor " + csv + " --from-release --release-time " + time,
                     {csv, "--release-time", "inside the record, which spans [0 s, 0.47752 s]",
                      "before the detected impact at 0.42776 s"});
  }
  // Inside the record: the sample's own release (0.05 s) gives its v0.
  const CliResult r = RunCli("-q analyze --sensor " + csv +
                             " --from-release --release-time 0.0500057 --format json");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(Contains(r.output, "\"impact_velocity_m_s\": 3.70")) << r.output;
}

// ---- Item 6: the frame rate against the exposure channel --------------------------------------

// `inputs.fps: 16000` with exposure edges at 1600 Hz gave 10x velocities with only a "momentum not
// conserved" warning.
TEST(PhysicsFaults, FrameRateMustAgreeWithTheExposureChannel) {
  TestDir dir;
  const std::string scene = SampleScene(dir, {{"fps: 1600", "fps: 16000"}}, kNoCorrelation);
  ExpectCliFailure("-q run " + scene + " -o " + dir.File("out"),
                   {scene, "inputs.fps", "got 16000 1/s",
                    "the frame rate of the exposure channel in " + kSample + "/sensor.csv",
                    "1598.31 1/s (54 rising edges"});
  EXPECT_FALSE(fs::exists(dir.File("out")));
  // The tolerance: 1 % plus one DAQ sample (40 us) over the edges' span (33.2 ms): 1.12 %. The
  // sample's edges give 1598.31 1/s; 1610 (+0.73 %) passes, 1625 (+1.67 %) does not.
  const SensorResult sensor = AnalyzeSensorCsv(kSample + "/sensor.csv", SensorOptions{});
  EXPECT_EQ(FrameTimes(sensor, 54, {.fps = 1600}).size(), 54u);
  EXPECT_EQ(FrameTimes(sensor, 54, {.fps = 1610}).size(), 54u);
  ExpectErrorContaining([&] { FrameTimes(sensor, 54, {.fps = 1625}); }, "within 1.1 %");
}

// A missing exposure column was reported as "frames: got 1 frames from 49 to 49" (the frames
// were timed from t = 0 by the offset, all before the impact).
TEST(PhysicsFaults, MissingExposureColumnIsNamedWithTheColumnsFound) {
  TestDir dir;
  const CsvTable table = ReadCsv(kSample + "/sensor.csv", CsvReadOptions{});
  WriteCsv(dir.File("daq.csv"), {"time_s", "accel_g", "base_center_N", "base_offset_N"},
           {table.Column("time_s"), table.Column("accel_g"), table.Column("base_center_N"),
            table.Column("base_offset_N")},
           12);
  const std::string scene =
      SampleScene(dir, {{"sensor: " + kSample + "/sensor.csv", "sensor: " + dir.File("daq.csv")}},
                  kNoCorrelation);
  const std::string output =
      ExpectCliFailure("-q run " + scene + " -o " + dir.File("out"),
                       {dir.File("daq.csv"), "column 'exposure' (sensor.exposure_column)",
                        "its columns are time_s, accel_g, base_center_N, base_offset_N",
                        "sensor.exposure_column: \"\""});
  EXPECT_FALSE(Contains(output, "got 1 frames")) << output;
  // Without an exposure channel by choice, frames timed by the default offset 0 all lie before
  // the impact (0.4278 s): the message says so.
  const std::string no_channel =
      SampleScene(dir,
                  {{"sensor: " + kSample + "/sensor.csv", "sensor: " + dir.File("daq.csv")},
                   {"exposure_column: exposure", "exposure_column: \"\""}},
                  kNoCorrelation);
  const std::string timing = ExpectCliFailure(
      "-q run " + no_channel + " -o " + dir.File("out"),
      {no_channel, "frame times", "frames 0..53 at 0 s .. 0.033125 s on the DAQ clock",
       "sensor.frame_time_offset_s + k / inputs.fps", "before the impact at 0.42776 s"});
  EXPECT_FALSE(Contains(timing, "got 1 frames")) << timing;
}

// ---- Item 7: a peak stage that was not analysed from its start --------------------------------

// The chain's correlation from frame `first` on (displacements relative to that frame), as
// `dic.first_frame: first` gives it.
CorrelationSeries ChainFromFrame(const Chain& c, std::size_t first) {
  const CorrelationSeries all = MakeChainCorrelation(c);
  CorrelationSeries dic = all;
  dic.frames = c.frames - first;
  dic.u_px.clear();
  dic.v_px.clear();
  for (std::size_t k = first; k < c.frames; ++k) {
    for (std::size_t s = 0; s < all.subsets; ++s) {
      dic.u_px.push_back(all.u_px[k * all.subsets + s] - all.u_px[first * all.subsets + s]);
      dic.v_px.push_back(all.v_px[k * all.subsets + s] - all.v_px[first * all.subsets + s]);
    }
  }
  return dic;
}

// With the first analysed frame 0.5 ms after the impact (chain: impact at frame 50, t_e at frame
// 78), t_e and m_add,max were "measured" from a soil already moving; now they are NaN with the
// reason, and the momentum stage fails. From frame 50 (at the impact) they are measured as before.
TEST(PhysicsFaults, PeakStageNotAnalysedFromItsStartMakesTeNull) {
  const Chain c;
  PanelMapping map;
  map.mm_per_px = c.scale;
  const SensorResult sensor = MakeChainSensor(c);
  const SceneAnalysis late =
      AnalyzeCorrelation(ChainFromFrame(c, 55), map, {.fps = c.fps, .offset_s = c.offset}, sensor,
                         ChainOptions(c), 55);
  const MomentumSummary& s = late.momentum.summary;
  EXPECT_FALSE(s.IsUsable());
  EXPECT_TRUE(std::isnan(s.t_end_peak_s));
  EXPECT_TRUE(std::isnan(s.added_mass_max_kg));
  EXPECT_TRUE(std::isnan(s.momentum_ratio));
  EXPECT_TRUE(std::isnan(s.momentum_conservation_error));
  EXPECT_TRUE(Contains(s.t_end_problem,
                       "the first analysed frame, at 0.010500 s, is 0.500 ms "
                       "after the impact at 0.010000 s"))
      << s.t_end_problem;
  EXPECT_TRUE(Contains(s.t_end_problem, "dic.first_frame")) << s.t_end_problem;
  EXPECT_NEAR(s.p_max_kg_m_s, c.PMax(), 1e-9);  // The sensor's figure stays.
  const SceneAnalysis at_impact =
      AnalyzeCorrelation(ChainFromFrame(c, 50), map, {.fps = c.fps, .offset_s = c.offset}, sensor,
                         ChainOptions(c), 50);
  const MomentumSummary& ok = at_impact.momentum.summary;
  EXPECT_TRUE(ok.IsUsable()) << ok.t_end_problem;
  EXPECT_NEAR(ok.t_end_peak_s, c.tau_e, 1 / c.fps + 1e-12);
  EXPECT_NEAR(ok.added_mass_max_kg, c.Ms(), 0.01 * c.Ms());
}

// The other end: frames that stop inside the peak stage (chain: 70 frames, the last 1.9 ms after
// the impact, t_e at 2.8 ms). No frame meets the t_e criteria, and the fallback, the frame of the
// maximum soil velocity, was the last frame: t_e 1.9 ms "measured" with a warning. Now NaN with the
// reason.
TEST(PhysicsFaults, FramesEndingInsideThePeakStageMakeTeNull) {
  Chain c;
  c.frames = 70;
  PanelMapping map;
  map.mm_per_px = c.scale;
  const SceneAnalysis a =
      AnalyzeCorrelation(MakeChainCorrelation(c), map, {.fps = c.fps, .offset_s = c.offset},
                         MakeChainSensor(c), ChainOptions(c));
  const MomentumSummary& s = a.momentum.summary;
  EXPECT_FALSE(s.IsUsable());
  EXPECT_TRUE(std::isnan(s.t_end_peak_s));
  EXPECT_TRUE(std::isnan(s.added_mass_max_kg));
  EXPECT_TRUE(Contains(s.t_end_problem,
                       "no analysed frame meets the t_e criteria, and the frames "
                       "end at 0.011900 s"))
      << s.t_end_problem;
  EXPECT_TRUE(Contains(s.t_end_problem, "before the pounder stops")) << s.t_end_problem;
}

// The same in a run of the sample (impact between frames 0 and 1): dic.first_frame 5 fails the
// run naming the momentum stage and why.
TEST(PhysicsFaults, RunWithTheFirstFrameAfterTheImpactFails) {
  TestDir dir;
  const std::string scene =
      SampleScene(dir, {{"dic:\n", "dic:\n  first_frame: 7\n  threads: 2\n"}});
  ExpectCliFailure("-q run " + scene + " -o " + dir.File("out"),
                   {"momentum: t_e is not measurable: the first analysed frame",
                    "after the impact at 0.427760 s", "dic.first_frame", "--allow-partial"});
  EXPECT_FALSE(fs::exists(dir.File("out")));
}

// ---- Done-when: summary.json is the same bytes for two runs ------------------------------------

// The wall-time rate dic_subsets_per_s made every summary.json differ; it is in timing.json now,
// with the run's and the stages' wall times.
TEST(PhysicsFaults, SummaryJsonIsByteIdenticalBetweenRuns) {
  TestDir dir;
  const std::string scene = SampleScene(dir, {});
  for (const char* out : {"a", "b"}) {
    const CliResult r = RunCli("-q run " + scene + " -o " + dir.File(out));
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  const std::string a = ReadBytes(dir.File("a/summary.json"));
  ASSERT_FALSE(a.empty());
  EXPECT_EQ(a, ReadBytes(dir.File("b/summary.json")));
  EXPECT_FALSE(Contains(a, "subsets_per_s")) << a;
  EXPECT_TRUE(Contains(a, "\"impact_velocity_m_s\"")) << a;
  const std::string timing = ReadBytes(dir.File("a/timing.json"));
  for (const char* key : {"\"seconds\"", "\"stages\"", "\"correlate\"", "\"dic_subsets_per_s\""})
    EXPECT_TRUE(Contains(timing, key)) << key << " missing from timing.json:\n" << timing;
  // The marker lists it among the run's outputs.
  EXPECT_TRUE(Contains(ReadBytes(dir.File("a/.impactdic-output")), "timing.json"));
}

}  // namespace
}  // namespace impactdic
