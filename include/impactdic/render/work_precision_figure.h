// The model's work-precision figure: error versus wall time per solver, drawn by the project's
// gnuplot driver (render/gnuplot.h).
//
//   const std::vector<WorkPrecisionRow> rows = RunWorkPrecision(options);
//   PlotWorkPrecision("out/work_precision.png", rows, /*case_name=*/"default");
#ifndef IMPACTDIC_RENDER_WORK_PRECISION_FIGURE_H_
#define IMPACTDIC_RENDER_WORK_PRECISION_FIGURE_H_

#include <string>
#include <vector>

#include "impactdic/model/work_precision.h"
#include "impactdic/render/gnuplot.h"

namespace impactdic {

// The plot of `case_name`'s rows: one line per solver, x = wall time per run [s], y = relative
// error of the crater depth (errors below 1e-17 drawn at 1e-17), logarithmic axes. Error
// kInvalidValue naming `case_name` when no row has that case.
Plot WorkPrecisionPlot(const std::vector<WorkPrecisionRow>& rows, const std::string& case_name);

// RenderPlot(WorkPrecisionPlot(rows, case_name), png_path) at 900 x 650 px; written atomically.
PlotSummary PlotWorkPrecision(const std::string& png_path,
                              const std::vector<WorkPrecisionRow>& rows,
                              const std::string& case_name = "default");

}  // namespace impactdic

#endif  // IMPACTDIC_RENDER_WORK_PRECISION_FIGURE_H_
