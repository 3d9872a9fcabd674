// The campaign's comparison figures (the paper's Figs. 5, 7, 8, 9 and 10): for each test, a value
// predicted by the model (x) against the value measured (y), with the 1:1 line, the least-squares
// line y = slope x + intercept with its R^2 in the key, and markers by pounder width D.
//
//   ComparisonFigureData f{.title = "Added mass (Fig. 5)", .x_label = "m_add,max by Eq. 4 [kg]",
//                          .y_label = "m_add,max measured [kg]", .points = points};
//   ComparisonFit fit = FitComparison(f.points);   // also drawn by PlotComparison
//   PlotComparison(f, "out/fig5_added_mass.png");
//
// Reference: Löwe, Thiele, Kanty, Kirstein, "Experimental investigation and modeling of impact
// stages during dynamic compaction" (Figs. 5, 7-10).
#ifndef IMPACTDIC_RENDER_COMPARISON_FIGURES_H_
#define IMPACTDIC_RENDER_COMPARISON_FIGURES_H_

#include <string>
#include <vector>

#include "impactdic/core/numeric.h"
#include "impactdic/render/gnuplot.h"

namespace impactdic {

// One test. A point with a non-finite predicted or observed value is not drawn and not fitted
// (ComparisonFit::skipped counts it).
struct ComparisonPoint {
  double predicted = kNaN;  // x: model / Eq. 4
  double observed = kNaN;   // y: measured
  double width_m = kNaN;    // D: selects the marker
  std::string label;        // test name (not drawn)
};

struct ComparisonFigureData {
  std::string title, x_label, y_label;
  std::vector<ComparisonPoint> points;
  // A model against a measurement: equal axes and the 1:1 line. False for a relation between two
  // different quantities (the wave's attenuation against the momentum ratio): each axis its own
  // range, no 1:1 line; the least-squares line and R^2 as for a comparison.
  bool identity_line = true;
};

// Least-squares line through the finite points, observed = slope * predicted + intercept, its
// R^2, and how far the points lie from the 1:1 line: RMS and largest |observed/predicted - 1|.
// Fewer than 2 finite points: slope, intercept and r_squared are NaN.
struct ComparisonFit {
  int n = 0;        // points fitted
  int skipped = 0;  // points with a non-finite value
  double slope = kNaN;
  double intercept = kNaN;
  double r_squared = kNaN;
  double rms_relative_deviation = kNaN;
  double max_relative_deviation = kNaN;
};
ComparisonFit FitComparison(const std::vector<ComparisonPoint>& points);

Plot MakeComparisonPlot(const ComparisonFigureData& data);
// Renders the figure (same engine and look as the per-scene figures). Error if no point is finite.
PlotSummary PlotComparison(const ComparisonFigureData& data, const std::string& png_path,
                           const PlotOptions& options = {});

}  // namespace impactdic

#endif  // IMPACTDIC_RENDER_COMPARISON_FIGURES_H_
