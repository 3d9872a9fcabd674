#include "impactdic/model/model_results.h"

#include <cstddef>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "impactdic/io/results_io.h"

namespace impactdic {
namespace L = results_layout;
namespace {

// The series of /model bound to an ImpactSeries (const for the writer, mutable for the reader),
// in the order written; decel_g is apart.
template <typename S>
auto ModelSeries(S& s) {
  using Vector = std::remove_reference_t<decltype((s.t_s))>;
  return std::vector<DatasetBinding<Vector>>{
      {L::kModelT, "s", "model time since impact", &s.t_s},
      {L::kModelZ, "m", "model penetration (down)", &s.z_m},
      {L::kModelV, "m/s", "model pounder velocity (down)", &s.v_m_s},
      {L::kModelAddedMass, "kg", "model added mass, Eq. 5", &s.m_add_kg},
      {L::kModelDvDt, "m/s^2", "dv/dt (NaN at v = 0, where the v^-n term is unbounded)",
       &s.dv_dt_m_s2},
      {L::kModelDmAddDt, "kg/s", "dm_add/dt (Eq. 6)", &s.dm_add_dt_kg_s},
      {L::kModelInertia, "N", "-(dm_add/dt) v", &s.inertia_N},
      {L::kModelDynamic, "N", "F_dyn = -k z (u - 1) / v^n (Eq. 8; NaN at v = 0)", &s.dynamic_N},
      {L::kModelFriction, "N", "F_fr = -k z (Eq. 7)", &s.friction_N},
      {L::kModelGravity, "N", "F_g = (m_p + m_add) g", &s.gravity_N}};
}

// The number attributes of /model bound to a summary and parameters (const or not).
template <typename S, typename P>
auto NumberAttributes(S& s, P& p) {
  using Number = std::remove_reference_t<decltype((s.t_end_s))>;
  return std::vector<std::pair<const char*, Number*>>{
      {"error_estimate", &s.error_estimate},
      {"t_end_s", &s.t_end_s},
      {"crater_depth_m", &s.crater_depth_m},
      {"relative_penetration", &s.relative_penetration},
      {"added_mass_max_kg", &s.added_mass_max_kg},
      {"peak_deceleration_g", &s.peak_deceleration_g},
      {"t_peak_s", &s.t_peak_s},
      {"plateau_deceleration_g", &s.plateau_deceleration_g},
      {"momentum_ratio", &s.momentum_ratio},
      {"pounder_mass_kg", &p.pounder_mass_kg},
      {"impact_velocity_m_s", &p.impact_velocity_m_s},
      {"width_m", &p.width_m},
      {"depth_m", &p.depth_m},
      {"K", &p.friction_K},
      {"n", &p.damping_exponent_n},
      {"u", &p.damping_factor_u},
      {"T_s", &p.sigmoid_delay_T_s},
      {"b_per_s", &p.sigmoid_rate_b_per_s},
      {"rho_kg_m3", &p.density_kg_m3},
      {"g_m_s2", &p.gravity_m_s2}};
}

}  // namespace

void WriteModelResults(H5Writer& out, const ImpactModelParameters& params, const ImpactRun& run) {
  const ImpactSeries s = MakeImpactSeries(params, run);
  out.Remove(L::kModelGroup);
  std::vector<double> decel(s.size());
  for (std::size_t i = 0; i < s.size(); ++i) decel[i] = -s.dv_dt_m_s2[i] / params.gravity_m_s2;
  for (const auto& d : ModelSeries(s)) {
    out.Write(d.path, *d.values, d.units, d.description);
    if (d.path == L::kModelT)
      out.Write(L::kModelDecel, decel, "g", "model pounder deceleration -dv/dt / g");
  }
  const ImpactSummary& sum = run.summary;
  out.SetAttribute(L::kModelGroup, L::kModelSummaryAttr, sum.BriefReport());
  out.SetAttribute(L::kModelGroup, L::kModelSolverAttr, sum.solver);
  for (const auto& [name, value] : NumberAttributes(sum, params))
    out.SetAttribute(L::kModelGroup, name, *value);
  std::string warnings;
  for (const std::string& w : sum.warnings) warnings += (warnings.empty() ? "" : "\n") + w;
  out.SetAttribute(L::kModelGroup, L::kModelWarningsAttr, warnings);
}

ModelResultsGroup ReadModelResults(const H5Reader& in, const std::string& file) {
  RequireGroup(in, L::kModelGroup, file, "the impact model's results (impactdic run or model -o)");
  ModelResultsGroup g;
  std::size_t k = kAnyLength;
  // A run's results.h5 before 2026-11-28 has t_s, decel_g, z_m, v_m_s and m_add_kg only.
  for (const auto& d : ModelSeries(g.series)) {
    if (d.path == L::kModelT || in.Exists(d.path)) *d.values = ReadSeries(in, d.path, file, &k);
  }
  g.decel_g = ReadSeries(in, L::kModelDecel, file, &k);
  for (const auto& [name, value] : NumberAttributes(g.summary, g.parameters))
    *value = ReadNumberAttributeOr(in, L::kModelGroup, name, kNaN);
  g.brief_report = ReadStringAttributeOr(in, L::kModelGroup, L::kModelSummaryAttr, "");
  g.summary.solver = ReadStringAttributeOr(in, L::kModelGroup, L::kModelSolverAttr, "");
  std::istringstream warnings(ReadStringAttributeOr(in, L::kModelGroup, L::kModelWarningsAttr, ""));
  for (std::string line; std::getline(warnings, line);) g.summary.warnings.push_back(line);
  return g;
}

}  // namespace impactdic
