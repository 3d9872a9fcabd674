// model: the impact model (Eq. 9) with the measured impact velocity (else the scene's v0); a solve
// that does not reach v = 0 is a failure. Also the measured plateau deceleration over [t1, stop].
#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "impactdic/core/numeric.h"
#include "impactdic/model/impact_model.h"
#include "impactdic/momentum/scene_analysis.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/run_data.h"
#include "impactdic/pipeline/scene.h"
#include "stage.h"

namespace impactdic::stages {
namespace {

class ModelStage : public Stage {
 public:
  const char* name() const override { return "model"; }

  std::string SkipReason(const StageContext& c) const override {
    return NotListed(c.scene, name());
  }

  std::string Run(StageContext& c) const override {
    const Scene& scene = c.scene;
    SceneRunData& d = c.data;
    SceneFigures& fig = c.summary.figures;
    const double measured_v0 = d.sensor ? d.sensor->summary.impact_velocity_m_s : kNaN;
    const double v0 = std::isfinite(measured_v0) ? measured_v0 : scene.ImpactVelocity();
    d.model_parameters = MakeModelParameters(scene, v0);
    d.model = SimulateImpact(d.model_parameters, scene.solver);
    const ImpactSummary& s = d.model->summary;
    for (const auto& w : s.warnings) c.summary.warnings.push_back("model: " + w);
    fig.added_mass_eq4_kg =
        AddedMassMaxEq4(scene.model.pounder_mass_kg, v0, scene.model.ContactArea_m2());
    fig.momentum_ratio_model = s.momentum_ratio;
    fig.peak_deceleration_model_g = s.peak_deceleration_g;
    fig.plateau_deceleration_model_g = s.plateau_deceleration_g;
    fig.crater_depth_model_m = s.crater_depth_m;
    fig.t_end_model_s = s.t_end_s;
    if (d.sensor) {
      fig.plateau_deceleration_measured_g =
          MeasuredPlateauDeceleration(*d.sensor, s.t1_s, scene.model.gravity_m_s2);
    }
    if (!s.IsUsable())
      c.summary.failures.push_back({"model", "the solve did not reach v = 0: " + s.stop_reason});
    return s.BriefReport();
  }
};

}  // namespace

std::unique_ptr<Stage> MakeModelStage() { return std::make_unique<ModelStage>(); }

}  // namespace impactdic::stages
