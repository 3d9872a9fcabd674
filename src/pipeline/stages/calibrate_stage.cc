// calibrate: the camera model (undistortion) and the panel scale.
#include <fmt/format.h>

#include <memory>
#include <optional>
#include <string>

#include "impactdic/calib/calibration.h"
#include "impactdic/core/error.h"
#include "impactdic/pipeline/run_data.h"
#include "impactdic/pipeline/scene.h"
#include "stage.h"

namespace impactdic::stages {
namespace {

class CalibrateStage : public Stage {
 public:
  const char* name() const override { return "calibrate"; }

  std::string SkipReason(const StageContext& c) const override {
    if (c.scene.inputs.calibration.empty()) return "no calibration file in the scene";
    return NotListed(c.scene, name());
  }

  std::string Run(StageContext& c) const override {
    const Scene& scene = c.scene;
    SceneRunData& d = c.data;
    d.calibration = LoadCalibration(scene.inputs.calibration);
    std::string note =
        fmt::format("{} (RMS {:.3f} px)", scene.inputs.calibration, d.calibration->rms_px);
    if (d.mm_per_px > 0)
      return note + fmt::format(", scale {:.5f} mm/px from the scene", d.mm_per_px);
    if (!d.calibration->plane) {
      throw Error(ErrorKind::kInvalidValue, "inputs.mm_per_px",
                  "0 and the calibration has no plane scale",
                  "a scale > 0 [mm/px] or a calibration with a plane scale")
          .WithFile(scene.path);
    }
    d.mm_per_px = d.calibration->plane->mm_per_px;
    return note + fmt::format(", plane scale {:.5f} +- {:.5f} mm/px", d.mm_per_px,
                              d.calibration->plane->mm_per_px_uncertainty);
  }
};

}  // namespace

std::unique_ptr<Stage> MakeCalibrateStage() { return std::make_unique<CalibrateStage>(); }

}  // namespace impactdic::stages
