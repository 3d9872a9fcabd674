// Work-precision study of the impact-model solvers and the paper's 27 test combinations.
//
// For each solver (dopri5, stiff, auto, ode45 rules) and tolerance (1e-3 .. 1e-12) the model is
// run on the exact cases of docs/model.md (conserved momentum: z and v at a fixed end time;
// harmonic: stop time and depth) and on the default case / Table 1 combinations against a
// converged reference (Dormand-Prince at rtol 1e-13), and the true relative errors of crater
// depth, t_end, peak and plateau deceleration are put next to the cost (wall time, RHS
// evaluations) and the solver's own error estimate.
//
//   WorkPrecisionOptions o;            // all solvers, 1e-3 .. 1e-12, all cases
//   std::vector<WorkPrecisionRow> rows = RunWorkPrecision(o);
//   std::cout << FormatWorkPrecision(rows);
#ifndef IMPACTDIC_MODEL_WORK_PRECISION_H_
#define IMPACTDIC_MODEL_WORK_PRECISION_H_

#include <algorithm>
#include <string>
#include <vector>

#include "impactdic/model/impact_model.h"

namespace impactdic {

// The paper's 27 combinations (Table 1): m_p 7/10/13 kg x h 0.2/0.7/1.2 m x D 0.10/0.15/0.20 m,
// v0 = sqrt(2 g h), other parameters from `base` (Table 2 defaults).
struct Table1Combination {
  double pounder_mass_kg, height_m, width_m;
  ImpactModelParameters params;
};
std::vector<Table1Combination> Table1Combinations(const ImpactModelParameters& base = {});

struct Table1Row {
  Table1Combination combination;
  ImpactSummary summary;
};
std::vector<Table1Row> RunTable1(const ImpactSolverOptions& options,
                                 const ImpactModelParameters& base = {});
// Text table (one line per combination) and CSV.
std::string FormatTable1(const std::vector<Table1Row>& rows);
void WriteTable1Csv(const std::string& path, const std::vector<Table1Row>& rows);
std::vector<std::string> Table1CsvColumns();  // WriteTable1Csv's header.

// A solver setting of the study: "dopri5", "stiff", "auto" or "ode45" (ode45's rules).
ImpactSolverOptions SolverSetting(const std::string& name, double rtol);

struct WorkPrecisionOptions {
  std::vector<std::string> solvers = {"dopri5", "stiff", "auto", "ode45"};
  // Relative tolerances; atol = 1e-3 rtol.
  std::vector<double> tolerances = {1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12};
  bool exact_cases = true;   // momentum and harmonic cases
  bool default_case = true;  // m_p 10 kg, h 0.7 m, D 0.15 m
  bool table1 = true;        // the 27 combinations (aggregated rows: max errors, summed cost)
  // Each run is repeated until this much wall time has passed; the fastest run is reported.
  double timing_budget_s = 0.005;
  void Check() const;
};

struct WorkPrecisionRow {
  std::string case_name;   // "momentum-exact", "harmonic-exact", "default", "table1-max"
  std::string solver;      // setting name
  std::string solver_ran;  // ImpactSummary::solver (of the last run for table1-max)
  double rtol = 0.0;
  // True relative errors (NaN where the quantity does not exist). For "momentum-exact" the depth
  // and t_end columns hold the errors of z and v at the end time.
  double depth_error = 0.0, t_end_error = 0.0, peak_error = 0.0, plateau_error = 0.0;
  // The run's own estimates (max over the combinations for table1-max): the companion-run
  // estimate (the default error_estimate) and the local-error sum.
  double error_estimate = 0.0, error_estimate_local = 0.0;
  double wall_time_s = 0.0;  // Per run (summed over the combinations for table1-max).
  long rhs_evals = 0, steps = 0, jacobian_evals = 0;
  int warnings = 0;
};

std::vector<WorkPrecisionRow> RunWorkPrecision(const WorkPrecisionOptions& options);
std::string FormatWorkPrecision(const std::vector<WorkPrecisionRow>& rows);
void WriteWorkPrecisionCsv(const std::string& path, const std::vector<WorkPrecisionRow>& rows);
std::vector<std::string> WorkPrecisionCsvColumns();  // WriteWorkPrecisionCsv's header.
// The figure: PlotWorkPrecision in render/work_precision_figure.h.

}  // namespace impactdic

#endif  // IMPACTDIC_MODEL_WORK_PRECISION_H_
