// The paper's figures from plain data (no dependency on the stages that compute it). Time is
// given in seconds (as the stages store it) and drawn in ms since impact. Each function builds a
// Plot (exposed as Make*Plot for tests and customisation) and renders it with RenderPlot.
//
//   MomentumFigureData m{.t_s = t, .p_pounder_Ns = pp, .p_gran_Ns = pg, .p_total_Ns = pt,
//                        .p_max_Ns = p_max, .t_e_s = t_e};
//   PlotMomentum(m, "out/momentum.png");
//
// Reference: Löwe, Thiele, Kanty, Kirstein, "Experimental investigation and modeling of impact
// stages during dynamic compaction" (Figs. 4 and 6; Eqs. 3 and 5).
#ifndef IMPACTDIC_RENDER_FIGURES_H_
#define IMPACTDIC_RENDER_FIGURES_H_

#include <string>
#include <vector>

#include "impactdic/core/numeric.h"
#include "impactdic/render/gnuplot.h"

namespace impactdic {

// "No value" for the optional scalars below.
inline constexpr double kFigureUnset = kNaN;

// Fig. 4: pounder, granular and total momentum [N s] over time, p_max line and t_e marker.
// Any of the three series may be empty (not drawn); each non-empty one has t_s.size() values.
struct MomentumFigureData {
  std::vector<double> t_s;           // time since impact [s]
  std::vector<double> p_pounder_Ns;  // m_p v_p [N s]
  std::vector<double> p_gran_Ns;     // granular momentum [N s]
  std::vector<double> p_total_Ns;    // p_pounder + p_gran [N s]
  // Standard uncertainties of p_gran and p_total [N s], drawn as +-1 u bands; empty = none.
  std::vector<double> p_gran_u_Ns, p_total_u_Ns;
  double p_max_Ns = kFigureUnset;  // maximum pounder momentum (horizontal line); NaN = none
  double t_e_s = kFigureUnset;     // end of the peak stage (vertical marker); NaN = none
};
Plot MakeMomentumPlot(const MomentumFigureData& data);
PlotSummary PlotMomentum(const MomentumFigureData& data, const std::string& png_path,
                         const PlotOptions& options = {});

// Fig. 6: measured (accelerometer) and modelled (Eq. 9) pounder deceleration in g over time.
// Either pair may be empty; deceleration is positive when the pounder slows down.
struct DecelerationFigureData {
  std::vector<double> measured_t_s;
  std::vector<double> measured_decel_g;
  std::vector<double> model_t_s;
  std::vector<double> model_decel_g;
  double t_e_s = kFigureUnset;  // optional marker for the end of the peak stage
};
Plot MakeDecelerationPlot(const DecelerationFigureData& data);
PlotSummary PlotDeceleration(const DecelerationFigureData& data, const std::string& png_path,
                             const PlotOptions& options = {});

// m_add(t) = p_max / v_p(t) - m_p (Eq. 3) measured, with its sigmoid fit
// m_add(t) = M / (1 + exp(-b (t - T))) (Eq. 5) drawn when M, b and T are finite.
struct AddedMassFigureData {
  std::vector<double> t_s;
  std::vector<double> m_add_kg;
  std::vector<double> m_add_u_kg;  // Standard uncertainty, drawn as a +-1 u band; empty = none.
  double sigmoid_M_kg = kFigureUnset;
  double sigmoid_b_per_s = kFigureUnset;
  double sigmoid_T_s = kFigureUnset;
  double t_e_s = kFigureUnset;  // optional marker
};
Plot MakeAddedMassPlot(const AddedMassFigureData& data);
PlotSummary PlotAddedMass(const AddedMassFigureData& data, const std::string& png_path,
                          const PlotOptions& options = {});

// Generic x-y figure (e.g. the model's work-precision plot, log-log): RenderPlot with a Plot you
// fill yourself. This helper builds one from parallel lists of series.
struct XySeries {
  std::vector<double> x, y;
  std::string label;
  SeriesStyle style = SeriesStyle::kLinesPoints;
};
struct XyFigureData {
  std::string title, x_label, y_label;
  std::vector<XySeries> series;
  bool log_x = false;
  bool log_y = false;
  LegendPosition legend = LegendPosition::kTopRight;
};
Plot MakeXyPlot(const XyFigureData& data);
PlotSummary PlotXy(const XyFigureData& data, const std::string& png_path,
                   const PlotOptions& options = {});

}  // namespace impactdic

#endif  // IMPACTDIC_RENDER_FIGURES_H_
