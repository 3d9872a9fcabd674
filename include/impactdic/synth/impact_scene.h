// Synthetic impact scenes (docs/synth.md): a high-speed sequence of the panel of the
// paper's test rig (Loewe, Thiele, Kanty, Kirstein, "Experimental investigation and modeling of
// impact stages during dynamic compaction", sections 2-4), rendered EXACTLY from known fields,
// with the matching accelerometer record, calibration images through the same lens, the scene
// file that processes it and the ground truth. The full description of the fields, the
// conventions and the truth file layout is docs/synth.md.
//
// Geometry. Panel coordinates (X, Y) [mm]: origin where the pounder's axis meets the undisturbed
// sand surface, X right, Y DOWN (depth). The camera is fronto-parallel at the distance
// d = s sqrt(fx fy) (s = camera.mm_per_px), so an ideal (undistorted, pinhole) pixel (u, v) sees
// X = (u - u_axis) d / fx, Y = (v - v_surface) d / fy. Material coordinates of the speckle are
// the reference ideal pixels (the undistorted first frame).
//
// Time. t [s] since the impact (contact), downward velocities positive. Frame k is exposed at
// t_k = (k - frames_before_impact + impact_phase) / fps (the rising edge of its exposure pulse);
// images are instantaneous at t_k (no motion blur).
//
// Soil field (material point X moves to x = X + u(X, t)), the sum of
//  * a punching zone: u = (0, W(t) f(X)), f = exp(-(dist(X, C) / L)^2), C the convex "cone" zone:
//    the footprint |X| <= D/2 from the surface down to core_depth, then a triangle down to an apex
//    cone_depth further below. f = 1 exactly in C, so the soil there translates rigidly;
//  * a compression wave from the impact point: u = (1 - f) A0 exp(-r / lambda)
//    S((t - r / c) / tau) e_r, c ~ 65 m/s (paper section 3.3), S a C2 smooth step 0 -> 1.
// W(t) is built from momentum conservation (paper Eq. 3, Fig. 4): with m_grid = rho_d *
// (area of the default momentum grid) * t_z, the core velocity is
//   v_sand(t) = (p_max - m_p v_p(t)) / m_grid  for 0 < t <= t_e,   v_sand = v_p  after t_e,
// where t_e solves (m_p + m_grid) v_p(t_e) = p_max; so p_pounder + p_gran = p_max exactly through
// the peak stage and pounder and soil move together afterwards. W = integral of v_sand (closed
// form before t_e: W = (p_max t - m_p z_p(t)) / m_grid).
//
//   ImpactSceneSpec spec = LoadImpactSceneSpec("spec.yaml");   // or ImpactScenePreset("small")
//   ImpactScene scene(spec);                                   // runs the impact model
//   cv::Mat frame = scene.RenderFrame(3);
//   ImpactSceneReport report = WriteImpactScene(scene, "out/");
#ifndef IMPACTDIC_SYNTH_IMPACT_SCENE_H_
#define IMPACTDIC_SYNTH_IMPACT_SCENE_H_

#include <array>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "impactdic/core/enum_names.h"
#include "impactdic/core/numeric.h"
#include "impactdic/model/impact_model.h"
#include "impactdic/synth/checkerboard.h"
#include "impactdic/synth/speckle.h"

namespace impactdic {

// The lens the scene is filmed through.
enum class SceneLens {
  kSample,  // SampleCamera() (the lens of calibration/ and sample_frames/), scaled to the size.
  kIdeal,   // Distortion-free pinhole, principal point at the image centre, f = 820 px * w / 640.
};
inline constexpr EnumNames<SceneLens, 2> kSceneLensNames{
    {{{SceneLens::kSample, "sample"}, {SceneLens::kIdeal, "ideal"}}}};
const char* ToString(SceneLens lens);
SceneLens SceneLensFromString(const std::string& text, const std::string& where);

// What the added mass M of the impact model is.
enum class SceneAddedMass {
  kGrid,   // M = m_grid (the soil of the momentum grid is the added mass).
  kEq4,    // M = 425 m_p^0.1 v0^0.2 A^1.3 (paper Eq. 4).
  kGiven,  // M = ImpactSceneSpec::added_mass_kg.
};
const char* ToString(SceneAddedMass mode);

struct SceneSoilOptions {
  double core_depth_mm = 0;  // Depth of the rigid core below the surface [mm], >= 0; 0 = auto
                             // (0.3 D, at least the default momentum grid plus one step).
  double cone_depth_mm = 0;  // Core bottom to cone apex [mm], >= 0; 0 = D / 2 (45 degrees).
  // L of f = exp(-(dist / L)^2) [mm], >= 0; 0 = 1.5 D. An affine DIC subset's centre is
  // biased by ~ u'' <x^2> / 2 ~ W S^2 / (12 L^2): a long decay keeps that small.
  double decay_length_mm = 0;
  double wave_speed_m_s = 65;         // c, > 0 (paper section 3.3).
  double wave_amplitude_mm = 1.0;     // A0 [mm], >= 0 (0 = no wave).
  double wave_decay_length_mm = 180;  // lambda [mm], > 0 (~4 % left at the 0.6 m bed bottom).
  double wave_rise_time_s = 1e-3;     // tau [s], > 0.
  void Check() const;
};

struct SceneSensorOptions {
  double rate_hz = 25000;          // DAQ sampling rate [Hz], in [1000, 1e6].
  double offset_g = 0.02;          // Accelerometer offset [g], finite.
  double noise_g = 0.05;           // Gaussian noise [g rms], >= 0.
  double exposure_s = 1.0 / 3200;  // Exposure pulse length [s], in (0, 1 / fps).
  double pre_release_s = 0.05;     // Record before the release (pounder held at rest) [s], >= 0.
  double tail_s = 0.02;            // Record after the last frame [s], > 0.
  void Check() const;
};

// Base force sensors under the bed (docs/synth.md, docs/wave.md), none unless `columns` is set.
// The wave model: sensor k (at horizontal offset x_k and depth d_k below the surface, sensing area
// A_k) reads the pounder's contact stress
//   sigma_p(t) = m_p (g - a_down(t)) / (D t_z) = m_p g a_g(t) / (D t_z)  for t >= 0 (contact),
//   0 before (a_g: the accelerometer's noise-free reading, 0 in free fall, so sigma_p starts
//   from 0 at the contact; it settles at the pounder's weight once it rests),
// delayed by the travel time r_k / c from the impact point (r_k = sqrt(x_k^2 + d_k^2), c =
// soil.wave_speed_m_s, the speed of the field's compression wave) and attenuated:
//   F_k(t) = ratio_k sigma_p(t - r_k / c) A_k,  ratio_k = stress_ratio (d_k / r_k)^spreading,
// so the sensor straight below reads stress_ratio times the pounder's contact stress, an
// off-centre one less by the longer path (plane strain: cylindrical spreading, exponent 1/2).
// Each column (in N) adds offset_n (the static load and the sensor's zero) and Gaussian noise of
// noise_n. The reading is the accelerometer record's own cell average (shifted by r_k / c). The
// tool's stress ratio divides by m_p a_peak / (D t_z), without the weight: stress_ratio
// (1 + 1 / decel_peak_g); truth.h5 gives it as measured from the noise-free records.
struct SceneBaseSensorOptions {
  std::vector<std::string> columns;  // CSV column names (in N); empty = no base sensors.
  std::vector<double> offset_mm;     // x_k [mm], one per column, finite.
  std::vector<double> depth_mm;      // d_k [mm], one per column, > 0.
  std::vector<double> area_mm2;      // A_k [mm^2], one per column, > 0.
  double stress_ratio = 0.04;        // (0, 1]; the paper: 3-5 % at its 0.6 m deep base.
  double spreading_exponent = 0.5;   // >= 0.
  double offset_n = 20;              // Finite [N].
  double noise_n = 0.05;             // >= 0 [N rms].
  void Check() const;
};

struct ImpactSceneSpec {
  std::string name = "synthetic_impact";
  // Test (paper Table 1; SI units). Defaults: the model's (ImpactModelParameters, defined once).
  double pounder_mass_kg = ImpactModelParameters{}.pounder_mass_kg;  // m_p, > 0.
  double drop_height_m = 0.7;                        // h, > 0 (unless impact_velocity_m_s is set).
  double impact_velocity_m_s = kNaN;                 // v0; NaN: sqrt(2gh).
  double width_m = ImpactModelParameters{}.width_m;  // D, > 0.
  double depth_m = ImpactModelParameters{}.depth_m;  // t_z, > 0.
  double density_kg_m3 = ImpactModelParameters{}.density_kg_m3;  // rho_d, > 0.
  double bed_height_m = ImpactModelParameters{}.bed_height_m;    // > 0.
  double g_m_s2 = ImpactModelParameters{}.gravity_m_s2;          // > 0.
  // Impact model: the paper's Table 2, as defined in ImpactModelParameters.
  SceneAddedMass added_mass = SceneAddedMass::kGrid;
  double added_mass_kg = kNaN;  // With kGiven, >= 0.
  double K = ImpactModelParameters{}.friction_K;
  double n = ImpactModelParameters{}.damping_exponent_n;
  double u = ImpactModelParameters{}.damping_factor_u;
  double T_s = ImpactModelParameters{}.sigmoid_delay_T_s;
  double b_per_s = ImpactModelParameters{}.sigmoid_rate_b_per_s;
  // Camera.
  SceneLens lens = SceneLens::kSample;
  int width = 640, height = 480;   // [px], >= 64 x 48.
  double mm_per_px = 1.25;         // Panel scale s [mm/px], > 0.
  double fps = 1600;               // > 0.
  double surface_fraction = 0.25;  // Sand surface at this fraction of the height, in [0.05, 0.8].
  // Frames.
  int frames_before_impact = 2;    // >= 1.
  int frames = 0;                  // Total frames >= frames_before_impact + 2; 0 = until the
                                   // pounder stops, plus 3.
  double impact_phase = 0.5;       // Impact time after the last pre-impact frame [frames], (0, 1].
  int bits = 8;                    // 8 or 16.
  double noise_sigma = 1.0;        // Gaussian noise [grey levels of the bit depth], >= 0.
  int supersampling = 3;           // Samples per pixel side, in [1, 8].
  SpeckleOptions speckle;          // Blob radius in px of the reference image.
  double background_level = 0.82;  // Above the surface, in [0, 1].
  double pounder_level = 0.10;     // The pounder, in [0, 1].
  // Soil field, sensor.
  SceneSoilOptions soil;
  SceneSensorOptions sensor;
  SceneBaseSensorOptions base_sensors;
  // DIC settings of the emitted scene and the default momentum grid.
  int subset_size = 21;              // Odd, >= 5.
  int step = 20;                     // >= 1.
  int grid_cols = 6, grid_rows = 2;  // >= 1.
  // Calibration images through the same lens (into DIR/calibration/).
  bool render_calibration = true;
  int calibration_views = 14;  // >= 4.
  // If not empty, the emitted scene points at this calibration YAML (relative to DIR) instead
  // of DIR/calibration/camera.yaml (e.g. "../calibration/camera.yaml" for the committed sample).
  std::string calibration_yaml;
  std::uint64_t seed = 1;  // Speckle, noise, sensor noise and calibration poses derive from it.

  double ImpactVelocity() const;  // v0
  // Throws Error(kInvalidValue) naming the first broken field by its YAML key path.
  void Check() const;
};

// Presets: "small" (640x480, sample lens, 1.25 mm/px: the paper's 80 x 60 cm panel),
// "full" (1920x1440 at 1600 fps, 0.42 mm/px, the sample lens scaled), "tiny" (160x120,
// 5 mm/px, ideal lens, for tests). Error(kInvalidValue) for another name.
ImpactSceneSpec ImpactScenePreset(const std::string& name);

// The scene spec YAML (keys in docs/synth.md): an optional `preset:` sets the defaults, the
// other keys override them. Errors (kInvalidValue / kFileFormat) carry the key path, the value
// found and what is expected; unknown keys are errors.
ImpactSceneSpec ParseImpactSceneSpec(const std::string& yaml_text, const std::string& path);
ImpactSceneSpec LoadImpactSceneSpec(const std::string& path);

// Truth of the momentum balance over the default grid (paper Eq. 3, Fig. 4).
struct SceneMomentumTruth {
  int cols = 6, rows = 2;
  std::vector<cv::Point2d> centres_px;  // Subset centres, reference ideal px, row-major.
  double cell_area_mm2 = 0;             // step^2 s^2: each subset stands for a step x step cell.
  double grid_area_mm2 = 0;             // cols * rows * cell area.
  double m_grid_kg = 0;                 // rho_d * grid area * t_z.
  double p_max_Ns = 0;                  // max of m_p v_p(t) (at t_pmax >= 0).
  double t_pmax_s = 0;
  double t_e_s = 0;                    // (m_p + m_grid) v_p(t_e) = p_max: end of the peak stage.
  double v_te_m_s = 0;                 // v_p(t_e) = v_sand(t_e).
  double m_add_max_kg = 0;             // p_max / v_p(t_e) - m_p = m_grid.
  double relative_penetration_mm = 0;  // z_p - W at t_e (constant afterwards).
  double conservation_error = 0;       // |p_p + p_gran - p_max| / p_max at t_e (0 by design).
};

// The DIC grid of the emitted scene (subset centres in the reference ideal image).
struct SceneDicGrid {
  std::array<int, 4> roi{0, 0, 0, 0};  // x0, y0, x1, y1 [px] (x1, y1 exclusive).
  int cols = 0, rows = 0;
  std::vector<cv::Point2d> centres_px;  // Row-major.
};

struct PounderState {
  double z_m = 0;    // Bottom below the undisturbed surface, down positive.
  double v_m_s = 0;  // Down positive.
};

class ImpactScene {
 public:
  // Runs the impact model and sets up the truth. Throws Error for a bad spec.
  explicit ImpactScene(const ImpactSceneSpec& spec);

  const ImpactSceneSpec& spec() const { return spec_; }
  const SynthCamera& camera() const { return camera_; }
  const ImpactModelParameters& model_parameters() const { return model_params_; }
  const ImpactRun& model_run() const { return run_; }
  const SceneMomentumTruth& momentum() const { return momentum_; }
  const SceneDicGrid& dic_grid() const { return dic_grid_; }

  // Geometry.
  double sx_mm_per_px() const { return sx_; }
  double sy_mm_per_px() const { return sy_; }
  double axis_px() const { return axis_px_; }              // u of the pounder axis (ideal px).
  double surface_px() const { return surface_px_; }        // v of the sand surface (ideal px).
  cv::Point2d PanelFromIdeal(cv::Point2d ideal_px) const;  // [mm]
  cv::Point2d IdealFromPanel(cv::Point2d panel_mm) const;  // [px]
  double core_depth_mm() const { return core_depth_mm_; }
  double cone_depth_mm() const { return cone_depth_mm_; }
  double decay_length_mm() const { return decay_mm_; }

  // Time.
  int frame_count() const { return frame_count_; }
  double FrameTime(int k) const;                                 // [s] since impact.
  double release_time_s() const { return -v0_ / spec_.g_m_s2; }  // < 0
  double t_end_s() const { return run_.summary.t_end_s; }

  // Pounder motion on the whole timeline (held before release, free fall, model, at rest).
  PounderState Pounder(double t_s) const;
  // Core (grid) displacement W(t) [m] and velocity v_sand(t) [m/s], down positive.
  double CoreDisplacement(double t_s) const;
  double CoreVelocity(double t_s) const;
  // Pounder momentum m_p v_p and granular momentum m_grid v_sand [N s].
  double PounderMomentum(double t_s) const;
  double GranularMomentum(double t_s) const;
  // Eq. 3 added mass p_max / v_p - m_p [kg] (NaN when v_p <= 0).
  double AddedMassEq3(double t_s) const;

  // Soil field in panel millimetres: displacement (u_X, u_Y), its Jacobian (du/dX, du/dY,
  // dv/dX, dv/dY) and velocity [mm/s], at material point (X, Y) [mm].
  cv::Vec2d SoilDisplacementMm(double X, double Y, double t_s) const;
  cv::Vec4d SoilGradient(double X, double Y, double t_s) const;
  cv::Vec2d SoilVelocityMmS(double X, double Y, double t_s) const;
  // The same field in reference ideal pixels (material coordinates of the speckle).
  DisplacementField SoilFieldPx(double t_s) const;
  // The speckle pattern painted on the sand.
  const SpecklePattern& pattern() const { return *pattern_; }

  // Renders frame k (or any time), CV_8U/CV_16U; with_noise = false gives the noise-free image.
  cv::Mat RenderFrame(int k, bool with_noise = true) const;
  cv::Mat RenderAt(double t_s, std::uint64_t noise_seed, bool with_noise) const;
  // Renders the scene with any soil field (reference ideal px) and pounder depth [m]: the
  // renderer of RenderAt, exposed for exactness tests.
  cv::Mat RenderWithField(const DisplacementField& soil_px, double pounder_z_m,
                          std::uint64_t noise_seed, bool with_noise) const;

  // Accelerometer record (sensor axis up: 0 g in free fall, 1 g at rest): time on the DAQ clock
  // [s], reading [g] with offset and noise, exposure (0/1), and the noise-free reading.
  struct SensorRecord {
    std::vector<double> time_s, accel_g, exposure, accel_true_g;
    // The base force channels (SceneBaseSensorOptions; [channel][sample], N): as written, and
    // noise-free without offset.
    std::vector<std::vector<double>> base_force_n, base_force_true_n;
    double frame0_daq_time_s = 0;  // DAQ time of frame 0 (a sample time exactly).
    double impact_daq_time_s = 0;  // DAQ time of t = 0.
    double release_daq_time_s = 0;
  };
  SensorRecord MakeSensorRecord() const;
  // Adds the base force channels (SceneBaseSensorOptions) to a record of MakeSensorRecord.
  void AddBaseForce(SensorRecord* rec) const;
  double DaqTime(double t_s) const { return t_s - daq_origin_s_; }

  // Whether the pounder covers any pixel of a subset of half-size `half` centred at the ideal
  // point (cx, cy) at time t.
  bool PounderCovers(double cx, double cy, double half, double t_s) const;

 private:
  struct SoilTime {
    double t_s = 0;
    double W_mm = 0;       // Core displacement.
    double Wdot_mm_s = 0;  // Core velocity (only needed for velocities).
  };
  // The steps of the constructor, in order.
  void SetUpCamera();
  void RunImpactModel();
  void FindPeakMomentum();
  void FindMomentumTruthAtTe();
  void LayOutGrids();
  void SetUpCoreGeometry();
  void MapPixelCorners();

  double DistanceToCore(double X, double Y, cv::Vec2d* gradient) const;
  cv::Vec2d EvalSoil(double X, double Y, const SoilTime& st, cv::Vec4d* grad, cv::Vec2d* vel) const;

  ImpactSceneSpec spec_;
  SynthCamera camera_;
  ImpactModelParameters model_params_;
  ImpactRun run_;
  double v0_ = 0;
  double sx_ = 1, sy_ = 1, axis_px_ = 0, surface_px_ = 0;
  double core_depth_mm_ = 0, cone_depth_mm_ = 0, decay_mm_ = 1;
  double W_te_m_ = 0, z_te_m_ = 0;
  int frame_count_ = 0;
  double daq_origin_s_ = 0;  // t of DAQ time 0.
  SceneMomentumTruth momentum_;
  SceneDicGrid dic_grid_;
  std::shared_ptr<SpecklePattern> pattern_;
  std::vector<cv::Point2d> corner_map_;  // Ideal px of the pixel corners, (w+1) x (h+1).
};

struct ImpactSceneReport {
  std::string out_dir;
  int frames = 0;
  std::string scene_yaml, truth_h5, sensor_csv, spec_yaml, calibration_dir;
  std::string calibration_yaml;  // What the scene points at (may not exist yet: see docs).
  double t_e_s = 0, p_max_Ns = 0, m_grid_kg = 0, crater_depth_m = 0;
  double render_seconds = 0, total_seconds = 0;
  std::string BriefReport() const;
};

// The entries WriteImpactScene (and `impactdic synth`, which adds calibration/camera.yaml) writes
// into its folder.
inline constexpr std::array<const char*, 6> kImpactSceneOutputNames = {
    "frames", "calibration", "sensor.csv", "spec.yaml", "truth.h5", "scene.yaml"};

// Writes the scene into out_dir: frames/frame_NNNN.png, sensor.csv, truth.h5, scene.yaml,
// spec.yaml (the spec used, all keys) and, if spec.render_calibration, calibration/ (views,
// plane view, board.yaml). The scene YAML points at spec.calibration_yaml if set, else at
// calibration/camera.yaml when calibration images are rendered (the CLI produces it with the
// calib module), else it carries mm_per_px. truth.h5 and scene.yaml are written last.
ImpactSceneReport WriteImpactScene(const ImpactScene& scene, const std::string& out_dir);

// The spec as YAML (every key, the form ParseImpactSceneSpec reads).
std::string ImpactSceneSpecToYaml(const ImpactSceneSpec& spec);
// The scene file (pipeline/scene.h format) the pipeline reads for this scene, with paths relative
// to the output folder.
std::string ImpactSceneYaml(const ImpactScene& scene, const std::string& calibration_yaml);

}  // namespace impactdic

#endif  // IMPACTDIC_SYNTH_IMPACT_SCENE_H_
