#include "impactdic/sensor/wave_results.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "impactdic/core/strings.h"
#include "impactdic/io/results_io.h"

namespace impactdic {
namespace L = results_layout;
namespace {

constexpr const char* kDefinitions =
    "distance = straight line from the impact point (pounder centre line at the surface) to the "
    "sensor; speed_peak = distance / (sensor peak - pounder peak deceleration); speed_onset = "
    "distance / (sensor onset - impact); sigma_t = sqrt(2 dt^2 / 12 + tau_f^2), tau_f = 1 / (2 pi "
    "f_c); sigma_c = c sigma_t / travel time; return time = 2 depth / speed_peak after the "
    "impact; stress ratio = peak stress / (m_p a_peak / (D t_z)); reflection: largest prominence "
    "of a local maximum of the filtered pounder deceleration within return time +- max(1 ms, "
    "3 sigma_return), a local maximum when above 3 noise standard deviations; the same for the "
    "mean vertical velocity of the near-surface subsets (either sign) over the frames around the "
    "window (docs/wave.md)";

// A [C] dataset of /wave: one number per channel, bound to its field.
struct Figure {
  const char* path;
  double& (*field)(WaveChannel&);
  const char* units;
  const char* description;
};

const std::vector<Figure>& Figures() {
  static const std::vector<Figure> kFigures = {
      {L::kWaveOffset, [](WaveChannel& c) -> double& { return c.offset_mm; }, "mm",
       "horizontal offset of the sensor from the pounder's centre line"},
      {L::kWaveDepth, [](WaveChannel& c) -> double& { return c.depth_mm; }, "mm",
       "depth of the sensor below the undisturbed surface"},
      {L::kWaveDistance, [](WaveChannel& c) -> double& { return c.distance_mm; }, "mm",
       "straight distance from the impact point to the sensor"},
      {L::kWaveArea, [](WaveChannel& c) -> double& { return c.area_mm2; }, "mm^2", "sensing area"},
      {L::kWaveOnset, [](WaveChannel& c) -> double& { return c.onset_s; }, "s",
       "arrival onset after the impact"},
      {L::kWavePeak, [](WaveChannel& c) -> double& { return c.peak_s; }, "s",
       "arrival peak after the impact"},
      {L::kWaveSpeedPeak, [](WaveChannel& c) -> double& { return c.speed_peak_m_s; }, "m/s",
       "wave speed from the peak travel time (pounder peak to sensor peak)"},
      {L::kWaveSpeedPeakSigma, [](WaveChannel& c) -> double& { return c.speed_peak_sigma_m_s; },
       "m/s", "standard uncertainty of speed_peak"},
      {L::kWaveSpeedOnset, [](WaveChannel& c) -> double& { return c.speed_onset_m_s; }, "m/s",
       "wave speed from the onset travel time (impact to sensor onset)"},
      {L::kWaveSpeedOnsetSigma, [](WaveChannel& c) -> double& { return c.speed_onset_sigma_m_s; },
       "m/s", "standard uncertainty of speed_onset"},
      {L::kWaveReturnTime, [](WaveChannel& c) -> double& { return c.return_time_s; }, "s",
       "predicted return of the reflection at the surface after the impact, 2 depth / speed_peak"},
      {L::kWaveReturnTimeSigma, [](WaveChannel& c) -> double& { return c.return_time_sigma_s; },
       "s", "standard uncertainty of return_time"},
      {L::kWavePeakForce, [](WaveChannel& c) -> double& { return c.peak_force_n; }, "N",
       "peak dynamic force"},
      {L::kWavePeakStress, [](WaveChannel& c) -> double& { return c.peak_stress_pa; }, "Pa",
       "peak dynamic stress, force / area"},
      {L::kWaveStressRatio, [](WaveChannel& c) -> double& { return c.stress_ratio; }, "1",
       "peak stress / the pounder's peak stress m_p a_peak / (D t_z)"},
      {L::kWaveReflectionStart, [](WaveChannel& c) -> double& { return c.reflection.window_s[0]; },
       "s", "reflection check window start after the impact"},
      {L::kWaveReflectionEnd, [](WaveChannel& c) -> double& { return c.reflection.window_s[1]; },
       "s", "reflection check window end after the impact"},
      {L::kWaveReflectionProminence,
       [](WaveChannel& c) -> double& { return c.reflection.prominence_g; }, "g",
       "largest prominence of a local maximum of the pounder's deceleration in the window"},
      {L::kWaveReflectionThreshold,
       [](WaveChannel& c) -> double& { return c.reflection.threshold_g; }, "g",
       "prominence above which a local maximum shows (3 noise standard deviations)"},
      {L::kWaveDicReflectionProminence,
       [](WaveChannel& c) -> double& { return c.dic_reflection.prominence_mm_s; }, "mm/s",
       "largest prominence of a local maximum (either sign) of the near-surface soil's mean "
       "vertical velocity in the window"},
      {L::kWaveDicReflectionThreshold,
       [](WaveChannel& c) -> double& { return c.dic_reflection.threshold_mm_s; }, "mm/s",
       "prominence above which the near-surface velocity's local maximum shows (3 standard "
       "deviations of its pre-impact noise)"},
  };
  return kFigures;
}

// "column: problem" lines (WaveResult::Warnings) back to the channels' problems.
void SetProblems(const std::string& text, std::vector<WaveChannel>* channels) {
  std::stringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    for (WaveChannel& c : *channels)
      if (line.rfind(c.column + ": ", 0) == 0)
        c.problems.push_back(line.substr(c.column.size() + 2));
  }
}

// The decay fits of one quantity: rows (t_e, end) of /wave/front/displacement or velocity.
void WriteDecay(H5Writer& out, const std::string& group, const DepthDecayFit& te,
                const DepthDecayFit& end, const char* unit, bool displacement) {
  const auto row = [&](double DepthDecayFit::*field) {
    return std::vector<double>{te.*field, end.*field};
  };
  out.Write(group + "/time_s", row(&DepthDecayFit::time_s), "s",
            "the frame's time after the impact (row 0: nearest t_e, row 1: the last frame)");
  out.Write(group + "/subsets",
            std::vector<double>{static_cast<double>(te.subsets), static_cast<double>(end.subsets)},
            "1", "centre-line subsets in the fit");
  out.Write(group + "/surface", row(&DepthDecayFit::surface_value), unit,
            "fitted value u0 at the pounder's base");
  out.Write(group + "/decay_length_mm", row(&DepthDecayFit::decay_length_mm), "mm",
            "decay length lambda of u0 exp(-z / lambda), z below the pounder's base");
  out.Write(group + "/decay_length_ci_low_mm",
            std::vector<double>{te.decay_length_ci_mm[0], end.decay_length_ci_mm[0]}, "mm",
            "lower end of lambda's 95 % interval");
  out.Write(group + "/decay_length_ci_high_mm",
            std::vector<double>{te.decay_length_ci_mm[1], end.decay_length_ci_mm[1]}, "mm",
            "upper end of lambda's 95 % interval (NaN: unbounded)");
  if (displacement)
    out.Write(group + "/depth_of_influence_mm", row(&DepthDecayFit::depth_of_influence_mm), "mm",
              "depth below the surface where the fitted displacement is 10 % of u0");
  // A row without a profile (t_e not measured) is written as NaN (in_fit 0).
  const std::size_t c = std::max(te.profile_depth_mm.size(), end.profile_depth_mm.size());
  if (c > 0) {
    const auto rows = [c](const auto& a, const auto& b) {
      std::vector<double> v(a.begin(), a.end());
      v.resize(c, a.empty() ? kNaN : 0);
      v.insert(v.end(), b.begin(), b.end());
      v.resize(2 * c, b.empty() ? kNaN : 0);
      return v;
    };
    out.Write(group + "/profile_depth_mm", rows(te.profile_depth_mm, end.profile_depth_mm), {2, c},
              "mm", "each centre-line subset's depth below the pounder's base (NaN: not below)");
    out.Write(group + "/profile_value", rows(te.profile_value, end.profile_value), {2, c}, unit,
              "each centre-line subset's downward value at the row's frame");
    out.Write(group + "/profile_in_fit", rows(te.profile_in_fit, end.profile_in_fit), {2, c}, "1",
              "1 = the subset entered the decay fit");
  }
  std::vector<std::string> problems;
  if (!te.problem.empty()) problems.push_back("0: " + te.problem);
  if (!end.problem.empty()) problems.push_back("1: " + end.problem);
  out.SetAttribute(group, L::kWaveFrontProblemAttr,
                   problems.empty() ? "none" : Join(problems, "\n"));
}

// `centre`: the centre-line subsets (the profiles' length).
void ReadDecay(const H5Reader& in, const std::string& group, const std::string& file,
               std::size_t centre, DepthDecayFit* te, DepthDecayFit* end, bool displacement) {
  std::size_t n = 2;
  const auto read = [&](const std::string& name, double DepthDecayFit::*field) {
    const std::vector<double> v = ReadSeries(in, group + "/" + name, file, &n);
    te->*field = v[0];
    end->*field = v[1];
  };
  read("time_s", &DepthDecayFit::time_s);
  read("surface", &DepthDecayFit::surface_value);
  read("decay_length_mm", &DepthDecayFit::decay_length_mm);
  if (displacement) read("depth_of_influence_mm", &DepthDecayFit::depth_of_influence_mm);
  const std::vector<double> count = ReadSeries(in, group + "/subsets", file, &n);
  te->subsets = static_cast<std::size_t>(count[0]);
  end->subsets = static_cast<std::size_t>(count[1]);
  const std::vector<double> lo = ReadSeries(in, group + "/decay_length_ci_low_mm", file, &n);
  const std::vector<double> hi = ReadSeries(in, group + "/decay_length_ci_high_mm", file, &n);
  te->decay_length_ci_mm = {lo[0], hi[0]};
  end->decay_length_ci_mm = {lo[1], hi[1]};
  if (centre > 0 && in.Exists(group + "/profile_depth_mm")) {
    const auto read_rows = [&](const std::string& name, auto* a, auto* b) {
      const std::vector<double> v = ReadField(in, group + "/" + name, file, {2, centre});
      a->clear();
      b->clear();
      for (std::size_t i = 0; i < 2 * centre; ++i) {
        // profile_in_fit: 1 = in the fit; anything else (0, NaN of a row without a profile) not.
        if constexpr (std::is_same_v<std::remove_pointer_t<decltype(a)>, std::vector<double>>)
          (i < centre ? a : b)->push_back(v[i]);
        else
          (i < centre ? a : b)->push_back(v[i] == 1 ? 1 : 0);
      }
    };
    read_rows("profile_depth_mm", &te->profile_depth_mm, &end->profile_depth_mm);
    read_rows("profile_value", &te->profile_value, &end->profile_value);
    read_rows("profile_in_fit", &te->profile_in_fit, &end->profile_in_fit);
  }
  std::stringstream lines(ReadStringAttributeOr(in, group, L::kWaveFrontProblemAttr, ""));
  for (std::string line; std::getline(lines, line);) {
    if (line.rfind("0: ", 0) == 0) te->problem = line.substr(3);
    if (line.rfind("1: ", 0) == 0) end->problem = line.substr(3);
  }
}

void WriteFront(H5Writer& out, const WaveFront& f) {
  const std::string g = L::kWaveFrontGroup;
  out.Write(L::kWaveFrontDistance, f.distance_mm, "mm",
            "distance of each subset's reference centre from the impact point");
  out.Write(L::kWaveFrontArrival, f.arrival_s, "s",
            "arrival of each subset's motion after the impact (NaN: none)");
  out.Write(L::kWaveFrontInFit, std::vector<double>(f.in_fit.begin(), f.in_fit.end()), "1",
            "1 = the subset's arrival is in the front speed fit");
  out.Write(L::kWaveFrontSpeed, std::vector<double>{f.speed_m_s}, "m/s",
            "front speed: 1 / slope of arrival against distance (least squares)");
  out.Write(L::kWaveFrontSpeedCiLow, std::vector<double>{f.speed_ci_m_s[0]}, "m/s",
            "lower end of the front speed's 95 % interval");
  out.Write(L::kWaveFrontSpeedCiHigh, std::vector<double>{f.speed_ci_m_s[1]}, "m/s",
            "upper end of the front speed's 95 % interval (NaN: unbounded)");
  out.Write(L::kWaveFrontIntercept, std::vector<double>{f.intercept_s}, "s",
            "fitted arrival at distance 0");
  out.Write(L::kWaveFrontRms, std::vector<double>{f.rms_residual_s}, "s",
            "rms residual of the arrivals in the fit");
  out.Write(L::kWaveFrontCentreLine,
            std::vector<double>(f.centre_line.begin(), f.centre_line.end()), "1",
            "the centre-line subsets' indices in /kinematics' order");
  const SpaceTime& st = f.space_time;
  if (!st.time_s.empty()) {
    out.Write(L::kWaveSpaceTimeT, st.time_s, "s", "each frame's time after the impact");
    out.Write(L::kWaveSpaceTimeDepth, st.depth_mm, "mm",
              "each centre-line row's depth below the undisturbed surface");
    out.Write(L::kWaveSpaceTimeVelocity, st.velocity_mm_s, {st.time_s.size(), st.rows()}, "mm/s",
              "each centre-line row's mean downward velocity per frame (NaN: none measured)");
    out.Write(L::kWaveSpaceTimeBase, st.pounder_base_mm, "mm",
              "the pounder's base below the undisturbed surface (its penetration)");
  }
  WriteDecay(out, L::kWaveFrontDisplacementGroup, f.displacement_te, f.displacement_end, "mm",
             /*displacement=*/true);
  WriteDecay(out, L::kWaveFrontVelocityGroup, f.velocity_te, f.velocity_end, "mm/s",
             /*displacement=*/false);
  out.SetAttribute(g, L::kWaveFrontProblemAttr, f.problem.empty() ? "none" : f.problem);
  for (const auto& [name, value] : std::vector<std::pair<const char*, double>>{
           {"noise_factor", f.noise_factor},
           {"peak_fraction", f.peak_fraction},
           {"arrivals", static_cast<double>(f.arrivals)},
           {"centre_line_subsets", static_cast<double>(f.centre_line_subsets)},
           {"pounder_base_depth_te_mm", f.pounder_base_depth_mm},
           {"crater_depth_mm", f.crater_depth_mm},
           {"influence_fraction", kInfluenceFraction}})
    out.SetAttribute(g, name, value);
}

WaveFront ReadFront(const H5Reader& in, const std::string& file) {
  WaveFront f;
  f.computed = true;
  std::size_t s = kAnyLength;
  f.distance_mm = ReadSeries(in, L::kWaveFrontDistance, file, &s);
  f.arrival_s = ReadSeries(in, L::kWaveFrontArrival, file, &s);
  for (double v : ReadSeries(in, L::kWaveFrontInFit, file, &s)) f.in_fit.push_back(v == 1 ? 1 : 0);
  f.fit_subsets = static_cast<std::size_t>(std::count(f.in_fit.begin(), f.in_fit.end(), 1));
  std::size_t one = 1;
  f.speed_m_s = ReadSeries(in, L::kWaveFrontSpeed, file, &one)[0];
  f.speed_ci_m_s = {ReadSeries(in, L::kWaveFrontSpeedCiLow, file, &one)[0],
                    ReadSeries(in, L::kWaveFrontSpeedCiHigh, file, &one)[0]};
  f.intercept_s = ReadSeries(in, L::kWaveFrontIntercept, file, &one)[0];
  f.rms_residual_s = ReadSeries(in, L::kWaveFrontRms, file, &one)[0];
  if (in.Exists(L::kWaveFrontCentreLine)) {
    std::size_t c = kAnyLength;
    for (double v : ReadSeries(in, L::kWaveFrontCentreLine, file, &c))
      f.centre_line.push_back(static_cast<std::size_t>(v));
  }
  if (in.Exists(L::kWaveSpaceTimeGroup)) {
    SpaceTime& st = f.space_time;
    std::size_t frames = kAnyLength, rows = kAnyLength;
    st.time_s = ReadSeries(in, L::kWaveSpaceTimeT, file, &frames);
    st.pounder_base_mm = ReadSeries(in, L::kWaveSpaceTimeBase, file, &frames);
    st.depth_mm = ReadSeries(in, L::kWaveSpaceTimeDepth, file, &rows);
    st.velocity_mm_s = ReadField(in, L::kWaveSpaceTimeVelocity, file, {frames, rows});
  }
  ReadDecay(in, L::kWaveFrontDisplacementGroup, file, f.centre_line.size(), &f.displacement_te,
            &f.displacement_end,
            /*displacement=*/true);
  ReadDecay(in, L::kWaveFrontVelocityGroup, file, f.centre_line.size(), &f.velocity_te,
            &f.velocity_end,
            /*displacement=*/false);
  const std::string g = L::kWaveFrontGroup;
  const std::string problem = ReadStringAttributeOr(in, g, L::kWaveFrontProblemAttr, "");
  if (problem != "none") f.problem = problem;
  f.noise_factor = ReadNumberAttributeOr(in, g, "noise_factor", kNaN);
  f.peak_fraction = ReadNumberAttributeOr(in, g, "peak_fraction", kNaN);
  f.arrivals = static_cast<std::size_t>(ReadNumberAttributeOr(in, g, "arrivals", 0));
  f.centre_line_subsets =
      static_cast<std::size_t>(ReadNumberAttributeOr(in, g, "centre_line_subsets", 0));
  f.pounder_base_depth_mm = ReadNumberAttributeOr(in, g, "pounder_base_depth_te_mm", kNaN);
  f.crater_depth_mm = ReadNumberAttributeOr(in, g, "crater_depth_mm", kNaN);
  return f;
}

}  // namespace

void WriteWaveResults(H5Writer& out, const SensorResult& sensor, const WaveResult& wave) {
  out.Remove(L::kWaveGroup);
  std::vector<WaveChannel> channels = wave.channels;  // Figure binds mutable fields.
  for (const Figure& f : Figures()) {
    std::vector<double> v;
    v.reserve(channels.size());
    for (WaveChannel& c : channels) v.push_back(f.field(c));
    out.Write(f.path, v, f.units, f.description);
  }
  std::vector<double> local_maximum;
  local_maximum.reserve(channels.size());
  for (const WaveChannel& c : channels)
    local_maximum.push_back(c.reflection.checked ? (c.reflection.local_maximum ? 1.0 : 0.0) : kNaN);
  out.Write(L::kWaveReflectionLocalMax, local_maximum, "1",
            "1 = the deceleration shows a local maximum around the return time, 0 = none, NaN = "
            "not checked");
  std::vector<double> dic_local_maximum, dic_subsets;
  for (const WaveChannel& c : channels) {
    const DicReflectionCheck& r = c.dic_reflection;
    dic_local_maximum.push_back(r.checked ? (r.local_maximum ? 1.0 : 0.0) : kNaN);
    dic_subsets.push_back(static_cast<double>(r.subsets));
  }
  out.Write(L::kWaveDicReflectionLocalMax, dic_local_maximum, "1",
            "1 = the near-surface soil's velocity shows a local maximum around the return time, "
            "0 = none, NaN = not checked");
  out.Write(L::kWaveDicReflectionSubsets, dic_subsets, "1",
            "near-surface subsets averaged (the shallowest row outside the pounder's columns)");
  std::vector<std::string> columns, units;
  for (const WaveChannel& c : wave.channels) {
    columns.push_back(c.column);
    units.push_back(c.unit);
  }
  for (const BaseForceChannel& b : sensor.base) {
    out.Write(std::string(L::kWaveForceGroup) + "/" + b.column, b.force_n, "N",
              "dynamic base force (pre-impact rest subtracted), zero-phase low-pass filtered; "
              "time axis /sensor/t_s");
  }
  out.SetAttribute(L::kWaveGroup, "pounder_peak_stress_Pa", wave.pounder_peak_stress_pa);
  out.SetAttribute(L::kWaveGroup, "pounder_peak_s", wave.pounder_peak_s);
  out.SetAttribute(L::kWaveGroup, "sample_interval_s", wave.sample_interval_s);
  out.SetAttribute(L::kWaveGroup, "filter_time_constant_s", wave.filter_time_constant_s);
  out.SetAttribute(L::kWaveGroup, "travel_time_sigma_s", wave.travel_time_sigma_s);
  out.SetAttribute(L::kWaveGroup, "noise_g", wave.noise_g);
  out.SetAttribute(L::kWaveGroup, L::kWaveColumnsAttr, Join(columns, ","));
  out.SetAttribute(L::kWaveGroup, L::kWaveUnitsAttr, Join(units, ","));
  std::string problems;
  for (const std::string& p : wave.Warnings()) problems += (problems.empty() ? "" : "\n") + p;
  out.SetAttribute(L::kWaveGroup, L::kWaveProblemsAttr, problems.empty() ? "none" : problems);
  out.SetAttribute(L::kWaveGroup, L::kWaveDefinitionsAttr, kDefinitions);
  if (wave.front.computed) WriteFront(out, wave.front);
}

WaveResult ReadWaveResults(const H5Reader& in, const std::string& file) {
  RequireGroup(in, L::kWaveGroup, file, "the wave figures (a run with sensor.base_columns)");
  WaveResult w;
  std::stringstream columns(ReadStringAttributeOr(in, L::kWaveGroup, L::kWaveColumnsAttr, ""));
  std::stringstream units(ReadStringAttributeOr(in, L::kWaveGroup, L::kWaveUnitsAttr, ""));
  for (std::string name, unit; std::getline(columns, name, ',');) {
    std::getline(units, unit, ',');
    WaveChannel& c = w.channels.emplace_back();
    c.column = name;
    c.unit = unit;
  }
  std::size_t n = w.channels.size();
  for (const Figure& f : Figures()) {
    const std::vector<double> v = ReadSeries(in, f.path, file, &n);
    for (std::size_t k = 0; k < n; ++k) f.field(w.channels[k]) = v[k];
  }
  const std::vector<double> local_maximum = ReadSeries(in, L::kWaveReflectionLocalMax, file, &n);
  const std::vector<double> dic_local_maximum =
      ReadSeries(in, L::kWaveDicReflectionLocalMax, file, &n);
  const std::vector<double> dic_subsets = ReadSeries(in, L::kWaveDicReflectionSubsets, file, &n);
  for (std::size_t k = 0; k < n; ++k) {
    w.channels[k].reflection.checked = !std::isnan(local_maximum[k]);
    w.channels[k].reflection.local_maximum = local_maximum[k] == 1;
    w.channels[k].dic_reflection.checked = !std::isnan(dic_local_maximum[k]);
    w.channels[k].dic_reflection.local_maximum = dic_local_maximum[k] == 1;
    w.channels[k].dic_reflection.subsets = static_cast<std::size_t>(dic_subsets[k]);
  }
  const std::string problems = ReadStringAttributeOr(in, L::kWaveGroup, L::kWaveProblemsAttr, "");
  if (problems != "none") SetProblems(problems, &w.channels);
  for (const auto& [name, value] : std::vector<std::pair<const char*, double*>>{
           {"pounder_peak_stress_Pa", &w.pounder_peak_stress_pa},
           {"pounder_peak_s", &w.pounder_peak_s},
           {"sample_interval_s", &w.sample_interval_s},
           {"filter_time_constant_s", &w.filter_time_constant_s},
           {"travel_time_sigma_s", &w.travel_time_sigma_s},
           {"noise_g", &w.noise_g}})
    *value = ReadNumberAttributeOr(in, L::kWaveGroup, name, kNaN);
  if (in.Exists(L::kWaveFrontGroup)) w.front = ReadFront(in, file);
  return w;
}

std::vector<BaseForceRecord> ReadBaseForceRecords(const H5Reader& in, const std::string& file,
                                                  const WaveResult& wave) {
  std::vector<BaseForceRecord> records;
  std::size_t n = kAnyLength;
  for (const WaveChannel& c : wave.channels) {
    const std::string path = std::string(L::kWaveForceGroup) + "/" + c.column;
    if (in.Exists(path)) records.push_back({c.column, ReadSeries(in, path, file, &n)});
  }
  return records;
}

}  // namespace impactdic
