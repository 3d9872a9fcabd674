// The wave figures through `run` (docs/wave.md): a scene synthesised with two base force sensors
// (under the pounder and 300 mm off-centre, 600 mm deep, the paper's layout) at a known wave speed
// and stress ratio; the run (stages sensor and outputs: the wave needs no correlation) recovers
// the speed within 5 % and the stress ratio within 10 % of the truth, writes /wave with units and
// summary.json's "wave". Each wrong input is refused naming the key or the column, or reported
// as implausible with the reason (never a silent wrong speed): a reversed sign, kN given for a
// record in N, a depth that makes the speed absurd, a sensor that peaks before the pounder, a
// missing column; a reflection put into the pounder's record at the return time is found.
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <fstream>
#include <functional>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "../cli/cli_runner.h"
#include "../core/expect_error.h"
#include "../io/test_dir.h"
#include "impactdic/io/csv.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/sensor/wave_results.h"
#include "scene_text.h"

namespace impactdic {
namespace {
namespace L = results_layout;

constexpr double kWaveSpeed = 80;  // [m/s], not the default 65: the speed comes from the spec.
constexpr double kStressRatio = 0.05;

class WaveRun : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = std::make_unique<TestDir>("WaveRun");
    const std::string spec =
        "preset: small\nname: wave\ncamera: {lens: ideal, width: 320, height: 240, mm_per_px: "
        "1.5}\nframes: {count: 6, before_impact: 2, supersampling: 1}\nsensor: {tail_s: 0.06}\n"
        "calibration: {render: false}\nsoil: {wave_speed_m_s: " +
        std::to_string(kWaveSpeed) +
        "}\nbase_sensors:\n  columns: [base_center_N, base_offset_N]\n  offsets_mm: [0, 300]\n"
        "  depths_mm: [600, 600]\n  areas_mm2: [2000, 1500]\n  stress_ratio: " +
        std::to_string(kStressRatio) + "\n";
    const CliResult synth =
        RunCli("-q synth " + dir_->Write("spec.yaml", spec) + " -o " + dir_->File("scene"));
    ASSERT_EQ(synth.exit_code, 0) << synth.output;
    scene_text_ = Replace(ReadText(dir_->File("scene/scene.yaml")), "name: wave\n",
                          "name: wave\nstages: [sensor, outputs]\n");
    scene_text_ = Replace(Replace(scene_text_, "  figures: true", "  figures: false"),
                          "  animation: true", "  animation: false");
  }
  static void TearDownTestSuite() { dir_.reset(); }

  static PipelineSummary Run(const std::string& name, const std::string& text) {
    PipelineOptions options;
    options.output_folder = dir_->File("out_" + name);
    return RunScene(LoadScene(dir_->Write("scene/" + name + ".yaml", text)), options);
  }

  // The scene's sensor.csv with column `name` changed by `edit` (time_s and the column's values),
  // written as `file` beside it; the scene text reading it.
  static std::string WithEditedCsv(
      const std::string& file, const std::string& name,
      const std::function<void(const std::vector<double>&, std::vector<double>*)>& edit) {
    CsvTable t = ReadCsv(dir_->File("scene/sensor.csv"));
    for (std::size_t c = 0; c < t.names.size(); ++c)
      if (t.names[c] == name) edit(t.Column("time_s"), &t.columns[c]);
    WriteCsv(dir_->File("scene/" + file), t.names, t.columns, 12);
    return Replace(scene_text_, "sensor: sensor.csv", "sensor: " + file);
  }

  static std::unique_ptr<TestDir> dir_;
  static std::string scene_text_;
};
std::unique_ptr<TestDir> WaveRun::dir_;
std::string WaveRun::scene_text_;

TEST_F(WaveRun, RecoversWaveSpeedAndStressRatio) {
  const PipelineSummary s = Run("good", scene_text_);
  ASSERT_TRUE(s.wave.has_value());
  const H5Reader truth(dir_->File("scene/truth.h5"));
  const std::vector<double> ratio = truth.ReadDouble("base_sensors/stress_ratio");
  const std::vector<double> travel = truth.ReadDouble("base_sensors/travel_time_s");
  ASSERT_EQ(s.wave->channels.size(), 2u);
  for (std::size_t k = 0; k < 2; ++k) {
    const WaveChannel& c = s.wave->channels[k];
    SCOPED_TRACE(c.column);
    EXPECT_TRUE(c.problems.empty()) << c.problems.front();
    // Done-when bounds: 5 % on the speed, 10 % on the stress ratio (measured: 0.1 % and 0.5 %,
    // docs/wave.md); the speed's own uncertainty (~1.2 %) must cover its error within 3 sigma.
    EXPECT_NEAR(c.speed_peak_m_s, kWaveSpeed, 0.05 * kWaveSpeed);
    EXPECT_NEAR(c.speed_peak_m_s, kWaveSpeed, 3 * c.speed_peak_sigma_m_s);
    EXPECT_NEAR(c.speed_onset_m_s, kWaveSpeed, 0.05 * kWaveSpeed);
    EXPECT_NEAR(c.stress_ratio, ratio[k], 0.10 * ratio[k]);
    EXPECT_NEAR(c.onset_s, travel[k], 3 * s.wave->travel_time_sigma_s);
    EXPECT_NEAR(c.return_time_s, 2 * 0.6 / kWaveSpeed, 0.05 * 2 * 0.6 / kWaveSpeed);
    EXPECT_TRUE(c.reflection.checked) << c.reflection.note;
    EXPECT_FALSE(c.reflection.local_maximum) << c.reflection.prominence_g;  // None in synth.
  }
  // The off-centre sensor reads less: the longer path (spreading).
  EXPECT_LT(s.wave->channels[1].stress_ratio, s.wave->channels[0].stress_ratio);

  const H5Reader results(dir_->File("out_good/results.h5"));
  const std::vector<double> speed = results.ReadDouble(L::kWaveSpeedPeak);
  ASSERT_EQ(speed.size(), 2u);
  EXPECT_DOUBLE_EQ(speed[0], s.wave->channels[0].speed_peak_m_s);
  EXPECT_EQ(results.ReadStringAttribute(L::kWaveSpeedPeak, "units"), "m/s");
  EXPECT_EQ(results.ReadStringAttribute(L::kWaveGroup, L::kWaveColumnsAttr),
            "base_center_N,base_offset_N");
  EXPECT_TRUE(results.Exists(std::string(L::kWaveForceGroup) + "/base_center_N"));
  const WaveResult back = ReadWaveResults(results, "results.h5");
  ASSERT_EQ(back.channels.size(), 2u);
  EXPECT_EQ(back.channels[1].column, "base_offset_N");
  EXPECT_EQ(back.channels[1].unit, "N");
  EXPECT_DOUBLE_EQ(back.channels[1].stress_ratio, s.wave->channels[1].stress_ratio);
  EXPECT_DOUBLE_EQ(back.channels[0].reflection.prominence_g,
                   s.wave->channels[0].reflection.prominence_g);
  EXPECT_TRUE(back.channels[0].reflection.checked);
  EXPECT_DOUBLE_EQ(back.travel_time_sigma_s, s.wave->travel_time_sigma_s);
  const std::string json = ReadText(dir_->File("out_good/summary.json"));
  EXPECT_NE(json.find("\"wave\""), std::string::npos);
  EXPECT_NE(json.find("\"speed_peak_m_s\""), std::string::npos);
}

TEST_F(WaveRun, ReversedSignIsRefusedNamingTheColumn) {
  const std::string text = WithEditedCsv("reversed.csv", "base_offset_N",
                                         [](const std::vector<double>&, std::vector<double>* f) {
                                           for (double& x : *f) x = -x;
                                         });
  ExpectErrorContaining([&] { Run("reversed", text); },
                        "sensor.base_columns: column 'base_offset_N'");
}

TEST_F(WaveRun, KilonewtonsForNewtonsReportsTheStressImplausible) {
  const PipelineSummary s =
      Run("kn", Replace(scene_text_, "base_units: [N, N]", "base_units: [kN, N]"));
  ASSERT_TRUE(s.wave.has_value());
  const WaveChannel& c = s.wave->channels[0];
  EXPECT_TRUE(std::isnan(c.stress_ratio));
  EXPECT_TRUE(std::isnan(c.peak_stress_pa));
  ASSERT_FALSE(c.problems.empty());
  EXPECT_NE(c.problems.front().find("sensor.base_units"), std::string::npos) << c.problems.front();
  EXPECT_FALSE(std::isnan(s.wave->channels[1].stress_ratio));  // The other channel is sound.
  EXPECT_NE(ReadText(dir_->File("out_kn/summary.json")).find("sensor.base_units"),
            std::string::npos);
  const WaveResult back = ReadWaveResults(H5Reader(dir_->File("out_kn/results.h5")), "results.h5");
  EXPECT_EQ(back.channels[0].problems, c.problems);
  EXPECT_TRUE(back.channels[1].problems.empty());
}

TEST_F(WaveRun, DepthGivingAnAbsurdSpeedIsReportedNotUsed) {
  // 600 mm written as 60 mm: 8 m/s, below any soil's.
  const PipelineSummary s =
      Run("depth", Replace(scene_text_, "base_depths_mm: [600, 600]", "base_depths_mm: [60, 600]"));
  ASSERT_TRUE(s.wave.has_value());
  const WaveChannel& c = s.wave->channels[0];
  EXPECT_TRUE(std::isnan(c.speed_peak_m_s));
  EXPECT_TRUE(std::isnan(c.speed_onset_m_s));
  EXPECT_TRUE(std::isnan(c.return_time_s));
  ASSERT_FALSE(c.problems.empty());
  EXPECT_NE(c.problems.front().find("sensor.base_depths_mm"), std::string::npos)
      << c.problems.front();
  EXPECT_FALSE(c.reflection.checked);
  bool warned = false;
  for (const std::string& w : s.warnings) warned = warned || w.find("base_center_N") != w.npos;
  EXPECT_TRUE(warned);
}

TEST_F(WaveRun, SensorPeakingBeforeThePounderIsReportedNotUsed) {
  // The centre record moved 8.5 ms earlier: its peak (~9.4 ms after the impact at 80 m/s) comes
  // ~1 ms after the impact, before the pounder's (~1.9 ms): a negative peak travel time.
  const std::string text = WithEditedCsv(
      "early.csv", "base_center_N", [](const std::vector<double>& t, std::vector<double>* f) {
        const double dt = t[1] - t[0];
        const auto shift = static_cast<std::size_t>(std::lround(0.0085 / dt));
        for (std::size_t i = 0; i + shift < f->size(); ++i) (*f)[i] = (*f)[i + shift];
      });
  const PipelineSummary s = Run("early", text);
  ASSERT_TRUE(s.wave.has_value());
  const WaveChannel& c = s.wave->channels[0];
  EXPECT_TRUE(std::isnan(c.speed_peak_m_s));
  ASSERT_FALSE(c.problems.empty());
  EXPECT_NE(c.problems.front().find("not positive"), std::string::npos) << c.problems.front();
}

TEST_F(WaveRun, MissingColumnNamesTheFileAndColumn) {
  const std::string text = Replace(scene_text_, "base_columns: [base_center_N, base_offset_N]",
                                   "base_columns: [base_centre_N, base_offset_N]");
  const std::string message = ErrorText([&] { Run("missing", text); });
  EXPECT_NE(message.find("base_centre_N"), std::string::npos) << message;
  EXPECT_NE(message.find("sensor.csv"), std::string::npos) << message;
}

TEST_F(WaveRun, ReflectionAtTheReturnTimeIsFound) {
  // A 3 g bump (0.4 ms wide) in the pounder's record at the return time, 2 x 0.6 m / 80 m/s.
  const H5Reader truth(dir_->File("scene/truth.h5"));
  const double impact = truth.ReadNumberAttribute("sensor", "impact_daq_time_s");
  const std::string text = WithEditedCsv(
      "reflection.csv", "accel_g", [impact](const std::vector<double>& t, std::vector<double>* a) {
        const double at = impact + 2 * 0.6 / kWaveSpeed;
        for (std::size_t i = 0; i < t.size(); ++i)
          (*a)[i] += 3 * std::exp(-0.5 * std::pow((t[i] - at) / 0.0004, 2));
      });
  const PipelineSummary s = Run("reflection", text);
  ASSERT_TRUE(s.wave.has_value());
  for (const WaveChannel& c : s.wave->channels) {
    EXPECT_TRUE(c.reflection.checked) << c.reflection.note;
    EXPECT_TRUE(c.reflection.local_maximum)
        << c.column << ": prominence " << c.reflection.prominence_g << " g, threshold "
        << c.reflection.threshold_g << " g";
  }
}

TEST(WaveKeys, ListsMustMatchTheColumns) {
  TestDir dir;
  const std::string base =
      "inputs: {frames: f}\nsensor:\n  base_columns: [a, b]\n  base_offsets_mm: [0, 300]\n"
      "  base_depths_mm: [600, 600]\n  base_areas_mm2: [2000, 2000]\n";
  EXPECT_NO_THROW(ParseScene(base + "  base_units: N, kN\n", dir.File("s.yaml")));
  ExpectErrorContaining([&] { ParseScene(base + "  base_units: [N]\n", dir.File("s.yaml")); },
                        "sensor.base_units");
  ExpectErrorContaining([&] { ParseScene(base + "  base_units: [N, lbf]\n", dir.File("s.yaml")); },
                        "sensor.base_units");
  ExpectErrorContaining(
      [&] {
        ParseScene(Replace(base, "[600, 600]", "[600, -1]") + "  base_units: [N, N]\n",
                   dir.File("s.yaml"));
      },
      "sensor.base_depths_mm");
  ExpectErrorContaining(
      [&] {
        ParseScene(Replace(base, "[2000, 2000]", "[2000]") + "  base_units: [N, N]\n",
                   dir.File("s.yaml"));
      },
      "sensor.base_areas_mm2");
}

}  // namespace
}  // namespace impactdic
