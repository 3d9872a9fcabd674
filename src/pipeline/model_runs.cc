#include "impactdic/pipeline/model_runs.h"

#include <fmt/format.h>

#include <string>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/csv.h"
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

}  // namespace impactdic
