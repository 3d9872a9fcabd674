// The impact model's results (the /model group, Eq. 9): the names, one writer, one reader. The
// same layout in a run's results.h5 (`impactdic run`) and in `impactdic model -o X.h5`. Other
// modules read /model through these names (namespace results_layout, like every group's;
// io/results_layout.h lists the owners).
//
//   H5Writer out("model.h5", /*owned_groups=*/{results_layout::kModelGroup});
//   WriteModelResults(out, params, SimulateImpact(params, options));
//   out.Commit();
//   const ModelResultsGroup m = ReadModelResults(H5Reader("model.h5"), "model.h5");
#ifndef IMPACTDIC_MODEL_MODEL_RESULTS_H_
#define IMPACTDIC_MODEL_MODEL_RESULTS_H_

#include <string>
#include <vector>

#include "impactdic/io/hdf5_store.h"
#include "impactdic/model/impact_model.h"

namespace impactdic {
namespace results_layout {

// The model's series (ImpactSeries), [K'] each: time since impact [s], pounder deceleration
// -dv/dt / g [g] (the accelerometer's decel_g), penetration [m] and velocity [m/s] (down +),
// added mass [kg] (Eq. 5); dv/dt [m/s^2] (NaN at v = 0), dm_add/dt [kg/s] (Eq. 6), the forces
// of Eq. 9 [N]: -(dm_add/dt) v, F_dyn (NaN at v = 0), F_fr, F_g. Until 2026-11-28 `model -o`
// wrote the series under /model/series/ (t_s, z_m, ...) and no decel_g.
inline constexpr const char* kModelGroup = "/model";
inline constexpr const char* kModelT = "/model/t_s";
inline constexpr const char* kModelDecel = "/model/decel_g";
inline constexpr const char* kModelZ = "/model/z_m";
inline constexpr const char* kModelV = "/model/v_m_s";
inline constexpr const char* kModelAddedMass = "/model/m_add_kg";
inline constexpr const char* kModelDvDt = "/model/dv_dt_m_s2";
inline constexpr const char* kModelDmAddDt = "/model/dm_add_dt_kg_s";
inline constexpr const char* kModelInertia = "/model/inertia_N";
inline constexpr const char* kModelDynamic = "/model/dynamic_N";
inline constexpr const char* kModelFriction = "/model/friction_N";
inline constexpr const char* kModelGravity = "/model/gravity_N";
// String attributes of kModelGroup: summary (ImpactSummary::BriefReport), solver, warnings (one a
// line); number attributes: error_estimate, the summary's figures (t_end_s, crater_depth_m,
// relative_penetration, added_mass_max_kg, peak_deceleration_g, t_peak_s,
// plateau_deceleration_g, momentum_ratio) and the parameters (pounder_mass_kg,
// impact_velocity_m_s, width_m, depth_m, K, n, u, T_s, b_per_s, rho_kg_m3, g_m_s2).
inline constexpr const char* kModelSummaryAttr = "summary";
inline constexpr const char* kModelSolverAttr = "solver";
inline constexpr const char* kModelWarningsAttr = "warnings";

}  // namespace results_layout

// /model as read: the series, decel_g, the parameters and the summary's figures (NaN where a
// file of an earlier version has none), the brief report and the warnings.
struct ModelResultsGroup {
  ImpactSeries series;
  std::vector<double> decel_g;
  ImpactModelParameters parameters;
  ImpactSummary summary;  // The figures above, solver, error_estimate and warnings.
  std::string brief_report;
};

// Writes /model (replacing an existing group) with units and descriptions on every dataset.
void WriteModelResults(H5Writer& out, const ImpactModelParameters& params, const ImpactRun& run);

// Reads /model back. Error kFileFormat naming `file` and the group or dataset when it is missing
// or a series' length differs from the others'.
ModelResultsGroup ReadModelResults(const H5Reader& in, const std::string& file);

}  // namespace impactdic

#endif  // IMPACTDIC_MODEL_MODEL_RESULTS_H_
