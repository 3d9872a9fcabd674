// The orchestration of one scene's analysis from its correlation (momentum/momentum.h
// AnalyzeCorrelation): the frames' timeline (sensor MakeFrameTimeline), kinematics, then the
// momentum analysis of momentum.cc.
#include <cstddef>
#include <vector>

#include "impactdic/kinematics/kinematics.h"
#include "impactdic/momentum/momentum.h"
#include "impactdic/sensor/frame_timeline.h"

namespace impactdic {

SceneAnalysis AnalyzeCorrelation(const CorrelationSeries& dic, const PanelMapping& mapping,
                                 const CameraClock& clock, const SensorResult& sensor,
                                 const MomentumOptions& options, std::size_t first_frame) {
  SceneAnalysis a;
  const FrameTimeline frames = MakeFrameTimeline(static_cast<int>(first_frame),
                                                 static_cast<int>(dic.frames), clock, &sensor);
  KinematicsOptions kopt;
  kopt.fps = frames.fps;
  a.kinematics = ComputeKinematics(dic, mapping, kopt);
  a.frame_time_s = frames.daq_time_s;
  a.momentum = AnalyzeMomentum(a.kinematics, a.frame_time_s, sensor, options);
  return a;
}

}  // namespace impactdic
