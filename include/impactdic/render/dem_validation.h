// Comparison of an `impactdic run` on footage filmed from a DEM simulation with the truth
// measured on the grains (docs/validation.md). Reads the truth.h5 of
// `impactdic synth --dem` and the results.h5 of `impactdic run`, and reports next to each other:
// the DIC velocity field error, p_gran of the tool against the grains' momentum in the same 6 x 2
// grid, p_max, t_e, the conservation error (Eq. 3) of the physics and of the tool, m_add(t) and
// the sigmoid fit (Eq. 5), and Eq. 9 run with the fitted M, b, T against the DEM pounder's
// deceleration. Optionally draws the figures of docs/validation.md.
//
//   DemValidation v = ValidateDemRun("scene/truth.h5", "run/results.h5", "figures/");
//   std::cout << v.Report();
#ifndef IMPACTDIC_RENDER_DEM_VALIDATION_H_
#define IMPACTDIC_RENDER_DEM_VALIDATION_H_

#include <cstddef>
#include <string>
#include <vector>

#include "impactdic/core/numeric.h"

namespace impactdic {

// One base force sensor of the DEM case (a floor window, docs/validation_dem.md "DEM
// agreement"): the tool's /wave figures next to the grains' (truth.h5 base_sensors/).
struct DemWaveChannel {
  std::string column;
  double distance_mm = kNaN;
  // The tool (results.h5 /wave): arrival times after the detected impact, speeds with their
  // standard uncertainties, stress ratio.
  double onset_tool_s = kNaN, peak_tool_s = kNaN;
  double speed_peak_tool_m_s = kNaN, speed_peak_sigma_m_s = kNaN;
  double speed_onset_tool_m_s = kNaN, speed_onset_sigma_m_s = kNaN;
  double stress_ratio_tool = kNaN;
  // The grains, on the noise-free floor force (after the contact): onset (the rise's 10-50 %
  // line at zero), peak, distance / peak travel time from the pounder's peak, stress ratio;
  // and the travel time at the bed's own P-wave speed.
  double onset_truth_s = kNaN, peak_truth_s = kNaN, speed_peak_truth_m_s = kNaN;
  double rise_10_truth_s = kNaN, rise_50_truth_s = kNaN;  // The rise's 10 % and 50 % times.
  double stress_ratio_truth = kNaN, p_wave_travel_s = kNaN;
};

// The front in the DIC field (docs/wave.md "The front in the DIC field"): its speed, the 95 %
// interval ([1] NaN: unbounded above), the intercept and rms residual of the arrival fit, the
// subsets in the fit; NaN with the reason in `problem` when not measured.
struct DemFront {
  double speed_m_s = kNaN;
  double ci_low_m_s = kNaN, ci_high_m_s = kNaN;
  double intercept_s = kNaN, rms_residual_s = kNaN;
  std::size_t fit_subsets = 0;
  std::string problem;
};

struct DemValidation {
  // Per analysed frame (time since contact on the DEM clock).
  std::vector<double> t_s, p_gran_tool_Ns, p_gran_truth_Ns, p_pounder_tool_Ns, p_pounder_truth_Ns;
  std::vector<double> v_sand_tool_m_s, v_sand_truth_m_s, m_add_tool_kg, m_add_truth_kg;
  std::vector<double> p_gran_fd_truth_Ns;  // grains, central differences (a perfect DIC)
  // DIC against the cells' grains (valid subsets of analysed frames after the contact).
  std::size_t dic_samples = 0;
  double dic_velocity_rms_mm_s = kNaN;     // against the grains' mean velocity
  double dic_velocity_rms_fd_mm_s = kNaN;  // against central differences of their displacement
  double dic_displacement_rms_px = kNaN;
  double truth_speed_max_mm_s = kNaN;  // largest cell speed (scale of the errors)
  // Momentum.
  double p_max_tool_Ns = kNaN, p_max_truth_Ns = kNaN;
  double t_e_tool_s = kNaN, t_e_truth_s = kNaN;
  double conservation_tool = kNaN, conservation_truth = kNaN, conservation_truth_peak = kNaN;
  double m_add_max_tool_kg = kNaN, m_add_max_truth_kg = kNaN;
  double grid_mass_truth_kg = kNaN, grid_mass_tool_kg = kNaN;
  // max |p_gran,tool - p_gran,grains| over the frames in [0, t_e (grains)], and relative to p_max.
  double p_gran_error_peak_Ns = kNaN, p_gran_error_peak_rel = kNaN;
  // Ratio of the sums of p_gran,tool and p_gran,grains over those frames (a scale error).
  double p_gran_ratio_peak = kNaN;
  // The same against the grains' central differences (what a perfect DIC at this frame rate
  // gives): separates the DIC error from the time sampling.
  double p_gran_fd_error_peak_rel = kNaN;
  // Sigmoid fit of the tool (Eq. 5).
  double sigmoid_M_kg = kNaN, sigmoid_b_per_s = kNaN, sigmoid_T_s = kNaN;
  // Eq. 9 with the fitted M, b, T (K, n, u of the scene) against the DEM pounder.
  double dem_peak_decel_g = kNaN, dem_t_peak_s = kNaN, model_peak_decel_g = kNaN,
         model_t_peak_s = kNaN;
  double dem_max_penetration_m = kNaN, model_crater_depth_m = kNaN;
  double decel_rms_g = kNaN;  // model - DEM over [0, min(t_end model, end of DEM record)]
  // The time of the velocity-field figure: the stored frame after the contact nearest the
  // grains' t_e (NaN when no figure was drawn).
  double velocity_figure_t_s = kNaN;
  // Wave propagation (with the DEM's floor windows and P-wave run; empty / NaN without them).
  std::vector<DemWaveChannel> wave;
  double p_wave_speed_m_s = kNaN, p_wave_speed_sigma_m_s = kNaN;            // Half-peak arrivals.
  double p_wave_speed_peak_m_s = kNaN, p_wave_speed_peak_sigma_m_s = kNaN;  // Peak times.
  double pounder_peak_tool_s = kNaN, pounder_peak_truth_s = kNaN;  // Peak deceleration time.
  double pounder_peak_stress_tool_Pa = kNaN, pounder_peak_stress_truth_Pa = kNaN;  // m_p a / D t_z
  // The front: the tool's (results.h5 /wave/front), and the same criterion
  // (momentum/wave_front.h) applied to the grains on the analysed frames, times since the
  // contact: to the cells' mean vertical velocity at each frame (truth.h5 soil/velocity_y_mm_s,
  // the grains' own front) and to central differences of the cells' mean displacement (what a
  // perfect DIC gives at this frame rate). Geometry from truth.h5 (/camera: the pounder's axis
  // and the surface; /dem: D). problem "not run" without base channels (no /wave).
  DemFront front_tool, front_grains, front_grains_fd;
  std::vector<std::string> notes;

  std::string Report() const;  // The table of docs/validation.md for this case, as text.
};

// Reads both files and compares. Error kFileFormat naming the file and what it is when the first
// is not a DEM truth file (a synthetic scene's truth, a run's results, ...) or the second not a
// run's results file; naming a missing dataset otherwise. figures_dir non-empty: writes
// velocity_field_compare.png (DIC field next to the grains', same colour scale, at the frame
// nearest t_e/2 of the grains among those the results store: all with `outputs.frames: all`,
// the <= 16 of the default preview; none with `none`, which skips this figure with a note),
// momentum_compare.png and deceleration_compare.png there.
DemValidation ValidateDemRun(const std::string& truth_h5, const std::string& results_h5,
                             const std::string& figures_dir = "");

// `impactdic validate-dem`: ValidateDemRun after checking, before any work, that both files exist
// (Error kFileNotFound naming "TRUTH" / "RESULTS") and that `csv_path` (when not empty) is a .csv
// that is not one of them ("--csv"); then writes the per-frame series there (t_s, then each
// quantity of the tool and of the grains: DemValidationCsvColumns).
// wave_csv_path (when not empty, a .csv, checked the same way, "--wave-csv"): one row per base
// sensor, DemValidationWaveCsvColumns (the DemWaveChannel figures, times in s, speeds in m/s;
// the bed's P-wave speed and the three DIC-field front speeds with their intervals repeated on
// each row).
DemValidation ValidateDemFiles(const std::string& truth_h5, const std::string& results_h5,
                               const std::string& figures_dir, const std::string& csv_path,
                               const std::string& wave_csv_path = "");
const std::vector<std::string>& DemValidationCsvColumns();
const std::vector<std::string>& DemValidationWaveCsvColumns();

}  // namespace impactdic

#endif  // IMPACTDIC_RENDER_DEM_VALIDATION_H_
