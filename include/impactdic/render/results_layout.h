// The names of the datasets and attributes of results.h5 that `impactdic render` reads, in one
// place (docs/render.md documents the layout). The pipeline writes them; if a name changes, change
// it here. Shapes: F = analysed frames, N = subsets, R x C = frame rows x columns, K = samples.
#ifndef IMPACTDIC_RENDER_RESULTS_LAYOUT_H_
#define IMPACTDIC_RENDER_RESULTS_LAYOUT_H_

#include <array>

namespace impactdic::results_layout {

// Time of every analysed frame since impact [ms], [F].
inline constexpr const char* kTimeMs = "/time/t_ms";

// Subset grid: reference centres [px], [N] (or [F x N] for Lagrangian positions).
inline constexpr const char* kDicX = "/dic/x_px";
inline constexpr const char* kDicY = "/dic/y_px";
// Accumulated displacement [px], [F x N]; when present the drawn subsets move with it
// (position = x_px + u_px), otherwise they stay at x_px, y_px.
inline constexpr const char* kDicU = "/dic/u_px";
inline constexpr const char* kDicV = "/dic/v_px";

// Subset velocity [mm/s], [F x N], NaN = invalid subset.
inline constexpr const char* kKinematicsGroup = "/kinematics";
inline constexpr const char* kVx = "/kinematics/vx_mm_s";
inline constexpr const char* kVy = "/kinematics/vy_mm_s";
// Attribute of kKinematicsGroup: panel scale [mm/px] (number).
inline constexpr const char* kMmPerPxAttr = "mm_per_px";
// Optional string attribute of kKinematicsGroup: "down" (default, image rows) or "up": the
// direction in which vy_mm_s is positive.
inline constexpr const char* kVyDirectionAttr = "vy_positive";

// Camera frames as analysed, [F x R x C], int32 grey values (0..255 or 0..65535; any numeric type
// is accepted). Optional number attribute kBitDepthAttr (8 or 16) on kFramesGroup.
inline constexpr const char* kFramesGroup = "/frames";
inline constexpr const char* kFrameImages = "/frames/images";
inline constexpr const char* kBitDepthAttr = "bit_depth";

// Momentum series (Fig. 4), [K] each; time since impact [s], momentum [N s].
inline constexpr const char* kMomentumGroup = "/momentum";
inline constexpr const char* kMomentumT = "/momentum/t_s";
inline constexpr const char* kPPounder = "/momentum/p_pounder";
inline constexpr const char* kPGran = "/momentum/p_gran";
inline constexpr const char* kPTotal = "/momentum/p_total";
// Added mass (Eq. 3) [kg] on the kMomentumT time base.
inline constexpr const char* kMAdd = "/momentum/m_add_kg";
// Number attributes of kMomentumGroup: p_max [N s], t_e [s] (end of the peak stage), and the
// sigmoid fit of m_add (Eq. 5): M [kg], b [1/s], T [s].
inline constexpr const char* kPMaxAttr = "p_max";
inline constexpr const char* kTeAttr = "t_e";
inline constexpr const char* kSigmoidMAttr = "M";
inline constexpr const char* kSigmoidBAttr = "b";
inline constexpr const char* kSigmoidTAttr = "T";

// Accelerometer: time since impact [s] and pounder deceleration [g] (positive = slowing), [K].
inline constexpr const char* kSensorT = "/sensor/t_s";
inline constexpr const char* kSensorDecel = "/sensor/decel_g";
// Impact model (Eq. 9): the same quantities, [K'].
inline constexpr const char* kModelT = "/model/t_s";
inline constexpr const char* kModelDecel = "/model/decel_g";

// Output file names written by RenderResults into the output folder.
inline constexpr const char* kMomentumPng = "momentum.png";
inline constexpr const char* kDecelerationPng = "deceleration.png";
inline constexpr const char* kAddedMassPng = "added_mass.png";
inline constexpr const char* kVelocitySnapshotPng = "velocity_field_te.png";
inline constexpr const char* kAnimationName = "velocity.mp4";
inline constexpr const char* kAnimationAviName = "velocity.avi";  // The MJPG fallback.
inline constexpr const char* kPngFramesDir = "velocity_frames";
// Everything RenderResults may write into its output folder (one generation, replaced together).
inline constexpr std::array<const char*, 7> kRenderOutputNames = {
    kMomentumPng,   kDecelerationPng,  kAddedMassPng, kVelocitySnapshotPng,
    kAnimationName, kAnimationAviName, kPngFramesDir};

// The other files of a run's output folder (`impactdic run`, pipeline/pipeline.h).
inline constexpr const char* kResultsFile = "results.h5";
inline constexpr const char* kSummaryJson = "summary.json";
inline constexpr const char* kSummaryCsv = "summary.csv";
inline constexpr std::array<const char*, 3> kRunOnlyOutputNames = {kResultsFile, kSummaryJson,
                                                                   kSummaryCsv};

}  // namespace impactdic::results_layout

#endif  // IMPACTDIC_RENDER_RESULTS_LAYOUT_H_
