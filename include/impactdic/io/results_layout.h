// The layout of the results files, in one place: the names of the datasets and attributes of
// results.h5 (`impactdic run`) and of `impactdic correlate -o X.h5`, which every writer and reader
// uses (README.md "HDF5 layout", docs/render.md). The /dic group is written and read by one
// writer and one reader (io/dic_results.h). If a name changes, change it here. Shapes: F =
// analysed frames, N = subsets, R x C = frame rows x columns, K = samples.
#ifndef IMPACTDIC_IO_RESULTS_LAYOUT_H_
#define IMPACTDIC_IO_RESULTS_LAYOUT_H_

#include <array>

namespace impactdic::results_layout {

// Time of every analysed frame since impact [ms], [F]; the frames' index in the input sequence
// [F] (equal to kDicFrame).
inline constexpr const char* kTimeMs = "/time/t_ms";
inline constexpr const char* kTimeFrameIndex = "/time/frame_index";

// --- The DIC results (/dic), layout version kDicLayoutVersion -------------------------------
// Row f of every [F x N] dataset is analysed frame f; row 0 is the first reference image itself
// (zero displacement, status converged, ZNCC 1, sigma 0; a subset the reference cannot carry --
// masked, featureless, low contrast, saturated -- has that status and NaN displacement there).
// Earlier files (no kLayoutVersionAttr on /dic) are read too (io/dic_results.h):
//   version 1, `impactdic run`: the same rows, u/v as float, no /dic/frame (kTimeFrameIndex);
//   version 1, `impactdic correlate`: no reference row (F - 1 rows of the deformed images),
//     /dic/frame 1-based; the status codes also under the attribute `status_names`, the shape
//     also under `shape_function`.
inline constexpr const char* kDicGroup = "/dic";
inline constexpr const char* kLayoutVersionAttr = "layout_version";  // Number attribute of /dic.
inline constexpr int kDicLayoutVersion = 2;
// Subset grid: reference centres [px], [N] (or [F x N] for Lagrangian positions).
inline constexpr const char* kDicX = "/dic/x_px";
inline constexpr const char* kDicY = "/dic/y_px";
// Accumulated displacement since the first reference [px], double, [F x N], NaN = failed; when
// present the drawn subsets move with it (position = x_px + u_px), otherwise they stay at x_px,
// y_px.
inline constexpr const char* kDicU = "/dic/u_px";
inline constexpr const char* kDicV = "/dic/v_px";
// Quality per frame and subset, [F x N]: ZNCC (float), IC-GN iterations (int32), status (int32,
// dic SubsetStatus; the attribute kStatusCodesAttr lists code=name). kValidStatusCode is the
// only status whose displacement is used (dic IsValidStatus).
inline constexpr const char* kDicZncc = "/dic/zncc";
inline constexpr const char* kDicIterations = "/dic/iterations";
inline constexpr const char* kDicStatus = "/dic/status";
inline constexpr const char* kStatusCodesAttr = "codes";
inline constexpr int kValidStatusCode = 0;
// Estimated standard deviations [px], float, [F x N] (0 in row 0, NaN = failed): u, v, the larger.
inline constexpr const char* kDicSigmaU = "/dic/sigma_u_px";
inline constexpr const char* kDicSigmaV = "/dic/sigma_v_px";
inline constexpr const char* kDicSigma = "/dic/sigma_px";
// Per row [F]: index of the image in the input sequence (0 = its first image; the first
// reference is row 0, at index first_frame), int32; the frame number from the file names
// (else the index), double; the index of the reference image the row was correlated against.
inline constexpr const char* kDicFrame = "/dic/frame";
inline constexpr const char* kDicFrameNumber = "/dic/frame_number";
inline constexpr const char* kDicReferenceFrame = "/dic/reference_frame";
// Per row [F], double, only when the source stores them (camera files): the image's time stamp
// [s] from the file (relative to the camera's trigger).
inline constexpr const char* kDicTimeS = "/dic/time_s";
// Number attribute of /dic: index in the input sequence of the first reference (row 0).
inline constexpr const char* kFirstFrameAttr = "first_frame";

// Subset velocity [mm/s], [F x N], NaN = invalid subset.
inline constexpr const char* kKinematicsGroup = "/kinematics";
inline constexpr const char* kVx = "/kinematics/vx_mm_s";
inline constexpr const char* kVy = "/kinematics/vy_mm_s";
// Attribute of kKinematicsGroup: panel scale [mm/px] (number).
inline constexpr const char* kMmPerPxAttr = "mm_per_px";
// Optional string attribute of kKinematicsGroup: "down" (default, image rows) or "up": the
// direction in which vy_mm_s is positive.
inline constexpr const char* kVyDirectionAttr = "vy_positive";

// Optional, [F x N] double, only when the correlation kept them (dic keep_warp_gradient, scene
// key strain.gradient: warp): the displacement gradient of the subset warp since the first
// reference, composed across reference updates (du/dX, du/dY, dv/dX, dv/dY), NaN = failed.
inline constexpr const char* kDicDudxWarp = "/dic/dudx_warp";
inline constexpr const char* kDicDudyWarp = "/dic/dudy_warp";
inline constexpr const char* kDicDvdxWarp = "/dic/dvdx_warp";
inline constexpr const char* kDicDvdyWarp = "/dic/dvdy_warp";

// --- Strain (/strain, scene key strain.enabled; strain/strain.h for the definitions) ---------
// [F x N] double, dimensionless, NaN = unknown. Image axes (x right, y DOWN), reference
// coordinates. The displacement gradient used, small strain (tension positive), Green-Lagrange
// strain (tension positive), volumetric strain eps_v = -(exx + eyy) (COMPRESSION positive, plane
// strain), principal strains eps_1 >= eps_2 and the direction of eps_1 [rad], maximum
// (engineering) shear strain gamma_max = eps_1 - eps_2.
inline constexpr const char* kStrainGroup = "/strain";
inline constexpr const char* kStrainDudx = "/strain/dudx";
inline constexpr const char* kStrainDudy = "/strain/dudy";
inline constexpr const char* kStrainDvdx = "/strain/dvdx";
inline constexpr const char* kStrainDvdy = "/strain/dvdy";
inline constexpr const char* kStrainExx = "/strain/exx";
inline constexpr const char* kStrainEyy = "/strain/eyy";
inline constexpr const char* kStrainExy = "/strain/exy";
inline constexpr const char* kStrainGxx = "/strain/green_lagrange_xx";
inline constexpr const char* kStrainGyy = "/strain/green_lagrange_yy";
inline constexpr const char* kStrainGxy = "/strain/green_lagrange_xy";
inline constexpr const char* kStrainEpsV = "/strain/eps_v";
inline constexpr const char* kStrainEps1 = "/strain/eps_1";
inline constexpr const char* kStrainEps2 = "/strain/eps_2";
inline constexpr const char* kStrainTheta1 = "/strain/theta_1_rad";
inline constexpr const char* kStrainGammaMax = "/strain/gamma_max";
// Rates [1/s], [F x N]: by the velocity's time differences.
inline constexpr const char* kStrainExxRate = "/strain/exx_rate_1_s";
inline constexpr const char* kStrainEyyRate = "/strain/eyy_rate_1_s";
inline constexpr const char* kStrainExyRate = "/strain/exy_rate_1_s";
inline constexpr const char* kStrainEpsVRate = "/strain/eps_v_rate_1_s";
inline constexpr const char* kStrainGammaMaxRate = "/strain/gamma_max_rate_1_s";
// Density rho = rho_d / (1 - eps_v) [kg/m^3], [F x N]; shear-band ridge mask (uint8), [F x N].
inline constexpr const char* kStrainDensity = "/strain/density_kg_m3";
inline constexpr const char* kStrainShearBand = "/strain/shear_band";
// String attributes of kStrainGroup: "gradient" ("warp" | "fit"), "convention" (the sign
// conventions above in words); number attributes: "window" (fit), "compaction_threshold",
// "shear_band_threshold"; the compacted zone at t_e and at the last frame: "compacted_area_te_mm2",
// "compacted_depth_te_mm", "compacted_area_end_mm2", "compacted_depth_end_mm" (NaN when t_e is not
// known, with the reason in the string attribute "compacted_te_note"), their frames (rows)
// "compacted_te_frame" (NaN when t_e is not known) and "compacted_end_frame", where the depth is
// measured from: the string "depth_from" ("momentum.surface_y_px" or "grid top row") and the
// number "surface_y_px" [px]; "dry_density_kg_m3" (rho_d, test.density_kg_m3). Reader and writer:
// strain/strain_results.h.
inline constexpr const char* kStrainGradientAttr = "gradient";
inline constexpr const char* kStrainConventionAttr = "convention";

// Camera frames as analysed, [F x R x C], int32 grey values (0..255 or 0..65535; any numeric type
// is accepted). Optional number attribute kBitDepthAttr (8 or 16) on kFramesGroup.
inline constexpr const char* kFramesGroup = "/frames";
inline constexpr const char* kFrameImages = "/frames/images";
// Since 2026-11-25 (`run`, outputs.frames): the stored frames may be a subset of the analysed
// ones, downsampled: kFrameRows [P] = the row of /time and /dic of each stored image (absent:
// every row), number attributes on kFramesGroup: kDownsampleAttr (integer shrink factor, absent =
// 1) and the full frame size kFrameWidthAttr x kFrameHeightAttr [px] (the subset positions'
// frame).
inline constexpr const char* kFrameRows = "/frames/row";
inline constexpr const char* kDownsampleAttr = "downsample";
inline constexpr const char* kFrameWidthAttr = "width_px";
inline constexpr const char* kFrameHeightAttr = "height_px";
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
// The same drawn by `render` into a run's folder from a preview of its frames (outputs.frames:
// preview): they keep the run's own, drawn from every analysed frame at full size.
inline constexpr const char* kPreviewSnapshotPng = "velocity_field_te_preview.png";
inline constexpr const char* kPreviewAnimationName = "velocity_preview.mp4";
inline constexpr const char* kPreviewAnimationAviName = "velocity_preview.avi";
inline constexpr const char* kPreviewPngFramesDir = "velocity_preview_frames";
// Everything RenderResults may write into its output folder (one generation, replaced together).
inline constexpr std::array<const char*, 11> kRenderOutputNames = {
    kMomentumPng,          kDecelerationPng,         kAddedMassPng,       kVelocitySnapshotPng,
    kAnimationName,        kAnimationAviName,        kPngFramesDir,       kPreviewSnapshotPng,
    kPreviewAnimationName, kPreviewAnimationAviName, kPreviewPngFramesDir};

// The other files of a run's output folder (`impactdic run`, pipeline/pipeline.h).
inline constexpr const char* kResultsFile = "results.h5";
inline constexpr const char* kSummaryJson = "summary.json";
inline constexpr const char* kSummaryCsv = "summary.csv";
// The run's wall times and rates (PipelineSummary::TimingJson), kept out of summary.json so that
// two runs of one scene give byte-identical summaries.
inline constexpr const char* kTimingJson = "timing.json";
// The strain series (scene keys strain.enabled and outputs.csv): one row per analysed frame and
// subset, the /strain measures (docs/strain.md).
inline constexpr const char* kStrainCsv = "strain.csv";
inline constexpr std::array<const char*, 5> kRunOnlyOutputNames = {
    kResultsFile, kSummaryJson, kSummaryCsv, kTimingJson, kStrainCsv};

}  // namespace impactdic::results_layout

#endif  // IMPACTDIC_IO_RESULTS_LAYOUT_H_
