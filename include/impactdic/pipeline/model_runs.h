// `impactdic model`'s runs as library functions (docs/model.md): one test, the paper's 27
// combinations (Table 1) and the solvers' work-precision study, each printing its report to `out`
// and writing its files. The output names are checked before any work (io/atomic_file.h; errors
// name the command's -o and --plot).
//
//   RunModelTest(MakeModelParameters(scene, v0), scene.solver, "series.csv", /*json=*/false,
//                std::cout);
#ifndef IMPACTDIC_PIPELINE_MODEL_RUNS_H_
#define IMPACTDIC_PIPELINE_MODEL_RUNS_H_

#include <ostream>
#include <string>

#include "impactdic/model/impact_model.h"
#include "impactdic/model/work_precision.h"

namespace impactdic {

// One test: prints the summary (text, or ImpactSummary::ToJson), writes the series to `output`
// (.csv, .h5, .hdf5; empty: none) when the solve reached the end of motion (v = 0), and throws
// Error(kNumerical) after printing when it did not (the series then not written).
void RunModelTest(const ImpactModelParameters& params, const ImpactSolverOptions& options,
                  const std::string& output, bool json, std::ostream& out);

// The 27 combinations of Table 1 about `base` (its soil and model parameters): the table, and
// `output` (.csv; empty: none).
void RunModelTable1(const ImpactModelParameters& base, const ImpactSolverOptions& options,
                    const std::string& output, std::ostream& out);

// The work-precision study: the table, `output` (.csv; empty: none) and the figure of
// `plot_case` as `plot` (.png; empty: none).
void RunModelWorkPrecision(const WorkPrecisionOptions& study, const std::string& plot_case,
                           const std::string& output, const std::string& plot, std::ostream& out);

}  // namespace impactdic

#endif  // IMPACTDIC_PIPELINE_MODEL_RUNS_H_
