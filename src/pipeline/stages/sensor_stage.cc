// sensor: the accelerometer record (impact time and velocity, pounder motion, crater depth), the
// wave figures of the base force channels when the scene names them (sensor/wave.h), and
// the measured peak deceleration over the peak stage as the scene's model has it (T + 4/b; the
// momentum stage measures it over t_e).
#include <fmt/format.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "impactdic/momentum/scene_analysis.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/run_data.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/sensor/sensor.h"
#include "impactdic/sensor/wave.h"
#include "stage.h"

namespace impactdic::stages {
namespace {

class SensorStage : public Stage {
 public:
  const char* name() const override { return "sensor"; }

  std::string SkipReason(const StageContext& c) const override {
    if (c.scene.inputs.sensor.empty()) return "no sensor CSV in the scene";
    return NotListed(c.scene, name());
  }

  std::string Run(StageContext& c) const override {
    const SensorOptions options = MakeSensorOptions(c.scene);
    const SensorResult& sensor =
        c.data.sensor.emplace(AnalyzeSensorCsv(c.scene.inputs.sensor, options));
    for (const auto& w : sensor.summary.warnings) c.summary.warnings.push_back("sensor: " + w);
    std::string wave_note;
    if (!sensor.base.empty()) {
      const WaveResult& wave =
          c.data.wave.emplace(AnalyzeWave(sensor, options, MakeWaveOptions(c.scene)));
      c.summary.wave = wave;
      for (const auto& w : wave.Warnings()) c.summary.warnings.push_back("wave: " + w);
      wave_note = fmt::format("; {} base channels", wave.channels.size());
      if (const WaveChannel* centre = wave.CentreChannel()) {
        c.summary.figures.wave_speed_peak_m_s = centre->speed_peak_m_s;
        c.summary.figures.wave_stress_ratio = centre->stress_ratio;
      }
    }
    c.summary.figures.impact_velocity_m_s = sensor.summary.impact_velocity_m_s;
    c.summary.figures.crater_depth_measured_m = sensor.summary.final_penetration_m;
    c.data.peak_stage_s = c.scene.model.sigmoid_delay_T_s + 4 / c.scene.model.sigmoid_rate_b_per_s;
    c.data.peak_deceleration_measured_g = MeasuredPeakDeceleration(sensor, c.data.peak_stage_s);
    c.summary.figures.peak_deceleration_measured_g = c.data.peak_deceleration_measured_g;
    return sensor.summary.BriefReport() + wave_note;
  }
};

}  // namespace

std::unique_ptr<Stage> MakeSensorStage() { return std::make_unique<SensorStage>(); }

}  // namespace impactdic::stages
