#include "impactdic/momentum/momentum_results.h"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "impactdic/io/results_io.h"
#include "impactdic/kinematics/kinematics_results.h"
#include "impactdic/sensor/sensor_results.h"

namespace impactdic {
namespace L = results_layout;
namespace {

// The per-frame series of /momentum bound to a result (const for the writer, mutable for the
// reader), in the order written.
template <typename R>
auto FrameSeries(R& m) {
  using Vector = std::remove_reference_t<decltype((m.frame_time_s))>;
  return std::vector<DatasetBinding<Vector>>{
      {L::kMomentumTimeDaq, "s", "frame time on the DAQ clock", &m.frame_time_s},
      {L::kVPounder, "m/s", "pounder velocity at the frames (down +)", &m.v_pounder_m_s},
      {L::kVSand, "m/s", "mean soil velocity over the grid (down +)", &m.v_sand_m_s},
      {L::kASand, "m/s^2", "mean soil acceleration over the grid (down +)", &m.a_sand_m_s2},
      {L::kPPounder, "N s", "pounder momentum m_p v_p", &m.p_pounder_kg_m_s},
      {L::kPGran, "N s", "granular momentum rho_d area t_z v_sand", &m.p_gran_kg_m_s},
      {L::kPTotal, "N s", "p_pounder + p_gran", &m.p_total_kg_m_s},
      {L::kMAdd, "kg", "added mass p_max / v_p - m_p (Eq. 3), NaN outside [impact, t_e]",
       &m.added_mass_kg},
      {L::kValidSubsets, "1", "valid subsets in the grid per frame", &m.valid_subsets}};
}

// The number attributes of /momentum bound to a summary; the sigmoid's are NaN when it was not
// fitted (the writer passes them separately).
template <typename S, typename Number>
auto SummaryAttributes(S& s, Number* m, Number* b, Number* t, Number* se_m, Number* se_b,
                       Number* se_t) {
  return std::vector<std::pair<const char*, Number*>>{
      {L::kPMaxAttr, &s.p_max_kg_m_s},
      {L::kTeAttr, &s.t_end_peak_s},
      {L::kSigmoidMAttr, m},
      {L::kSigmoidBAttr, b},
      {L::kSigmoidTAttr, t},
      {"p_max_kg_m_s", &s.p_max_kg_m_s},
      {"t_end_peak_s", &s.t_end_peak_s},
      {"momentum_conservation_error", &s.momentum_conservation_error},
      {"added_mass_max_kg", &s.added_mass_max_kg},
      {"momentum_ratio", &s.momentum_ratio},
      {"v_sand_max_m_s", &s.v_sand_max_m_s},
      {"v_p_max_m_s", &s.v_p_max_m_s},
      {"grid_area_m2", &s.grid.area_m2},
      {"grid_mass_kg", &s.grid.mass_kg},
      {"sigmoid_se_M_kg", se_m},
      {"sigmoid_se_b_per_s", se_b},
      {"sigmoid_se_T_s", se_t}};
}

// The per-frame standard uncertainties (bands of the figures), [K] each, when estimated.
template <typename R>
auto UncertaintySeries(R& m) {
  using Vector = std::remove_reference_t<decltype((m.frame_time_s))>;
  return std::vector<DatasetBinding<Vector>>{
      {L::kVSandU, "m/s", "standard uncertainty of v_sand", &m.v_sand_u_m_s},
      {L::kPGranU, "N s", "standard uncertainty of p_gran", &m.p_gran_u_kg_m_s},
      {L::kPTotalU, "N s", "standard uncertainty of p_total", &m.p_total_u_kg_m_s},
      {L::kMAddU, "kg", "standard uncertainty of m_add", &m.added_mass_u_kg}};
}

// The figures' values new with the uncertainty (the others are attributes already) and every
// figure's NAME_u (momentum UncertainFigures), the method and the draws.
void WriteUncertainty(H5Writer& out, const MomentumResult& m) {
  const MomentumSummary& s = m.summary;
  const MomentumUncertainty& u = s.uncertainty;
  for (const auto& [name, value] : {std::pair{"impact_velocity_m_s", s.impact_velocity_m_s},
                                    std::pair{"p_gran_te_kg_m_s", s.p_gran_te_kg_m_s},
                                    std::pair{"v_sand_te_m_s", s.v_sand_te_m_s}})
    out.SetAttribute(L::kMomentumGroup, name, value);
  for (const auto& f : UncertainFigures(s))
    out.SetAttribute(L::kMomentumGroup, std::string(f.name) + "_u", u.draws > 0 ? *f.u : kNaN);
  out.SetAttribute(L::kMomentumGroup, L::kUncertaintyDrawsAttr, static_cast<double>(u.draws));
  out.SetAttribute(L::kMomentumGroup, L::kUncertaintyMethodAttr,
                   std::string(kMomentumUncertaintyMethod));
  if (m.v_sand_u_m_s.size() != m.frame_time_s.size()) return;
  for (const auto& d : UncertaintySeries(m)) out.Write(d.path, *d.values, d.units, d.description);
}

std::string TeFoundText(const MomentumSummary& s) {
  if (!s.t_end_problem.empty()) return "not measurable: " + s.t_end_problem;
  return s.t_end_found ? "yes" : "no (max soil velocity)";
}

}  // namespace

void WriteMomentumResults(H5Writer& out, const MomentumResult& m, double impact_time_s) {
  out.Remove(L::kMomentumGroup);
  const MomentumSummary& s = m.summary;
  std::vector<double> t_after(m.frame_time_s.size());
  for (std::size_t i = 0; i < t_after.size(); ++i) t_after[i] = m.frame_time_s[i] - impact_time_s;
  out.Write(L::kMomentumT, t_after, "s", "frame time since the detected impact");
  for (const auto& d : FrameSeries(m)) out.Write(d.path, *d.values, d.units, d.description);
  if (!m.added_mass_daq_kg.empty()) {
    out.Write(L::kAddedMassDaqT, m.added_mass_time_after_impact_s, "s",
              "DAQ sample time since the impact");
    out.Write(L::kAddedMassDaq, m.added_mass_daq_kg, "kg",
              "p_max / v_p - m_p at the DAQ rate (what the sigmoid is fitted to)");
  }
  std::vector<std::int32_t> ids(s.grid.subset_ids.begin(), s.grid.subset_ids.end());
  out.Write(L::kGridSubsetIds, ids, Dims{ids.size()}, "1", "subsets of the momentum grid");
  const bool fit = s.sigmoid_fitted;
  const SigmoidFit& f = s.sigmoid;
  const double sig[6] = {fit ? f.M_kg : kNaN,    fit ? f.b_per_s : kNaN,    fit ? f.T_s : kNaN,
                         fit ? f.se_M_kg : kNaN, fit ? f.se_b_per_s : kNaN, fit ? f.se_T_s : kNaN};
  for (const auto& [name, value] :
       SummaryAttributes(s, &sig[0], &sig[1], &sig[2], &sig[3], &sig[4], &sig[5]))
    out.SetAttribute(L::kMomentumGroup, name, *value);
  out.SetAttribute(L::kMomentumGroup, L::kTeFoundAttr, TeFoundText(s));
  WriteUncertainty(out, m);
}

MomentumResultsGroup ReadMomentumResults(const H5Reader& in, const std::string& file) {
  RequireGroup(in, L::kMomentumGroup, file,
               "the momentum validation's results (impactdic run or analyze)");
  MomentumResultsGroup g;
  MomentumResult& m = g.momentum;
  std::size_t k = kAnyLength;
  g.t_after_impact_s = ReadSeries(in, L::kMomentumT, file, &k);
  for (const auto& d : FrameSeries(m)) *d.values = ReadSeries(in, d.path, file, &k);
  if (in.Exists(L::kAddedMassDaqGroup)) {
    std::size_t daq = kAnyLength;
    m.added_mass_time_after_impact_s = ReadSeries(in, L::kAddedMassDaqT, file, &daq);
    m.added_mass_daq_kg = ReadSeries(in, L::kAddedMassDaq, file, &daq);
  }
  MomentumSummary& s = m.summary;
  for (std::int32_t id : in.ReadInt(L::kGridSubsetIds))
    s.grid.subset_ids.push_back(static_cast<std::size_t>(id));
  SigmoidFit& f = s.sigmoid;
  for (const auto& [name, value] :
       SummaryAttributes(s, &f.M_kg, &f.b_per_s, &f.T_s, &f.se_M_kg, &f.se_b_per_s, &f.se_T_s))
    *value = ReadNumberAttributeOr(in, L::kMomentumGroup, name, kNaN);
  s.sigmoid_fitted = std::isfinite(f.M_kg);
  for (const auto& figure : UncertainFigures(s))
    *figure.u = ReadNumberAttributeOr(in, L::kMomentumGroup, std::string(figure.name) + "_u", kNaN);
  for (const auto& [name, value] : {std::pair{"impact_velocity_m_s", &s.impact_velocity_m_s},
                                    std::pair{"p_gran_te_kg_m_s", &s.p_gran_te_kg_m_s},
                                    std::pair{"v_sand_te_m_s", &s.v_sand_te_m_s}})
    *value = ReadNumberAttributeOr(in, L::kMomentumGroup, name, kNaN);
  s.uncertainty.draws =
      static_cast<int>(ReadNumberAttributeOr(in, L::kMomentumGroup, L::kUncertaintyDrawsAttr, 0.0));
  if (in.Exists(L::kPGranU))
    for (const auto& d : UncertaintySeries(m)) *d.values = ReadSeries(in, d.path, file, &k);
  g.t_e_found = ReadStringAttributeOr(in, L::kMomentumGroup, L::kTeFoundAttr, "");
  s.t_end_found = g.t_e_found == "yes";
  const std::string not_measurable = "not measurable: ";
  if (g.t_e_found.rfind(not_measurable, 0) == 0)
    s.t_end_problem = g.t_e_found.substr(not_measurable.size());
  return g;
}

// The scene analysis's groups, each by its owner's writer.
void WriteSensor(H5Writer& out, const SensorResult& sensor) { WriteSensorResults(out, sensor); }

void WriteKinematics(H5Writer& out, const KinematicsResult& kinematics,
                     const std::vector<double>& frame_time_s) {
  WriteKinematicsResults(out, kinematics, frame_time_s);
}

void WriteMomentum(H5Writer& out, const MomentumResult& momentum, const SensorResult& sensor) {
  WriteMomentumResults(out, momentum, sensor.summary.impact_time_s);
}

void WriteAnalysis(H5Writer& out, const SceneAnalysis& analysis, const SensorResult& sensor) {
  WriteKinematics(out, analysis.kinematics, analysis.frame_time_s);
  WriteSensor(out, sensor);
  WriteMomentum(out, analysis.momentum, sensor);
}

}  // namespace impactdic
