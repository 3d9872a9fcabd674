// impactdic model: the added-mass impact model (Eq. 9, docs/model.md) for one test, the
// work-precision study of its solvers, or the paper's 27 combinations (Table 1).
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "commands.h"
#include "impactdic/core/enum_names.h"
#include "impactdic/core/error.h"
#include "impactdic/core/range.h"
#include "impactdic/core/strings.h"
#include "impactdic/model/impact_model.h"
#include "impactdic/model/work_precision.h"
#include "impactdic/pipeline/model_runs.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/pipeline/scene_flags.h"

namespace impactdic::cli {
namespace {

// The numbers of test.* and model.* are bound by their scene keys (their flags' names, help and
// defaults: the option table, pipeline/scene_flags.h); unset: the library's default.
struct ModelArgs {
  std::map<std::string, std::optional<double>> values;  // By key ("model.K").
  std::optional<double> t_max;
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
  std::optional<double> Get(const std::string& key) const { return values.at(key); }
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
    const auto height = a.Get("test.drop_height_m");
    if (e.where() == "impact_velocity_m_s")
      option =
          height ? fmt::format("--height (v0 = sqrt(2 g h) = {} m/s)", e.found()) : "--velocity";
    throw Error(e.kind(), option,
                height && e.where() == "impact_velocity_m_s" ? Num(*height) : e.found(),
                e.expected());
  }
}

// Validates everything before any work; returns the parameters (mass etc. only for a single run).
ImpactModelParameters ValidatedParameters(const ModelArgs& a, bool single_run) {
  const auto mass = a.Get("test.mass_kg"), width = a.Get("test.width_m");
  const auto height = a.Get("test.drop_height_m"), velocity = a.Get("test.impact_velocity_m_s");
  const double g = a.Get("test.g_m_s2").value_or(ImpactModelParameters{}.gravity_m_s2);
  if (a.work_precision && a.table1)
    throw Error(ErrorKind::kInvalidValue, "--work-precision", "together with --table1",
                "one of --work-precision, --table1 or a single run");
  if (single_run) {
    if (!mass)
      throw Error(ErrorKind::kInvalidValue, "--mass", "missing",
                  "the pounder mass in kg (> 0) for a single run");
    if (!width)
      throw Error(ErrorKind::kInvalidValue, "--width", "missing",
                  "the pounder width D in m (> 0) for a single run");
    if (height && velocity)
      throw Error(ErrorKind::kInvalidValue, "--height/--velocity", "both given",
                  "exactly one of --height (drop height, m) or --velocity (impact velocity, m/s)");
    if (!height && !velocity)
      throw Error(ErrorKind::kInvalidValue, "--height/--velocity", "neither given",
                  "exactly one of --height (drop height, m) or --velocity (impact velocity, m/s)");
  } else {
    for (const char* key : {"test.mass_kg", "test.drop_height_m", "test.impact_velocity_m_s",
                            "test.width_m", "model.added_mass_kg"})
      if (a.Get(key))
        throw Error(ErrorKind::kInvalidValue, SceneFlagShortName("model", key),
                    a.table1 ? "with --table1" : "with --work-precision",
                    "no per-test option: these runs use the paper's 27 combinations / fixed cases");
  }
  // Each value is read as its scene key (the key's one parser and range; it stores the value in
  // `scene`), naming the short flag; g may be 0 here (the exact solutions), not in a scene, and the
  // tolerances are the solver options' (ValidatedSolverOptions).
  Scene scene;
  for (const auto& [key, value] : a.values) {
    if (value && key != "test.g_m_s2" && key != "model.rtol" && key != "model.atol")
      SetSceneKey(&scene, key, Num(*value), SceneFlagShortName("model", key));
  }
  RequirePositive(height, "--height", "a drop height > 0 m");
  CheckRange(g, kGravityRange, "--g", "a gravitational acceleration");
  if (height && g <= 0)
    throw Error(ErrorKind::kInvalidValue, "--g", Num(g),
                "g > 0 when the impact velocity comes from --height (v0 = sqrt(2 g h))");
  ImpactModelParameters p = scene.model;
  p.gravity_m_s2 = g;
  if (velocity) p.impact_velocity_m_s = *velocity;
  if (height) p.impact_velocity_m_s = ImpactVelocityFromHeight(*height, g);
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
       {std::pair{a.Get("model.rtol"), "--rtol"}, std::pair{a.Get("model.atol"), "--atol"},
        std::pair{a.t_max, "--t-max"}}) {
    if (value) CheckValue(!std::isnan(*value), flag, Num(*value), "a number");
  }
  o.rtol = a.Get("model.rtol").value_or(o.rtol);
  o.atol = a.Get("model.atol").value_or(o.atol);
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
  RunModelTest(p, ValidatedSolverOptions(a), a.output, a.format == "json", std::cout);
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
  RunModelWorkPrecision(w, plot_case, a.output, a.plot, std::cout);
}

void RunTable1Command(const ModelArgs& a) {
  const ImpactModelParameters base = ValidatedParameters(a, /*single_run=*/false);
  RunModelTable1(base, ValidatedSolverOptions(a), a.output, std::cout);
}

}  // namespace

void RegisterModelCommand(CLI::App& app) {
  auto args = std::make_shared<ModelArgs>();
  auto* cmd = app.add_subcommand(
      "model",
      "Simulate the added-mass impact model (Eq. 9): one test, the solvers' work-precision study "
      "(--work-precision) or the paper's 27 combinations (--table1)");
  // The required inputs of a single run show no default; g may be 0 (the exact solutions).
  const std::set<std::string> no_default = {"test.mass_kg", "test.drop_height_m",
                                            "test.impact_velocity_m_s", "test.width_m"};
  for (const SceneKeyFlag& f : SceneKeyFlags({"test", "model"})) {
    if (f.key == "model.solver") continue;
    AddSceneKeyOption(cmd, f.key, &args->values[f.key], f.help,
                      no_default.count(f.key) ? "" : f.default_text);
  }
  AddSceneKeyOption(cmd, "model.solver", &args->solver, Join(kImpactSolverNames.Names(), " | "),
                    args->solver);
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
    CheckFormat(a.format);
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
