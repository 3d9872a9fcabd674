// The small synthesised impact scene the pipeline's end-to-end tests render with `impactdic synth`:
// 320x240 px at 1.5 mm/px, ideal lens (the lens path is covered by the calib and preprocess tests
// and by the committed sample), 14 frames, the sensor record running 50 ms past the last frame so
// that it contains the stop (crater depth).
#ifndef IMPACTDIC_TESTS_PIPELINE_SMALL_SCENE_SPEC_H_
#define IMPACTDIC_TESTS_PIPELINE_SMALL_SCENE_SPEC_H_

namespace impactdic {

inline constexpr const char* kSmallSceneSpec = R"(
preset: small
name: e2e
camera: {lens: ideal, width: 320, height: 240, mm_per_px: 1.5}
frames: {count: 14, before_impact: 2, supersampling: 2}
sensor: {tail_s: 0.05}
calibration: {render: false}
dic: {subset_size: 21, step: 12}
)";

}  // namespace impactdic

#endif  // IMPACTDIC_TESTS_PIPELINE_SMALL_SCENE_SPEC_H_
