#include "impactdic/render/work_precision_figure.h"

#include <algorithm>
#include <string>
#include <vector>

#include "impactdic/core/error.h"

namespace impactdic {

Plot WorkPrecisionPlot(const std::vector<WorkPrecisionRow>& rows, const std::string& case_name) {
  Plot plot;
  plot.title = "impact model work-precision (" + case_name + ", rtol 1e-3..1e-12)";
  plot.x_label = "wall time per run [s]";
  plot.y_label = "relative error of the crater depth [-]";
  plot.log_x = plot.log_y = true;
  plot.legend = LegendPosition::kOutsideRight;
  for (const WorkPrecisionRow& r : rows) {
    if (r.case_name != case_name) continue;
    auto it = std::find_if(plot.series.begin(), plot.series.end(),
                           [&](const PlotSeries& s) { return s.label == r.solver; });
    if (it == plot.series.end()) {
      plot.series.push_back({.label = r.solver, .style = SeriesStyle::kLinesPoints});
      it = plot.series.end() - 1;
    }
    it->x.push_back(r.wall_time_s);
    it->y.push_back(std::max(r.depth_error, 1e-17));
  }
  if (plot.series.empty())
    throw Error(ErrorKind::kInvalidValue, "case_name", case_name, "a case present in the study");
  return plot;
}

PlotSummary PlotWorkPrecision(const std::string& png_path,
                              const std::vector<WorkPrecisionRow>& rows,
                              const std::string& case_name) {
  PlotOptions options;
  options.width_px = 900;
  options.height_px = 650;
  options.font_size_pt = 11;
  return RenderPlot(WorkPrecisionPlot(rows, case_name), png_path, options);
}

}  // namespace impactdic
