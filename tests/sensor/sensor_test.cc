#include "impactdic/sensor/sensor.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "../core/expect_error.h"
#include "../io/test_dir.h"
#include "impactdic/core/error.h"
#include "impactdic/io/csv.h"
#include "impactdic/sensor/frame_timeline.h"
#include "synthetic_record.h"

namespace impactdic {
namespace {

using testing::MakeRecord;
using testing::PulseMotion;
using testing::SyntheticRecord;
using testing::WriteRecordCsv;

constexpr double kFs = 25000;

// 40 g half-sine pulse (peak inside the pulse), 3.7 m/s impact.
PulseMotion Motion() {
  PulseMotion m;
  m.a_pk = 40 * m.g;
  return m;
}

SyntheticRecord Record(const PulseMotion& m, double offset_g, double noise_g, unsigned seed) {
  return MakeRecord(m, kFs, m.t_impact() + 0.05, offset_g, noise_g, seed);
}

// The accelerometer record of a known motion with offset (0.05 g) and noise (0.05 g rms, seeded,
// as in the synth module's records): impact velocity within 0.5 %, crater depth within 1 %,
// impact time within one sample (the tolerances). The error budget: the offset estimated
// over the whole free fall (9400 samples) is good to ~0.0005 g, i.e. ~0.05 % of v0.
TEST(Sensor, RecoversKnownMotionFromRelease) {
  const PulseMotion m = Motion();
  TestDir dir;
  for (unsigned seed : {1u, 2u, 3u, 4u, 5u}) {
    const SyntheticRecord rec = Record(m, 0.05, 0.05, seed);
    const std::string csv = dir.File("daq.csv");
    WriteRecordCsv(csv, rec);
    SensorOptions opt;
    const SensorResult r = AnalyzeSensorCsv(csv, opt);
    const SensorSummary& s = r.summary;
    EXPECT_NEAR(s.sample_rate_hz, kFs, 1e-3);
    EXPECT_NEAR(s.offset_g, 0.05, 0.002);  // 4 sd of the whole-fall mean
    EXPECT_NEAR(s.offset_window_s[0], m.t_release + opt.quiet_guard_s, 2 / kFs);
    EXPECT_NEAR(s.impact_time_s, m.t_impact(), 1 / kFs) << "seed " << seed;
    EXPECT_NEAR(s.impact_velocity_m_s, m.v0, 0.005 * m.v0) << "seed " << seed;
    EXPECT_NEAR(s.final_penetration_m, m.CraterDepth(), 0.01 * m.CraterDepth()) << "seed " << seed;
    EXPECT_TRUE(s.stopped);
    EXPECT_NEAR(s.stop_time_s - m.t_impact(), m.TauStop(), 2e-4);
    // Peak deceleration a_pk / g - 1 = 39 g in the middle of the pulse (smooth: the filter does
    // not reduce it beyond the noise).
    EXPECT_NEAR(s.peak_deceleration_g, 39.0, 0.3);
    EXPECT_NEAR(s.t_peak_s, m.t_d / 2, 5e-4);
    EXPECT_NEAR(s.release_time_s, m.t_release, 1 / kFs);
    EXPECT_TRUE(s.IsUsable());
    std::printf("seed %u: impact time error %.3f samples, v0 error %.4f %%, depth error %.4f %%\n",
                seed, (s.impact_time_s - m.t_impact()) * kFs,
                100 * (s.impact_velocity_m_s / m.v0 - 1),
                100 * (s.final_penetration_m / m.CraterDepth() - 1));
  }
}

TEST(Sensor, RecoversCraterDepthFromGivenImpactVelocity) {
  const PulseMotion m = Motion();
  const SyntheticRecord rec = Record(m, -0.03, 0.02, 7);
  SensorRecord raw;
  raw.time_s = rec.time_s;
  raw.accel_g = rec.accel_g;
  raw.sample_rate_hz = kFs;
  SensorOptions opt;
  opt.integrate_from = IntegrationStart::kImpact;
  opt.impact_velocity_m_s = m.v0;
  const SensorResult r = ProcessSensor(raw, opt);
  EXPECT_NEAR(r.summary.impact_time_s, m.t_impact(), 1 / kFs);
  EXPECT_DOUBLE_EQ(r.summary.impact_velocity_m_s, m.v0);
  EXPECT_NEAR(r.summary.final_penetration_m, m.CraterDepth(), 0.01 * m.CraterDepth());
  // Velocity series against the closed form in the middle of the pulse.
  const std::size_t k = static_cast<std::size_t>((m.t_impact() + 0.005) * kFs);
  EXPECT_NEAR(r.velocity_m_s[k], m.V(r.time_s[k] - m.t_impact()), 0.01);
}

// Offset from the quiet window before the impact only: fine with low noise (0.005 g).
TEST(Sensor, FreeFallWindowOffsetReference) {
  const PulseMotion m = Motion();
  const SyntheticRecord rec = MakeRecord(m, kFs, m.t_impact() + 0.05, -0.07, 0.005, 12);
  SensorRecord raw;
  raw.time_s = rec.time_s;
  raw.accel_g = rec.accel_g;
  raw.sample_rate_hz = kFs;
  SensorOptions opt;
  opt.offset_reference = OffsetReference::kFreeFallWindow;
  const SensorResult r = ProcessSensor(raw, opt);
  EXPECT_NEAR(r.summary.offset_g, -0.07, 0.002);
  EXPECT_NEAR(r.summary.offset_window_s[1] - r.summary.offset_window_s[0], 0.005 - 1 / kFs, 1e-9);
  EXPECT_NEAR(r.summary.impact_velocity_m_s, m.v0, 0.005 * m.v0);
}

// Offset from the rest window (1 g before release) instead of the free fall: same results.
TEST(Sensor, RestOffsetReference) {
  const PulseMotion m = Motion();
  const SyntheticRecord rec = MakeRecord(m, kFs, m.t_impact() + 0.05, 0.04, 0.005, 11);
  SensorRecord raw;
  raw.time_s = rec.time_s;
  raw.accel_g = rec.accel_g;
  raw.sample_rate_hz = kFs;
  SensorOptions opt;
  opt.offset_reference = OffsetReference::kRest;
  opt.quiet_window_s = 0.015;
  const SensorResult r = ProcessSensor(raw, opt);
  EXPECT_NEAR(r.summary.offset_g, 0.04, 0.002);
  EXPECT_NEAR(r.summary.impact_velocity_m_s, m.v0, 0.005 * m.v0);
  EXPECT_NEAR(r.summary.final_penetration_m, m.CraterDepth(), 0.01 * m.CraterDepth());
}

// A record that starts in free fall cannot be integrated from the release: the release is not in
// it, and a release time before the record would assume a free fall nobody recorded (once,
// `--release-time -5` gave v0 = 52.8 m/s). A given release time inside a whole record is used.
TEST(Sensor, RecordStartingInFreeFallNeedsTheImpactVelocity) {
  const PulseMotion m = Motion();
  const SyntheticRecord full = Record(m, 0.0, 0.01, 5);
  SensorRecord raw;
  const std::size_t skip = static_cast<std::size_t>(0.2 * kFs);
  raw.time_s.assign(full.time_s.begin() + skip, full.time_s.end());
  raw.accel_g.assign(full.accel_g.begin() + skip, full.accel_g.end());
  raw.sample_rate_hz = kFs;
  SensorOptions opt;
  const std::string msg = ErrorText([&] { ProcessSensor(raw, opt); });
  EXPECT_NE(msg.find("not at rest"), std::string::npos) << msg;
  EXPECT_NE(msg.find("release time inside the record"), std::string::npos) << msg;
  opt.offset_reference = OffsetReference::kRest;
  const std::string rest_msg = ErrorText([&] { ProcessSensor(raw, opt); });
  EXPECT_NE(rest_msg.find("offset_reference = rest"), std::string::npos) << rest_msg;
  opt.offset_reference = OffsetReference::kFreeFall;
  opt.release_time_s = m.t_release;
  const std::string before = ErrorText([&] { ProcessSensor(raw, opt); });
  EXPECT_NE(before.find("sensor.release_time_s"), std::string::npos) << before;
  EXPECT_NE(before.find("spans [0.2 s, 0.44724 s]"), std::string::npos) << before;
  opt.release_time_s = kNaN;
  opt.integrate_from = IntegrationStart::kImpact;
  opt.impact_velocity_m_s = m.v0;
  EXPECT_NEAR(ProcessSensor(raw, opt).summary.final_penetration_m, m.CraterDepth(),
              0.01 * m.CraterDepth());
  SensorRecord whole;
  whole.time_s = full.time_s;
  whole.accel_g = full.accel_g;
  whole.sample_rate_hz = kFs;
  SensorOptions given;
  given.release_time_s = m.t_release;
  EXPECT_NEAR(ProcessSensor(whole, given).summary.impact_velocity_m_s, m.v0, 0.005 * m.v0);
}

// Exposure rising edges give the frame times to within one DAQ sample.
TEST(Sensor, FrameTimesFromExposureWithinOneSample) {
  const PulseMotion m = Motion();
  const SyntheticRecord rec = Record(m, 0.05, 0.02, 3);
  TestDir dir;
  const std::string csv = dir.File("daq.csv");
  WriteRecordCsv(csv, rec);
  const SensorResult r = AnalyzeSensorCsv(csv, SensorOptions{});
  const int frames = static_cast<int>(rec.frame_times.size()) - 1;
  ASSERT_GT(frames, 50);
  const std::vector<double> t = FrameTimes(r, frames, CameraClock{});
  ASSERT_EQ(t.size(), static_cast<std::size_t>(frames));
  for (int k = 0; k < frames; ++k) EXPECT_NEAR(t[k], rec.frame_times[k], 1 / kFs) << k;
  // More frames than exposure pulses: the record does not cover the frames.
  const std::string msg = ErrorText([&] { FrameTimes(r, frames + 10, {.fps = 1600}); });
  EXPECT_NE(msg.find("does not cover the frames"), std::string::npos) << msg;
}

TEST(Sensor, FrameTimesFromOffsetAndCoverage) {
  const PulseMotion m = Motion();
  const SyntheticRecord rec = Record(m, 0.0, 0.01, 4);
  SensorRecord raw;
  raw.time_s = rec.time_s;
  raw.accel_g = rec.accel_g;
  raw.sample_rate_hz = kFs;
  const SensorResult r = ProcessSensor(raw, SensorOptions{});
  const std::vector<double> t = FrameTimes(r, 10, {.fps = 1600, .offset_s = 0.3});
  EXPECT_DOUBLE_EQ(t[0], 0.3);
  EXPECT_DOUBLE_EQ(t[9], 0.3 + 9 / 1600.0);
  const std::string msg = ErrorText([&] { FrameTimes(r, 2000, {.fps = 1600, .offset_s = 0.3}); });
  EXPECT_NE(msg.find("does not cover the frames"), std::string::npos) << msg;
  const std::string msg2 = ErrorText([&] {
    SampleSeries(r.time_s, r.velocity_m_s, {0.1, 9.0}, "pounder velocity");
  });
  EXPECT_NE(msg2.find("pounder velocity"), std::string::npos) << msg2;
  EXPECT_NE(msg2.find("does not cover"), std::string::npos) << msg2;
}

// The frame timeline: analysed rows are source frames first.. with their numbers, timed on the
// camera clock (time stamps, else index / fps) and on the DAQ clock (here the exposure edges) as
// the frames of the whole source are; Rows keeps them together.
TEST(FrameTimeline, RowsKeepTheirSourcePositionNumberAndTimes) {
  const PulseMotion m = Motion();
  const SyntheticRecord rec = Record(m, 0.05, 0.02, 3);
  TestDir dir;
  const std::string csv = dir.File("daq.csv");
  WriteRecordCsv(csv, rec);
  const SensorResult r = AnalyzeSensorCsv(csv, SensorOptions{});
  const CameraClock clock{.fps = 1600};
  const FrameTimeline all = MakeFrameTimeline(0, 20, clock, &r);
  // Frames 5..9 numbered by a camera that saves every 2nd frame from -10 on.
  const FrameTimeline part = MakeFrameTimeline(5, {0, 2, 4, 6, 8}, clock, &r);
  ASSERT_EQ(part.size(), 5u);
  EXPECT_EQ(part.index, (std::vector<int>{5, 6, 7, 8, 9}));
  EXPECT_EQ(part.number, (std::vector<long long>{0, 2, 4, 6, 8}));
  EXPECT_EQ(all.exposure_edges, part.exposure_edges);
  EXPECT_NE(part.daq_clock.find("exposure edges"), std::string::npos) << part.daq_clock;
  for (std::size_t k = 0; k < part.size(); ++k) {
    EXPECT_EQ(part.daq_time_s[k], all.daq_time_s[5 + k]) << k;
    EXPECT_NEAR(part.daq_time_s[k], rec.frame_times[5 + k], 1 / kFs) << k;
    EXPECT_DOUBLE_EQ(part.camera_time_s[k], (5.0 + static_cast<double>(k)) / 1600) << k;
  }
  const FrameTimeline rows = all.Rows(5, 9);
  EXPECT_EQ(rows.index, part.index);
  EXPECT_EQ(rows.daq_time_s, part.daq_time_s);
  EXPECT_EQ(all.RowOfIndex(7), 7u);
  EXPECT_EQ(rows.RowOfIndex(7), 2u);
  EXPECT_EQ(rows.RowOfIndex(4), rows.size());
  // Since the impact on the DAQ clock.
  const std::vector<double> ms = rows.MsSinceStart();
  EXPECT_DOUBLE_EQ(ms[1], 1e3 * (rows.daq_time_s[1] - r.summary.impact_time_s));
  EXPECT_THROW(all.Rows(3, 20), Error);
}

// Without a sensor record: the camera clock alone, by the camera's time stamps when it has them
// (then any origin: times since the first frame), else index / fps; NaN without a rate.
TEST(FrameTimeline, CameraClockWithoutASensorRecord) {
  const FrameTimeline by_rate = MakeFrameTimeline(2, 3, CameraClock{.fps = 100}, nullptr);
  EXPECT_FALSE(by_rate.OnDaqClock());
  EXPECT_FALSE(by_rate.camera_stamps);
  const std::vector<double> ms = by_rate.MsSinceStart();
  ASSERT_EQ(ms.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) EXPECT_NEAR(ms[k], 10.0 * static_cast<double>(k), 1e-12);
  EXPECT_EQ(by_rate.number, (std::vector<long long>{2, 3, 4}));
  CameraClock stamped{.fps = 100};
  stamped.time_s = {-0.05, -0.04, -0.03, -0.02};
  const FrameTimeline by_stamps = MakeFrameTimeline(1, {-4, -3}, stamped, nullptr);
  EXPECT_TRUE(by_stamps.camera_stamps);
  EXPECT_EQ(by_stamps.camera_time_s, (std::vector<double>{-0.04, -0.03}));
  const FrameTimeline unknown = MakeFrameTimeline(0, 2, CameraClock{}, nullptr);
  EXPECT_TRUE(std::isnan(unknown.camera_time_s[1]));
  EXPECT_EQ(unknown.fps, 0);
  // More frames than time stamps: an error, not a read past the end.
  EXPECT_THROW(MakeFrameTimeline(3, {0, 1}, stamped, nullptr), Error);
}

TEST(Sensor, AccelerationInMetresPerSecondSquared) {
  const PulseMotion m = Motion();
  SyntheticRecord rec = Record(m, 0.0, 0.01, 9);
  for (double& a : rec.accel_g) a *= m.g;
  TestDir dir;
  const std::string csv = dir.File("daq.csv");
  WriteCsv(csv, {"time_s", "accel_m_s2", "force_top_N"}, {rec.time_s, rec.accel_g, rec.accel_g});
  SensorOptions opt;
  opt.columns.accel = "";  // first of accel_g / accel_m_s2
  const SensorResult r = AnalyzeSensorCsv(csv, opt);
  EXPECT_NEAR(r.summary.impact_velocity_m_s, m.v0, 0.005 * m.v0);
  ASSERT_EQ(r.force_names.size(), 1u);
  EXPECT_EQ(r.force_names[0], "force_top_N");
  EXPECT_EQ(r.force[0].size(), rec.time_s.size());
}

// Bad input: clear errors naming the problem.
TEST(Sensor, BadCsvInputs) {
  TestDir dir;
  std::string body = "time_s,accel_g\n";
  for (int i = 0; i < 1000; ++i) body += std::to_string(i * 4e-5) + ",0.0\n";
  const std::string good = dir.Write("good.csv", body);

  const std::string nan = dir.Write("nan.csv", "time_s,accel_g\n0,0\n4e-5,nan\n8e-5,0\n");
  std::string msg = ErrorText([&] { AnalyzeSensorCsv(nan, SensorOptions{}); });
  EXPECT_NE(msg.find("accel_g"), std::string::npos) << msg;
  EXPECT_NE(msg.find("finite"), std::string::npos) << msg;

  std::string gap_body = "time_s,accel_g\n";
  for (int i = 0; i < 100; ++i) gap_body += std::to_string((i < 50 ? i : i + 7) * 4e-5) + ",0\n";
  const std::string gap = dir.Write("gap.csv", gap_body);
  msg = ErrorText([&] { AnalyzeSensorCsv(gap, SensorOptions{}); });
  EXPECT_NE(msg.find("uniform sampling"), std::string::npos) << msg;
  EXPECT_NE(msg.find("gap"), std::string::npos) << msg;

  const std::string back = dir.Write("back.csv", "time_s,accel_g\n0,0\n2e-5,0\n1e-5,0\n");
  msg = ErrorText([&] { AnalyzeSensorCsv(back, SensorOptions{}); });
  EXPECT_NE(msg.find("strictly increasing"), std::string::npos) << msg;

  const std::string names = dir.Write("names.csv", "t,acc\n0,0\n1,0\n");
  msg = ErrorText([&] { AnalyzeSensorCsv(names, SensorOptions{}); });
  EXPECT_NE(msg.find("time_s"), std::string::npos) << msg;
  EXPECT_NE(msg.find("t, acc"), std::string::npos) << msg;  // lists the columns found
  SensorOptions opt;
  opt.columns.time = "t";
  msg = ErrorText([&] { AnalyzeSensorCsv(names, opt); });
  EXPECT_NE(msg.find("accel_g"), std::string::npos) << msg;

  // No impact in the record.
  msg = ErrorText([&] { AnalyzeSensorCsv(good, SensorOptions{}); });
  EXPECT_NE(msg.find("impact"), std::string::npos) << msg;
}

TEST(SensorOptions, DefaultsPassAndEachBadFieldIsNamed) {
  SensorOptions ok;
  EXPECT_NO_THROW(ok.Check());
  auto expect_named = [](SensorOptions o, const std::string& field) {
    const std::string msg = ErrorText([&] { o.Check(); });
    EXPECT_NE(msg.find(field), std::string::npos) << msg;
  };
  SensorOptions o;
  o.cutoff_hz = -1;
  expect_named(o, "cutoff_hz");
  o = {};
  o.quiet_window_s = 0;
  expect_named(o, "quiet_window_s");
  o = {};
  o.integrate_from = IntegrationStart::kImpact;
  expect_named(o, "impact_velocity_m_s");
  o = {};
  o.impact_threshold_g = 0.5;
  expect_named(o, "impact_threshold_g");
  o = {};
  o.g_m_s2 = 0;
  expect_named(o, "g_m_s2");
  o = {};
  o.noise_band_sigma = 0;
  expect_named(o, "noise_band_sigma");
  o = {};
  o.stop_velocity_m_s = -1;
  expect_named(o, "stop_velocity_m_s");
  EXPECT_EQ(OffsetReferenceFromString(ToString(OffsetReference::kRest)), OffsetReference::kRest);
  EXPECT_EQ(AccelUnitFromString("m/s^2"), AccelUnit::kMetrePerSecond2);
  EXPECT_EQ(IntegrationStartFromString("impact"), IntegrationStart::kImpact);
  EXPECT_THROW(AccelUnitFromString("furlongs"), Error);
}

}  // namespace
}  // namespace impactdic
