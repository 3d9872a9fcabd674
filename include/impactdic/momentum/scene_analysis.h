// `impactdic analyze SCENE.yaml`: the sensor, kinematics and momentum stages of one scene from its
// correlation results (HDF5), written back into the same file.
//
// Correlation layout read (render/results_layout.h, the dic stage's output):
//   /dic/x_px, /dic/y_px   subset centres in the reference frame, [N] (or [R x C], or [F x N]:
//                          then the first row)
//   /dic/u_px, /dic/v_px   displacement since the reference frame, [F x N] (or [F x R x C])
//   /dic/status            optional, same shape as u_px, 0 = converged (dic SubsetStatus);
//                          anything else, or a non-finite displacement, is invalid.
//   /dic/frame             optional, image index of each row. When it starts at 1 (the dic
//                          stage's rows are the deformed images only), a zero-displacement row
//                          for the reference image (frame 0) is prepended.
//   Optional number attribute "first_frame" of /dic: index of the first correlated frame in the
//   camera sequence (default: the scene's dic.first_frame).
//
//   Scene scene = LoadScene("scene.yaml");
//   SceneAnalysisRun run = AnalyzeSceneResults(scene, "results/results.h5", /*mm_per_px=*/0.1);
#ifndef IMPACTDIC_MOMENTUM_SCENE_ANALYSIS_H_
#define IMPACTDIC_MOMENTUM_SCENE_ANALYSIS_H_

#include <string>

#include "impactdic/io/scene.h"
#include "impactdic/momentum/momentum.h"

namespace impactdic {

// The scene's sensor section and test parameters as SensorOptions (integrate_from = impact uses the
// test's impact velocity).
SensorOptions SensorOptionsFromScene(const Scene& scene);

// The scene's test and momentum sections as MomentumOptions; the pounder footprint from
// momentum.pounder_center_x_px / surface_y_px (converted with the uniform scale mm_per_px).
// Error when neither those keys nor momentum.rect_mm are given.
MomentumOptions MomentumOptionsFromScene(const Scene& scene, double mm_per_px);

// Reads the correlation results (layout above). *first_frame (optional) receives the /dic
// attribute first_frame, or -1 when absent.
CorrelationSeries ReadCorrelationSeries(const std::string& h5_path, long* first_frame = nullptr);

struct SceneAnalysisRun {
  SensorResult sensor;
  SceneAnalysis analysis;
  std::string results_path;
};

// Reads the correlation results, analyses the sensor record, computes kinematics and momentum
// and writes /sensor, /kinematics and /momentum into results_path (update in place, atomically).
SceneAnalysisRun AnalyzeSceneResults(const Scene& scene, const std::string& results_path,
                                     double mm_per_px);

}  // namespace impactdic

#endif  // IMPACTDIC_MOMENTUM_SCENE_ANALYSIS_H_
