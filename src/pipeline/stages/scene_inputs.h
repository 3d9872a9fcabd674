// The scene's sections as the options of the libraries the stages call (private to the pipeline
// module; MakeDicOptions is public in pipeline/pipeline.h).
#ifndef IMPACTDIC_SRC_PIPELINE_STAGES_SCENE_INPUTS_H_
#define IMPACTDIC_SRC_PIPELINE_STAGES_SCENE_INPUTS_H_

#include <array>
#include <opencv2/core.hpp>
#include <vector>

#include "impactdic/io/scene.h"
#include "impactdic/model/impact_model.h"
#include "impactdic/pipeline/pipeline.h"

namespace impactdic::stages {

// Polygon vertices [px] as integer points.
std::vector<cv::Point> PolygonPoints(const std::vector<std::array<double, 2>>& vertices);

// The correlator's mask from the scene's polygon and mask image (empty if neither is given):
// non-zero where subsets may be centred. Error naming dic.mask / dic.roi_polygon.
cv::Mat SceneMask(const Scene& scene, cv::Size frame_size);

// The scene's test and model sections as the impact model's parameters, with the impact
// velocity given (the sensor's, else the scene's v0).
ImpactModelParameters MakeModelParameters(const Scene& scene, double impact_velocity_m_s);

}  // namespace impactdic::stages

#endif  // IMPACTDIC_SRC_PIPELINE_STAGES_SCENE_INPUTS_H_
