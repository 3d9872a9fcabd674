// strain: the strain fields of the correlated soil (strain/strain.h, docs/strain.md), the density,
// the compacted zone at t_e (from the momentum stage) and at the last frame next to the crater
// depths (from the model stage and the sensor record), and the shear bands. Only with
// strain.enabled; the samples the kinematics leave out (momentum.max_sigma_px / max_sigma_ratio)
// are left out here too.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/numeric.h"
#include "impactdic/io/dic_results.h"
#include "impactdic/momentum/scene_analysis.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/run_data.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/strain/strain.h"
#include "impactdic/strain/strain_results.h"
#include "scene_inputs.h"
#include "stage.h"

namespace impactdic::stages {
namespace {

// The subset warp's gradient of the correlation (/dic/*_warp, DicOptions::keep_warp_gradient,
// which the correlate stage sets for strain.gradient: warp), NaN where the series' sample is not
// valid (the kinematics' rule). The table's *_warp columns are not among those `series` borrows.
DisplacementGradient WarpGradient(const Scene& scene, const DicResultsTable& table,
                                  const CorrelationSeries& series) {
  const std::size_t n = series.frames * series.subsets;
  for (const std::vector<double>* c :
       {&table.dudx_warp, &table.dudy_warp, &table.dvdx_warp, &table.dvdy_warp}) {
    if (c->size() != n) {
      throw Error(ErrorKind::kInvalidValue, "strain.gradient", "warp",
                  "correlation results with the subset warp's gradient (/dic/dudx_warp ...: "
                  "DicOptions::keep_warp_gradient), or strain.gradient: fit")
          .WithFile(scene.path);
    }
  }
  DisplacementGradient g;
  g.frames = series.frames;
  g.subsets = series.subsets;
  g.dudx.assign(n, kNaN);
  g.dudy.assign(n, kNaN);
  g.dvdx.assign(n, kNaN);
  g.dvdy.assign(n, kNaN);
  for (std::size_t j = 0; j < n; ++j) {
    const bool valid = (series.valid.empty() || series.valid[j] != 0) &&
                       std::isfinite(series.u_px[j]) && std::isfinite(series.v_px[j]);
    if (!valid) continue;
    g.dudx[j] = table.dudx_warp[j];
    g.dudy[j] = table.dudy_warp[j];
    g.dvdx[j] = table.dvdx_warp[j];
    g.dvdy[j] = table.dvdy_warp[j];
  }
  return g;
}

// The displacement gradient the scene asks for (strain.gradient).
DisplacementGradient GradientOfScene(const Scene& scene, const DicResultsTable& table,
                                     const CorrelationSeries& series) {
  if (scene.strain.gradient == StrainGradient::kWarp) return WarpGradient(scene, table, series);
  try {
    return FitDisplacementGradient(series, scene.strain.window);
  } catch (Error& e) {  // strain.window against the correlation's grid: the scene's key.
    if (e.where() == "strain.window" && e.file().empty()) e.WithFile(scene.path);
    throw;
  }
}

// The frame of t_e (the momentum stage's end of the peak stage), or why there is none.
std::optional<std::size_t> TeFrame(const SceneRunData& d, std::size_t frames, std::string* note) {
  if (!d.momentum) {
    *note = "t_e is not known: the momentum stage did not run (it needs the sensor record)";
    return std::nullopt;
  }
  const MomentumSummary& m = d.momentum->summary;
  if (!std::isfinite(m.t_end_peak_s) || m.end_frame >= frames) {
    *note = "t_e was not measured: " +
            (m.t_end_problem.empty() ? std::string("no frame of t_e") : m.t_end_problem);
    return std::nullopt;
  }
  return m.end_frame;
}

// Whether any strain is finite after the first reference (row 0, where the fit and the warp give
// 0 for every valid subset).
bool AnyStrainAfterReference(const StrainField& s) {
  if (s.eps_v.size() <= s.subsets) return false;
  return std::any_of(s.eps_v.begin() + static_cast<std::ptrdiff_t>(s.subsets), s.eps_v.end(),
                     [](double e) { return std::isfinite(e); });
}

// The strain result of the series (the gradient, every measure, density, bands, zones).
StrainResult ComputeStrainResult(const StageContext& c, const CorrelationSeries& series) {
  const Scene& scene = c.scene;
  const SceneRunData& d = c.data;
  StrainResult r;
  r.options = scene.strain;
  r.gradient = GradientOfScene(scene, *d.dic, series);
  r.field = ComputeStrain(r.gradient, d.timeline.fps);
  r.dry_density_kg_m3 = scene.model.density_kg_m3;
  r.density_kg_m3 = DensityField(r.field, r.dry_density_kg_m3);
  r.shear_band = ShearBands(r.field, series, r.options);
  if (scene.momentum.surface_y_px) {
    r.depth_from = "momentum.surface_y_px";
    r.surface_y_px = *scene.momentum.surface_y_px;
  } else {
    r.depth_from = "grid top row";
    r.surface_y_px = kNaN;
  }
  const std::size_t frames = r.field.frames;
  r.zone_end =
      FindCompactedZone(r.field, series, frames - 1, r.options, d.mm_per_px, r.surface_y_px);
  if (const std::optional<std::size_t> te = TeFrame(d, frames, &r.te_note)) {
    r.te_known = true;
    r.zone_te = FindCompactedZone(r.field, series, *te, r.options, d.mm_per_px, r.surface_y_px);
  }
  if (!AnyStrainAfterReference(r.field)) {
    // Nothing measured (the last frame may be the reference): no zone, not an empty one.
    r.zone_end.area_mm2 = r.zone_end.depth_mm = kNaN;
    r.zone_te.area_mm2 = r.zone_te.depth_mm = kNaN;
  }
  if (!std::isfinite(r.surface_y_px)) {
    double top = series.y_px.front();
    for (double y : series.y_px) top = std::min(top, y);
    r.surface_y_px = top;  // As FindCompactedZone took it.
  }
  return r;
}

// The strain figures, next to the crater depths of the model and the sensor record (NaN when
// their stage did not run).
StrainFigures FiguresOf(const StrainResult& r, const SceneRunData& d) {
  StrainFigures s;
  s.gradient = kStrainGradientNames.Name(r.options.gradient);
  s.depth_from = r.depth_from;
  s.te_note = r.te_known ? "" : r.te_note;
  s.compacted_area_te_mm2 = r.zone_te.area_mm2;
  s.compacted_depth_te_mm = r.zone_te.depth_mm;
  s.compacted_area_end_mm2 = r.zone_end.area_mm2;
  s.compacted_depth_end_mm = r.zone_end.depth_mm;
  s.crater_depth_model_mm = d.model ? 1e3 * d.model->summary.crater_depth_m : kNaN;
  s.crater_depth_measured_mm = d.sensor ? 1e3 * d.sensor->summary.final_penetration_m : kNaN;
  return s;
}

// Why the compacted zone is null where FindCompactedZone found no finite strain in its frame: no
// finite strain after the reference is the stage's failure (it measured nothing); a zone at t_e or
// at the last frame alone, a warning.
void ReportUnmeasuredZones(StageContext& c, const StrainResult& r) {
  if (!AnyStrainAfterReference(r.field)) {
    c.summary.failures.push_back(
        {"strain", fmt::format("no finite strain after the reference frame: in the {} later "
                               "analysed frame(s) every subset is invalid{}, so the compacted "
                               "zone was not measured",
                               r.field.frames - std::min<std::size_t>(r.field.frames, 1),
                               r.options.gradient == StrainGradient::kFit
                                   ? " or has fewer than 3 valid, non-collinear neighbours in "
                                     "its strain.window"
                                   : "")});
    return;
  }
  if (std::isnan(r.zone_end.area_mm2)) {
    c.summary.warnings.push_back(
        "strain: no finite strain in the last analysed frame: the compacted zone at the end is "
        "null");
  }
  if (r.te_known && std::isnan(r.zone_te.area_mm2)) {
    c.summary.warnings.push_back(
        fmt::format("strain: no finite strain in the frame of t_e (analysed frame {}): the "
                    "compacted zone at t_e is null",
                    r.zone_te.frame));
  }
}

class StrainStage : public Stage {
 public:
  const char* name() const override { return "strain"; }

  std::string SkipReason(const StageContext& c) const override {
    if (!c.scene.strain.enabled) return "strain.enabled is false";
    if (!c.data.dic) return "no correlation results";
    return NotListed(c.scene, name());
  }

  std::string Run(StageContext& c) const override {
    SceneRunData& d = c.data;
    RequireScale(c.scene, d.mm_per_px);
    {
      // The rows of /dic borrowed (no copy), without the samples the kinematics leave out (their
      // warning is the kinematics stage's).
      BorrowedCorrelationSeries series(&*d.dic);
      ExcludeUncertainSamplesOfScene(c.scene, &series.series());
      d.strain = ComputeStrainResult(c, series.series());
    }
    const StrainResult& r = *d.strain;
    c.summary.strain = FiguresOf(r, d);
    ReportUnmeasuredZones(c, r);
    const auto zone = [](const CompactedZone& z) {
      return std::isnan(z.area_mm2)
                 ? std::string("not measured (no finite strain)")
                 : fmt::format("{:.4g} mm^2, {:.4g} mm deep", z.area_mm2, z.depth_mm);
    };
    return fmt::format(
        "{} gradient{}; compacted zone (eps_v > {}) at the end {} (from the {}); at t_e {}",
        kStrainGradientNames.Name(r.options.gradient),
        r.options.gradient == StrainGradient::kFit ? fmt::format(" ({0}x{0})", r.options.window)
                                                   : std::string(),
        r.options.compaction_threshold, zone(r.zone_end), r.depth_from,
        r.te_known ? zone(r.zone_te) : std::string("unknown"));
  }
};

}  // namespace

std::unique_ptr<Stage> MakeStrainStage() { return std::make_unique<StrainStage>(); }

}  // namespace impactdic::stages
