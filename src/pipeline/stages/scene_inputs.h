// The scene's sections as the options of the libraries the stages call (private to the pipeline
// module; MakeDicOptions is public in pipeline/pipeline.h).
#ifndef IMPACTDIC_SRC_PIPELINE_STAGES_SCENE_INPUTS_H_
#define IMPACTDIC_SRC_PIPELINE_STAGES_SCENE_INPUTS_H_

#include <array>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "impactdic/kinematics/kinematics.h"
#include "impactdic/pipeline/scene.h"

namespace impactdic::stages {

// Polygon vertices [px] as integer points.
std::vector<cv::Point> PolygonPoints(const std::vector<std::array<double, 2>>& vertices);

// The correlator's mask from the scene's polygon and mask image (empty if neither is given):
// non-zero where subsets may be centred. Error naming dic.mask / dic.roi_polygon.
cv::Mat SceneMask(const Scene& scene, cv::Size frame_size);

// The panel scale [mm/px] a stage that works in millimetres needs (the kinematics and strain
// stages): mm_per_px itself, or Error naming inputs.mm_per_px and the scene file when it is not >
// 0.
double RequireScale(const Scene& scene, double mm_per_px);

// Leaves the uncertain samples of the scene's correlation series out of its kinematics and
// momentum (momentum.max_sigma_px if set, else momentum.max_sigma_ratio) and returns the warning
// saying how many (empty when neither applies, or the ratio rule left nothing out). The one rule
// of the kinematics and strain stages.
std::string ExcludeUncertainSamplesOfScene(const Scene& scene, CorrelationSeries* series);

}  // namespace impactdic::stages

#endif  // IMPACTDIC_SRC_PIPELINE_STAGES_SCENE_INPUTS_H_
