// Writing the model's time series: CSV here, HDF5 by the /model group's writer (model_results.cc).
#include <string>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/strings.h"
#include "impactdic/io/csv.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/model/impact_model.h"
#include "impactdic/model/model_results.h"

namespace impactdic {
std::vector<std::string> ImpactSeriesColumns() {
  return {"t_s",       "z_m",       "v_m_s",      "dv_dt_m_s2", "m_add_kg", "dm_add_dt_kg_s",
          "inertia_N", "dynamic_N", "friction_N", "gravity_N"};
}

void WriteImpactSeries(const std::string& path, const ImpactModelParameters& params,
                       const ImpactRun& run) {
  if (EndsWithIgnoreCase(path, ".csv")) {
    const ImpactSeries s = MakeImpactSeries(params, run);
    const std::vector<std::vector<double>> columns = {
        s.t_s,       s.z_m,       s.v_m_s,      s.dv_dt_m_s2, s.m_add_kg, s.dm_add_dt_kg_s,
        s.inertia_N, s.dynamic_N, s.friction_N, s.gravity_N};
    WriteCsv(path, ImpactSeriesColumns(), columns, /*precision=*/17);
    return;
  }
  if (!EndsWithIgnoreCase(path, ".h5") && !EndsWithIgnoreCase(path, ".hdf5"))
    throw Error(ErrorKind::kInvalidValue, "path", path, "a file name ending in .csv, .h5 or .hdf5");
  // The run's /model layout (model/model_results.h); other groups of an existing file stay.
  H5Writer out(path, /*owned_groups=*/{results_layout::kModelGroup});
  WriteModelResults(out, params, run);
  out.Commit();
}

}  // namespace impactdic
