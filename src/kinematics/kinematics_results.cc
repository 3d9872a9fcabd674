#include "impactdic/kinematics/kinematics_results.h"

#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "impactdic/io/results_io.h"

namespace impactdic {
namespace L = results_layout;

void WriteKinematicsResults(H5Writer& out, const KinematicsResult& k,
                            const std::vector<double>& frame_time_daq_s, double mm_per_px) {
  const Dims fs{k.frames, k.subsets};
  out.Remove(L::kKinematicsGroup);
  out.Write(L::kKinematicsTime, k.time_s, "s", "frame time k / fps since frame 0");
  if (!frame_time_daq_s.empty()) {
    out.Write(L::kKinematicsFrameTimeDaq, frame_time_daq_s, "s",
              "frame time on the DAQ clock (exposure edges or offset + k / fps)");
  }
  out.Write(L::kKinematicsX, k.x_mm, "mm", "reference subset centre x (panel, right)");
  out.Write(L::kKinematicsY, k.y_mm, "mm", "reference subset centre y (panel, down)");
  out.Write(L::kUxMm, k.disp_x_mm, fs, "mm", "displacement x [frames x subsets]");
  out.Write(L::kUyMm, k.disp_y_mm, fs, "mm",
            "displacement y, downward positive [frames x subsets]");
  out.Write(L::kVx, k.vel_x_mm_s, fs, "mm/s", "subset velocity x (right), central differences");
  out.Write(L::kVy, k.vel_y_mm_s, fs, "mm/s", "subset velocity y (down), central differences");
  out.Write(L::kAx, k.acc_x_mm_s2, fs, "mm/s^2", "subset acceleration x (right)");
  out.Write(L::kAy, k.acc_y_mm_s2, fs, "mm/s^2", "subset acceleration y (down)");
  out.SetAttribute(L::kKinematicsGroup, L::kVyDirectionAttr, "down");
  if (std::isfinite(mm_per_px)) out.SetAttribute(L::kKinematicsGroup, L::kMmPerPxAttr, mm_per_px);
}

KinematicsResultsGroup ReadKinematicsResults(const H5Reader& in, const std::string& file) {
  RequireGroup(in, L::kKinematicsGroup, file, "the soil's kinematics (impactdic run or analyze)");
  KinematicsResultsGroup g;
  KinematicsResult& k = g.kinematics;
  std::size_t frames = kAnyLength, subsets = kAnyLength;
  k.time_s = ReadSeries(in, L::kKinematicsTime, file, &frames);
  if (in.Exists(L::kKinematicsFrameTimeDaq))
    g.frame_time_daq_s = ReadSeries(in, L::kKinematicsFrameTimeDaq, file, &frames);
  k.x_mm = ReadSeries(in, L::kKinematicsX, file, &subsets);
  k.y_mm = ReadSeries(in, L::kKinematicsY, file, &subsets);
  k.frames = frames;
  k.subsets = subsets;
  const Dims fs{frames, subsets};
  k.disp_x_mm = ReadField(in, L::kUxMm, file, fs);
  k.disp_y_mm = ReadField(in, L::kUyMm, file, fs);
  k.vel_x_mm_s = ReadField(in, L::kVx, file, fs);
  k.vel_y_mm_s = ReadField(in, L::kVy, file, fs);
  k.acc_x_mm_s2 = ReadField(in, L::kAx, file, fs);
  k.acc_y_mm_s2 = ReadField(in, L::kAy, file, fs);
  g.mm_per_px = ReadNumberAttributeOr(in, L::kKinematicsGroup, L::kMmPerPxAttr, kNaN);
  g.vy_positive = ReadStringAttributeOr(in, L::kKinematicsGroup, L::kVyDirectionAttr, "down");
  return g;
}

}  // namespace impactdic
