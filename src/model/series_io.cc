// Writing the model's time series (CSV or HDF5).
#include <cstddef>
#include <string>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/strings.h"
#include "impactdic/io/csv.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/model/impact_model.h"

namespace impactdic {
std::vector<std::string> ImpactSeriesColumns() {
  return {"t_s",       "z_m",       "v_m_s",      "dv_dt_m_s2", "m_add_kg", "dm_add_dt_kg_s",
          "inertia_N", "dynamic_N", "friction_N", "gravity_N"};
}

void WriteImpactSeries(const std::string& path, const ImpactModelParameters& params,
                       const ImpactRun& run) {
  const ImpactSeries s = MakeImpactSeries(params, run);
  const std::vector<std::string> names = ImpactSeriesColumns();
  const std::vector<std::vector<double>> columns = {
      s.t_s,       s.z_m,       s.v_m_s,      s.dv_dt_m_s2, s.m_add_kg, s.dm_add_dt_kg_s,
      s.inertia_N, s.dynamic_N, s.friction_N, s.gravity_N};
  if (EndsWithIgnoreCase(path, ".csv")) {
    WriteCsv(path, names, columns, /*precision=*/17);
    return;
  }
  if (!EndsWithIgnoreCase(path, ".h5") && !EndsWithIgnoreCase(path, ".hdf5"))
    throw Error(ErrorKind::kInvalidValue, "path", path, "a file name ending in .csv, .h5 or .hdf5");
  const std::vector<std::string> units = {"s",    "m", "m/s", "m/s^2", "kg",
                                          "kg/s", "N", "N",   "N",     "N"};
  const std::vector<std::string> what = {"time since contact",
                                         "penetration depth z (downward positive)",
                                         "pounder velocity v = dz/dt (downward positive)",
                                         "dv/dt (NaN at v = 0, where the v^-n term is unbounded)",
                                         "added mass m_add(t) (Eq. 5)",
                                         "dm_add/dt (Eq. 6)",
                                         "-(dm_add/dt) v",
                                         "F_dyn = -k z (u - 1) / v^n (Eq. 8; NaN at v = 0)",
                                         "F_fr = -k z (Eq. 7)",
                                         "F_g = (m_p + m_add) g"};
  H5Writer out(path, /*owned_groups=*/{"/model"});  // Other groups of an existing file stay.
  for (std::size_t i = 0; i < names.size(); ++i)
    out.Write("model/series/" + names[i], columns[i], units[i], what[i]);
  const ImpactSummary& sum = run.summary;
  out.SetAttribute("model", "t_end_s", sum.t_end_s);
  out.SetAttribute("model", "crater_depth_m", sum.crater_depth_m);
  out.SetAttribute("model", "relative_penetration", sum.relative_penetration);
  out.SetAttribute("model", "added_mass_max_kg", sum.added_mass_max_kg);
  out.SetAttribute("model", "peak_deceleration_g", sum.peak_deceleration_g);
  out.SetAttribute("model", "t_peak_s", sum.t_peak_s);
  out.SetAttribute("model", "plateau_deceleration_g", sum.plateau_deceleration_g);
  out.SetAttribute("model", "momentum_ratio", sum.momentum_ratio);
  out.SetAttribute("model", "error_estimate", sum.error_estimate);
  out.SetAttribute("model", "solver", sum.solver);
  std::string warnings;
  for (const std::string& w : sum.warnings) warnings += (warnings.empty() ? "" : "\n") + w;
  out.SetAttribute("model", "warnings", warnings);
  out.SetAttribute("model", "pounder_mass_kg", params.pounder_mass_kg);
  out.SetAttribute("model", "impact_velocity_m_s", params.impact_velocity_m_s);
  out.SetAttribute("model", "width_m", params.width_m);
  out.SetAttribute("model", "depth_m", params.depth_m);
  out.SetAttribute("model", "K", params.friction_K);
  out.SetAttribute("model", "n", params.damping_exponent_n);
  out.SetAttribute("model", "u", params.damping_factor_u);
  out.SetAttribute("model", "T_s", params.sigmoid_delay_T_s);
  out.SetAttribute("model", "b_per_s", params.sigmoid_rate_b_per_s);
  out.SetAttribute("model", "rho_kg_m3", params.density_kg_m3);
  out.SetAttribute("model", "g_m_s2", params.gravity_m_s2);
  out.Commit();
}

}  // namespace impactdic
