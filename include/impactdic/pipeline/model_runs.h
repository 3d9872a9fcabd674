// `impactdic model`'s runs as library functions (docs/model.md): one test, the paper's 27
// combinations (Table 1) and the solvers' work-precision study, each printing its report to `out`
// and writing its files. The output names are checked before any work (io/atomic_file.h; errors
// name the command's -o and --plot).
//
//   RunModelTest(MakeModelParameters(scene, v0), scene.solver, "series.csv", /*json=*/false,
//                std::cout);
#ifndef IMPACTDIC_PIPELINE_MODEL_RUNS_H_
#define IMPACTDIC_PIPELINE_MODEL_RUNS_H_

#include <map>
#include <optional>
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

// `impactdic model` as one request: the test.* and model.* scene keys given (their ranges are the
// scene's, pipeline/scene.cc; the solver's are ImpactSolverOptions::Check()'s) and the choice of
// run, whose options are not scene keys (named in errors by the command's flags, as -o and --plot
// above). A key is named in errors by `key_names` (the
// flag the user typed for it, "--mass"), else by the key itself.
//
//   ModelRequest r;
//   r.keys["test.mass_kg"] = 10;  r.keys["test.width_m"] = 0.15;  r.keys["test.drop_height_m"] =
//   0.7; RunModelRequest(r, std::cout);
struct ModelRequest {
  std::map<std::string, std::optional<double>> keys;  // Numbers by key ("model.K"); unset: default.
  std::string solver = ToString(ImpactSolverOptions{}.solver);  // model.solver
  std::string error_estimator = ToString(ImpactSolverOptions{}.error_estimator);
  bool ode45_defaults = false;                   // model.ode45_defaults
  std::map<std::string, std::string> key_names;  // Key -> the name errors give it.
  // The run: one test (mass, width and exactly one of drop height / impact velocity required), the
  // paper's 27 combinations (--table1) or the work-precision study (--work-precision; comma lists
  // of WorkPrecisionOptions' solvers and of its cases exact, default, table1). Both of these
  // refuse the per-test keys (test.mass_kg, drop height, impact velocity, width, added mass).
  bool table1 = false;
  bool work_precision = false;
  std::string wp_solvers = "dopri5,stiff,auto,ode45";
  std::string wp_cases = "exact,default,table1";
  std::string wp_tolerances;  // Comma list of rtols; empty: WorkPrecisionOptions' (1e-3 .. 1e-12).
  double wp_timing_budget_s = WorkPrecisionOptions{}.timing_budget_s;
  std::string format = "text";  // text, or json: a single run's summary as ImpactSummary::ToJson.
  std::string output;           // -o: see RunModelTest / RunModelTable1 / RunModelWorkPrecision.
  std::string plot;             // --plot: only with work_precision.
};

// The request's model parameters (a single run: v0 from the height or the velocity given),
// checked by the scene keys' parsers and ImpactModelParameters::Check(); Error(kInvalidValue)
// naming the key (key_names) otherwise. Throws also when the keys do not fit the run (above).
ImpactModelParameters ModelRequestParameters(const ModelRequest& request);
// The solver options (model.solver, rtol, atol, error_estimator, ode45_defaults, t_max_s), checked
// by ImpactSolverOptions::Check(), naming the key.
ImpactSolverOptions ModelRequestSolverOptions(const ModelRequest& request);
// The work-precision study of wp_solvers and wp_cases (Error naming --wp-solvers / --wp-cases).
WorkPrecisionOptions ModelRequestStudy(const ModelRequest& request);

// Validates the whole request before any work, then runs it (RunModelTest, RunModelTable1 or
// RunModelWorkPrecision).
void RunModelRequest(const ModelRequest& request, std::ostream& out);

}  // namespace impactdic

#endif  // IMPACTDIC_PIPELINE_MODEL_RUNS_H_
