// The layout of the results files: the names of the datasets and attributes of results.h5
// (`impactdic run`) and of `impactdic correlate -o X.h5` (docs/results.md,
// docs/render.md). Each group has one owner, which declares its names in this namespace beside its
// writer and reader; every other file uses those names (a test, results_paths_test, keeps string
// literals of results paths out of the rest of src/):
//   /dic         io/dic_results.h (names here)       /strain   strain/strain_results.h (names here)
//   /sensor      sensor/sensor_results.h             /kinematics  kinematics/kinematics_results.h
//   /momentum    momentum/momentum_results.h         /model    model/model_results.h
//   /time        sensor/frame_timeline.h (names here) /wave     sensor/wave_results.h
//   /frames, /xdmf, the output folder's file names: here (the run's outputs, pipeline/outputs).
// If a name changes, change it at its owner. Shapes: F = analysed frames, N = subsets,
// R x C = frame rows x columns, K = samples.
#ifndef IMPACTDIC_IO_RESULTS_LAYOUT_H_
#define IMPACTDIC_IO_RESULTS_LAYOUT_H_

#include <array>

namespace impactdic::results_layout {

// The analysed frames' timeline (sensor/frame_timeline.h), [F] each: time since the impact on
// the DAQ clock [ms] (without a sensor record: since the first analysed frame on the camera
// clock); the frames' index in the input sequence (equal to kDicFrame); their number on the
// source's own count (a camera's, with its start frame and save step; a numbered file name's);
// their time on the camera clock [s] (NaN without a frame rate) and on the DAQ clock [s] (only
// with a sensor record). Attributes on kTimeGroup say where the times come from. Owner:
// sensor/frame_timeline.h (WriteFrameTimeline, ReadFrameTimeline).
inline constexpr const char* kTimeGroup = "/time";
inline constexpr const char* kTimeMs = "/time/t_ms";
inline constexpr const char* kTimeFrameIndex = "/time/frame_index";
inline constexpr const char* kTimeFrameNumber = "/time/frame_number";
inline constexpr const char* kTimeCameraS = "/time/camera_time_s";
inline constexpr const char* kTimeDaqS = "/time/daq_time_s";
inline constexpr const char* kTimeCameraClockAttr = "camera_clock";
inline constexpr const char* kTimeDaqClockAttr = "daq_clock";
inline constexpr const char* kTimeFpsAttr = "fps";
inline constexpr const char* kTimeImpactAttr = "impact_time_s";

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

// Output file names written by RenderResults into the output folder.
inline constexpr const char* kMomentumPng = "momentum.png";
inline constexpr const char* kDecelerationPng = "deceleration.png";
inline constexpr const char* kAddedMassPng = "added_mass.png";
// The wave figures (render/wave_figures.h), when results.h5 has /wave.
inline constexpr const char* kWaveSpaceTimePng = "wave_space_time.png";
inline constexpr const char* kWaveBaseForcePng = "wave_base_force.png";
inline constexpr const char* kWaveDepthProfilePng = "wave_depth_profile.png";
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
// The strain maps (eps_v and gamma_max side by side) at t_e and at the last analysed frame, and
// their animation, drawn when the file has kStrainGroup; the preview names as above.
inline constexpr const char* kStrainTePng = "strain_te.png";
inline constexpr const char* kStrainEndPng = "strain_end.png";
inline constexpr const char* kStrainAnimationName = "strain.mp4";
inline constexpr const char* kStrainAnimationAviName = "strain.avi";  // The MJPG fallback.
inline constexpr const char* kStrainPngFramesDir = "strain_frames";
inline constexpr const char* kStrainTePreviewPng = "strain_te_preview.png";
inline constexpr const char* kStrainEndPreviewPng = "strain_end_preview.png";
inline constexpr const char* kStrainPreviewAnimationName = "strain_preview.mp4";
inline constexpr const char* kStrainPreviewAnimationAviName = "strain_preview.avi";
inline constexpr const char* kStrainPreviewPngFramesDir = "strain_preview_frames";
// Everything RenderResults may write into its output folder (one generation, replaced together).
inline constexpr std::array<const char*, 21> kRenderOutputNames = {kMomentumPng,
                                                                   kDecelerationPng,
                                                                   kAddedMassPng,
                                                                   kVelocitySnapshotPng,
                                                                   kAnimationName,
                                                                   kAnimationAviName,
                                                                   kPngFramesDir,
                                                                   kPreviewSnapshotPng,
                                                                   kPreviewAnimationName,
                                                                   kPreviewAnimationAviName,
                                                                   kPreviewPngFramesDir,
                                                                   kStrainTePng,
                                                                   kStrainEndPng,
                                                                   kStrainAnimationName,
                                                                   kStrainAnimationAviName,
                                                                   kStrainPngFramesDir,
                                                                   kStrainTePreviewPng,
                                                                   kStrainEndPreviewPng,
                                                                   kStrainPreviewAnimationName,
                                                                   kStrainPreviewAnimationAviName,
                                                                   kStrainPreviewPngFramesDir};

// The other files of a run's output folder (`impactdic run`, pipeline/pipeline.h).
inline constexpr const char* kResultsFile = "results.h5";
inline constexpr const char* kSummaryJson = "summary.json";
inline constexpr const char* kSummaryCsv = "summary.csv";
// The run's wall times and rates (PipelineSummary::TimingJson), kept out of summary.json so that
// two runs of one scene give byte-identical summaries.
inline constexpr const char* kTimingJson = "timing.json";
// results.xdmf (outputs.xdmf, with outputs.hdf5): the XDMF 3 description of results.h5's subset
// fields for ParaView and VisIt. It references views in results.h5 (kXdmfGroup): HDF5 virtual
// datasets that hold no data of their own, so readers that take whole datasets (meshio) read it
// as well as those that take hyperslabs. kXdmfPoints [N x 2] = (kDicX, kDicY) [px];
// kXdmfVertices [N x 1] int32 = 0..N-1 (the Polyvertex topology, the only stored data); per
// analysed frame f a group kXdmfFramePrefix + f (6 digits) of [N] views of row f of the [F x N]
// datasets of /dic, /kinematics and /strain, and [N x 3] vectors (x, y, 0).
inline constexpr const char* kXdmfFile = "results.xdmf";
inline constexpr const char* kXdmfGroup = "/xdmf";
inline constexpr const char* kXdmfPoints = "/xdmf/points_px";
inline constexpr const char* kXdmfVertices = "/xdmf/vertices";
inline constexpr const char* kXdmfFramePrefix = "/xdmf/frame_";
// The strain series (scene keys strain.enabled and outputs.csv): one row per analysed frame and
// subset, the /strain measures (docs/strain.md).
inline constexpr const char* kStrainCsv = "strain.csv";
inline constexpr std::array<const char*, 6> kRunOnlyOutputNames = {
    kResultsFile, kSummaryJson, kSummaryCsv, kTimingJson, kXdmfFile, kStrainCsv};

}  // namespace impactdic::results_layout

#endif  // IMPACTDIC_IO_RESULTS_LAYOUT_H_
