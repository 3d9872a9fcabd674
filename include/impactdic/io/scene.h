// The scene file (YAML): one impact test, its inputs, parameters, the stages and outputs wanted,
// and per-stage options. Defaults are the paper's values (README.md, "References"). The full format
// with every key is documented in README.md ("Scene file").
//
//   Scene scene = LoadScene("sample_frames/scene.yaml");   // throws Error listing every problem
//   double v0 = scene.test.ImpactVelocity();
//
// Loading checks every key: wrong types and out-of-range values are reported with the file name,
// the key path (e.g. "dic.subset_size"), the value found and what is expected; unknown keys are
// errors with a "did you mean" suggestion. Relative paths resolve against the scene file's folder.
// Enumerated options are kept as validated strings here; each stage converts them to its enum.
#ifndef IMPACTDIC_IO_SCENE_H_
#define IMPACTDIC_IO_SCENE_H_

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace impactdic {

struct SceneInputs {
  std::string frames;       // Folder, glob ("frames/*.png") or video file; resolved path.
  double fps = 1600;        // Camera frame rate [1/s], kCameraFpsRange (core/range.h).
  std::string calibration;  // Calibration YAML (calib module); empty = none (scale from mm_per_px).
  // Scale when there is no calibration file [mm/px], kMmPerPxRange; 0 = from the calibration.
  double mm_per_px = 0;
  std::string sensor;  // DAQ CSV; empty = no sensor stage.
  std::string truth;   // Optional ground-truth HDF5 (synthetic scenes) for comparison.
};

struct SceneTest {
  // Allowed ranges: core/range.h (the same for `impactdic model` and synthetic specs).
  double mass_kg = 10;         // Pounder mass m_p [kg], kPounderMassRange.
  double drop_height_m = 0.7;  // Drop height h [m], kDropHeightRange (used if no impact velocity).
  std::optional<double> impact_velocity_m_s;  // v0 [m/s], kImpactVelocityRange; overrides h.
  double width_m = 0.15;                      // Pounder width D [m], kPounderSizeRange.
  double depth_m = 0.192;                     // Out-of-plane depth t_z [m], kPounderSizeRange.
  double density_kg_m3 = 1550;                // Dry density rho_d [kg/m^3], kSoilDensityRange.
  double bed_height_m = 0.6;                  // Sand bed height [m], kBedHeightRange.
  double g_m_s2 = 9.81;  // Gravitational acceleration [m/s^2], > 0 and in kGravityRange.

  // v0 = impact_velocity_m_s if given, else sqrt(2 g h).
  double ImpactVelocity() const;
  // Contact area A = D * t_z [m^2].
  double ContactArea() const { return width_m * depth_m; }
};

struct ScenePreprocess {
  bool gaussian = false;          // Gaussian blur on/off.
  double gaussian_sigma = 1.0;    // [px], > 0.
  int gaussian_kernel = 5;        // Kernel size [px], odd >= 3.
  bool clahe = false;             // CLAHE on/off.
  double clahe_clip_limit = 2.0;  // > 0.
  int clahe_tile_grid = 8;        // Tiles per side, >= 1.
};

struct SceneDic {
  int subset_size = 25;  // S [px], odd, >= 5.
  int step = 10;         // Grid step [px], >= 1.
  // Region of interest x0, y0, x1, y1 [px] in the first frame; all zero = whole image less margins.
  std::array<int, 4> roi{0, 0, 0, 0};
  // Optional polygon region of interest [[x, y], ...] [px] (>= 3 vertices): only subsets whose
  // centre lies inside it are correlated (the grid covers its bounding box, within `roi` if set).
  std::vector<std::array<double, 2>> roi_polygon;
  // Optional mask image (same size as the frames after preprocessing): only subsets whose centre
  // pixel is non-zero are correlated. Resolved against the scene file's folder.
  std::string mask;
  std::string interpolation = "bicubic";  // bicubic | biquintic
  std::string shape = "affine";           // affine | quadratic
  std::string reference_update = "auto";  // fixed | incremental | every:N | auto
  double min_zncc = 0.8;         // Correlation threshold for `auto` updates and validity, (0, 1).
  int max_iterations = 30;       // IC-GN iteration cap, >= 1.
  double convergence_px = 1e-3;  // IC-GN stop when the update moves no subset point more [px], > 0.
  int search_radius_px = 20;     // Integer-pixel initial-guess search radius [px], >= 1.
  int threads = 0;               // 0 = all cores, N >= 1 = at most N (core/threads.h).
  int first_frame = 0;           // First frame to correlate (index in the sequence), >= 0.
  int last_frame = -1;           // Last frame (inclusive); -1 = the last frame.
  // Uncertainty limit [px] (dic IcgnOptions::max_uncertainty_px): a converged subset whose
  // estimated sd of u or v exceeds it is `uncertain` (NaN). Unset: the library's default; 0 or
  // `none` (+inf): no limit, every converged subset is kept with its sigma_u_px, sigma_v_px.
  std::optional<double> max_uncertainty_px;
};

struct SceneSensor {
  std::string time_column = "time_s";
  std::string accel_column = "accel_g";
  std::string accel_unit = "g";  // g | m/s^2
  std::string exposure_column =
      "exposure";                          // Empty or absent in the CSV = use frame_time_offset_s.
  double cutoff_hz = 1500;                 // Low-pass cut-off [Hz], > 0 and < fs/2.
  std::string integrate_from = "release";  // release | impact (impact uses test's v0)
  double frame_time_offset_s = 0;  // Time of frame 0 on the DAQ clock [s] (no exposure channel).
  double quiet_window_s = 0.005;   // Length of the quiet window for offset correction [s], > 0.
};

struct SceneMomentum {
  // Where the pounder hits, in pixels of the first frame (x right, y down): the horizontal centre
  // of its footprint and the sand surface line (its bottom at impact). The default grid is
  // grid_cols x grid_rows subsets centred under the footprint, starting just below the surface.
  // Required by the momentum stage unless rect_mm is given.
  std::optional<double> pounder_center_x_px;
  std::optional<double> surface_y_px;
  int grid_cols = 6;  // Subsets across the pounder's footprint, >= 1.
  int grid_rows = 2;  // Subset rows beneath the pounder, >= 1.
  // Optional rectangle in panel millimetres (x0, y0, x1, y1) instead of the default grid.
  std::optional<std::array<double, 4>> rect_mm;
  // Per frame, the fraction of the grid's subsets that must be valid for p_gran to be measured
  // there, in (0, 1]; unset: MomentumOptions::min_valid_fraction (the default is defined there).
  std::optional<double> min_valid_fraction;
  // Subset samples whose correlation sigma_u or sigma_v exceeds this [px] are left out of the
  // kinematics and the momentum grid mean (kinematics ExcludeUncertainSamples; /dic keeps them),
  // > 0; unset: none left out. Pairs with dic.max_uncertainty_px: none.
  std::optional<double> max_sigma_px;
};

struct SceneModel {
  std::optional<double> added_mass_kg;  // M [kg], kAddedMassRange; default: Eq. 4 from m_p, v0, A.
  double K = 50, n = 0.2, u = 1.9, T_s = 0.002, b_per_s = 2500;  // Table 2.
  std::string solver = "auto";                                   // auto | dopri5 | stiff
  double rtol = 1e-8, atol = 1e-12;
};

struct SceneOutputs {
  std::string folder = "results";  // Output folder; resolved path.
  bool hdf5 = true;
  bool csv = true;
  bool figures = true;
  bool animation = true;
  bool png_frames = false;
};

struct Scene {
  std::string path;       // Scene file path as given.
  std::string folder;     // Its folder (relative paths resolve against it).
  std::string yaml_text;  // The file's text (stored in outputs for provenance).
  std::string name;       // Free-form name, default: the file stem.

  SceneInputs inputs;
  SceneTest test;
  // Stages to run, in pipeline order; default all whose inputs exist:
  // calibrate, frames, correlate, kinematics, sensor, momentum, model, outputs.
  std::vector<std::string> stages;
  ScenePreprocess preprocess;
  SceneDic dic;
  SceneSensor sensor;
  SceneMomentum momentum;
  SceneModel model;
  SceneOutputs outputs;

  bool HasStage(const std::string& stage) const;
};

// All known stage names in pipeline order.
const std::vector<std::string>& AllSceneStages();

// Loads and validates a scene file; throws Error (kFileNotFound / kInvalidValue / kFileFormat)
// listing every problem found, one per line.
Scene LoadScene(const std::string& path);
// Same, from text (`path` is used for messages and to resolve relative paths).
Scene ParseScene(const std::string& yaml_text, const std::string& path);

// Closest candidate by edit distance, or "" when none is close (for "did you mean").
std::string ClosestMatch(const std::string& word, const std::vector<std::string>& candidates);

}  // namespace impactdic

#endif  // IMPACTDIC_IO_SCENE_H_
