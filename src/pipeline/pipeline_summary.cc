#include <fmt/format.h>

#include <cstddef>
#include <string>
#include <vector>

#include "impactdic/io/json.h"
#include "impactdic/pipeline/pipeline.h"

namespace impactdic {

JsonObject SceneFigures::ToJson() const {
  JsonObject j;
  const auto names = CsvNames();
  const auto values = CsvValues();
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] != "dic_subsets_per_s") j.Add(names[i], values[i]);
  return j;
}

std::vector<std::string> SceneFigures::CsvNames() const {
  return {"impact_velocity_m_s",
          "p_max_kg_m_s",
          "t_end_peak_s",
          "momentum_conservation_error",
          "added_mass_max_kg",
          "added_mass_eq4_kg",
          "sigmoid_M_kg",
          "sigmoid_b_per_s",
          "sigmoid_T_s",
          "momentum_ratio_measured",
          "momentum_ratio_model",
          "v_sand_max_m_s",
          "peak_deceleration_measured_g",
          "peak_deceleration_model_g",
          "plateau_deceleration_measured_g",
          "plateau_deceleration_model_g",
          "crater_depth_measured_m",
          "crater_depth_model_m",
          "t_end_model_s",
          "dic_valid_fraction",
          "dic_subsets_per_s",
          "wave_speed_peak_m_s",
          "wave_stress_ratio",
          "wave_front_speed_m_s",
          "wave_decay_length_te_mm"};
}

std::vector<double> SceneFigures::CsvValues() const {
  return {impact_velocity_m_s,
          p_max_kg_m_s,
          t_end_peak_s,
          momentum_conservation_error,
          added_mass_max_kg,
          added_mass_eq4_kg,
          sigmoid_M_kg,
          sigmoid_b_per_s,
          sigmoid_T_s,
          momentum_ratio_measured,
          momentum_ratio_model,
          v_sand_max_m_s,
          peak_deceleration_measured_g,
          peak_deceleration_model_g,
          plateau_deceleration_measured_g,
          plateau_deceleration_model_g,
          crater_depth_measured_m,
          crater_depth_model_m,
          t_end_model_s,
          dic_valid_fraction,
          dic_subsets_per_s,
          wave_speed_peak_m_s,
          wave_stress_ratio,
          wave_front_speed_m_s,
          wave_decay_length_te_mm};
}

std::vector<std::string> StrainFigures::CsvNames() const {
  return {"strain_compacted_area_te_mm2",  "strain_compacted_depth_te_mm",
          "strain_compacted_area_end_mm2", "strain_compacted_depth_end_mm",
          "strain_crater_depth_model_mm",  "strain_crater_depth_measured_mm"};
}

std::vector<double> StrainFigures::CsvValues() const {
  return {compacted_area_te_mm2,  compacted_depth_te_mm, compacted_area_end_mm2,
          compacted_depth_end_mm, crater_depth_model_mm, crater_depth_measured_mm};
}

JsonObject StrainFigures::ToJson() const {
  JsonObject j;
  j.Add("gradient", gradient)
      .Add("compacted_area_te_mm2", compacted_area_te_mm2)
      .Add("compacted_depth_te_mm", compacted_depth_te_mm)
      .Add("compacted_area_end_mm2", compacted_area_end_mm2)
      .Add("compacted_depth_end_mm", compacted_depth_end_mm)
      .Add("crater_depth_model_mm", crater_depth_model_mm)
      .Add("crater_depth_measured_mm", crater_depth_measured_mm)
      .Add("depth_from", depth_from);
  if (!te_note.empty()) j.Add("te_note", te_note);
  return j;
}

namespace {

JsonObject DecayJson(const DepthDecayFit& d, const char* unit) {
  JsonObject j;
  j.Add("time_s", d.time_s)
      .Add("subsets", static_cast<int>(d.subsets))
      .Add(std::string("surface_") + unit, d.surface_value)
      .Add("decay_length_mm", d.decay_length_mm)
      .Add("decay_length_ci_mm",
           std::vector<double>{d.decay_length_ci_mm[0], d.decay_length_ci_mm[1]});
  if (std::string(unit) == "mm") j.Add("depth_of_influence_mm", d.depth_of_influence_mm);
  if (!d.problem.empty()) j.Add("problem", d.problem);
  return j;
}

JsonObject FrontJson(const WaveFront& f) {
  JsonObject j;
  j.Add("criterion",
        fmt::format("arrival: first downward vertical velocity above max({} x pre-impact sd, {} x "
                    "own peak), linear between frames; speed: least squares of arrival against "
                    "distance from the impact point, subsets outside the footprint columns",
                    f.noise_factor, f.peak_fraction))
      .Add("arrivals", static_cast<int>(f.arrivals))
      .Add("fit_subsets", static_cast<int>(f.fit_subsets))
      .Add("speed_m_s", f.speed_m_s)
      .Add("speed_ci_m_s", std::vector<double>{f.speed_ci_m_s[0], f.speed_ci_m_s[1]})
      .Add("intercept_s", f.intercept_s)
      .Add("rms_residual_s", f.rms_residual_s);
  if (!f.problem.empty()) j.Add("problem", f.problem);
  JsonObject decay;
  decay.Add("centre_line_subsets", static_cast<int>(f.centre_line_subsets))
      .Add("pounder_base_depth_te_mm", f.pounder_base_depth_mm)
      .Add("displacement_te", DecayJson(f.displacement_te, "mm"))
      .Add("velocity_te", DecayJson(f.velocity_te, "mm_s"))
      .Add("displacement_end", DecayJson(f.displacement_end, "mm"))
      .Add("velocity_end", DecayJson(f.velocity_end, "mm_s"))
      .Add("influence_fraction", kInfluenceFraction)
      .Add("crater_depth_mm", f.crater_depth_mm);
  j.Add("decay", decay);
  return j;
}

}  // namespace

JsonObject WaveJson(const WaveResult& wave) {
  JsonObject channels;
  for (const WaveChannel& c : wave.channels) {
    const ReflectionCheck& r = c.reflection;
    JsonObject reflection;
    reflection.Add("checked", r.checked);
    if (r.checked) {
      reflection.Add("window_s", std::vector<double>{r.window_s[0], r.window_s[1]})
          .Add("statistic", "largest prominence of a local maximum of the filtered deceleration")
          .Add("prominence_g", r.prominence_g)
          .Add("threshold_g", r.threshold_g)
          .Add("local_maximum", r.local_maximum);
    } else {
      reflection.Add("note", r.note);
    }
    const DicReflectionCheck& rd = c.dic_reflection;
    JsonObject dic_reflection;
    dic_reflection.Add("checked", rd.checked);
    if (rd.checked) {
      dic_reflection.Add("window_s", std::vector<double>{r.window_s[0], r.window_s[1]})
          .Add("statistic",
               "largest prominence of a local maximum of the near-surface soil's mean vertical "
               "velocity, either sign")
          .Add("subsets", static_cast<std::int64_t>(rd.subsets))
          .Add("prominence_mm_s", rd.prominence_mm_s)
          .Add("threshold_mm_s", rd.threshold_mm_s)
          .Add("local_maximum", rd.local_maximum);
    } else {
      dic_reflection.Add("note", rd.note);
    }
    JsonObject j;
    j.Add("unit", c.unit)
        .Add("offset_mm", c.offset_mm)
        .Add("depth_mm", c.depth_mm)
        .Add("distance_mm", c.distance_mm)
        .Add("area_mm2", c.area_mm2)
        .Add("onset_s", c.onset_s)
        .Add("peak_s", c.peak_s)
        .Add("speed_peak_m_s", c.speed_peak_m_s)
        .Add("speed_peak_sigma_m_s", c.speed_peak_sigma_m_s)
        .Add("speed_onset_m_s", c.speed_onset_m_s)
        .Add("speed_onset_sigma_m_s", c.speed_onset_sigma_m_s)
        .Add("return_time_s", c.return_time_s)
        .Add("return_time_sigma_s", c.return_time_sigma_s)
        .Add("peak_force_N", c.peak_force_n)
        .Add("peak_stress_Pa", c.peak_stress_pa)
        .Add("stress_ratio", c.stress_ratio)
        .Add("reflection", reflection)
        .Add("reflection_dic", dic_reflection)
        .Add("plausible", c.problems.empty())
        .Add("problems", c.problems);
    channels.Add(c.column, j);
  }
  JsonObject j;
  j.Add("pounder_peak_stress_Pa", wave.pounder_peak_stress_pa)
      .Add("pounder_peak_s", wave.pounder_peak_s)
      .Add("sample_interval_s", wave.sample_interval_s)
      .Add("filter_time_constant_s", wave.filter_time_constant_s)
      .Add("travel_time_sigma_s", wave.travel_time_sigma_s)
      .Add("channels", channels);
  if (wave.front.computed || !wave.front.problem.empty()) j.Add("front", FrontJson(wave.front));
  return j;
}

std::string PipelineSummary::FailureText() const {
  std::string text;
  for (const StageFailure& f : failures)
    text += (text.empty() ? "" : "; ") + f.stage + ": " + f.reason;
  return text;
}

std::string PipelineSummary::BriefReport() const {
  return fmt::format(
             "{}: conservation error {:.2f} %, m_add,max {:.3f} kg (Eq. 4: {:.3f} kg), crater "
             "depth {:.2f} mm measured / {:.2f} mm model, {:.1f} s",
             scene_name, 100 * figures.momentum_conservation_error, figures.added_mass_max_kg,
             figures.added_mass_eq4_kg, 1e3 * figures.crater_depth_measured_m,
             1e3 * figures.crater_depth_model_m, seconds) +
         (failures.empty() ? "" : "; PARTIAL: " + FailureText());
}

JsonObject PipelineSummary::ToJson() const {
  JsonObject j = figures.ToJson();
  if (uncertainty) j.Add("uncertainty", *uncertainty);
  if (strain) j.Add("strain", strain->ToJson());
  if (wave) j.Add("wave", WaveJson(*wave));
  JsonObject failed;
  for (const StageFailure& f : failures) failed.Add(f.stage, f.reason);
  j.Add("usable", IsUsable()).Add("failures", failed).Add("warnings", warnings);
  return j;
}

JsonObject PipelineSummary::TimingJson() const {
  JsonObject by_stage;
  for (const StageReport& s : stages)
    if (s.ran) by_stage.Add(s.name, s.seconds);
  JsonObject j;
  j.Add("seconds", seconds)
      .Add("stages", by_stage)
      .Add("dic_subsets_per_s", figures.dic_subsets_per_s);
  return j;
}

std::string PipelineSummary::FullReport() const {
  std::string text = fmt::format("Scene {} -> {}\n", scene_name, output_folder);
  for (const auto& s : stages) {
    text += fmt::format("  {:<11} {} {}\n", s.name,
                        s.ran ? fmt::format("{:6.2f} s", s.seconds) : " skipped", s.note);
  }
  for (const StageFailure& f : failures)
    text += fmt::format("  FAILED {}: {} (its figures are null)\n", f.stage, f.reason);
  text += "Key figures (measured / model):\n";
  const auto names = figures.CsvNames();
  const auto values = figures.CsvValues();
  for (std::size_t i = 0; i < names.size(); ++i)
    text += fmt::format("  {:<32} {:.6g}\n", names[i], values[i]);
  if (strain) {
    const auto strain_names = strain->CsvNames();
    const auto strain_values = strain->CsvValues();
    for (std::size_t i = 0; i < strain_names.size(); ++i)
      text += fmt::format("  {:<32} {:.6g}\n", strain_names[i], strain_values[i]);
    text += "  strain compacted depth from the " + strain->depth_from +
            (strain->te_note.empty() ? "" : "; " + strain->te_note) + "\n";
  }
  if (wave) {
    for (const WaveChannel& c : wave->channels) {
      text += fmt::format(
          "  wave {}: speed {:.4g} +- {:.2g} m/s (peak), {:.4g} +- {:.2g} m/s (onset), stress "
          "ratio {:.4g}, return {:.4g} ms, reflection {} (pounder), {} (near-surface DIC)\n",
          c.column, c.speed_peak_m_s, c.speed_peak_sigma_m_s, c.speed_onset_m_s,
          c.speed_onset_sigma_m_s, c.stress_ratio, 1e3 * c.return_time_s,
          !c.reflection.checked        ? "not checked"
          : c.reflection.local_maximum ? "local maximum"
                                       : "none",
          !c.dic_reflection.checked        ? "not checked"
          : c.dic_reflection.local_maximum ? "local maximum"
                                           : "none");
    }
    const WaveFront& f = wave->front;
    if (f.computed) {
      text += fmt::format(
          "  wave front: speed {:.4g} m/s [{:.4g}, {:.4g}] ({} subsets); decay length at t_e "
          "{:.4g} mm, depth of influence {:.4g} mm (crater {:.4g} mm)\n",
          f.speed_m_s, f.speed_ci_m_s[0], f.speed_ci_m_s[1], f.fit_subsets,
          f.displacement_te.decay_length_mm, f.displacement_te.depth_of_influence_mm,
          f.crater_depth_mm);
    }
  }
  for (const auto& w : warnings) text += "  warning: " + w + "\n";
  text += "Outputs:\n";
  for (const auto& o : outputs) text += "  " + o + "\n";
  return text;
}

}  // namespace impactdic
