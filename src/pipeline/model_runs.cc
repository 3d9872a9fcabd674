#include "impactdic/pipeline/model_runs.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/core/range.h"
#include "impactdic/core/strings.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/csv.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/pipeline/scene_flags.h"
#include "impactdic/render/work_precision_figure.h"

namespace impactdic {

void RunModelTest(const ImpactModelParameters& p, const ImpactSolverOptions& o,
                  const std::string& output, bool json, std::ostream& out) {
  if (!output.empty()) {
    CheckOutputLocation(
        output, {"-o", {".csv", ".h5", ".hdf5"}, {}, {CsvHeaderLine(ImpactSeriesColumns())}});
  }
  const ImpactRun run = SimulateImpact(p, o);
  const ImpactSummary& s = run.summary;
  for (const std::string& w : s.warnings) LogWarning("model: {}", w);
  // A solve that did not reach the end of motion writes no series (nothing that looks complete)
  // but still prints its summary, then fails (below).
  if (!output.empty() && s.IsUsable()) {
    WriteImpactSeries(output, p, run);
    LogInfo("model: wrote the time series to {}", output);
  }
  if (json) {
    out << s.ToJson(p, o).Dump() << "\n";
  } else {
    out << fmt::format("impact model: m_p {} kg, v0 {:.6g} m/s, D {} m, t_z {} m\n",
                       p.pounder_mass_kg, p.impact_velocity_m_s, p.width_m, p.depth_m);
    out << s.FullReport();
  }
  out.flush();
  if (!s.IsUsable()) {
    throw Error(
        ErrorKind::kNumerical,
        fmt::format("model: the solve did not reach the end of motion (v = 0): {}{}", s.stop_reason,
                    output.empty() ? "" : "; the series " + output + " was not written"));
  }
}

void RunModelTable1(const ImpactModelParameters& base, const ImpactSolverOptions& o,
                    const std::string& output, std::ostream& out) {
  if (!output.empty())
    CheckOutputLocation(output, {"-o", {".csv"}, {}, {CsvHeaderLine(Table1CsvColumns())}});
  const std::vector<Table1Row> rows = RunTable1(o, base);
  out << FormatTable1(rows);
  for (const Table1Row& r : rows)
    for (const std::string& w : r.summary.warnings)
      LogWarning("model: m_p {} kg, h {} m, D {} m: {}", r.combination.pounder_mass_kg,
                 r.combination.height_m, r.combination.width_m, w);
  if (!output.empty()) {
    WriteTable1Csv(output, rows);
    LogInfo("model: wrote the Table 1 results to {}", output);
  }
}

void RunModelWorkPrecision(const WorkPrecisionOptions& w, const std::string& plot_case,
                           const std::string& output, const std::string& plot, std::ostream& out) {
  if (!output.empty())
    CheckOutputLocation(output, {"-o", {".csv"}, {}, {CsvHeaderLine(WorkPrecisionCsvColumns())}});
  if (!plot.empty()) CheckOutputLocation(plot, {"--plot", {".png"}, {}});
  const std::vector<WorkPrecisionRow> rows = RunWorkPrecision(w);
  out << FormatWorkPrecision(rows);
  if (!output.empty()) {
    WriteWorkPrecisionCsv(output, rows);
    LogInfo("model: wrote the work-precision table to {}", output);
  }
  if (!plot.empty()) {
    PlotWorkPrecision(plot, rows, plot_case);
    LogInfo("model: wrote the work-precision figure ({}) to {}", plot_case, plot);
  }
}

namespace {

std::string Num(double v) { return fmt::format("{}", v); }

// The name errors give `key` (the flag typed for it), else the key.
std::string NameOf(const ModelRequest& r, const std::string& key) {
  const auto it = r.key_names.find(key);
  return it == r.key_names.end() ? key : it->second;
}

std::optional<double> Given(const ModelRequest& r, const std::string& key) {
  const auto it = r.keys.find(key);
  return it == r.keys.end() ? std::nullopt : it->second;
}

// Runs `f`; an Error it throws whose `where` is a name of `names` is thrown again under its new
// name.
template <typename F>
void Naming(const std::vector<std::pair<std::string, std::string>>& names, F&& f) {
  try {
    f();
  } catch (const Error& e) {
    for (const auto& [field, name] : names)
      if (e.where() == field) throw Error(e.kind(), name, e.found(), e.expected());
    throw;
  }
}

std::vector<std::string> SplitList(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}

constexpr const char* kHeight = "test.drop_height_m";
constexpr const char* kVelocity = "test.impact_velocity_m_s";
constexpr const char* kGravity = "test.g_m_s2";
constexpr const char* kTMax = "model.t_max_s";

// Which inputs the run takes: a single run needs the test's mass, width and exactly one of the
// drop height and impact velocity; --table1 and --work-precision take none of them.
void CheckRunInputs(const ModelRequest& r) {
  if (r.work_precision && r.table1)
    throw Error(ErrorKind::kInvalidValue, "--work-precision", "together with --table1",
                "one of --work-precision, --table1 or a single run");
  if (r.work_precision || r.table1) {
    for (const char* key :
         {"test.mass_kg", kHeight, kVelocity, "test.width_m", "model.added_mass_kg"})
      if (Given(r, key))
        throw Error(ErrorKind::kInvalidValue, NameOf(r, key),
                    r.table1 ? "with --table1" : "with --work-precision",
                    "no per-test option: these runs use the paper's 27 combinations / fixed cases");
    return;
  }
  if (!Given(r, "test.mass_kg"))
    throw Error(ErrorKind::kInvalidValue, NameOf(r, "test.mass_kg"), "missing",
                "the pounder mass in kg (> 0) for a single run");
  if (!Given(r, "test.width_m"))
    throw Error(ErrorKind::kInvalidValue, NameOf(r, "test.width_m"), "missing",
                "the pounder width D in m (> 0) for a single run");
  const bool height = Given(r, kHeight).has_value(), velocity = Given(r, kVelocity).has_value();
  if (height == velocity)
    throw Error(ErrorKind::kInvalidValue, NameOf(r, kHeight) + "/" + NameOf(r, kVelocity),
                height ? "both given" : "neither given",
                fmt::format("exactly one of {} (drop height, m) or {} (impact velocity, m/s)",
                            NameOf(r, kHeight), NameOf(r, kVelocity)));
}

}  // namespace

ImpactModelParameters ModelRequestParameters(const ModelRequest& r) {
  CheckRunInputs(r);
  // Each value is read as its scene key (the key's one parser and range); g may be 0 here (the
  // exact solutions), not in a scene, and the tolerances and t_max are the solver options'
  // (ModelRequestSolverOptions).
  Scene scene;
  for (const auto& [key, value] : r.keys)
    if (value && key != kGravity && key != "model.rtol" && key != "model.atol" && key != kTMax)
      SetSceneKey(&scene, key, Num(*value), NameOf(r, key));
  const auto height = Given(r, kHeight), velocity = Given(r, kVelocity);
  const double g = Given(r, kGravity).value_or(ImpactModelParameters{}.gravity_m_s2);
  if (height)
    CheckValue(std::isfinite(*height) && *height > 0, NameOf(r, kHeight), Num(*height),
               "a drop height > 0 m");
  CheckRange(g, kGravityRange, NameOf(r, kGravity), "a gravitational acceleration");
  CheckValue(!height || g > 0, NameOf(r, kGravity), Num(g),
             fmt::format("g > 0 when the impact velocity comes from {} (v0 = sqrt(2 g h))",
                         NameOf(r, kHeight)));
  ImpactModelParameters p = scene.model;
  p.gravity_m_s2 = g;
  if (velocity) p.impact_velocity_m_s = *velocity;
  if (height) p.impact_velocity_m_s = ImpactVelocityFromHeight(*height, g);
  // The library's check (the keys' ranges are its fields': only v0 from a height can fail here).
  try {
    p.Check();
  } catch (const Error& e) {
    if (e.where() != "impact_velocity_m_s") throw;
    if (!height) throw Error(e.kind(), NameOf(r, kVelocity), e.found(), e.expected());
    throw Error(e.kind(),
                fmt::format("{} (v0 = sqrt(2 g h) = {} m/s)", NameOf(r, kHeight), e.found()),
                Num(*height), e.expected());
  }
  return p;
}

ImpactSolverOptions ModelRequestSolverOptions(const ModelRequest& r) {
  ImpactSolverOptions o;
  const std::string rtol = NameOf(r, "model.rtol"), atol = NameOf(r, "model.atol"),
                    t_max = NameOf(r, "model.t_max_s");
  Naming({{"solver", NameOf(r, "model.solver")},
          {"error_estimator", NameOf(r, "model.error_estimator")}},
         [&] {
           o.solver = ImpactSolverFromString(r.solver);
           o.error_estimator = ErrorEstimatorFromString(r.error_estimator);
         });
  o.ode45_defaults = r.ode45_defaults;
  // A given tolerance or time must be a number: NaN means "unset" to the library.
  for (const auto& [key, name] :
       {std::pair{"model.rtol", rtol}, std::pair{"model.atol", atol}, std::pair{kTMax, t_max}})
    if (const auto value = Given(r, key))
      CheckValue(!std::isnan(*value), name, Num(*value), "a number");
  o.rtol = Given(r, "model.rtol").value_or(o.rtol);
  o.atol = Given(r, "model.atol").value_or(o.atol);
  o.t_max_s = Given(r, kTMax).value_or(o.t_max_s);
  // The library's check (the allowed ranges are defined there).
  Naming({{"rtol", rtol},
          {"atol", atol},
          {"t_max_s", t_max},
          {"ode45_defaults", NameOf(r, "model.ode45_defaults")}},
         [&] { o.Check(); });
  return o;
}

WorkPrecisionOptions ModelRequestStudy(const ModelRequest& r) {
  WorkPrecisionOptions w;
  const std::vector<std::string> known = w.solvers;
  w.solvers = SplitList(r.wp_solvers);
  for (const std::string& s : w.solvers)
    CheckValue(std::find(known.begin(), known.end(), s) != known.end(), "--wp-solvers", s,
               "a comma-separated list of " + Join(known));
  w.exact_cases = w.default_case = w.table1 = false;
  for (const std::string& c : SplitList(r.wp_cases)) {
    bool* flag = c == "exact"     ? &w.exact_cases
                 : c == "default" ? &w.default_case
                 : c == "table1"  ? &w.table1
                                  : nullptr;
    CheckValue(flag != nullptr, "--wp-cases", c,
               "a comma-separated list of exact, default, table1");
    *flag = true;
  }
  CheckValue(w.exact_cases || w.default_case || w.table1, "--wp-cases", r.wp_cases,
             "at least one case");
  if (!r.wp_tolerances.empty()) w.tolerances.clear();
  for (const std::string& t : SplitList(r.wp_tolerances)) {
    const std::optional<double> rtol = ParseNumber(t);
    CheckValue(rtol.has_value(), "--wp-tolerances", t, "a comma-separated list of numbers");
    w.tolerances.push_back(*rtol);
  }
  w.timing_budget_s = r.wp_timing_budget_s;
  Naming({{"work_precision.tolerances", "--wp-tolerances"},
          {"work_precision.timing_budget_s", "--wp-timing-budget"}},
         [&] { w.Check(); });
  return w;
}

void RunModelRequest(const ModelRequest& r, std::ostream& out) {
  CheckValue(r.format == "text" || r.format == "json", "--format", r.format, "text or json");
  CheckValue(r.plot.empty() || r.work_precision, "--plot", r.plot,
             "only together with --work-precision");
  const ImpactModelParameters p = ModelRequestParameters(r);
  if (r.work_precision) {
    const WorkPrecisionOptions w = ModelRequestStudy(r);
    const std::string plot_case = w.default_case  ? "default"
                                  : w.exact_cases ? "harmonic-exact"
                                                  : "table1-max";
    RunModelWorkPrecision(w, plot_case, r.output, r.plot, out);
  } else if (r.table1) {
    RunModelTable1(p, ModelRequestSolverOptions(r), r.output, out);
  } else {
    RunModelTest(p, ModelRequestSolverOptions(r), r.output, r.format == "json", out);
  }
}

}  // namespace impactdic
