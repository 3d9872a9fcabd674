// The small synthesised impact scene the pipeline's end-to-end tests render with `impactdic synth`:
// 320x240 px at 1.5 mm/px, ideal lens (the lens path is covered by the calib and preprocess tests
// and by the committed sample), 14 frames, the sensor record running 50 ms past the last frame so
// that it contains the stop (crater depth). SmallSceneSpec gives it with other frame counts and
// grids (e.g. a long recording).
#ifndef IMPACTDIC_TESTS_PIPELINE_SMALL_SCENE_SPEC_H_
#define IMPACTDIC_TESTS_PIPELINE_SMALL_SCENE_SPEC_H_

#include <string>

namespace impactdic {

struct SmallScene {
  int frames = 14, supersampling = 2;
  double tail_s = 0.05;  // The sensor record past the last frame [s].
  int subset_size = 21, step = 12;
};

inline std::string SmallSceneSpec(const SmallScene& s = {}) {
  return "preset: small\nname: e2e\ncamera: {lens: ideal, width: 320, height: 240, mm_per_px: "
         "1.5}\nframes: {count: " +
         std::to_string(s.frames) +
         ", before_impact: 2, supersampling: " + std::to_string(s.supersampling) +
         "}\nsensor: {tail_s: " + std::to_string(s.tail_s) +
         "}\ncalibration: {render: false}\ndic: {subset_size: " + std::to_string(s.subset_size) +
         ", step: " + std::to_string(s.step) + "}\n";
}

inline const std::string kSmallSceneSpec = SmallSceneSpec();

}  // namespace impactdic

#endif  // IMPACTDIC_TESTS_PIPELINE_SMALL_SCENE_SPEC_H_
