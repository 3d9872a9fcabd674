// momentum: the momentum balance of pounder and soil (needs the kinematics and the sensor record);
// t_e not measurable is a failure. Also the measured peak deceleration of the peak stage
// (impact .. t_e), in place of the sensor stage's over the scene model's T + 4/b. With base force
// channels, the front in the DIC field (the kinematics, the sensor and t_e are all here).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/model/impact_model.h"
#include "impactdic/momentum/fit.h"
#include "impactdic/momentum/momentum.h"
#include "impactdic/momentum/scene_analysis.h"
#include "impactdic/momentum/wave_front.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/run_data.h"
#include "impactdic/pipeline/scene.h"
#include "stage.h"

namespace impactdic::stages {
namespace {

class MomentumStage : public Stage {
 public:
  const char* name() const override { return "momentum"; }

  std::string SkipReason(const StageContext& c) const override {
    if (!c.data.kinematics) return "no kinematics";
    if (!c.data.sensor) return "needs the sensor record (pounder velocity)";
    return NotListed(c.scene, name());
  }

  std::string Run(StageContext& c) const override {
    SceneRunData& d = c.data;
    MomentumOptions options = MakeMomentumOptions(c.scene, d.mm_per_px);
    // The scale's uncertainty: inputs.mm_per_px_u, else the calibration's plane scale's own
    // (the homography fit's residuals and the local scale's spread) when the scale is its.
    const bool scale_of_calibration =
        !(c.scene.inputs.mm_per_px > 0) && d.calibration && d.calibration->plane && d.mm_per_px > 0;
    if (c.scene.inputs.mm_per_px_u == 0 && scale_of_calibration &&
        std::isfinite(d.calibration->plane->mm_per_px_uncertainty))
      options.uncertainty.scale_u_fraction =
          d.calibration->plane->mm_per_px_uncertainty / d.mm_per_px;
    try {
      d.momentum = AnalyzeMomentum(*d.kinematics, d.timeline.daq_time_s, *d.sensor, options);
    } catch (Error& e) {
      NameFileToFix(c, e);
      throw;
    }
    const MomentumSummary& ms = d.momentum->summary;
    for (const auto& w : ms.warnings) c.summary.warnings.push_back("momentum: " + w);
    SceneFigures& fig = c.summary.figures;
    fig.p_max_kg_m_s = ms.p_max_kg_m_s;
    fig.t_end_peak_s = ms.t_end_peak_s;
    fig.momentum_conservation_error = ms.momentum_conservation_error;
    fig.added_mass_max_kg = ms.added_mass_max_kg;
    fig.v_sand_max_m_s = ms.v_sand_max_m_s;
    fig.momentum_ratio_measured = ms.momentum_ratio;
    if (ms.sigmoid_fitted) {
      fig.sigmoid_M_kg = ms.sigmoid.M_kg;
      fig.sigmoid_b_per_s = ms.sigmoid.b_per_s;
      fig.sigmoid_T_s = ms.sigmoid.T_s;
    }
    c.summary.uncertainty = UncertaintyJson(ms);
    if (!ms.IsUsable())
      c.summary.failures.push_back({"momentum", "t_e is not measurable: " + ms.t_end_problem});
    MeasurePeakDeceleration(c);
    std::string front_note;
    if (d.wave) front_note = MeasureWaveFront(c, options);
    return ms.BriefReport() + front_note;
  }

 private:
  // With base force channels (the wave figures): the front in the DIC field (momentum/
  // wave_front.h), into the wave figures of the run data and the summary.
  static std::string MeasureWaveFront(StageContext& c, const MomentumOptions& m) {
    SceneRunData& d = c.data;
    WaveFrontOptions o;
    o.pounder_center_x_mm = (m.footprint.x_left_mm + m.footprint.x_right_mm) / 2;
    o.surface_y_mm = m.footprint.bottom_y_mm;
    o.pounder_width_mm = m.footprint.x_right_mm - m.footprint.x_left_mm;
    d.wave->front = AnalyzeWaveFront(*d.kinematics, d.timeline.daq_time_s, *d.sensor,
                                     d.momentum->summary.t_end_peak_s, o);
    CheckDicReflections(*d.kinematics, d.timeline.daq_time_s, *d.sensor, o, &d.wave->channels);
    if (c.summary.wave) {
      c.summary.wave->front = d.wave->front;
      c.summary.wave->channels = d.wave->channels;
    }
    const WaveFront& f = d.wave->front;
    c.summary.figures.wave_front_speed_m_s = f.speed_m_s;
    c.summary.figures.wave_decay_length_te_mm = f.displacement_te.decay_length_mm;
    if (!f.problem.empty()) {
      c.summary.warnings.push_back("wave front: " + f.problem);
      return "; wave front: not measured";
    }
    return fmt::format("; wave front {:.4g} m/s", f.speed_m_s);
  }

  // The peak stage ends at t_e; without it the sensor stage's T + 4/b of the scene's model stays
  // (said in a warning).
  static void MeasurePeakDeceleration(StageContext& c) {
    SceneRunData& d = c.data;
    const double t_e = d.momentum->summary.t_end_peak_s;
    if (std::isfinite(t_e)) {
      d.peak_stage_s = t_e;
      d.peak_deceleration_measured_g = MeasuredPeakDeceleration(*d.sensor, t_e);
      c.summary.figures.peak_deceleration_measured_g = d.peak_deceleration_measured_g;
      return;
    }
    c.summary.warnings.push_back(fmt::format(
        "peak deceleration (measured): t_e was not measured, so the peak stage is taken as the "
        "first T + 4/b = {:.3f} ms after the impact (the scene's model)",
        1e3 * d.peak_stage_s));
  }
};

}  // namespace

std::unique_ptr<Stage> MakeMomentumStage() { return std::make_unique<MomentumStage>(); }

}  // namespace impactdic::stages
