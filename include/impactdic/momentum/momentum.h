// The momentum validation of Eq. 3 of the paper (docs/analysis.md): granular momentum of the soil
// beneath the pounder, pounder momentum, the end of the peak stage, added mass and its sigmoid fit.
//
// Conventions: vertical velocities are DOWNWARD positive (pounder: sensor module; soil: the
// kinematics module's panel y axis, which points down). Times are on the DAQ clock unless named
// *_after_impact_s (t = 0 at the detected impact).
//
//  - Grid: by count (default 6 x 2): the `grid_rows` subset rows whose centres lie just below the
//    pounder's initial bottom edge, and in them the `grid_cols` subset columns nearest the
//    pounder's centre line among those whose centres lie within its width; or by a rectangle in
//    panel mm (every subset whose centre lies inside). Area in the panel plane: by count, the
//    number of subsets times one grid cell (step_x * step_y in mm, from the subset spacing); by
//    rectangle, the rectangle's area. Mass m_s = rho_d * area * t_z.
//  - p_gran(t) = m_s * mean vertical soil velocity over the grid (NaN subsets skipped), measured
//    only in frames where at least min_valid_fraction of the grid's subsets are valid: elsewhere
//    v_sand, a_sand, p_gran and p_tot are NaN (a warning gives their count and frames);
//    p_p(t) = m_p v_p(t); p_max = max p_p after the impact (at the DAQ rate); p_tot = p_p + p_gran.
//  - t_e (end of the peak stage; paper: the soil stops accelerating and moves with the pounder):
//    the first frame after the impact where (1) v_p - v_sand <= velocity_match_tolerance *
//    v_p,max: the pounder no longer outruns the soil, i.e. they move together OR the soil has
//    overtaken the pounder since the previous frame (a light pounder: v_p - v_sand changes sign
//    between two frames, and |v_p - v_sand| may exceed the tolerance at every frame after), and
//    (2) the soil stops accelerating: its mean acceleration there is <= sand_accel_tolerance *
//    (its maximum after the impact), and its velocity never again exceeds v_sand there by more
//    than velocity_match_tolerance * v_p,max until the pounder stops (a late re-acceleration,
//    e.g. a wave reflected by the floor, that gains less does not move t_e). Sub-frame t_e from
//    the frames' displacements (RefineEndOfPeakStage in momentum.cc): where the soil overtook
//    the pounder, the maximum of the gap between pounder and soil (v_p = v_sand). If no frame
//    satisfies both, the frame of the maximum soil velocity, with a warning, provided the
//    analysed frames reach the pounder's stop (else t_e is not measurable). t_e is NOT
//    MEASURABLE (NaN, and with it the conservation error, m_add(t), m_add,max, the sigmoid fit,
//    v_sand,max and the momentum ratio; MomentumSummary::t_end_problem says why) when the first
//    analysed frame is exposed after the impact (more than one DAQ sample; the start of the peak
//    stage was not analysed), when no frame
//    between the impact and the stop has a measured p_gran, or when a frame from the impact to t_e
//    has none (t_e is the FIRST frame meeting the criteria: an unmeasured frame before it could
//    have been t_e).
//  - Conservation error |p_tot(t_e) - p_max| / p_max.
//  - m_add(t) = p_max / v_p(t) - m_p (Eq. 3) from the impact to t_e; m_add,max = m_add(t_e).
//  - Sigmoid (Eq. 5) fitted to m_add(t) at the DAQ rate between impact and t_e, thinned to one
//    sample per filter resolution (f_s / (2 f_c) samples) so that residuals are nearly
//    independent, counted back from the last sample before t_e (the data always reach t_e).
//  - Momentum ratio (Eq. 11) = m_add,max * v_sand,max / (m_p * v_p,max).
#ifndef IMPACTDIC_MOMENTUM_MOMENTUM_H_
#define IMPACTDIC_MOMENTUM_MOMENTUM_H_

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "impactdic/core/numeric.h"
#include "impactdic/core/range.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/json.h"
#include "impactdic/kinematics/kinematics.h"
#include "impactdic/momentum/fit.h"
#include "impactdic/momentum/uncertainty.h"
#include "impactdic/sensor/sensor.h"

namespace impactdic {

class H5Writer;

// The pounder's footprint in panel mm at frame 0 (x right, y down). NaN = default: centred on the
// correlated grid, width pounder_width_m, bottom edge half a grid step above the top subset row.
struct PounderFootprint {
  double x_left_mm = kNaN;
  double x_right_mm = kNaN;
  double bottom_y_mm = kNaN;
};

// The allowed values of the t_e tolerances, read by MomentumOptions::Check() and the scene's
// momentum.* keys.
inline constexpr ValueRange kVelocityMatchToleranceRange{0, 1, "", /*min_open=*/true};
inline constexpr ValueRange kSandAccelToleranceRange{0, 1, "", /*min_open=*/false,
                                                     /*max_open=*/true};

struct MomentumOptions {
  double pounder_mass_kg = 10;                   // m_p [kg], > 0.
  double pounder_width_m = 0.15;                 // D [m], > 0 (default footprint only).
  double depth_m = 0.192;                        // Out-of-plane depth t_z [m], > 0.
  double density_kg_m3 = 1550;                   // Dry density rho_d [kg/m^3], > 0.
  int grid_cols = 6;                             // Subsets across the footprint, >= 1.
  int grid_rows = 2;                             // Subset rows beneath the pounder, >= 1.
  std::optional<std::array<double, 4>> rect_mm;  // x0, y0, x1, y1 [mm], x0 < x1, y0 < y1.
  PounderFootprint footprint;
  double velocity_match_tolerance = 0.05;  // Of v_p,max, kVelocityMatchToleranceRange.
  // Of the maximum soil acceleration, kSandAccelToleranceRange.
  double sand_accel_tolerance = 0.05;
  // Per frame, the fraction of the grid's subsets that must be valid for p_gran to be measured
  // there (else NaN), in (0, 1]; scene key momentum.min_valid_fraction (this is its default).
  // p_gran stands for the whole grid's mass through the mean over its valid subsets, and subsets
  // fail where the soil shears hardest or is covered, not at random: 0.5 asks for a majority of
  // the grid (6 of the default 6 x 2). docs/analysis.md has what dropping subsets does on the
  // sample.
  double min_valid_fraction = 0.5;
  bool fit_sigmoid = true;
  SigmoidFitOptions sigmoid;
  // The figures' standard uncertainties (momentum/uncertainty.h).
  MomentumUncertaintyOptions uncertainty;
  void Check() const;
};

// The subsets of the momentum grid.
struct MomentumGrid {
  std::vector<std::size_t> subset_ids;
  int cols = 0, rows = 0;
  std::array<double, 4> rect_mm{};  // Extent of the grid cells (x0, y0, x1, y1).
  double area_m2 = 0;
  double mass_kg = 0;
};

// Selects the grid (file comment). Error (kInvalidValue) when the requested grid lies (partly)
// outside the correlated region.
MomentumGrid SelectMomentumGrid(const KinematicsResult& kin, const MomentumOptions& options);

struct MomentumSummary {
  MomentumGrid grid;
  double p_max_kg_m_s = kNaN;
  double t_p_max_s = kNaN;
  double v_p_max_m_s = kNaN;
  std::size_t end_frame = 0;   // Frame index of t_e (meaningful only when t_e is measured).
  double t_end_peak_s = kNaN;  // t_e after the impact.
  double t_end_peak_daq_s = kNaN;
  double momentum_conservation_error = kNaN;
  double added_mass_max_kg = kNaN;
  double v_sand_max_m_s = kNaN;
  double momentum_ratio = kNaN;
  double impact_velocity_m_s = kNaN;  // v0, the sensor's.
  double p_gran_te_kg_m_s = kNaN;     // p_gran at t_e (interpolated like p_tot).
  double v_sand_te_m_s = kNaN;        // v_sand at t_e.
  bool t_end_found = false;           // Both t_e criteria met.
  bool t_end_refined = false;         // t_e refined between two frames (else on a frame).
  // Why t_e (and every figure that depends on it) is NaN; empty when t_e was measured.
  std::string t_end_problem;
  std::size_t unmeasured_frames = 0;  // Frames whose p_gran is NaN (too few valid grid subsets).
  SigmoidFit sigmoid;
  bool sigmoid_fitted = false;
  MomentumUncertainty uncertainty;  // Standard uncertainties of the figures above.
  double seconds = 0;
  std::vector<std::string> warnings;
  // Whether the stage measured what it is for: t_e and m_add,max.
  bool IsUsable() const { return t_end_problem.empty() && std::isfinite(added_mass_max_kg); }
  std::string BriefReport() const;
  std::string FullReport() const;
  // The analyze command's JSON keys: p_max_kg_m_s, t_end_peak_s, momentum_conservation_error,
  // added_mass_max_kg, sigmoid_b_per_s, sigmoid_T_s, momentum_ratio, v_sand_max_m_s, then more
  // (t_end_problem: "" when t_e was measured), and "uncertainty" (UncertaintyJson).
  JsonObject ToJson() const;
};

// A headline figure and its standard uncertainty, by the name summary.json and the /momentum
// attributes give it (the uncertainty as NAME_u).
template <typename Number>
struct FigureWithUncertainty {
  const char* name;
  Number* value;
  Number* u;
};
// The figures with an uncertainty, in their order (the one list summary.json's "uncertainty"
// object and the /momentum attributes NAME_u are written from). Const for the writers, mutable
// for the reader.
template <typename S>
auto UncertainFigures(S& s) {
  using Number = std::remove_reference_t<decltype((s.p_max_kg_m_s))>;
  auto& u = s.uncertainty;
  return std::vector<FigureWithUncertainty<Number>>{
      {"impact_velocity_m_s", &s.impact_velocity_m_s, &u.impact_velocity_m_s},
      {"p_max_kg_m_s", &s.p_max_kg_m_s, &u.p_max_kg_m_s},
      {"t_end_peak_s", &s.t_end_peak_s, &u.t_end_peak_s},
      {"p_gran_te_kg_m_s", &s.p_gran_te_kg_m_s, &u.p_gran_te_kg_m_s},
      {"v_sand_te_m_s", &s.v_sand_te_m_s, &u.v_sand_te_m_s},
      {"added_mass_max_kg", &s.added_mass_max_kg, &u.added_mass_max_kg},
      {"momentum_conservation_error", &s.momentum_conservation_error,
       &u.momentum_conservation_error},
      {"momentum_ratio", &s.momentum_ratio, &u.momentum_ratio},
      {"v_sand_max_m_s", &s.v_sand_max_m_s, &u.v_sand_max_m_s},
      {"sigmoid_M_kg", &s.sigmoid.M_kg, &u.sigmoid_M_kg},
      {"sigmoid_b_per_s", &s.sigmoid.b_per_s, &u.sigmoid_b_per_s},
      {"sigmoid_T_s", &s.sigmoid.T_s, &u.sigmoid_T_s}};
}

// summary.json's and `analyze`'s "uncertainty": "method" (how it was propagated), "draws",
// then per figure of UncertainFigures {"value", "u"} (null when not available), "t_end_grid_s",
// "inputs" (what was propagated: accel_noise_g, dic_sigma_median_mm, scale_u_fraction,
// density_u_kg_m3, depth_u_m, subset_size_mm) and "notes".
JsonObject UncertaintyJson(const MomentumSummary& summary);

struct MomentumResult {
  // Per frame.
  std::vector<double> frame_time_s;  // DAQ clock.
  std::vector<double> v_pounder_m_s;
  std::vector<double> v_sand_m_s;  // Mean over the grid.
  std::vector<double> a_sand_m_s2;
  std::vector<double> p_pounder_kg_m_s, p_gran_kg_m_s, p_total_kg_m_s;
  std::vector<double> added_mass_kg;  // NaN outside [impact, t_e].
  std::vector<double> valid_subsets;  // Count of finite velocities in the grid (all frames).
  // Standard uncertainties of v_sand, p_gran, p_tot and m_add per frame (the Monte Carlo's,
  // momentum/uncertainty.h); empty when not estimated, NaN where the series is.
  std::vector<double> v_sand_u_m_s, p_gran_u_kg_m_s, p_total_u_kg_m_s, added_mass_u_kg;
  // At the DAQ rate between impact and t_e (what the sigmoid is fitted to, before thinning).
  std::vector<double> added_mass_time_after_impact_s, added_mass_daq_kg;
  MomentumSummary summary;
};

// kin: soil kinematics; frame_time_s: the frames on the DAQ clock (FrameTimeline::daq_time_s);
// sensor: pounder.
MomentumResult AnalyzeMomentum(const KinematicsResult& kin, const std::vector<double>& frame_time_s,
                               const SensorResult& sensor, const MomentumOptions& options);

// The standard uncertainties of result's figures and series (momentum/uncertainty.h), by
// options.uncertainty.draws Monte Carlo draws (none when 0 or when the kinematics carry no
// sigmas: then a note says so). AnalyzeMomentum calls it; the draws are seeded, so a result is
// reproducible.
void EstimateMomentumUncertainty(const KinematicsResult& kin, const SensorResult& sensor,
                                 const MomentumOptions& options, MomentumResult* result);

// The whole analysis of one scene from the correlation arrays: the frames' timeline (sensor
// MakeFrameTimeline of source frames first_frame .. first_frame + dic.frames - 1: exposure edges,
// or the camera clock), kinematics (dt = 1 / the timeline's fps), momentum. `first_frame` is the
// index in the camera sequence of the first correlated frame.
struct SceneAnalysis {
  KinematicsResult kinematics;
  std::vector<double> frame_time_s;
  MomentumResult momentum;
};
SceneAnalysis AnalyzeCorrelation(const CorrelationSeries& dic, const PanelMapping& mapping,
                                 const CameraClock& clock, const SensorResult& sensor,
                                 const MomentumOptions& options, std::size_t first_frame = 0);

// The groups of the scene analysis, each written by its owner (names, units and descriptions
// there): /sensor by sensor/sensor_results.h, /kinematics by kinematics/kinematics_results.h,
// /momentum by momentum/momentum_results.h (their readers are there too). WriteAnalysis writes
// the three; each replaces its group if it exists, so calling several is harmless.
void WriteSensor(H5Writer& out, const SensorResult& sensor);
void WriteAnalysis(H5Writer& out, const SceneAnalysis& analysis, const SensorResult& sensor);
// frame_time_daq_s only when frame_time_s is not empty.
void WriteKinematics(H5Writer& out, const KinematicsResult& kinematics,
                     const std::vector<double>& frame_time_s);
void WriteMomentum(H5Writer& out, const MomentumResult& momentum, const SensorResult& sensor);

}  // namespace impactdic

#endif  // IMPACTDIC_MOMENTUM_MOMENTUM_H_
