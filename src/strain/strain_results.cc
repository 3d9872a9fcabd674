#include "impactdic/strain/strain_results.h"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/io/results_io.h"
#include "impactdic/io/results_layout.h"

namespace impactdic {
namespace L = results_layout;
namespace {

// Every double dataset of /strain, bound to `r` (StrainResult, const or not).
template <typename R>
auto Datasets(R& r) {
  auto& g = r.gradient;
  auto& s = r.field;
  using Vector = std::remove_reference_t<decltype((g.dudx))>;
  return std::vector<DatasetBinding<Vector>>{
      {L::kStrainDudx, "1", "displacement gradient du/dX (x right, y down, reference)", &g.dudx},
      {L::kStrainDudy, "1", "displacement gradient du/dY", &g.dudy},
      {L::kStrainDvdx, "1", "displacement gradient dv/dX", &g.dvdx},
      {L::kStrainDvdy, "1", "displacement gradient dv/dY", &g.dvdy},
      {L::kStrainExx, "1", "small strain eps_xx = du/dX (tension positive)", &s.exx},
      {L::kStrainEyy, "1", "small strain eps_yy = dv/dY (tension positive)", &s.eyy},
      {L::kStrainExy, "1", "small strain eps_xy = (du/dY + dv/dX) / 2 (tensor shear)", &s.exy},
      {L::kStrainGxx, "1", "Green-Lagrange E_xx of (H + H^T + H^T H) / 2 (tension positive)",
       &s.gxx},
      {L::kStrainGyy, "1", "Green-Lagrange E_yy (tension positive)", &s.gyy},
      {L::kStrainGxy, "1", "Green-Lagrange E_xy (tensor shear)", &s.gxy},
      {L::kStrainEpsV, "1", "volumetric strain -(eps_xx + eps_yy), COMPRESSION positive", &s.eps_v},
      {L::kStrainEps1, "1", "major principal small strain eps_1 >= eps_2", &s.eps_1},
      {L::kStrainEps2, "1", "minor principal small strain eps_2", &s.eps_2},
      {L::kStrainTheta1, "rad",
       "direction of eps_1 from +x towards +y (y down: clockwise on screen), in (-pi/2, pi/2]",
       &s.theta_1_rad},
      {L::kStrainGammaMax, "1", "maximum engineering shear strain eps_1 - eps_2 (>= 0)",
       &s.gamma_max},
      {L::kStrainExxRate, "1/s", "d eps_xx / dt (the velocity's time differences)", &s.exx_rate},
      {L::kStrainEyyRate, "1/s", "d eps_yy / dt", &s.eyy_rate},
      {L::kStrainExyRate, "1/s", "d eps_xy / dt", &s.exy_rate},
      {L::kStrainEpsVRate, "1/s", "d eps_v / dt (compression positive)", &s.eps_v_rate},
      {L::kStrainGammaMaxRate, "1/s", "d gamma_max / dt", &s.gamma_max_rate},
      {L::kStrainDensity, "kg/m^3", "dry density rho_d / (1 - eps_v)", &r.density_kg_m3},
  };
}

// The number attributes (name, value) of `r` (StrainResult, const or not).
template <typename R>
auto NumberAttributes(R& r) {
  using Number = std::remove_reference_t<decltype((r.surface_y_px))>;
  return std::vector<std::pair<const char*, Number*>>{
      {"compacted_area_te_mm2", &r.zone_te.area_mm2},
      {"compacted_depth_te_mm", &r.zone_te.depth_mm},
      {"compacted_area_end_mm2", &r.zone_end.area_mm2},
      {"compacted_depth_end_mm", &r.zone_end.depth_mm},
      {"dry_density_kg_m3", &r.dry_density_kg_m3},
      {"surface_y_px", &r.surface_y_px},
      {"compaction_threshold", &r.options.compaction_threshold},
      {"shear_band_threshold", &r.options.shear_band_threshold}};
}

}  // namespace

std::string StrainMeasure::Name() const {
  const std::string p = path;
  return p.substr(p.rfind('/') + 1);
}

std::vector<StrainMeasure> StrainMeasures(const StrainResult& result) {
  std::vector<StrainMeasure> m;
  for (const auto& d : Datasets(result)) m.push_back({d.path, d.units, d.description, d.values});
  return m;
}

const char* StrainConventionText() {
  return "image axes x right, y DOWN, reference (first frame) coordinates; H = [[du/dX, du/dY], "
         "[dv/dX, dv/dY]]; small strain (H + H^T) / 2 and Green-Lagrange (H + H^T + H^T H) / 2, "
         "tension positive; eps_v = -(eps_xx + eps_yy), COMPRESSION positive (plane strain); "
         "eps_1 >= eps_2 principal small strains, theta_1_rad from +x towards +y; gamma_max = "
         "eps_1 - eps_2 (engineering shear); rates by the velocity's time differences [1/s]";
}

void WriteStrainResults(H5Writer& out, const StrainResult& result) {
  const StrainResult& r = result;
  const Dims dims{r.field.frames, r.field.subsets};
  out.Remove(L::kStrainGroup);
  for (const auto& d : Datasets(r)) out.Write(d.path, *d.values, dims, d.units, d.description);
  out.Write(L::kStrainShearBand, r.shear_band, dims, "1",
            "1 = ridge of gamma_max above shear_band_threshold (a shear band), else 0");
  out.SetAttribute(L::kStrainGroup, L::kStrainGradientAttr,
                   kStrainGradientNames.Name(r.options.gradient));
  out.SetAttribute(L::kStrainGroup, L::kStrainConventionAttr, StrainConventionText());
  out.SetAttribute(L::kStrainGroup, "window", static_cast<double>(r.options.window));
  for (const auto& [name, value] : NumberAttributes(r))
    out.SetAttribute(L::kStrainGroup, name, *value);
  out.SetAttribute(L::kStrainGroup, "compacted_te_frame",
                   r.te_known ? static_cast<double>(r.zone_te.frame) : kNaN);
  out.SetAttribute(L::kStrainGroup, "compacted_end_frame", static_cast<double>(r.zone_end.frame));
  out.SetAttribute(L::kStrainGroup, "compacted_te_note", r.te_known ? "" : r.te_note);
  out.SetAttribute(L::kStrainGroup, "depth_from", r.depth_from);
}

StrainResult ReadStrainResults(const H5Reader& in, const std::string& file) {
  if (!in.Exists(L::kStrainGroup)) {
    throw Error(ErrorKind::kFileFormat, L::kStrainGroup, "missing",
                "a /strain group (scene key strain.enabled: true)")
        .WithFile(file);
  }
  StrainResult r;
  Dims first;
  for (const auto& d : Datasets(r)) {
    Dims dims;
    *d.values = in.ReadDouble(d.path, &dims);
    if (first.empty()) first = dims;
    if (dims.size() != 2 || dims != first) {
      throw Error(ErrorKind::kFileFormat, d.path, fmt::format("{} dimensions", dims.size()),
                  "[frames x subsets] like the other /strain datasets")
          .WithFile(file);
    }
  }
  r.gradient.frames = r.field.frames = first[0];
  r.gradient.subsets = r.field.subsets = first[1];
  Dims band_dims;
  for (std::int32_t v : in.ReadInt(L::kStrainShearBand, &band_dims))
    r.shear_band.push_back(static_cast<std::uint8_t>(v != 0));
  if (band_dims != first) {
    throw Error(ErrorKind::kFileFormat, L::kStrainShearBand, "another shape",
                "[frames x subsets] like the other /strain datasets")
        .WithFile(file);
  }
  r.options.enabled = true;
  r.options.gradient = kStrainGradientNames.Parse(
      in.ReadStringAttribute(L::kStrainGroup, L::kStrainGradientAttr),
      std::string(L::kStrainGroup) + " attribute " + L::kStrainGradientAttr);
  r.options.window =
      static_cast<int>(std::lround(in.ReadNumberAttribute(L::kStrainGroup, "window")));
  for (const auto& [name, value] : NumberAttributes(r))
    *value = in.ReadNumberAttribute(L::kStrainGroup, name);
  const double te_frame = in.ReadNumberAttribute(L::kStrainGroup, "compacted_te_frame");
  r.te_known = std::isfinite(te_frame);
  if (r.te_known) r.zone_te.frame = static_cast<std::size_t>(std::lround(te_frame));
  r.zone_end.frame = static_cast<std::size_t>(
      std::lround(in.ReadNumberAttribute(L::kStrainGroup, "compacted_end_frame")));
  r.te_note = in.ReadStringAttribute(L::kStrainGroup, "compacted_te_note");
  r.depth_from = in.ReadStringAttribute(L::kStrainGroup, "depth_from");
  return r;
}

}  // namespace impactdic
