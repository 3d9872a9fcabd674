// The orchestration of one scene's analysis from its correlation (momentum/momentum.h
// AnalyzeCorrelation): frame times, kinematics, then the momentum analysis of momentum.cc.
#include <cstddef>
#include <vector>

#include "impactdic/kinematics/kinematics.h"
#include "impactdic/momentum/momentum.h"
#include "impactdic/sensor/sensor.h"

namespace impactdic {

SceneAnalysis AnalyzeCorrelation(const CorrelationSeries& dic, const PanelMapping& mapping,
                                 const CameraClock& clock, const SensorResult& sensor,
                                 const MomentumOptions& options, std::size_t first_frame) {
  SceneAnalysis a;
  KinematicsOptions kopt;
  kopt.fps = clock.fps;
  a.kinematics = ComputeKinematics(dic, mapping, kopt);
  const std::vector<double> all =
      FrameTimes(sensor, static_cast<int>(first_frame + dic.frames), clock);
  a.frame_time_s.assign(all.begin() + static_cast<std::ptrdiff_t>(first_frame), all.end());
  a.momentum = AnalyzeMomentum(a.kinematics, a.frame_time_s, sensor, options);
  return a;
}

}  // namespace impactdic
