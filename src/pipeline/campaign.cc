#include "impactdic/pipeline/campaign.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/core/threads.h"
#include "impactdic/core/timer.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/csv.h"
#include "impactdic/io/output_generation.h"
#include "impactdic/pipeline/scene.h"

namespace impactdic {
namespace fs = std::filesystem;
namespace {

constexpr const char* kCampaignCsv = "campaign.csv";
constexpr const char* kRegressionJson = "regression.json";

// A campaign's outputs are one generation of its folder (io/output_generation.h). From scenes it
// replaces the whole folder; from a table (`scene_names` empty) it redoes campaign.csv and
// regression.json and keeps the rest (the scene folders of an earlier campaign).
OutputGenerationOptions CampaignGenerationOptions(const std::vector<Scene>& scenes,
                                                  bool from_table) {
  OutputGenerationOptions o;
  o.command = from_table ? "impactdic campaign --from-table" : "impactdic campaign";
  o.own_names = {kCampaignCsv, kRegressionJson};
  for (const Scene& scene : scenes) o.own_names.push_back(scene.name);
  o.keep_other_entries = from_table;
  return o;
}

// Fits Eq. 4 over the scenes with a usable m_add,max and writes campaign.csv and regression.json
// into `folder` (the staging folder of the campaign's generation).
void FitAndWrite(CampaignSummary* summary, const CampaignOptions& options,
                 const std::string& folder) {
  std::vector<PowerLawSample> samples;
  for (auto& s : summary->scenes) {
    if (s.excluded.empty() &&
        !(std::isfinite(s.figures.added_mass_max_kg) && s.figures.added_mass_max_kg > 0)) {
      s.excluded = fmt::format("no measured m_add,max (got {})", s.figures.added_mass_max_kg);
    }
    if (s.excluded.empty()) {
      samples.push_back({s.mass_kg, s.velocity_m_s, s.area_m2, s.figures.added_mass_max_kg});
    } else {
      LogWarning("campaign: scene {} is left out of the Eq. 4 fit: {}", s.name, s.excluded);
    }
  }
  if (samples.size() >= 5) {
    summary->fit = FitPowerLaw(samples, options.confidence);
    summary->fitted = true;
  } else {
    summary->fit_note = fmt::format(
        "{} of {} scenes have a measured m_add,max; the Eq. 4 regression needs at least 5",
        samples.size(), summary->scenes.size());
    LogWarning("campaign: {}", summary->fit_note);
  }
  const std::string csv = (fs::path(folder) / kCampaignCsv).string();
  std::vector<std::string> names = {"mass_kg", "velocity_m_s", "area_m2"};
  for (const auto& n : SceneFigures{}.CsvNames()) names.push_back(n);
  names.push_back("eq4_fit");
  std::vector<std::vector<std::string>> rows;
  names.insert(names.begin(), "scene");
  for (const auto& s : summary->scenes) {
    std::vector<std::string> row = {s.name, fmt::format("{:.10g}", s.mass_kg),
                                    fmt::format("{:.10g}", s.velocity_m_s),
                                    fmt::format("{:.10g}", s.area_m2)};
    for (double v : s.figures.CsvValues())
      row.push_back(std::isfinite(v) ? fmt::format("{:.10g}", v) : "nan");
    row.push_back(s.excluded.empty() ? "used" : "excluded");
    rows.push_back(row);
  }
  WriteCsvRows(csv, names, rows);
  summary->outputs.push_back(csv);
  const std::string json = (fs::path(folder) / kRegressionJson).string();
  WriteTextFileAtomic(json, summary->RegressionJson().Dump() + "\n");
  summary->outputs.push_back(json);
}

}  // namespace

void CampaignOptions::Check() const {
  CheckValue(!output_folder.empty(), "output_folder", "an empty path", "a folder");
  CheckValue(threads == -1 || IsValidThreadCount(threads), "threads", std::to_string(threads),
             std::string("-1 (each scene's dic.threads) or ") + kThreadCountExpected);
  CheckValue(confidence > 0 && confidence < 1, "confidence", fmt::format("{}", confidence),
             "a level in (0, 1)");
}

JsonObject CampaignSummary::RegressionJson() const {
  JsonObject j;
  j.Add("scenes", static_cast<int>(scenes.size()));
  j.Add("fitted", fitted);
  JsonObject excluded;
  for (const auto& s : scenes)
    if (!s.excluded.empty()) excluded.Add(s.name, s.excluded);
  j.Add("excluded", excluded);
  if (!fitted) {
    j.Add("note", fit_note);
    return j;
  }
  j.Add("c", fit.c).Add("a", fit.a).Add("b", fit.b).Add("g", fit.g);
  j.Add("ci_c", std::vector<double>{fit.ci_c[0], fit.ci_c[1]});
  j.Add("ci_a", std::vector<double>{fit.ci_a[0], fit.ci_a[1]});
  j.Add("ci_b", std::vector<double>{fit.ci_b[0], fit.ci_b[1]});
  j.Add("ci_g", std::vector<double>{fit.ci_g[0], fit.ci_g[1]});
  j.Add("confidence", fit.confidence)
      .Add("r_squared", fit.r_squared)
      .Add("n", static_cast<int>(fit.n));
  j.Add("residual_sd_log", fit.residual_sd);
  j.Add("paper", JsonObject().Add("c", 425.0).Add("a", 0.1).Add("b", 0.2).Add("g", 1.3));
  return j;
}

std::string CampaignSummary::FullReport() const {
  std::string text = fmt::format("Campaign of {} scenes ({:.1f} s)\n", scenes.size(), seconds);
  for (const auto& s : scenes) {
    text +=
        fmt::format("  {:<20} m_p {:6.2f} kg  v0 {:5.2f} m/s  A {:.4f} m^2  m_add,max {:.3f} kg\n",
                    s.name, s.mass_kg, s.velocity_m_s, s.area_m2, s.figures.added_mass_max_kg);
    if (!s.excluded.empty())
      text += "  " + std::string(20, ' ') + "  not in the Eq. 4 fit: " + s.excluded + "\n";
  }
  if (fitted) {
    text += "Eq. 4: " + fit.BriefReport() + "\n";
  } else {
    text += "Eq. 4: not fitted: " + fit_note + "\n";
  }
  for (const auto& o : outputs) text += "  " + o + "\n";
  return text;
}

CampaignSummary RunCampaign(const std::vector<std::string>& scene_paths,
                            const CampaignOptions& options) {
  options.Check();
  if (scene_paths.empty()) {
    throw Error(ErrorKind::kInvalidValue, "scenes", "none", "at least one scene file");
  }
  // Load (and so validate) every scene before running any.
  std::vector<Scene> scenes;
  for (const auto& path : scene_paths) scenes.push_back(LoadScene(path));
  // The new generation replaces the campaign's folder whole: no scene may read from it.
  for (const Scene& scene : scenes)
    CheckOutputFolderHoldsNoInput(scene, options.output_folder, "-o");
  WallTimer timer;
  CampaignSummary summary;
  OutputGeneration generation(options.output_folder,
                              CampaignGenerationOptions(scenes, /*from_table=*/false));
  for (const Scene& scene : scenes) {
    PipelineOptions p;
    p.output_folder = generation.Path(scene.name);
    p.threads = options.threads;
    p.allow_partial = true;  // Its outputs are written; it stays out of the fit (below).
    LogInfo("campaign: scene {} -> {}", scene.name,
            (fs::path(options.output_folder) / scene.name).string());
    const PipelineSummary run = RunScene(scene, p);
    CampaignScene s;
    s.name = scene.name;
    s.mass_kg = scene.model.pounder_mass_kg;
    s.velocity_m_s = std::isfinite(run.figures.impact_velocity_m_s)
                         ? run.figures.impact_velocity_m_s
                         : scene.ImpactVelocity();
    s.area_m2 = scene.model.ContactArea_m2();
    s.figures = run.figures;
    if (!run.IsUsable()) s.excluded = "a stage produced nothing usable: " + run.FailureText();
    summary.scenes.push_back(s);
  }
  FitAndWrite(&summary, options, generation.staging_folder());
  generation.Commit();
  for (auto& o : summary.outputs) o = generation.FinalPath(o);
  summary.seconds = timer.ElapsedSeconds();
  return summary;
}

CampaignSummary RegressCampaignTable(const std::string& csv_path, const CampaignOptions& options) {
  options.Check();
  CsvReadOptions read;
  read.required_columns = {"mass_kg", "velocity_m_s", "area_m2", "added_mass_max_kg"};
  read.allow_non_finite = true;  // A scene without a measurement has nan; it is left out.
  read.text_columns = {"scene", "eq4_fit"};
  const CsvTable table = ReadCsv(csv_path, read);
  const auto has_text = [&](const char* name) {
    return std::find(table.text_names.begin(), table.text_names.end(), name) !=
           table.text_names.end();
  };
  const bool named = has_text("scene"), marked = has_text("eq4_fit");
  CampaignSummary summary;
  for (std::size_t r = 0; r < table.rows(); ++r) {
    CampaignScene s;
    s.name = named ? table.TextColumn("scene")[r] : fmt::format("row {}", r + 1);
    s.mass_kg = table.Column("mass_kg")[r];
    s.velocity_m_s = table.Column("velocity_m_s")[r];
    s.area_m2 = table.Column("area_m2")[r];
    s.figures.added_mass_max_kg = table.Column("added_mass_max_kg")[r];
    if (marked && table.TextColumn("eq4_fit")[r] == "excluded")
      s.excluded = "marked excluded in " + csv_path + " (eq4_fit)";
    if (!(s.mass_kg > 0 && s.velocity_m_s > 0 && s.area_m2 > 0)) {
      throw Error(ErrorKind::kFileFormat, "row of " + s.name,
                  fmt::format("m_p {}, v0 {}, A {}", s.mass_kg, s.velocity_m_s, s.area_m2),
                  "positive mass_kg, velocity_m_s and area_m2")
          .WithFile(csv_path);
    }
    summary.scenes.push_back(s);
  }
  OutputGeneration generation(options.output_folder,
                              CampaignGenerationOptions({}, /*from_table=*/true));
  FitAndWrite(&summary, options, generation.staging_folder());
  generation.Commit();
  for (auto& o : summary.outputs) o = generation.FinalPath(o);
  return summary;
}

}  // namespace impactdic
