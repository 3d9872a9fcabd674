// The campaign's table: campaign.csv rows (written and read back exactly), the Eq. 4 regression,
// the comparison figures, campaign.h5 and regression.json; merging shards; the regression from a
// table.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <iterator>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "campaign_internal.h"
#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/csv.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/json.h"
#include "impactdic/io/output_generation.h"
#include "impactdic/momentum/fit.h"
#include "impactdic/pipeline/campaign.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/render/comparison_figures.h"

namespace impactdic {
namespace fs = std::filesystem;
namespace campaign_internal {
namespace {

constexpr const char* kTextColumns[] = {"scene",      "eq4_fit",     "source",
                                        "status",     "error",       "eq4_excluded_reason",
                                        "scene_hash", "tool_version"};

// Shortest text that reads back to the same double; NaN as "nan".
std::string Num(double v) { return std::isfinite(v) ? fmt::format("{}", v) : "nan"; }

// A cell of text: no comma, quote or line break (the CSV has no quoting).
std::string Cell(std::string text) {
  for (char& c : text) {
    if (c == ',') c = ';';
    if (c == '"') c = '\'';
    if (c == '\n' || c == '\r') c = ' ';
  }
  return text;
}

// The unit of a column, from its name's suffix.
std::string UnitOf(const std::string& name) {
  const auto ends = [&](const char* s) { return name.ends_with(s); };
  if (ends("_per_s")) return "1/s";
  if (ends("_kg_m_s")) return "kg m/s";
  if (ends("_m_s")) return "m/s";
  if (ends("_kg")) return "kg";
  if (ends("_m2")) return "m^2";
  if (ends("_mm")) return "mm";
  if (ends("_m")) return "m";
  if (ends("_g")) return "g";
  if (ends("_s")) return "s";
  return "1";
}

std::vector<std::string> NumericColumnNames() {
  std::vector<std::string> names = {"mass_kg", "velocity_m_s", "area_m2"};
  for (const auto& n : SceneFigures{}.CsvNames()) names.push_back(n);
  for (const char* n : {"test_index", "drop_height_m", "width_m", "relative_penetration_measured",
                        "relative_penetration_model", "wall_time_s", "added_mass_given_kg"})
    names.push_back(n);
  return names;
}

std::vector<double> NumericValues(const CampaignRow& r) {
  std::vector<double> v = {r.mass_kg, r.velocity_m_s, r.area_m2};
  v.insert(v.end(), r.figures.begin(), r.figures.end());
  for (double x :
       {static_cast<double>(r.index), r.drop_height_m, r.width_m, r.RelativePenetrationMeasured(),
        r.RelativePenetrationModel(), r.wall_time_s, r.added_mass_given_kg})
    v.push_back(x);
  return v;
}

}  // namespace

const std::vector<ComparisonSpec>& ComparisonSpecs() {
  static const std::vector<ComparisonSpec> specs = {
      {"fig5_added_mass.png", "Added mass (Fig. 5)", "m_add,max by Eq. 4 [kg]",
       "m_add,max measured [kg]", "added_mass_max_kg", "added_mass_eq4_kg"},
      {"fig7_peak_deceleration.png", "Peak deceleration (Fig. 7)", "simulated [g]", "measured [g]",
       "peak_deceleration_measured_g", "peak_deceleration_model_g"},
      {"fig8_plateau_deceleration.png", "Plateau deceleration (Fig. 8)", "simulated [g]",
       "measured [g]", "plateau_deceleration_measured_g", "plateau_deceleration_model_g"},
      {"fig9_relative_penetration.png", "Relative penetration depth / D (Fig. 9, Eq. 10)",
       "simulated", "measured", "relative_penetration_measured", "relative_penetration_model"},
      {"fig10_momentum_ratio.png", "Momentum ratio p_gran / p_max (Fig. 10, Eq. 11)", "simulated",
       "measured", "momentum_ratio_measured", "momentum_ratio_model"},
      {"wave_attenuation.png", "Wave attenuation against the momentum ratio (Eq. 11)",
       "momentum ratio p_gran / p_max measured [1]",
       "base stress / pounder stress under the pounder [1]", "wave_stress_ratio",
       "momentum_ratio_measured", /*relation=*/true},
  };
  return specs;
}

std::vector<std::string> CampaignFileNames() {
  std::vector<std::string> names = {kCampaignCsv, kCampaignH5, kRegressionJson};
  for (const auto& s : ComparisonSpecs()) names.push_back(s.file);
  return names;
}

std::vector<std::string> RowColumnNames() {
  std::vector<std::string> names = {"scene", "mass_kg", "velocity_m_s", "area_m2"};
  for (const auto& n : SceneFigures{}.CsvNames()) names.push_back(n);
  for (const char* n :
       {"eq4_fit", "test_index", "source", "drop_height_m", "width_m",
        "relative_penetration_measured", "relative_penetration_model", "status", "error",
        "eq4_excluded_reason", "scene_hash", "tool_version", "wall_time_s", "added_mass_given_kg"})
    names.push_back(n);
  return names;
}

std::vector<std::string> RowCells(const CampaignRow& r) {
  std::vector<std::string> c = {Cell(r.name), Num(r.mass_kg), Num(r.velocity_m_s), Num(r.area_m2)};
  for (double v : r.figures) c.push_back(Num(v));
  c.push_back(r.excluded.empty() ? "used" : "excluded");
  c.push_back(fmt::format("{}", r.index));
  c.push_back(Cell(r.source));
  c.push_back(Num(r.drop_height_m));
  c.push_back(Num(r.width_m));
  c.push_back(Num(r.RelativePenetrationMeasured()));
  c.push_back(Num(r.RelativePenetrationModel()));
  for (const std::string* s : {&r.status, &r.error, &r.excluded, &r.scene_hash, &r.tool_version})
    c.push_back(Cell(*s));
  c.push_back(Num(r.wall_time_s));
  c.push_back(Num(r.added_mass_given_kg));
  return c;
}

void WriteRows(const std::string& csv_path, const std::vector<CampaignRow>& rows) {
  std::vector<std::vector<std::string>> cells;
  cells.reserve(rows.size());
  for (const auto& r : rows) cells.push_back(RowCells(r));
  WriteCsvRows(csv_path, RowColumnNames(), cells);
}

std::vector<CampaignRow> ReadRows(const std::string& csv_path) {
  CsvReadOptions read;
  read.required_columns = NumericColumnNames();
  read.allow_non_finite = true;
  read.text_columns.assign(std::begin(kTextColumns), std::end(kTextColumns));
  const CsvTable table = ReadCsv(csv_path, read);
  for (const char* name : kTextColumns) {
    if (std::find(table.text_names.begin(), table.text_names.end(), name) ==
        table.text_names.end()) {
      throw Error(ErrorKind::kFileFormat, "column " + std::string(name), "missing",
                  "a campaign.csv written by impactdic campaign")
          .WithFile(csv_path);
    }
  }
  const std::vector<std::string> figure_names = SceneFigures{}.CsvNames();
  std::vector<CampaignRow> rows(table.rows());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    CampaignRow& r = rows[i];
    const auto num = [&](const std::string& n) { return table.Column(n)[i]; };
    const auto text = [&](const char* n) { return table.TextColumn(n)[i]; };
    r.index = static_cast<int>(num("test_index"));
    r.name = text("scene");
    r.source = text("source");
    r.mass_kg = num("mass_kg");
    r.velocity_m_s = num("velocity_m_s");
    r.area_m2 = num("area_m2");
    r.drop_height_m = num("drop_height_m");
    r.width_m = num("width_m");
    for (std::size_t f = 0; f < figure_names.size(); ++f) r.figures[f] = num(figure_names[f]);
    r.status = text("status");
    r.error = text("error");
    r.excluded = text("eq4_excluded_reason");
    if (r.excluded.empty() && text("eq4_fit") == "excluded") r.excluded = "marked excluded";
    r.scene_hash = text("scene_hash");
    r.tool_version = text("tool_version");
    r.wall_time_s = num("wall_time_s");
    r.added_mass_given_kg = num("added_mass_given_kg");
  }
  return rows;
}

namespace {

double Column(const CampaignRow& r, const std::string& name) {
  if (name == "relative_penetration_measured") return r.RelativePenetrationMeasured();
  if (name == "relative_penetration_model") return r.RelativePenetrationModel();
  return r.Figure(name);
}

// Marks the rows without a usable m_add,max excluded and fits Eq. 4 over the others.
void FitEq4(CampaignSummary* summary, const CampaignOptions& options) {
  std::vector<PowerLawSample> samples;
  for (auto& r : summary->rows) {
    const double m_add = r.Figure("added_mass_max_kg");
    if (r.excluded.empty() && r.status == "failed") r.excluded = "failed: " + r.error;
    if (r.excluded.empty() && !(std::isfinite(m_add) && m_add > 0))
      r.excluded = fmt::format("no measured m_add,max (got {})", m_add);
    if (r.excluded.empty() && !(r.mass_kg > 0 && r.velocity_m_s > 0 && r.area_m2 > 0)) {
      r.excluded = fmt::format("no positive m_p, v0, A (got {}, {}, {})", r.mass_kg, r.velocity_m_s,
                               r.area_m2);
    }
    if (r.excluded.empty()) {
      samples.push_back({r.mass_kg, r.velocity_m_s, r.area_m2, m_add});
    } else {
      LogWarning("campaign: test {} is left out of the Eq. 4 fit: {}", r.name, r.excluded);
    }
  }
  summary->fitted = false;
  if (samples.size() >= 5) {
    try {
      summary->fit = FitPowerLaw(samples, options.confidence);
      summary->fitted = true;
    } catch (const Error& e) {
      summary->fit_note = std::string("the Eq. 4 regression failed: ") + e.what();
    }
  } else {
    summary->fit_note = fmt::format(
        "{} of {} tests have a measured m_add,max; the Eq. 4 regression needs at least 5",
        samples.size(), summary->rows.size());
  }
  if (!summary->fitted) {
    LogWarning("campaign: {}", summary->fit_note);
    summary->warnings.push_back(summary->fit_note);
  }
}

// The comparison fits, and the figures into `folder` if options.figures.
void Compare(CampaignSummary* summary, const CampaignOptions& options, const std::string& folder) {
  summary->comparisons.clear();
  for (const ComparisonSpec& spec : ComparisonSpecs()) {
    ComparisonFigureData data{spec.title, spec.x_label, spec.y_label, {}, !spec.relation};
    for (const auto& r : summary->rows)
      data.points.push_back(
          {Column(r, spec.predicted), Column(r, spec.observed), r.width_m, r.name});
    const ComparisonFit fit = FitComparison(data.points);
    if (spec.relation && fit.n == 0) continue;  // No test has the data: nothing to say.
    summary->comparisons.emplace_back(fs::path(spec.file).stem().string(), fit);
    if (!options.figures) continue;
    if (fit.n == 0) {
      summary->warnings.push_back(std::string(spec.file) + " not drawn: no test has both values");
      continue;
    }
    const std::string png = (fs::path(folder) / spec.file).string();
    PlotComparison(data, png);
    summary->outputs.push_back(png);
  }
}

void WriteH5(const CampaignSummary& s, const std::string& path, const std::string& plan_text) {
  H5Writer out(path);
  out.WriteProvenance(plan_text);
  out.CreateGroup("campaign");
  out.SetAttribute("campaign", "tests_total", static_cast<double>(s.tests_total));
  out.SetAttribute("campaign", "tests_in_file", static_cast<double>(s.rows.size()));
  out.CreateGroup("tests");
  const std::vector<std::string> names = NumericColumnNames();
  if (!s.rows.empty()) {
    std::vector<std::vector<double>> columns(names.size());
    for (const auto& r : s.rows) {
      const std::vector<double> v = NumericValues(r);
      for (std::size_t c = 0; c < names.size(); ++c) columns[c].push_back(v[c]);
    }
    for (std::size_t c = 0; c < names.size(); ++c)
      out.Write("tests/" + names[c], columns[c], UnitOf(names[c]), names[c] + " per test");
  }
  for (const char* text : kTextColumns) {
    std::vector<std::string> values;
    for (const auto& r : s.rows) {
      const std::vector<std::string> cells = RowCells(r);
      const auto all = RowColumnNames();
      values.push_back(cells[std::find(all.begin(), all.end(), text) - all.begin()]);
    }
    std::string json = "[";
    for (std::size_t i = 0; i < values.size(); ++i) json += (i ? ", " : "") + JsonString(values[i]);
    out.SetAttribute("tests", text, json + "]");
  }
  out.CreateGroup("regression");
  out.SetAttribute("regression", "json", s.RegressionJson().Dump());
  out.Commit();
}

}  // namespace

void FitAndWrite(CampaignSummary* summary, const CampaignOptions& options,
                 const std::string& folder, const std::string& plan_text) {
  std::sort(summary->rows.begin(), summary->rows.end(),
            [](const CampaignRow& a, const CampaignRow& b) { return a.index < b.index; });
  FitEq4(summary, options);
  Compare(summary, options, folder);
  const std::string csv = (fs::path(folder) / kCampaignCsv).string();
  WriteRows(csv, summary->rows);
  summary->outputs.push_back(csv);
  const std::string json = (fs::path(folder) / kRegressionJson).string();
  WriteTextFileAtomic(json, summary->RegressionJson().Dump() + "\n");
  summary->outputs.push_back(json);
  const std::string h5 = (fs::path(folder) / kCampaignH5).string();
  WriteH5(*summary, h5, plan_text);
  summary->outputs.push_back(h5);
}

}  // namespace campaign_internal

using namespace campaign_internal;

double CampaignRow::Figure(const std::string& csv_name) const {
  static const std::vector<std::string> names = SceneFigures{}.CsvNames();
  const auto it = std::find(names.begin(), names.end(), csv_name);
  if (it == names.end() || figures.size() != names.size())
    throw Error(ErrorKind::kInvalidValue, "campaign column", csv_name, "a SceneFigures name");
  return figures[static_cast<std::size_t>(it - names.begin())];
}

double CampaignRow::RelativePenetrationMeasured() const {
  return Figure("crater_depth_measured_m") / width_m;
}
double CampaignRow::RelativePenetrationModel() const {
  return Figure("crater_depth_model_m") / width_m;
}

JsonObject CampaignSummary::RegressionJson() const {
  JsonObject j;
  j.Add("tests", static_cast<int>(rows.size()));
  j.Add("tests_total", tests_total);
  j.Add("fitted", fitted);
  JsonObject excluded;
  for (const auto& r : rows)
    if (!r.excluded.empty()) excluded.Add(r.name, r.excluded);
  j.Add("excluded", excluded);
  JsonObject comparison;
  for (const auto& [name, f] : comparisons) {
    comparison.Add(name, JsonObject()
                             .Add("n", f.n)
                             .Add("slope", f.slope)
                             .Add("intercept", f.intercept)
                             .Add("r_squared", f.r_squared)
                             .Add("rms_relative_deviation", f.rms_relative_deviation)
                             .Add("max_relative_deviation", f.max_relative_deviation));
  }
  j.Add("comparison", comparison);
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
  std::string text = fmt::format("Campaign: {} of {} tests ({} resumed, {} failed, {:.1f} s)\n",
                                 rows.size(), tests_total, resumed, failed, seconds);
  for (const auto& r : rows) {
    text += fmt::format(
        "  {:>3} {:<24} m_p {:6.2f} kg  v0 {:5.2f} m/s  A {:.4f} m^2  m_add,max {:.3f} kg  {}\n",
        r.index, r.name, r.mass_kg, r.velocity_m_s, r.area_m2, r.Figure("added_mass_max_kg"),
        r.status);
    if (!r.error.empty()) text += "      error: " + r.error + "\n";
    if (!r.excluded.empty() && r.status != "failed")
      text += "      not in the Eq. 4 fit: " + r.excluded + "\n";
  }
  text += fitted ? "Eq. 4: " + fit.BriefReport() + "\n" : "Eq. 4: not fitted: " + fit_note + "\n";
  for (const auto& [name, f] : comparisons) {
    text += fmt::format(
        "  {:<28} n {:2d}  slope {:.4f}  intercept {:.4g}  R^2 {:.4f}  "
        "rms |obs/pred - 1| {:.4f}\n",
        name, f.n, f.slope, f.intercept, f.r_squared, f.rms_relative_deviation);
  }
  for (const auto& w : warnings) text += "  warning: " + w + "\n";
  for (const auto& o : outputs) text += "  " + o + "\n";
  return text;
}

namespace campaign_internal {

OutputGenerationOptions CampaignLevelGeneration(const std::string& command, bool force) {
  OutputGenerationOptions o;
  o.command = command;
  o.nested_kinds = {"campaign test"};  // Its tests' folders, each a generation of its own.
  o.force = force;
  o.own_names = CampaignFileNames();
  o.keep_other_entries = true;  // The test folders (and anything else impactdic wrote there).
  return o;
}

}  // namespace campaign_internal

CampaignSummary MergeCampaigns(const std::vector<std::string>& folders,
                               const CampaignOptions& options) {
  options.Check();
  if (folders.empty())
    throw Error(ErrorKind::kInvalidValue, "merge folders", "no folder", "shard output folders");
  CampaignSummary summary;
  std::map<int, std::string> holder;  // test index -> folder
  for (const auto& folder : folders) {
    const std::string csv = (fs::path(folder) / kCampaignCsv).string();
    const std::string h5 = (fs::path(folder) / kCampaignH5).string();
    if (!fs::is_regular_file(csv) || !fs::is_regular_file(h5)) {
      throw Error(ErrorKind::kFileNotFound, "merge folders", folder,
                  "a campaign output folder (with campaign.csv and campaign.h5)");
    }
    const int total =
        static_cast<int>(H5Reader(h5).ReadNumberAttribute("/campaign", "tests_total"));
    if (summary.tests_total != 0 && total != summary.tests_total) {
      throw Error(ErrorKind::kInvalidValue, "merge folders",
                  fmt::format("{} holds a campaign of {} tests", folder, total),
                  fmt::format("shards of one campaign ({} tests, as {})", summary.tests_total,
                              holder.begin()->second));
    }
    summary.tests_total = total;
    for (auto& r : ReadRows(csv)) {
      if (holder.count(r.index)) {
        throw Error(
            ErrorKind::kInvalidValue, "merge folders",
            fmt::format("test {} ({}) in both {} and {}", r.index, r.name, holder[r.index], folder),
            "each test in one shard only");
      }
      holder[r.index] = folder;
      summary.rows.push_back(std::move(r));
    }
  }
  std::vector<std::string> missing;
  for (int k = 1; k <= summary.tests_total; ++k)
    if (!holder.count(k)) missing.push_back(std::to_string(k));
  if (!missing.empty()) {
    throw Error(
        ErrorKind::kInvalidValue, "merge folders",
        fmt::format("tests {} of {} missing", fmt::join(missing, ", "), summary.tests_total),
        "the output folders of all shards");
  }
  OutputGeneration generation(options.output_folder,
                              CampaignLevelGeneration("impactdic campaign (merge)", options.force));
  std::string sources = "# merged from:\n";
  for (const auto& f : folders) sources += "#   " + f + "\n";
  FitAndWrite(&summary, options, generation.staging_folder(), sources);
  generation.Commit();
  for (auto& o : summary.outputs) o = generation.FinalPath(o);
  for (const auto& r : summary.rows) summary.failed += r.status == "failed";
  return summary;
}

CampaignSummary RegressCampaignTable(const std::string& csv_path, const CampaignOptions& options) {
  options.Check();
  CsvReadOptions read;
  read.required_columns = {"mass_kg", "velocity_m_s", "area_m2", "added_mass_max_kg"};
  read.allow_non_finite = true;  // A test without a measurement has nan; it is left out.
  read.text_columns.assign(std::begin(kTextColumns), std::end(kTextColumns));  // campaign.csv's
  const CsvTable table = ReadCsv(csv_path, read);
  const auto has_text = [&](const char* name) {
    return std::find(table.text_names.begin(), table.text_names.end(), name) !=
           table.text_names.end();
  };
  const bool named = has_text("scene"), marked = has_text("eq4_fit");
  CampaignSummary summary;
  for (std::size_t i = 0; i < table.rows(); ++i) {
    CampaignRow r;
    r.index = static_cast<int>(i) + 1;
    r.name = named ? table.TextColumn("scene")[i] : fmt::format("row {}", i + 1);
    r.source = csv_path;
    r.status = "ok";
    r.mass_kg = table.Column("mass_kg")[i];
    r.velocity_m_s = table.Column("velocity_m_s")[i];
    r.area_m2 = table.Column("area_m2")[i];
    // Every SceneFigures column the table has (at least added_mass_max_kg).
    const std::vector<std::string> figure_names = SceneFigures{}.CsvNames();
    for (std::size_t f = 0; f < figure_names.size(); ++f)
      if (table.Has(figure_names[f])) r.figures[f] = table.Column(figure_names[f])[i];
    if (table.Has("width_m")) r.width_m = table.Column("width_m")[i];
    if (marked && table.TextColumn("eq4_fit")[i] == "excluded")
      r.excluded = "marked excluded in " + csv_path + " (eq4_fit)";
    if (!(r.mass_kg > 0 && r.velocity_m_s > 0 && r.area_m2 > 0)) {
      throw Error(ErrorKind::kFileFormat, "row of " + r.name,
                  fmt::format("m_p {}, v0 {}, A {}", r.mass_kg, r.velocity_m_s, r.area_m2),
                  "positive mass_kg, velocity_m_s and area_m2")
          .WithFile(csv_path);
    }
    summary.rows.push_back(r);
  }
  summary.tests_total = static_cast<int>(summary.rows.size());
  OutputGeneration generation(
      options.output_folder,
      CampaignLevelGeneration("impactdic campaign (from a table)", options.force));
  CampaignOptions o = options;
  o.figures = false;  // A table has no modelled values to compare.
  FitAndWrite(&summary, o, generation.staging_folder(), "# from table " + csv_path + "\n");
  generation.Commit();
  for (auto& out : summary.outputs) out = generation.FinalPath(out);
  return summary;
}

}  // namespace impactdic
