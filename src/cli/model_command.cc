// impactdic model: the added-mass impact model (Eq. 9, docs/model.md) for one test, the
// work-precision study of its solvers, or the paper's 27 combinations (Table 1).
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "commands.h"
#include "impactdic/core/enum_names.h"
#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/core/range.h"
#include "impactdic/core/strings.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/csv.h"
#include "impactdic/io/json.h"
#include "impactdic/model/impact_model.h"
#include "impactdic/model/work_precision.h"
#include "impactdic/render/work_precision_figure.h"

namespace impactdic::cli {
namespace {

// Defaults: the model library's ImpactModelParameters and ImpactSolverOptions (Table 2 is
// defined there once).
struct ModelArgs {
  std::optional<double> mass, height, velocity, width, added_mass;
  double depth = ImpactModelParameters{}.depth_m;
  double K = ImpactModelParameters{}.friction_K;
  double n = ImpactModelParameters{}.damping_exponent_n;
  double u = ImpactModelParameters{}.damping_factor_u;
  double T = ImpactModelParameters{}.sigmoid_delay_T_s;
  double b = ImpactModelParameters{}.sigmoid_rate_b_per_s;
  double rho = ImpactModelParameters{}.density_kg_m3;
  double g = ImpactModelParameters{}.gravity_m_s2;
  double bed_height = ImpactModelParameters{}.bed_height_m;
  std::optional<double> rtol, atol, t_max;
  std::string solver = ToString(ImpactSolverOptions{}.solver);
  std::string error_estimate = ToString(ImpactSolverOptions{}.error_estimator);
  bool ode45_defaults = false;
  std::string format = "text";
  std::string output;
  bool work_precision = false;
  std::string plot;
  std::string wp_solvers = "dopri5,stiff,auto,ode45";
  std::string wp_cases = "exact,default,table1";
  bool table1 = false;
};

std::string Num(double v) { return fmt::format("{}", v); }

std::vector<std::string> SplitList(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}

void RequirePositive(const std::optional<double>& v, const char* option, const char* what) {
  if (v && !(std::isfinite(*v) && *v > 0))
    throw Error(ErrorKind::kInvalidValue, option, Num(*v), what);
}

// ImpactModelParameters::Check() (the allowed ranges are defined there), its errors naming the
// command-line option instead of the library's field.
void CheckNamingOptions(const ImpactModelParameters& p, const ModelArgs& a) {
  try {
    p.Check();
  } catch (const Error& e) {
    static const std::vector<std::pair<std::string, std::string>> kOptions = {
        {"pounder_mass_kg", "--mass"},   {"width_m", "--width"},
        {"depth_m", "--depth"},          {"added_mass_kg", "--added-mass"},
        {"friction_K", "--K"},           {"damping_exponent_n", "--n"},
        {"damping_factor_u", "--u"},     {"sigmoid_delay_T_s", "--T"},
        {"sigmoid_rate_b_per_s", "--b"}, {"density_kg_m3", "--rho"},
        {"gravity_m_s2", "--g"},         {"bed_height_m", "--bed-height"}};
    std::string option = e.where();
    for (const auto& [field, name] : kOptions)
      if (e.where() == field) option = name;
    if (e.where() == "impact_velocity_m_s")
      option =
          a.height ? fmt::format("--height (v0 = sqrt(2 g h) = {} m/s)", e.found()) : "--velocity";
    throw Error(e.kind(), option,
                a.height && e.where() == "impact_velocity_m_s" ? Num(*a.height) : e.found(),
                e.expected());
  }
}

// Validates everything before any work; returns the parameters (mass etc. only for a single run).
ImpactModelParameters ValidatedParameters(const ModelArgs& a, bool single_run) {
  if (a.work_precision && a.table1)
    throw Error(ErrorKind::kInvalidValue, "--work-precision", "together with --table1",
                "one of --work-precision, --table1 or a single run");
  if (single_run) {
    if (!a.mass)
      throw Error(ErrorKind::kInvalidValue, "--mass", "missing",
                  "the pounder mass in kg (> 0) for a single run");
    if (!a.width)
      throw Error(ErrorKind::kInvalidValue, "--width", "missing",
                  "the pounder width D in m (> 0) for a single run");
    if (a.height && a.velocity)
      throw Error(ErrorKind::kInvalidValue, "--height/--velocity", "both given",
                  "exactly one of --height (drop height, m) or --velocity (impact velocity, m/s)");
    if (!a.height && !a.velocity)
      throw Error(ErrorKind::kInvalidValue, "--height/--velocity", "neither given",
                  "exactly one of --height (drop height, m) or --velocity (impact velocity, m/s)");
  } else {
    for (const auto& [given, name] :
         {std::pair{a.mass.has_value(), "--mass"}, std::pair{a.height.has_value(), "--height"},
          std::pair{a.velocity.has_value(), "--velocity"},
          std::pair{a.width.has_value(), "--width"},
          std::pair{a.added_mass.has_value(), "--added-mass"}})
      if (given)
        throw Error(ErrorKind::kInvalidValue, name,
                    a.table1 ? "with --table1" : "with --work-precision",
                    "no per-test option: these runs use the paper's 27 combinations / fixed cases");
  }
  // The physical ranges shared with scene files (core/range.h).
  if (a.mass) CheckRange(*a.mass, kPounderMassRange, "--mass", "a pounder mass");
  RequirePositive(a.height, "--height", "a drop height > 0 m");
  if (a.height) CheckRange(*a.height, kDropHeightRange, "--height", "a drop height");
  if (a.velocity) CheckRange(*a.velocity, kImpactVelocityRange, "--velocity", "an impact velocity");
  if (a.width) CheckRange(*a.width, kPounderSizeRange, "--width", "a pounder width D");
  CheckRange(a.depth, kPounderSizeRange, "--depth", "an out-of-plane depth t_z");
  if (a.added_mass) CheckRange(*a.added_mass, kAddedMassRange, "--added-mass", "an added mass M");
  CheckRange(a.K, kFrictionKRange, "--K", "a friction coefficient K");
  CheckRange(a.n, kDampingExponentNRange, "--n", "a damping exponent n");
  CheckRange(a.u, kDampingFactorURange, "--u", "a damping factor u (F_dyn must resist the motion)");
  CheckRange(a.T, kSigmoidDelayRange, "--T", "a sigmoid delay T");
  CheckRange(a.b, kSigmoidRateRange, "--b", "a sigmoid rate b");
  CheckRange(a.rho, kSoilDensityRange, "--rho", "a dry density");
  CheckRange(a.g, kGravityRange, "--g", "a gravitational acceleration");
  CheckRange(a.bed_height, kBedHeightRange, "--bed-height", "a bed height");
  if (a.height && a.g <= 0)
    throw Error(ErrorKind::kInvalidValue, "--g", Num(a.g),
                "g > 0 when the impact velocity comes from --height (v0 = sqrt(2 g h))");

  ImpactModelParameters p;
  if (a.mass) p.pounder_mass_kg = *a.mass;
  if (a.width) p.width_m = *a.width;
  p.depth_m = a.depth;
  if (a.added_mass) p.added_mass_kg = *a.added_mass;
  p.friction_K = a.K;
  p.damping_exponent_n = a.n;
  p.damping_factor_u = a.u;
  p.sigmoid_delay_T_s = a.T;
  p.sigmoid_rate_b_per_s = a.b;
  p.density_kg_m3 = a.rho;
  p.gravity_m_s2 = a.g;
  p.bed_height_m = a.bed_height;
  if (a.velocity) p.impact_velocity_m_s = *a.velocity;
  if (a.height) p.impact_velocity_m_s = ImpactVelocityFromHeight(*a.height, a.g);
  CheckNamingOptions(p, a);
  return p;
}

ImpactSolverOptions ValidatedSolverOptions(const ModelArgs& a) {
  ImpactSolverOptions o;
  WithFlagNames({{"solver", "--solver"}, {"error_estimator", "--error-estimate"}}, [&] {
    o.solver = ImpactSolverFromString(a.solver);
    o.error_estimator = ErrorEstimatorFromString(a.error_estimate);
  });
  o.ode45_defaults = a.ode45_defaults;
  // A given tolerance or time must be a number: NaN means "unset" to the library.
  for (const auto& [value, flag] :
       {std::pair{a.rtol, "--rtol"}, std::pair{a.atol, "--atol"}, std::pair{a.t_max, "--t-max"}}) {
    if (value) CheckValue(!std::isnan(*value), flag, Num(*value), "a number");
  }
  if (a.rtol) o.rtol = *a.rtol;
  if (a.atol) o.atol = *a.atol;
  if (a.t_max) o.t_max_s = *a.t_max;
  // The library's check (the allowed ranges are defined there), naming the flags.
  WithFlagNames({{"rtol", "--rtol"},
                 {"atol", "--atol"},
                 {"t_max_s", "--t-max"},
                 {"ode45_defaults", "--ode45-defaults"}},
                [&] { o.Check(); });
  return o;
}

void RunSingle(const ModelArgs& a) {
  const ImpactModelParameters p = ValidatedParameters(a, /*single_run=*/true);
  const ImpactSolverOptions o = ValidatedSolverOptions(a);
  if (!a.output.empty()) {
    CheckOutputLocation(
        a.output, {"-o", {".csv", ".h5", ".hdf5"}, {}, {CsvHeaderLine(ImpactSeriesColumns())}});
  }
  const ImpactRun run = SimulateImpact(p, o);
  const ImpactSummary& s = run.summary;
  for (const std::string& w : s.warnings) LogWarning("model: {}", w);
  // A solve that did not reach the end of motion writes no series (nothing that looks complete)
  // but still prints its summary, then fails (below).
  if (!a.output.empty() && s.IsUsable()) {
    WriteImpactSeries(a.output, p, run);
    LogInfo("model: wrote the time series to {}", a.output);
  }
  if (a.format == "json") {
    JsonObject j;
    j.Add("t_end_s", s.t_end_s)
        .Add("crater_depth_m", s.crater_depth_m)
        .Add("relative_penetration", s.relative_penetration)
        .Add("added_mass_max_kg", s.added_mass_max_kg)
        .Add("peak_deceleration_g", s.peak_deceleration_g)
        .Add("t_peak_s", s.t_peak_s)
        .Add("plateau_deceleration_g", s.plateau_deceleration_g)
        .Add("momentum_ratio", s.momentum_ratio)
        .Add("solver", s.solver)
        .Add("steps", static_cast<std::int64_t>(s.steps))
        .Add("rejected_steps", static_cast<std::int64_t>(s.rejected_steps))
        .Add("rhs_evals", static_cast<std::int64_t>(s.rhs_evals))
        .Add("jacobian_evals", static_cast<std::int64_t>(s.jacobian_evals))
        .Add("error_estimate", s.error_estimate)
        .Add("wall_time_s", s.wall_time_s)
        .Add("warnings", s.warnings)
        .Add("solver_reason", s.solver_reason)
        .Add("error_estimator", s.error_estimator)
        .Add("error_estimate_local", s.error_estimate_local)
        .Add("impact_velocity_m_s", p.impact_velocity_m_s)
        .Add("rtol", o.EffectiveRtol())
        .Add("atol", o.EffectiveAtol())
        .Add("stopped", s.stopped)
        .Add("stop_reason", s.stop_reason)
        .Add("t_reached_s", s.t_reached_s);
    std::cout << j.Dump() << "\n";
  } else {
    std::cout << fmt::format("impact model: m_p {} kg, v0 {:.6g} m/s, D {} m, t_z {} m\n",
                             p.pounder_mass_kg, p.impact_velocity_m_s, p.width_m, p.depth_m);
    std::cout << s.FullReport();
  }
  std::cout.flush();
  if (!s.IsUsable()) {
    throw Error(
        ErrorKind::kNumerical,
        fmt::format("model: the solve did not reach the end of motion (v = 0): {}{}", s.stop_reason,
                    a.output.empty() ? "" : "; the series " + a.output + " was not written"));
  }
}

void RunWorkPrecisionCommand(const ModelArgs& a) {
  ValidatedParameters(a, /*single_run=*/false);
  WorkPrecisionOptions w;
  w.solvers = SplitList(a.wp_solvers);
  for (const std::string& s : w.solvers)
    if (s != "dopri5" && s != "stiff" && s != "auto" && s != "ode45")
      throw Error(ErrorKind::kInvalidValue, "--wp-solvers", s,
                  "a comma-separated list of dopri5, stiff, auto, ode45");
  w.exact_cases = w.default_case = w.table1 = false;
  for (const std::string& c : SplitList(a.wp_cases)) {
    if (c == "exact")
      w.exact_cases = true;
    else if (c == "default")
      w.default_case = true;
    else if (c == "table1")
      w.table1 = true;
    else
      throw Error(ErrorKind::kInvalidValue, "--wp-cases", c,
                  "a comma-separated list of exact, default, table1");
  }
  const std::string plot_case = w.default_case  ? "default"
                                : w.exact_cases ? "harmonic-exact"
                                                : "table1-max";
  if (!w.exact_cases && !w.default_case && !w.table1)
    throw Error(ErrorKind::kInvalidValue, "--wp-cases", a.wp_cases, "at least one case");
  if (!a.output.empty())
    CheckOutputLocation(a.output, {"-o", {".csv"}, {}, {CsvHeaderLine(WorkPrecisionCsvColumns())}});
  if (!a.plot.empty()) CheckOutputLocation(a.plot, {"--plot", {".png"}, {}});
  const std::vector<WorkPrecisionRow> rows = RunWorkPrecision(w);
  std::cout << FormatWorkPrecision(rows);
  if (!a.output.empty()) {
    WriteWorkPrecisionCsv(a.output, rows);
    LogInfo("model: wrote the work-precision table to {}", a.output);
  }
  if (!a.plot.empty()) {
    PlotWorkPrecision(a.plot, rows, plot_case);
    LogInfo("model: wrote the work-precision figure ({}) to {}", plot_case, a.plot);
  }
}

void RunTable1Command(const ModelArgs& a) {
  const ImpactModelParameters base = ValidatedParameters(a, /*single_run=*/false);
  const ImpactSolverOptions o = ValidatedSolverOptions(a);
  if (!a.output.empty())
    CheckOutputLocation(a.output, {"-o", {".csv"}, {}, {CsvHeaderLine(Table1CsvColumns())}});
  const std::vector<Table1Row> rows = RunTable1(o, base);
  std::cout << FormatTable1(rows);
  for (const Table1Row& r : rows)
    for (const std::string& w : r.summary.warnings)
      LogWarning("model: m_p {} kg, h {} m, D {} m: {}", r.combination.pounder_mass_kg,
                 r.combination.height_m, r.combination.width_m, w);
  if (!a.output.empty()) {
    WriteTable1Csv(a.output, rows);
    LogInfo("model: wrote the Table 1 results to {}", a.output);
  }
}

}  // namespace

void RegisterModelCommand(CLI::App& app) {
  auto args = std::make_shared<ModelArgs>();
  auto* cmd = app.add_subcommand(
      "model",
      "Simulate the added-mass impact model (Eq. 9): one test, the solvers' work-precision study "
      "(--work-precision) or the paper's 27 combinations (--table1)");
  cmd->add_option("--mass", args->mass, "pounder mass m_p, in " + kPounderMassRange.Text());
  cmd->add_option("--height", args->height,
                  "drop height h, > 0 and in " + kDropHeightRange.Text() + " (v0 = sqrt(2 g h))");
  cmd->add_option("--velocity", args->velocity,
                  "impact velocity v0, in " + kImpactVelocityRange.Text());
  cmd->add_option("--width", args->width, "pounder width D, in " + kPounderSizeRange.Text());
  cmd->add_option("--depth", args->depth, "out-of-plane depth t_z, in " + kPounderSizeRange.Text())
      ->capture_default_str();
  cmd->add_option("--added-mass", args->added_mass,
                  "maximum added mass M, in " + kAddedMassRange.Text() + " (default: Eq. 4)");
  cmd->add_option("--K", args->K, "friction coefficient K, in " + kFrictionKRange.Text())
      ->capture_default_str();
  cmd->add_option("--n", args->n, "damping exponent n, in " + kDampingExponentNRange.Text())
      ->capture_default_str();
  cmd->add_option("--u", args->u, "damping factor u, in " + kDampingFactorURange.Text())
      ->capture_default_str();
  cmd->add_option("--T", args->T, "sigmoid delay T, in " + kSigmoidDelayRange.Text())
      ->capture_default_str();
  cmd->add_option("--b", args->b, "sigmoid rate b, in " + kSigmoidRateRange.Text())
      ->capture_default_str();
  cmd->add_option("--rho", args->rho, "dry density rho_d, in " + kSoilDensityRange.Text())
      ->capture_default_str();
  cmd->add_option("--g", args->g, "gravity g, in " + kGravityRange.Text())->capture_default_str();
  cmd->add_option("--bed-height", args->bed_height,
                  "sand bed height for the penetration warning, in " + kBedHeightRange.Text())
      ->capture_default_str();
  cmd->add_option("--solver", args->solver, Join(kImpactSolverNames.Names(), " | "))
      ->capture_default_str();
  cmd->add_option("--rtol", args->rtol, "relative tolerance, [1e-14, 0.1] (default 1e-6)");
  cmd->add_option("--atol", args->atol, "absolute tolerance, > 0 (default 1e-3 * rtol)");
  cmd->add_flag(
      "--ode45-defaults", args->ode45_defaults,
      "MATLAB ode45's rules and defaults (RelTol 1e-3, AbsTol 1e-6), the paper's setting");
  cmd->add_option("--error-estimate", args->error_estimate,
                  "companion (a run at rtol/10; default) | local (summed local estimates)");
  cmd->add_option("--t-max", args->t_max,
                  "give up if v has not reached 0 by then [s] (default 10)");
  cmd->add_option("--format", args->format, "text | json (default text)");
  cmd->add_option("-o,--output", args->output,
                  "single run: time series SERIES.csv | SERIES.h5; --work-precision / --table1: "
                  "TABLE.csv");
  cmd->add_flag("--work-precision", args->work_precision,
                "error vs cost of every solver at rtol 1e-3 .. 1e-12 on the exact cases, the "
                "default case and the 27 combinations");
  cmd->add_option("--plot", args->plot, "with --work-precision: FIGURE.png (gnuplot)");
  cmd->add_option("--wp-solvers", args->wp_solvers,
                  "with --work-precision: solvers (default dopri5,stiff,auto,ode45)");
  cmd->add_option("--wp-cases", args->wp_cases,
                  "with --work-precision: cases (default exact,default,table1)");
  cmd->add_flag(
      "--table1", args->table1,
      "the paper's 27 combinations (m_p 7/10/13 kg, h 0.2/0.7/1.2 m, D 0.10/0.15/0.20 m)");
  cmd->callback([args] {
    const ModelArgs& a = *args;
    if (a.format != "text" && a.format != "json")
      throw Error(ErrorKind::kInvalidValue, "--format", a.format, "text or json");
    if (!a.plot.empty() && !a.work_precision)
      throw Error(ErrorKind::kInvalidValue, "--plot", a.plot,
                  "only together with --work-precision");
    if (a.work_precision) {
      RunWorkPrecisionCommand(a);
    } else if (a.table1) {
      RunTable1Command(a);
    } else {
      RunSingle(a);
    }
  });
}

}  // namespace impactdic::cli
