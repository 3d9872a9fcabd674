// The scene file (YAML): one impact test, its inputs, the stages and outputs wanted, and the
// options of each stage. The full format with every key is documented in docs/scene_keys.md
// (generated from the option tables); docs/architecture.md ("Options") says where each option is
// defined.
//
//   Scene scene = LoadScene("sample_frames/scene.yaml");   // throws Error listing every problem
//   double v0 = scene.ImpactVelocity();
//   Correlate(frames, scene.dic.options);                   // the library's own option struct
//
// The scene holds the libraries' option structs (DicOptions, PreprocessOptions, SensorOptions,
// MomentumOptions, ImpactModelParameters, ImpactSolverOptions): its keys are bound to their fields
// (SceneOptionTables), so a key the file leaves out has the library's default, defined once in the
// struct. Only what is about the scene itself (paths, frame range, the pounder's position in
// pixels, ...) is declared here.
//
// Loading checks every key before any work: wrong types and out-of-range values are reported with
// the file, line, the key path the user wrote (e.g. "model.u"), the value found and what is
// expected; unknown keys are errors with a "did you mean" suggestion. Relative paths resolve
// against the scene file's folder.
#ifndef IMPACTDIC_PIPELINE_SCENE_H_
#define IMPACTDIC_PIPELINE_SCENE_H_

#include <algorithm>
#include <array>
#include <optional>
#include <string>
#include <vector>

#include "impactdic/core/enum_names.h"
#include "impactdic/dic/options.h"
#include "impactdic/io/yaml.h"
#include "impactdic/model/impact_model.h"
#include "impactdic/momentum/momentum.h"
#include "impactdic/preprocess/preprocess.h"
#include "impactdic/render/animation.h"
#include "impactdic/render/gnuplot.h"
#include "impactdic/render/render_results.h"
#include "impactdic/render/strain_field.h"
#include "impactdic/render/velocity_field.h"
#include "impactdic/sensor/sensor.h"
#include "impactdic/sensor/wave.h"
#include "impactdic/strain/strain.h"

namespace impactdic {

struct SceneInputs {
  // Folder, glob ("frames/*.png"), video or camera file (.cine, .mraw, .cih, .cihx); resolved path.
  std::string frames;
  // Instead of `frames`: image files in this order, the first the reference (`impactdic correlate
  // --reference REF --deformed DEF ...`; not a scene-file key). Each file once.
  std::vector<std::string> frame_files;
  // Camera frame rate [1/s], kCameraFpsRange (core/range.h). A camera file states its own rate
  // (pipeline SceneFrameClock): then inputs.fps is not needed, and one given must agree with it.
  double fps = 1600;
  bool fps_given = false;   // inputs.fps is in the scene file.
  std::string calibration;  // Calibration YAML (calib module); empty = none (scale from mm_per_px).
  // Scale when there is no calibration file [mm/px], kMmPerPxRange; 0 = from the calibration.
  double mm_per_px = 0;
  // Standard uncertainty of the scale [mm/px], >= 0; 0 = the calibration's plane-scale
  // uncertainty when the scale is the calibration's, else exact. The momentum figures'
  // uncertainty propagates it (momentum/uncertainty.h; the momentum stage).
  double mm_per_px_u = 0;
  std::string sensor;  // DAQ CSV; empty = no sensor stage.
  std::string truth;   // Optional ground-truth HDF5 (synthetic scenes) for comparison.
};

// How fast the pounder hits (`test.drop_height_m`, `test.impact_velocity_m_s`); the pounder and
// the soil (`test.mass_kg`, ...) are bound to Scene::model.
struct SceneTest {
  double drop_height_m = 0.7;  // Drop height h [m], kDropHeightRange (used if no impact velocity).
  std::optional<double> impact_velocity_m_s;  // v0 [m/s], kImpactVelocityRange; overrides h.
};

// `dic.*`: DicOptions plus what depends on the frames (applied by MakeDicOptions).
struct SceneDic {
  DicOptions options;  // subset_size, step, interpolation, shape, reference_update, ...
  // Region of interest x0, y0, x1, y1 [px] in the first frame; all zero = whole image less margins.
  std::array<int, 4> roi{0, 0, 0, 0};
  // Optional polygon region of interest [[x, y], ...] [px] (>= 3 vertices): only subsets whose
  // centre lies inside it are correlated (the grid covers its bounding box, within `roi` if set).
  std::vector<std::array<double, 2>> roi_polygon;
  // Optional mask image (same size as the frames after preprocessing): only subsets whose centre
  // pixel is non-zero are correlated. Resolved against the scene file's folder.
  std::string mask;
  int threads = 0;      // 0 = all cores, N >= 1 = at most N (core/threads.h).
  int first_frame = 0;  // First frame to correlate (index in the sequence), >= 0.
  int last_frame = -1;  // Last frame (inclusive); -1 = the last frame.
  // The analysed frames by the source's own numbers (FrameSource::FrameNumber: a numbered file
  // name's number, a camera's frame number; `impactdic correlate --first/--last`; not scene-file
  // keys): when set, they replace first_frame / last_frame.
  std::optional<long long> first_frame_number, last_frame_number;
};

// `sensor.*`: SensorOptions (g and, with integrate_from: impact, v0 come from the test).
struct SceneSensor {
  SensorOptions options;
  double frame_time_offset_s = 0;  // Time of frame 0 on the DAQ clock [s] (no exposure channel).
};

// `momentum.*`: MomentumOptions (the pounder and soil come from the test) plus the pounder's
// position in pixels, converted to the footprint once the image scale is known.
struct SceneMomentum {
  MomentumOptions options;  // grid_cols, grid_rows, rect_mm, min_valid_fraction.
  // Where the pounder hits, in pixels of the first frame (x right, y down): the horizontal centre
  // of its footprint and the sand surface line (its bottom at impact). Required by the momentum
  // stage unless rect_mm is given.
  std::optional<double> pounder_center_x_px;
  std::optional<double> surface_y_px;
  // Subset samples whose correlation sigma_u or sigma_v exceeds this [px] are left out of the
  // kinematics and the momentum grid mean (kinematics ExcludeUncertainSamples; /dic keeps them),
  // > 0; unset: none left out. Pairs with dic.max_uncertainty_px: none.
  std::optional<double> max_sigma_px;
  // Unless max_sigma_px is set: in each frame, the samples whose sigma_u or sigma_v exceeds this
  // many times the frame's median sigma are left out the same way (kinematics
  // ExcludeSamplesAboveMedianSigma), > 1; +inf: none. Only what no texture supports (a featureless
  // or glaring patch): coherent motion under a pounder reaches 28x the median of a mostly static
  // field (the DEM case, 10 kg, peak stage), real sand's static field 8.4x at its 99.9th
  // percentile (docs/analysis.md).
  double max_sigma_ratio = kDefaultMaxSigmaRatio;
  static constexpr double kDefaultMaxSigmaRatio = 50;
};

// Which analysed frames results.h5 stores in /frames/images (`outputs.frames`). The figures and
// the animation re-read the frames from their source whatever this says.
//  kNone:    none.
//  kPreview: a decimated preview of bounded size (FramePreviewPlan, docs/architecture.md
//            "Memory"): at most kPreviewFrames frames, evenly spaced, each downsampled by an
//            integer factor to at most kPreviewLongSidePx on its longer side.
//  kAll:     every analysed frame at full size, appended one chunk (frame) at a time; the file is
//            built on the disk (io/hdf5_store.h), so it costs disk (the compressed frames), not
//            memory.
enum class FrameStorage { kNone, kPreview, kAll };
inline constexpr EnumNames<FrameStorage, 3> kFrameStorageNames{
    {{{FrameStorage::kNone, "none"},
      {FrameStorage::kPreview, "preview"},
      {FrameStorage::kAll, "all"}}}};
const char* ToString(FrameStorage storage);
FrameStorage FrameStorageFromString(const std::string& text);

struct SceneOutputs {
  std::string folder = "results";  // Output folder; resolved path.
  FrameStorage frames = FrameStorage::kPreview;
  bool hdf5 = true;
  // results.xdmf beside results.h5 (only with hdf5): the subset grid and its fields per frame for
  // ParaView and VisIt, as views of results.h5's datasets (/xdmf), no copied data.
  // Off by default: the views cost memory while results.h5 is built (docs/python.md, "Cost").
  bool xdmf = false;
  bool csv = true;
  bool figures = true;
  bool animation = true;
  bool png_frames = false;
  // How the figures and animations are drawn: `outputs.plot.*` (the gnuplot figures),
  // `outputs.video.*` (the animations' rate and codec), `outputs.velocity_map.*` (the velocity
  // snapshot and animation), `outputs.strain_map.*` (the strain maps and animation). `impactdic
  // render` takes the same keys as flags (SceneRenderOptions).
  PlotOptions plot;
  AnimationOptions video;
  VelocityOverlayOptions velocity_map;
  StrainOverlayOptions strain_map;
};

struct Scene {
  std::string path;       // Scene file path as given.
  std::string folder;     // Its folder (relative paths resolve against it).
  std::string yaml_text;  // The file's text (stored in outputs for provenance).
  std::string name;       // Free-form name, default: the file stem.

  SceneInputs inputs;
  SceneTest test;
  // Stages to run, in pipeline order; default all whose inputs exist:
  // calibrate, frames, correlate, kinematics, sensor, momentum, model, strain, outputs (strain
  // runs only with strain.enabled).
  std::vector<std::string> stages;
  PreprocessOptions preprocess;  // `preprocess.gaussian.*`, `preprocess.clahe.*`.
  SceneDic dic;
  SceneSensor sensor;
  SceneMomentum momentum;
  // `test.*` (pounder, soil, g) and `model.*` (Table 2: K, n, u, T_s, b_per_s; added_mass_kg).
  // impact_velocity_m_s is ImpactVelocity().
  ImpactModelParameters model;
  ImpactSolverOptions solver;  // `model.solver`, `rtol`, `atol`, `error_estimator`,
                               // `ode45_defaults`, `t_max_s`.
  // `strain.*` (docs/strain.md): off unless strain.enabled; rho_d is test.density_kg_m3.
  StrainOptions strain;
  SceneOutputs outputs;

  bool HasStage(const std::string& stage) const;
  // v0 = test.impact_velocity_m_s if given, else sqrt(2 g h).
  double ImpactVelocity() const;
};

// All known stage names in pipeline order.
const std::vector<std::string>& AllSceneStages();

// The scene's keys, one table per section, bound to the fields of `scene` (parsing and the key
// reference in docs; defaults are the fields' values). Keys that are not a plain field (stages,
// roi, roi_polygon, rect_mm) are read by ParseScene itself.
std::vector<YamlOptionTable> SceneOptionTables(Scene* scene);

// A field of a library option struct that no scene key reaches, named by its path in the struct
// after the library's name ("dic.init.seed_spacing", "sensor.max_step_deviation",
// "momentum.sigmoid.max_iterations"; "model." for ImpactModelParameters, "solver." for
// ImpactSolverOptions), and why it is not a key.
struct InternalOption {
  const char* field;
  const char* reason;
};
// Those of the libraries a scene configures (DicOptions, PreprocessOptions, SensorOptions,
// KinematicsOptions, MomentumOptions, ImpactModelParameters, ImpactSolverOptions, StrainOptions),
// each list next to its section's table (src/pipeline/scene.cc). A field set from other keys
// (sensor.g_m_s2 from test.g_m_s2) is reached by them and not listed.
const std::vector<InternalOption>& InternalLibraryOptions();

// Loads and validates a scene file; throws Error (kFileNotFound / kInvalidValue / kFileFormat)
// listing every problem found, one per line.
Scene LoadScene(const std::string& path);
// Same, from text (`path` is used for messages and to resolve relative paths).
Scene ParseScene(const std::string& yaml_text, const std::string& path);

// The rule across the outputs.* keys, which a flag can break after the file was read (the flags
// set one key at a time): outputs.xdmf needs outputs.hdf5 (results.xdmf's fields are views of
// results.h5's datasets). Error(kInvalidValue) naming both keys and the scene file. ParseScene
// reports the file's breach with its line; RunScene checks the scene it is given.
void CheckSceneOutputs(const Scene& scene);

// The library options the stages take, from the scene (the sensor's g and v0, the momentum's
// pounder and soil from the test; the momentum footprint from the pixel position and the scale).
// The drawing of the figures and animations the scene's outputs.* keys ask for (figures, animation,
// png_frames, plot, video, velocity_map, strain_map); the output folder and generation are the
// caller's.
RenderResultsOptions SceneRenderOptions(const Scene& scene);
SensorOptions MakeSensorOptions(const Scene& scene);
// The wave analysis' pounder (test.mass_kg, width_m, depth_m, g_m_s2; sensor/wave.h).
WaveOptions MakeWaveOptions(const Scene& scene);
MomentumOptions MakeMomentumOptions(const Scene& scene, double mm_per_px);
// The model's parameters for impact velocity v0.
ImpactModelParameters MakeModelParameters(const Scene& scene, double impact_velocity_m_s);

}  // namespace impactdic

#endif  // IMPACTDIC_PIPELINE_SCENE_H_
