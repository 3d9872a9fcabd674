#include "impactdic/model/work_precision.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

#include "impactdic/core/error.h"
#include "impactdic/core/numeric.h"
#include "impactdic/core/progress.h"
#include "impactdic/core/timer.h"
#include "impactdic/io/csv.h"

namespace impactdic {
namespace {

double RelErr(double value, double reference) {
  if (std::isnan(reference)) return kNaN;
  if (std::isnan(value)) return std::numeric_limits<double>::infinity();
  return std::abs(value - reference) / std::max(std::abs(reference), 1e-300);
}

// Runs until `budget` seconds have passed (at least once); returns the first run and the fastest
// wall time of the primary run (the companion run of the error estimate is not counted).
ImpactRun TimedRun(const ImpactModelParameters& p, const ImpactSolverOptions& o, double budget,
                   double* best_time) {
  WallTimer total;
  ImpactRun run = SimulateImpact(p, o);
  double best = run.summary.primary_wall_time_s;
  ImpactSolverOptions local = o;
  local.error_estimator = ErrorEstimator::kLocalSum;
  while (total.ElapsedSeconds() < budget) {
    ImpactRun again = SimulateImpact(p, local);
    best = std::min(best, again.summary.primary_wall_time_s);
  }
  *best_time = best;
  return run;
}

// The reference: Dormand-Prince at rtol 1e-13, atol 1e-16.
ImpactSummary Reference(const ImpactModelParameters& p, double t_max) {
  ImpactSolverOptions o;
  o.solver = ImpactSolver::kDopri5;
  o.rtol = 1e-13;
  o.atol = 1e-16;
  o.t_max_s = t_max;
  return SimulateImpact(p, o).summary;
}

ImpactModelParameters DefaultCase() {
  ImpactModelParameters p;
  p.pounder_mass_kg = 10.0;
  p.width_m = 0.15;
  p.impact_velocity_m_s = ImpactVelocityFromHeight(0.7, p.gravity_m_s2);
  return p;
}

}  // namespace

std::vector<Table1Combination> Table1Combinations(const ImpactModelParameters& base) {
  std::vector<Table1Combination> out;
  for (double m : {7.0, 10.0, 13.0})
    for (double h : {0.2, 0.7, 1.2})
      for (double d : {0.10, 0.15, 0.20}) {
        Table1Combination c{m, h, d, base};
        c.params.pounder_mass_kg = m;
        c.params.width_m = d;
        c.params.impact_velocity_m_s = ImpactVelocityFromHeight(h, base.gravity_m_s2);
        out.push_back(c);
      }
  return out;
}

std::vector<Table1Row> RunTable1(const ImpactSolverOptions& options,
                                 const ImpactModelParameters& base) {
  std::vector<Table1Row> rows;
  ProgressBar bar("table1", 27);
  for (const Table1Combination& c : Table1Combinations(base)) {
    rows.push_back({c, SimulateImpact(c.params, options).summary});
    bar.Advance();
  }
  bar.Finish();
  return rows;
}

std::string FormatTable1(const std::vector<Table1Row>& rows) {
  std::string out = fmt::format(
      "{:>5} {:>5} {:>5} {:>7} {:>7} {:>9} {:>9} {:>7} {:>8} {:>9} {:>8} {:>7} {:>6} {}\n", "m_p",
      "h", "D", "v0", "M", "t_end", "crater", "z/D", "peak_g", "t_peak", "plat_g", "p_ratio",
      "steps", "warnings");
  out +=
      fmt::format("{:>5} {:>5} {:>5} {:>7} {:>7} {:>9} {:>9} {:>7} {:>8} {:>9} {:>8} {:>7} {:>6}\n",
                  "kg", "m", "m", "m/s", "kg", "s", "m", "-", "g", "s", "g", "-", "-");
  for (const Table1Row& r : rows) {
    const ImpactSummary& s = r.summary;
    out += fmt::format(
        "{:5.1f} {:5.2f} {:5.2f} {:7.4f} {:7.4f} {:9.6f} {:9.6f} {:7.4f} {:8.3f} {:9.6f} {:8.3f} "
        "{:7.4f} {:6d} {}\n",
        r.combination.pounder_mass_kg, r.combination.height_m, r.combination.width_m,
        r.combination.params.impact_velocity_m_s, s.added_mass_max_kg, s.t_end_s, s.crater_depth_m,
        s.relative_penetration, s.peak_deceleration_g, s.t_peak_s, s.plateau_deceleration_g,
        s.momentum_ratio, s.steps, s.warnings.size());
  }
  return out;
}

std::vector<std::string> Table1CsvColumns() {
  return {"pounder_mass_kg",
          "height_m",
          "width_m",
          "impact_velocity_m_s",
          "added_mass_max_kg",
          "t_end_s",
          "crater_depth_m",
          "relative_penetration",
          "peak_deceleration_g",
          "t_peak_s",
          "plateau_deceleration_g",
          "momentum_ratio",
          "steps",
          "rhs_evals",
          "error_estimate",
          "solver",
          "warnings"};
}

void WriteTable1Csv(const std::string& path, const std::vector<Table1Row>& rows) {
  const std::vector<std::string> names = Table1CsvColumns();
  std::vector<std::vector<std::string>> cells;
  auto num = [](double v) { return std::isfinite(v) ? fmt::format("{:.17g}", v) : "nan"; };
  for (const Table1Row& r : rows) {
    const ImpactSummary& s = r.summary;
    std::string warnings;
    for (const std::string& w : s.warnings) warnings += (warnings.empty() ? "" : "; ") + w;
    std::string quoted = "\"";
    for (char ch : warnings) quoted += ch == '"' ? std::string("\"\"") : std::string(1, ch);
    quoted += "\"";
    cells.push_back({num(r.combination.pounder_mass_kg), num(r.combination.height_m),
                     num(r.combination.width_m), num(r.combination.params.impact_velocity_m_s),
                     num(s.added_mass_max_kg), num(s.t_end_s), num(s.crater_depth_m),
                     num(s.relative_penetration), num(s.peak_deceleration_g), num(s.t_peak_s),
                     num(s.plateau_deceleration_g), num(s.momentum_ratio), std::to_string(s.steps),
                     std::to_string(s.rhs_evals), num(s.error_estimate), s.solver, quoted});
  }
  WriteCsvRows(path, names, cells);
}

ImpactSolverOptions SolverSetting(const std::string& name, double rtol) {
  ImpactSolverOptions o;
  o.rtol = rtol;
  o.atol = 1e-3 * rtol;
  if (name == "ode45") {
    o.solver = ImpactSolver::kDopri5;
    o.ode45_defaults = true;
  } else {
    o.solver = ImpactSolverFromString(name);
  }
  return o;
}

void WorkPrecisionOptions::Check() const {
  CheckValue(!solvers.empty(), "work_precision.solvers", "empty", "at least one solver");
  for (const std::string& s : solvers) {
    if (s != "ode45") ImpactSolverFromString(s);
  }
  for (double t : tolerances)
    CheckValue(t >= 1e-14 && t <= 0.1, "work_precision.tolerances", fmt::format("{}", t),
               "tolerances in [1e-14, 0.1]");
  CheckValue(timing_budget_s >= 0, "work_precision.timing_budget_s",
             fmt::format("{}", timing_budget_s), ">= 0 s");
}

namespace {

void FillCost(WorkPrecisionRow& row, const ImpactSummary& s, double time) {
  row.solver_ran = s.solver;
  row.error_estimate = s.error_estimate_companion;
  row.error_estimate_local = s.error_estimate_local;
  row.wall_time_s = time;
  row.rhs_evals = s.rhs_evals;
  row.steps = s.steps;
  row.jacobian_evals = s.jacobian_evals;
  row.warnings = static_cast<int>(s.warnings.size());
}

// The two cases with exact solutions and their exact figures.
struct ExactCases {
  // (a) conserved momentum (K = 0, g = 0), compared at a fixed end time.
  ImpactModelParameters momentum;
  double t_fixed = 0.02;
  ImpactState momentum_state;
  double momentum_peak_g = kNaN;
  // (b) harmonic (M = 0, u = 1).
  ImpactModelParameters harmonic;
  HarmonicStop harmonic_stop;
  double harmonic_plateau_g = kNaN;
};

ExactCases MakeExactCases() {
  ExactCases e;
  e.momentum = DefaultCase();
  e.momentum.friction_K = 0.0;
  e.momentum.gravity_m_s2 = 0.0;
  e.momentum_state = ExactConservedMomentum(e.momentum, e.t_fixed);
  {
    // The exact peak of -dv/dt = p0 (dm/dt) / m^2 by golden-section search on the closed form.
    const ImpactModelParameters& m = e.momentum;
    const double M = m.AddedMassMax_kg(), mp = m.pounder_mass_kg;
    const double b = m.sigmoid_rate_b_per_s, T = m.sigmoid_delay_T_s;
    const double p0 = (mp + AddedMassAt(M, b, T, 0.0).m_add_kg) * m.impact_velocity_m_s;
    auto decel = [&](double t) {
      const AddedMass am = AddedMassAt(M, b, T, t);
      return p0 * am.dm_dt_kg_s / ((mp + am.m_add_kg) * (mp + am.m_add_kg));
    };
    e.momentum_peak_g =
        decel(GoldenSectionMaximize(decel, T - 5.0 / b, T + 5.0 / b, {.max_iterations = 300})) /
        9.81;
  }
  e.harmonic = DefaultCase();
  e.harmonic.added_mass_kg = 0.0;
  e.harmonic.damping_factor_u = 1.0;
  e.harmonic_stop = ExactHarmonicStop(e.harmonic);
  {
    const ImpactModelParameters& h = e.harmonic;
    const double k = h.Stiffness_N_m(), m = h.pounder_mass_kg;
    const double w = std::sqrt(k / m), delta = m * h.gravity_m_s2 / k;
    const double t1 = h.sigmoid_delay_T_s + 4.0 / h.sigmoid_rate_b_per_s;
    const double v1 = delta * w * std::sin(w * t1) + h.impact_velocity_m_s * std::cos(w * t1);
    e.harmonic_plateau_g = v1 / (e.harmonic_stop.t_end_s - t1) / h.gravity_m_s2;
  }
  return e;
}

WorkPrecisionRow MomentumExactRow(const ExactCases& e, const std::string& solver, double tol,
                                  const ImpactSolverOptions& so, double timing_budget_s) {
  ImpactSolverOptions o = so;
  o.t_max_s = e.t_fixed;
  double time = 0;
  const ImpactRun run = TimedRun(e.momentum, o, timing_budget_s, &time);
  WorkPrecisionRow row{"momentum-exact", solver, "", tol};
  row.depth_error = RelErr(run.solution.z_end_m, e.momentum_state.z_m);
  row.t_end_error = RelErr(run.solution.v_end_m_s, e.momentum_state.v_m_s);
  row.peak_error = RelErr(run.summary.peak_deceleration_g, e.momentum_peak_g);
  row.plateau_error = kNaN;
  FillCost(row, run.summary, time);  // Only warning expected: v does not reach 0 by t_max.
  return row;
}

WorkPrecisionRow HarmonicExactRow(const ExactCases& e, const std::string& solver, double tol,
                                  const ImpactSolverOptions& so, double timing_budget_s) {
  double time = 0;
  const ImpactRun run = TimedRun(e.harmonic, so, timing_budget_s, &time);
  WorkPrecisionRow row{"harmonic-exact", solver, "", tol};
  row.depth_error = RelErr(run.summary.crater_depth_m, e.harmonic_stop.crater_depth_m);
  row.t_end_error = RelErr(run.summary.t_end_s, e.harmonic_stop.t_end_s);
  row.peak_error = kNaN;
  row.plateau_error = RelErr(run.summary.plateau_deceleration_g, e.harmonic_plateau_g);
  FillCost(row, run.summary, time);
  return row;
}

WorkPrecisionRow DefaultCaseRow(const ImpactSummary& ref, const std::string& solver, double tol,
                                const ImpactSolverOptions& so, double timing_budget_s) {
  double time = 0;
  const ImpactRun run = TimedRun(DefaultCase(), so, timing_budget_s, &time);
  WorkPrecisionRow row{"default", solver, "", tol};
  row.depth_error = RelErr(run.summary.crater_depth_m, ref.crater_depth_m);
  row.t_end_error = RelErr(run.summary.t_end_s, ref.t_end_s);
  row.peak_error = RelErr(run.summary.peak_deceleration_g, ref.peak_deceleration_g);
  row.plateau_error = RelErr(run.summary.plateau_deceleration_g, ref.plateau_deceleration_g);
  FillCost(row, run.summary, time);
  return row;
}

// The worst errors over the 27 combinations, costs summed.
WorkPrecisionRow Table1MaxRow(const std::vector<Table1Combination>& combos,
                              const std::vector<ImpactSummary>& refs, const std::string& solver,
                              double tol, const ImpactSolverOptions& so, ProgressBar* bar) {
  WorkPrecisionRow row{"table1-max", solver, "", tol};
  row.error_estimate = 0.0;
  for (std::size_t i = 0; i < combos.size(); ++i) {
    double time = 0;
    const ImpactRun run = TimedRun(combos[i].params, so, 0.0, &time);
    const ImpactSummary& s = run.summary;
    const ImpactSummary& ref = refs[i];
    row.depth_error = std::max(row.depth_error, RelErr(s.crater_depth_m, ref.crater_depth_m));
    row.t_end_error = std::max(row.t_end_error, RelErr(s.t_end_s, ref.t_end_s));
    row.peak_error =
        std::max(row.peak_error, RelErr(s.peak_deceleration_g, ref.peak_deceleration_g));
    row.plateau_error =
        std::max(row.plateau_error, RelErr(s.plateau_deceleration_g, ref.plateau_deceleration_g));
    row.error_estimate = std::max(row.error_estimate, s.error_estimate_companion);
    row.error_estimate_local = std::max(row.error_estimate_local, s.error_estimate_local);
    row.wall_time_s += time;
    row.rhs_evals += s.rhs_evals;
    row.steps += s.steps;
    row.jacobian_evals += s.jacobian_evals;
    row.warnings += static_cast<int>(s.warnings.size());
    row.solver_ran = s.solver;
    bar->Advance();
  }
  return row;
}

}  // namespace

std::vector<WorkPrecisionRow> RunWorkPrecision(const WorkPrecisionOptions& options) {
  options.Check();
  std::vector<WorkPrecisionRow> rows;
  const std::size_t per_setting =
      (options.exact_cases ? 2 : 0) + (options.default_case ? 1 : 0) + (options.table1 ? 27 : 0);
  ProgressBar bar("work-precision",
                  per_setting * options.solvers.size() * options.tolerances.size());
  const ExactCases exact = MakeExactCases();
  // References.
  ImpactSummary def_ref;
  if (options.default_case) def_ref = Reference(DefaultCase(), 10.0);
  std::vector<Table1Combination> combos;
  std::vector<ImpactSummary> combo_refs;
  if (options.table1) {
    combos = Table1Combinations();
    combo_refs.reserve(combos.size());
    for (const Table1Combination& c : combos) combo_refs.push_back(Reference(c.params, 10.0));
  }
  const double budget = options.timing_budget_s;
  for (const std::string& solver : options.solvers) {
    for (double tol : options.tolerances) {
      const ImpactSolverOptions so = SolverSetting(solver, tol);
      if (options.exact_cases) {
        rows.push_back(MomentumExactRow(exact, solver, tol, so, budget));
        bar.Advance();
        rows.push_back(HarmonicExactRow(exact, solver, tol, so, budget));
        bar.Advance();
      }
      if (options.default_case) {
        rows.push_back(DefaultCaseRow(def_ref, solver, tol, so, budget));
        bar.Advance();
      }
      if (options.table1) rows.push_back(Table1MaxRow(combos, combo_refs, solver, tol, so, &bar));
    }
  }
  bar.Finish();
  return rows;
}

std::string FormatWorkPrecision(const std::vector<WorkPrecisionRow>& rows) {
  std::string out = fmt::format(
      "{:<15} {:<7} {:>7} {:>9} {:>9} {:>9} {:>9} {:>9} {:>8} {:>9} {:>8} {:>10} {:>8} {:>7} "
      "{:>4}\n",
      "case", "solver", "rtol", "err_depth", "err_tend", "err_peak", "err_plat", "est_comp",
      "comp/tru", "est_local", "loc/tru", "time_s", "rhs", "steps", "warn");
  for (const WorkPrecisionRow& r : rows) {
    const double true_err = std::max(r.depth_error, r.t_end_error);
    out += fmt::format(
        "{:<15} {:<7} {:7.0e} {:9.2e} {:9.2e} {:9.2e} {:9.2e} {:9.2e} {:8.2g} {:9.2e} {:8.2g} "
        "{:10.3e} {:8d} {:7d} {:4d}\n",
        r.case_name, r.solver, r.rtol, r.depth_error, r.t_end_error, r.peak_error, r.plateau_error,
        r.error_estimate, r.error_estimate / true_err, r.error_estimate_local,
        r.error_estimate_local / true_err, r.wall_time_s, r.rhs_evals, r.steps, r.warnings);
  }
  return out;
}

std::vector<std::string> WorkPrecisionCsvColumns() {
  return {"case",        "solver",     "solver_ran",    "rtol",           "depth_error",
          "t_end_error", "peak_error", "plateau_error", "error_estimate", "error_estimate_local",
          "wall_time_s", "rhs_evals",  "steps",         "jacobian_evals", "warnings"};
}

void WriteWorkPrecisionCsv(const std::string& path, const std::vector<WorkPrecisionRow>& rows) {
  const std::vector<std::string> names = WorkPrecisionCsvColumns();
  auto num = [](double v) { return std::isnan(v) ? std::string("nan") : fmt::format("{:.6g}", v); };
  std::vector<std::vector<std::string>> cells;
  cells.reserve(rows.size());
  for (const WorkPrecisionRow& r : rows)
    cells.push_back({r.case_name, r.solver, r.solver_ran, num(r.rtol), num(r.depth_error),
                     num(r.t_end_error), num(r.peak_error), num(r.plateau_error),
                     num(r.error_estimate), num(r.error_estimate_local), num(r.wall_time_s),
                     std::to_string(r.rhs_evals), std::to_string(r.steps),
                     std::to_string(r.jacobian_evals), std::to_string(r.warnings)});
  WriteCsvRows(path, names, cells);
}

}  // namespace impactdic
