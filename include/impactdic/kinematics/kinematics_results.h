// The soil's kinematics (the /kinematics group of results.h5): the names, one writer, one reader.
// Other modules read /kinematics through these names (namespace results_layout, like every
// group's; io/results_layout.h lists the owners).
//
//   H5Writer out("run/results.h5");
//   WriteKinematicsResults(out, kinematics, frame_time_daq_s, /*mm_per_px=*/0.4);
//   out.Commit();
//   const KinematicsResultsGroup k = ReadKinematicsResults(H5Reader("run/results.h5"), "...");
#ifndef IMPACTDIC_KINEMATICS_KINEMATICS_RESULTS_H_
#define IMPACTDIC_KINEMATICS_KINEMATICS_RESULTS_H_

#include <string>
#include <vector>

#include "impactdic/core/numeric.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/kinematics/kinematics.h"

namespace impactdic {
namespace results_layout {

// Frame times [F]: k / fps since frame 0 [s]; on the DAQ clock [s] (exposure edges or offset +
// k / fps; only when the run had a sensor record).
inline constexpr const char* kKinematicsGroup = "/kinematics";
inline constexpr const char* kKinematicsTime = "/kinematics/time_s";
inline constexpr const char* kKinematicsFrameTimeDaq = "/kinematics/frame_time_daq_s";
// Subset velocity [mm/s], [F x N], NaN = invalid subset.
inline constexpr const char* kVx = "/kinematics/vx_mm_s";
inline constexpr const char* kVy = "/kinematics/vy_mm_s";
// Subset acceleration [mm/s^2] and displacement since the first reference [mm] on the panel,
// [F x N] (x right, y down), NaN = invalid subset; reference subset centres on the panel [mm], [N].
inline constexpr const char* kAx = "/kinematics/ax_mm_s2";
inline constexpr const char* kAy = "/kinematics/ay_mm_s2";
inline constexpr const char* kUxMm = "/kinematics/ux_mm";
inline constexpr const char* kUyMm = "/kinematics/uy_mm";
inline constexpr const char* kKinematicsX = "/kinematics/x_mm";
inline constexpr const char* kKinematicsY = "/kinematics/y_mm";
// Attribute of kKinematicsGroup: panel scale [mm/px] (number).
inline constexpr const char* kMmPerPxAttr = "mm_per_px";
// Optional string attribute of kKinematicsGroup: "down" (default, image rows) or "up": the
// direction in which vy_mm_s is positive.
inline constexpr const char* kVyDirectionAttr = "vy_positive";

}  // namespace results_layout

// /kinematics as read.
struct KinematicsResultsGroup {
  KinematicsResult kinematics;           // frames, subsets, time_s, x_mm .. acc_y_mm_s2.
  std::vector<double> frame_time_daq_s;  // Empty when the file has none.
  double mm_per_px = kNaN;               // NaN when the file has none.
  std::string vy_positive = "down";
};

// Writes /kinematics (replacing an existing group), with units and descriptions on every dataset;
// frame_time_daq_s only when not empty, the attribute mm_per_px only when finite.
void WriteKinematicsResults(H5Writer& out, const KinematicsResult& kinematics,
                            const std::vector<double>& frame_time_daq_s, double mm_per_px = kNaN);

// Reads /kinematics back. Error kFileFormat naming `file` and the group or dataset when it is
// missing or of another shape than [frames] / [subsets] / [frames x subsets].
KinematicsResultsGroup ReadKinematicsResults(const H5Reader& in, const std::string& file);

}  // namespace impactdic

#endif  // IMPACTDIC_KINEMATICS_KINEMATICS_RESULTS_H_
