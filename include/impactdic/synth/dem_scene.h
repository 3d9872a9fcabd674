// Footage, accelerometer record and ground truth rendered from a discrete-element (DEM)
// simulation of the impact (docs/validation.md). The DEM (validation/dem/, LAMMPS) is
// physics nobody here wrote: a quasi-2D bed of polydisperse discs (each a cylinder spanning the
// panel depth t_z, so masses and forces are those of the whole slab) hit by a rigid flat pounder.
// This module reads its output, films it with the camera, lens, noise and DAQ of the synthetic
// scenes (impact_scene.h), and writes the truth measured on the grains directly.
//
// DEM folder (written by validation/dem/impact.in; SI units, LAMMPS frame: x right, y UP):
//   meta.txt     "key value" lines: pounder_mass_kg, pounder_width_m, depth_m,
//                impact_velocity_m_s, pounder_axis_x_m, pounder_bottom_offset_m (centre of mass
//                to bottom), bed_top_m, box_width_m, timestep_s, gravity_m_s2 (others ignored)
//   grains.dump  LAMMPS `dump custom` text: id x y vx vy radius mass, one snapshot per frame
//                (1600 fps), the first at DEM time 0 (before contact)
//   near.dump    id x y vx vy of the grains near the footprint at the DAQ rate (optional)
//   pounder.txt  `fix ave/time` text: step, time, centre-of-mass y, vy, net force fy
//                (gravity included) at twice the DAQ rate
//   floor.txt    `fix ave/time` text (optional): step, then the floor's contact force on the
//                grains (y up) in two windows, averaged over the steps since the last line: the
//                base force sensors (meta.txt: floor_window_width_m, floor_window_center_x_m,
//                floor_window_offset_x_m; the floor at y = 0)
//   pwave_meta.txt, pwave.txt, pwave_rest.txt  (optional, validation/dem/pwave.in): the bed's
//                own small-strain P-wave speed: "key value" lines of the set-up (timestep_s,
//                pulse_start_s, pulse_duration_s, bed_top_m, one layer_depth_m per layer), and
//                step, then each layer's mean vy, with the pulse and without it (the same run)
//
// Conventions of the rendered scene are those of docs/synth.md: t = 0 at contact (the first
// pounder sample with a contact force), panel mm with X right from the pounder axis and Y DOWN
// from the pounder bottom at contact (the "surface"), velocities down positive.
//
//   DemRecord dem = ReadDemRecord("dem_case/");
//   DemScene scene(dem, ImpactScenePreset("small"));
//   DemSceneReport report = WriteDemScene(scene, "out/");
#ifndef IMPACTDIC_SYNTH_DEM_SCENE_H_
#define IMPACTDIC_SYNTH_DEM_SCENE_H_

#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <unordered_map>
#include <vector>

#include "impactdic/synth/impact_scene.h"

namespace impactdic {

struct DemGrain {
  std::int64_t id = 0;
  double x_m = 0, y_m = 0;        // Centre, LAMMPS frame (y up).
  double vx_m_s = 0, vy_m_s = 0;  // Velocity, y up.
  double radius_m = 0;
  double mass_kg = 0;  // Of the whole slab of depth t_z.
};

struct DemSnapshot {
  std::int64_t step = 0;
  std::vector<DemGrain> grains;  // Sorted by id.
};

struct DemPounderSample {
  double t_s = 0;     // DEM time.
  double yc_m = 0;    // Centre of mass, y up.
  double vy_m_s = 0;  // y up.
  double fy_N = 0;    // Net force (contacts + gravity), y up.
};

struct DemMeta {
  double pounder_mass_kg = 0, pounder_width_m = 0, depth_m = 0, impact_velocity_m_s = 0;
  double pounder_axis_x_m = 0, pounder_bottom_offset_m = 0, bed_top_m = 0, box_width_m = 0;
  double timestep_s = 0, gravity_m_s2 = 0;
  // The floor force windows (floor.txt; NaN without them): width and centres [m].
  double floor_window_width_m = kNaN, floor_window_center_x_m = kNaN,
         floor_window_offset_x_m = kNaN;
};

// floor.txt: the floor's force on the grains of each window, y up [N], averaged over the DEM
// steps (previous line's step, step].
struct DemFloorSample {
  std::int64_t step = 0;
  std::vector<double> force_N;  // One per window: centre, offset.
};

// The P-wave run (validation/dem/pwave.in). Each layer's pulse response is the mean vy with the
// pulse minus the same without it (serial LAMMPS is deterministic, so the difference is the
// pulse's alone, free of the settled grains' own motion).
struct DemPWaveRecord {
  double timestep_s = 0, pulse_start_s = 0, pulse_duration_s = 0, bed_top_m = 0;
  std::vector<double> layer_depth_m;              // Below bed_top_m.
  std::vector<std::int64_t> step;                 // Output steps (every 4: 100 kHz).
  std::vector<std::vector<double>> response_m_s;  // [layer][sample]: downward velocity.
  bool empty() const { return layer_depth_m.empty(); }
};

// The small-strain P-wave speed of the bed from a DemPWaveRecord. A layer's arrival is the
// first time its downward velocity reaches half its peak (the DIC front's criterion,
// momentum/wave_front.h), linear between samples; its peak time is the largest sample, refined
// by a parabola. Speeds: least squares of depth against time over the layers between
// DemPWaveOptions' fractions of the bed depth with a peak inside the record; sigma is the
// slope's standard error (n - 2 degrees of freedom).
struct DemPWave {
  std::vector<double> layer_depth_m, half_peak_s, peak_s, peak_m_s;  // Since the pulse start.
  std::vector<int> in_fit;
  double speed_m_s = kNaN, speed_sigma_m_s = kNaN;            // From the half-peak arrivals.
  double speed_peak_m_s = kNaN, speed_peak_sigma_m_s = kNaN;  // From the peak times.
  double rms_residual_s = kNaN;                               // Of the half-peak fit.
  std::string problem;                                        // Why a speed is NaN.
};
struct DemPWaveOptions {
  // The layers in the fits: depth within [min, max] x the bed depth, 0 <= min < max <= 1. The
  // pulse forms in the top layers (its half-peak arrivals there lie off the line); near the floor
  // its reflection meets it.
  double min_depth_fraction = 0.15;
  double max_depth_fraction = 0.85;
  void Check() const;
};
DemPWave MeasurePWave(const DemPWaveRecord& record, const DemPWaveOptions& options = {});

struct DemRecord {
  DemMeta meta;
  std::vector<DemSnapshot> frames;  // grains.dump, one per camera frame.
  std::vector<DemSnapshot> near;    // near.dump (may be empty).
  std::vector<DemPounderSample> pounder;
  std::vector<DemFloorSample> floor;  // floor.txt (may be empty).
  DemPWaveRecord pwave;               // pwave*.txt (may be empty).
};

// Readers. Errors (kFileFormat / kIo) name the file, the line and what was expected.
std::vector<DemSnapshot> ReadLammpsDump(const std::string& path);
std::vector<DemPounderSample> ReadDemPounder(const std::string& path);
DemMeta ReadDemMeta(const std::string& path);
std::vector<DemFloorSample> ReadDemFloor(const std::string& path);
// dir/pwave_meta.txt, pwave.txt and pwave_rest.txt.
DemPWaveRecord ReadDemPWave(const std::string& dir);
DemRecord ReadDemRecord(const std::string& dir);

// Truth measured on the grains. A DIC cell is the step x step px square around a subset centre
// of the reference frame (the last frame before contact); its grains are those whose centres lie
// in it then (Lagrangian: the same grains later, as the subsets follow the soil). Velocities and
// displacements are mass-weighted means over a cell's grains.
struct DemTruth {
  int reference_frame = 0;
  std::vector<double> frame_time_s;  // Since contact.
  // Per frame x DIC subset (row-major [frame][subset]); NaN for a cell without grains.
  std::vector<double> u_px, v_px;                        // Mean displacement since the reference.
  std::vector<double> velocity_x_mm_s, velocity_y_mm_s;  // Mean velocity, y down.
  std::vector<int> grains_per_cell;
  // Per frame x DIC subset: the gradient (du/dX, du/dY, dv/dX, dv/dY) [px/px] of the
  // least-squares affine fit u = a + H (X - centre) of the displacements of the grains whose
  // reference centre lies in the subset (|X - cx|, |Y - cy| <= subset_size / 2); NaN for fewer
  // than 3 such grains or nearly collinear ones (docs/validation_strain.md "Strain").
  std::vector<double> dudx, dudy, dvdx, dvdy;
  std::vector<int> grains_per_subset;
  // Default momentum grid (cols x rows cells).
  double grid_mass_kg = 0;         // Sum of the grid grains' masses.
  double grid_mass_bulk_kg = 0;    // rho_d * grid area * t_z with the bed's bulk density.
  double bulk_density_kg_m3 = 0;   // Grain mass / area over the bed under the footprint.
  std::vector<double> p_gran_Ns;   // Per frame: sum m v_down of the grid grains.
  std::vector<double> v_sand_m_s;  // Per frame: p_gran / grid mass.
  // Per frame: what a perfect DIC would give: the grid mass times the central difference (one
  // sided at the ends) of the grid grains' mean displacement, as the kinematics stage does.
  std::vector<double> p_gran_fd_Ns;
  // Fine series at the DAQ rate (from near.dump; empty without it): time since contact.
  std::vector<double> fine_t_s, fine_p_gran_Ns, fine_v_sand_m_s, fine_v_p_m_s, fine_p_p_Ns;
  // Pounder.
  double p_max_Ns = 0, t_pmax_s = 0;
  // End of the peak stage from the grains (paper: no further positive soil acceleration and
  // v_p = v_sand): the first time after t_pmax at which v_p - v_sand <= tol and v_sand never
  // again exceeds its value then by more than tol (tol = velocity_tolerance * v_p,max), on the
  // fine series (else on the frames). NaN with a reason in `notes` if there is none.
  double t_e_s = 0, v_te_m_s = 0, m_add_max_kg = 0;
  double conservation_error_te = 0;    // |p_p + p_gran - p_max| / p_max at t_e.
  double conservation_error_peak = 0;  // Its maximum over [t_pmax, t_e].
  // Base force sensors (with floor.txt): per window (centre, offset), from the noise-free DAQ
  // record (the floor force's DAQ-interval averages minus its mean before the contact): the
  // peak and its time (largest sample), and the onset: where the straight line through the
  // 10 % and 50 % of peak crossings of the rise meets zero (the rise's front extrapolated to
  // the rest level). peak_speed_m_s: distance / (peak time - the pounder's peak time), the
  // paper's definition on the noise-free records; stress ratio: peak force / area over
  // m_p a_peak / (D t_z), a_peak the pounder's noise-free peak deceleration (the tool's).
  std::vector<double> base_peak_s, base_peak_force_N, base_onset_s, base_peak_speed_m_s,
      base_stress_ratio;
  std::vector<double> base_rise_10_s, base_rise_50_s;  // The 10 % and 50 % crossings.
  double pounder_peak_decel_s = kNaN, pounder_peak_stress_Pa = kNaN;
  DemPWave pwave;  // The bed's own P-wave speed (empty without pwave*.txt).
  std::vector<std::string> notes;
};

struct DemSceneOptions {
  double velocity_tolerance = 0.02;  // Of t_e, fraction of v_p,max, in (0, 0.5].
  double grain_level_min = 0.25;     // Grain grey levels uniform in [min, max], in [0, 1].
  double grain_level_max = 0.95;
  double pore_level = 0.06;  // Between grains and above the bed, in [0, 1].
  void Check() const;
};

// A DEM run filmed by the camera of `spec` (lens, size, scale, fps must be the DEM's frame rate,
// noise, bits, sensor options, DIC settings). The test (m_p, D, t_z, v0, g) comes from the DEM;
// the bed's bulk density is measured on the grains and becomes the scene's rho_d.
class DemScene {
 public:
  DemScene(DemRecord record, ImpactSceneSpec spec, DemSceneOptions options = {});

  const ImpactScene& base() const { return *base_; }  // Camera, geometry, DIC grid, scene YAML.
  const DemRecord& record() const { return record_; }
  const DemTruth& truth() const { return truth_; }
  int frame_count() const { return static_cast<int>(record_.frames.size()); }
  double FrameTime(int k) const;                          // Since contact [s].
  double contact_time_s() const { return t_contact_s_; }  // DEM time of t = 0.
  double surface_y_m() const { return surface_y_m_; }     // Pounder bottom at contact.

  // Pounder at time t since contact (down positive: depth below the surface, velocity); free
  // fall before the DEM's start, held before the release. Linear between DEM samples.
  PounderState Pounder(double t_s) const;
  double release_time_s() const { return release_time_s_; }

  // Panel mm (X right from the axis, Y down from the surface) of a LAMMPS point.
  cv::Point2d PanelFromDem(double x_m, double y_m) const;

  cv::Mat RenderFrame(int k, bool with_noise = true) const;
  // The accelerometer and, with floor.txt, the base force channels (base_center_N,
  // base_offset_N): each DAQ sample the floor force's average over the sample interval, its
  // static load before the contact held before the DEM starts, plus base_sensors.offset_n and
  // noise_n of the spec.
  ImpactScene::SensorRecord MakeSensorRecord() const;
  // Average over [t0_s, t1_s] (since contact) of window w's floor force minus its mean before
  // the contact (the dynamic force) [N]; 0 before the DEM starts.
  double FloorDynamicForce(std::size_t w, double t0_s, double t1_s) const;
  std::size_t floor_windows() const { return floor_static_N_.size(); }
  double floor_static_N(std::size_t w) const { return floor_static_N_[w]; }

 private:
  void ComputeTruth();
  void SetUpFloorSensors();
  void ComputeWaveTruth();
  // grid_mass_of: mass of each grid grain by id.
  void ComputePeakStageTruth(const std::unordered_map<std::int64_t, double>& grid_mass_of);

  DemRecord record_;
  ImpactSceneSpec spec_;
  DemSceneOptions options_;
  std::unique_ptr<ImpactScene> base_;
  std::vector<cv::Point2d> corner_map_;  // Ideal px of the pixel corners, (w+1) x (h+1).
  double t_contact_s_ = 0, surface_y_m_ = 0, release_time_s_ = 0, v_start_m_s_ = 0;
  double daq_origin_s_ = 0;  // Time since contact of DAQ sample 0.
  // Floor force: DEM times of floor.txt's lines (from 0) and each window's impulse since DEM
  // time 0 there [N s]; its mean before the contact [N].
  std::vector<double> floor_t_s_;
  std::vector<std::vector<double>> floor_impulse_Ns_;
  std::vector<double> floor_static_N_;
  DemTruth truth_;
};

struct DemSceneReport {
  std::string out_dir, scene_yaml, truth_h5, sensor_csv, calibration_yaml;
  int frames = 0, grains = 0;
  double render_seconds = 0;
  std::string BriefReport() const;
};

// Writes frames/, sensor.csv, calibration/ (if spec.render_calibration), truth.h5 (layout in
// docs/validation.md), spec.yaml and scene.yaml (the last two atomically, last).
DemSceneReport WriteDemScene(const DemScene& scene, const std::string& out_dir);

}  // namespace impactdic

#endif  // IMPACTDIC_SYNTH_DEM_SCENE_H_
