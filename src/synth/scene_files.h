// What synth writes for a scene, whoever films it (impact_scene_io.cc: the model's soil;
// dem_scene_io.cc: a DEM run's grains). Internal to the synth module.
#ifndef IMPACTDIC_SRC_SYNTH_SCENE_FILES_H_
#define IMPACTDIC_SRC_SYNTH_SCENE_FILES_H_

#include <functional>
#include <opencv2/core.hpp>
#include <string>

#include "impactdic/synth/impact_scene.h"

namespace impactdic::synth_internal {

struct SceneFiles {
  std::string scene_yaml, truth_h5, sensor_csv, spec_yaml, calibration_dir;
  std::string calibration_yaml;  // What the scene points at (see WriteImpactScene).
  double render_seconds = 0;
};

// Writes into out_dir (created; stale outputs of an earlier scene removed first):
// frames/frame_NNNN.png (render_frame(k) for k < frames, under a progress bar named
// `progress_label`), calibration/ through base's lens if base.spec().render_calibration,
// sensor.csv (`record`), spec.yaml, truth.h5 (write_truth(path, spec_yaml_text)) and scene.yaml,
// the last two last. The names are kImpactSceneOutputNames.
SceneFiles WriteSceneFiles(
    const ImpactScene& base, int frames, const std::function<cv::Mat(int)>& render_frame,
    const std::string& progress_label, const ImpactScene::SensorRecord& record,
    const std::function<void(const std::string&, const std::string&)>& write_truth,
    const std::string& out_dir);

}  // namespace impactdic::synth_internal

#endif  // IMPACTDIC_SRC_SYNTH_SCENE_FILES_H_
