// The momentum validation's results (the /momentum group of results.h5 and of `impactdic analyze
// --output`): the names, one writer, one reader. Other modules read /momentum through these names
// (namespace results_layout, like every group's; io/results_layout.h lists the owners).
//
//   H5Writer out("run/results.h5");
//   WriteMomentumResults(out, momentum, sensor.summary.impact_time_s);
//   out.Commit();
//   const MomentumResultsGroup m = ReadMomentumResults(H5Reader("run/results.h5"), "...");
#ifndef IMPACTDIC_MOMENTUM_MOMENTUM_RESULTS_H_
#define IMPACTDIC_MOMENTUM_MOMENTUM_RESULTS_H_

#include <string>
#include <vector>

#include "impactdic/io/hdf5_store.h"
#include "impactdic/momentum/momentum.h"

namespace impactdic {
namespace results_layout {

// Momentum series (Fig. 4), [K] each, K = analysed frames: time since impact [s] and on the DAQ
// clock [s]; pounder velocity, mean soil velocity over the grid [m/s] and acceleration [m/s^2]
// (down +); momentum [N s]; valid grid subsets per frame.
inline constexpr const char* kMomentumGroup = "/momentum";
inline constexpr const char* kMomentumT = "/momentum/t_s";
inline constexpr const char* kMomentumTimeDaq = "/momentum/time_daq_s";
inline constexpr const char* kVPounder = "/momentum/v_pounder_m_s";
inline constexpr const char* kVSand = "/momentum/v_sand_m_s";
inline constexpr const char* kASand = "/momentum/a_sand_m_s2";
inline constexpr const char* kPPounder = "/momentum/p_pounder";
inline constexpr const char* kPGran = "/momentum/p_gran";
inline constexpr const char* kPTotal = "/momentum/p_total";
inline constexpr const char* kValidSubsets = "/momentum/valid_subsets";
// Added mass (Eq. 3) [kg] on the kMomentumT time base.
inline constexpr const char* kMAdd = "/momentum/m_add_kg";
// The same at the DAQ rate between the impact and t_e (what the sigmoid is fitted to), [K'] each:
// time since impact [s], added mass [kg]. Only when t_e was measured.
inline constexpr const char* kAddedMassDaqGroup = "/momentum/added_mass_daq";
inline constexpr const char* kAddedMassDaqT = "/momentum/added_mass_daq/t_s";
inline constexpr const char* kAddedMassDaq = "/momentum/added_mass_daq/m_add_kg";
// Standard uncertainties of v_sand [m/s], p_gran and p_total [N s] and m_add [kg] per frame [K]
// (the momentum Monte Carlo, momentum/uncertainty.h); only when it was estimated.
inline constexpr const char* kVSandU = "/momentum/v_sand_u_m_s";
inline constexpr const char* kPGranU = "/momentum/p_gran_u";
inline constexpr const char* kPTotalU = "/momentum/p_total_u";
inline constexpr const char* kMAddU = "/momentum/m_add_u_kg";
// The subsets of the momentum grid (int32) [G].
inline constexpr const char* kGridSubsetIds = "/momentum/grid_subset_ids";
// Number attributes of kMomentumGroup: p_max [N s], t_e [s] (end of the peak stage), and the
// sigmoid fit of m_add (Eq. 5): M [kg], b [1/s], T [s]; then the summary's numbers
// (momentum_results.cc); the string attribute t_e_found.
inline constexpr const char* kPMaxAttr = "p_max";
inline constexpr const char* kTeAttr = "t_e";
inline constexpr const char* kSigmoidMAttr = "M";
inline constexpr const char* kSigmoidBAttr = "b";
inline constexpr const char* kSigmoidTAttr = "T";
inline constexpr const char* kTeFoundAttr = "t_e_found";
// The uncertainty (momentum/uncertainty.h): every figure of UncertainFigures as a number attribute
// NAME_u (the standard uncertainty; NaN when not estimated), the values impact_velocity_m_s,
// p_gran_te_kg_m_s and v_sand_te_m_s, the number of draws (0: not estimated) and the method.
inline constexpr const char* kUncertaintyDrawsAttr = "uncertainty_draws";
inline constexpr const char* kUncertaintyMethodAttr = "uncertainty_method";

}  // namespace results_layout

// /momentum as read: the series and the summary's numbers (grid subset ids, area and mass, p_max,
// t_e, the conservation error, m_add,max, the momentum ratio, v_sand,max, v_p,max, the sigmoid
// and its standard errors; sigmoid_fitted when M is a number; t_end_found / t_end_problem from
// t_e_found), and the derived time base.
struct MomentumResultsGroup {
  MomentumResult momentum;
  std::vector<double> t_after_impact_s;  // kMomentumT.
  std::string t_e_found;                 // "yes", "no (max soil velocity)", "not measurable: ..".
};

// Writes /momentum (replacing an existing group) with units and descriptions on every dataset;
// times since the impact at impact_time_s (DAQ clock).
void WriteMomentumResults(H5Writer& out, const MomentumResult& momentum, double impact_time_s);

// Reads /momentum back. Error kFileFormat naming `file` and the group or dataset when it is
// missing or a series' length differs from the others'.
MomentumResultsGroup ReadMomentumResults(const H5Reader& in, const std::string& file);

}  // namespace impactdic

#endif  // IMPACTDIC_MOMENTUM_MOMENTUM_RESULTS_H_
