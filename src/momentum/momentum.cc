#include "impactdic/momentum/momentum.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/core/numeric.h"
#include "impactdic/core/timer.h"
#include "momentum_internal.h"

namespace impactdic {

void MomentumOptions::Check() const {
  CheckValue(std::isfinite(pounder_mass_kg) && pounder_mass_kg > 0, "momentum.pounder_mass_kg",
             fmt::format("{}", pounder_mass_kg), "> 0 kg");
  CheckValue(std::isfinite(pounder_width_m) && pounder_width_m > 0, "momentum.pounder_width_m",
             fmt::format("{}", pounder_width_m), "> 0 m");
  CheckValue(std::isfinite(depth_m) && depth_m > 0, "momentum.depth_m", fmt::format("{}", depth_m),
             "> 0 m");
  CheckValue(std::isfinite(density_kg_m3) && density_kg_m3 > 0, "momentum.density_kg_m3",
             fmt::format("{}", density_kg_m3), "> 0 kg/m^3");
  CheckValue(grid_cols >= 1, "momentum.grid_cols", fmt::format("{}", grid_cols), ">= 1");
  CheckValue(grid_rows >= 1, "momentum.grid_rows", fmt::format("{}", grid_rows), ">= 1");
  if (rect_mm) {
    const auto& r = *rect_mm;
    CheckValue(std::isfinite(r[0] + r[1] + r[2] + r[3]) && r[0] < r[2] && r[1] < r[3],
               "momentum.rect_mm", fmt::format("[{}, {}, {}, {}]", r[0], r[1], r[2], r[3]),
               "finite x0 < x1 and y0 < y1");
  }
  CheckValue(kVelocityMatchToleranceRange.Contains(velocity_match_tolerance),
             "momentum.velocity_match_tolerance", fmt::format("{}", velocity_match_tolerance),
             "in (0, 1]");
  CheckValue(kSandAccelToleranceRange.Contains(sand_accel_tolerance),
             "momentum.sand_accel_tolerance", fmt::format("{}", sand_accel_tolerance), "in [0, 1)");
  CheckValue(min_valid_fraction > 0 && min_valid_fraction <= 1, "momentum.min_valid_fraction",
             fmt::format("{}", min_valid_fraction), "a fraction of the grid's subsets in (0, 1]");
  sigmoid.Check();
  uncertainty.Check();
}

namespace {

// The correlated grid's columns and rows of subset centres, their steps and a description for
// messages.
struct GridLayout {
  std::vector<double> xs, ys;  // Distinct centre coordinates [mm], sorted.
  double sx = 0, sy = 0;       // Median steps [mm] (NaN for a single column and row).
  double tol = 0;              // Coordinates closer than this are the same [mm].
  std::string region;
};

GridLayout LayoutOf(const KinematicsResult& kin) {
  GridLayout g;
  const auto [xmin_it, xmax_it] = std::minmax_element(kin.x_mm.begin(), kin.x_mm.end());
  const auto [ymin_it, ymax_it] = std::minmax_element(kin.y_mm.begin(), kin.y_mm.end());
  const double extent = std::max({1.0, *xmax_it - *xmin_it, *ymax_it - *ymin_it});
  g.tol = 1e-6 * extent;
  g.xs = UniqueSorted(kin.x_mm, g.tol);
  g.ys = UniqueSorted(kin.y_mm, g.tol);
  g.sx = MedianStep(g.xs);
  g.sy = MedianStep(g.ys);
  if (std::isnan(g.sx)) g.sx = g.sy;
  if (std::isnan(g.sy)) g.sy = g.sx;
  g.region = fmt::format(
      "the correlated grid has subset centres x = [{:.3f}, {:.3f}] mm, y = [{:.3f}, {:.3f}] mm",
      g.xs.front(), g.xs.back(), g.ys.front(), g.ys.back());
  return g;
}

// The subsets inside MomentumOptions::rect_mm.
MomentumGrid GridInRectangle(const KinematicsResult& kin, const MomentumOptions& options,
                             const GridLayout& layout) {
  const auto& [xs, ys, sx, sy, tol, region] = layout;
  MomentumGrid grid;
  const auto& r = *options.rect_mm;
  const double hx = std::isnan(sx) ? 0 : 0.5 * sx, hy = std::isnan(sy) ? 0 : 0.5 * sy;
  const bool inside = r[0] >= xs.front() - hx - tol && r[2] <= xs.back() + hx + tol &&
                      r[1] >= ys.front() - hy - tol && r[3] <= ys.back() + hy + tol;
  if (!inside) {
    throw Error(ErrorKind::kInvalidValue, "momentum.rect_mm",
                fmt::format("[{}, {}, {}, {}] mm", r[0], r[1], r[2], r[3]),
                "a rectangle inside the correlated region (" + region +
                    "): the grid lies outside the correlated region");
  }
  std::vector<double> cx, cy;
  for (std::size_t i = 0; i < kin.subsets; ++i) {
    if (kin.x_mm[i] >= r[0] && kin.x_mm[i] <= r[2] && kin.y_mm[i] >= r[1] && kin.y_mm[i] <= r[3]) {
      grid.subset_ids.push_back(i);
      cx.push_back(kin.x_mm[i]);
      cy.push_back(kin.y_mm[i]);
    }
  }
  if (grid.subset_ids.empty()) {
    throw Error(
        ErrorKind::kInvalidValue, "momentum.rect_mm",
        fmt::format("[{}, {}, {}, {}] mm containing no subset centre", r[0], r[1], r[2], r[3]),
        "a rectangle containing subset centres (" + region + ")");
  }
  grid.cols = static_cast<int>(UniqueSorted(cx, tol).size());
  grid.rows = static_cast<int>(UniqueSorted(cy, tol).size());
  grid.rect_mm = r;
  grid.area_m2 = (r[2] - r[0]) * (r[3] - r[1]) * 1e-6;
  return grid;
}

// grid_cols x grid_rows subsets under the pounder footprint, centred on it, from the first row
// below its bottom edge.
MomentumGrid GridUnderFootprint(const KinematicsResult& kin, const MomentumOptions& options,
                                const GridLayout& layout) {
  const auto& [xs, ys, sx, sy, tol, region] = layout;
  MomentumGrid grid;
  if (std::isnan(sx)) {
    throw Error(ErrorKind::kInvalidValue, "correlated grid", "a single subset",
                "at least two subsets (the grid step defines the cell area), or rect_mm");
  }
  PounderFootprint fp = options.footprint;
  const double half_width = 500 * options.pounder_width_m;
  const double centre_default = 0.5 * (xs.front() + xs.back());
  if (std::isnan(fp.x_left_mm)) fp.x_left_mm = centre_default - half_width;
  if (std::isnan(fp.x_right_mm)) fp.x_right_mm = centre_default + half_width;
  if (std::isnan(fp.bottom_y_mm)) fp.bottom_y_mm = ys.front() - 0.5 * sy;
  const double centre = 0.5 * (fp.x_left_mm + fp.x_right_mm);
  std::vector<double> cols;
  for (double x : xs)
    if (x >= fp.x_left_mm - tol && x <= fp.x_right_mm + tol) cols.push_back(x);
  if (cols.size() < static_cast<std::size_t>(options.grid_cols)) {
    throw Error(ErrorKind::kInvalidValue, "momentum grid",
                fmt::format("{} subset columns under the pounder footprint x = [{:.3f}, {:.3f}] "
                            "mm",
                            cols.size(), fp.x_left_mm, fp.x_right_mm),
                fmt::format("grid_cols = {} columns ({}): the grid lies outside the correlated "
                            "region",
                            options.grid_cols, region));
  }
  std::stable_sort(cols.begin(), cols.end(),
                   [&](double a, double b) { return std::abs(a - centre) < std::abs(b - centre); });
  cols.resize(static_cast<std::size_t>(options.grid_cols));
  std::sort(cols.begin(), cols.end());
  std::vector<double> rows;
  for (double y : ys)
    if (y > fp.bottom_y_mm + tol && rows.size() < static_cast<std::size_t>(options.grid_rows))
      rows.push_back(y);
  if (rows.size() < static_cast<std::size_t>(options.grid_rows)) {
    throw Error(ErrorKind::kInvalidValue, "momentum grid",
                fmt::format("{} subset rows below the pounder's bottom edge y = {:.3f} mm",
                            rows.size(), fp.bottom_y_mm),
                fmt::format("grid_rows = {} rows ({}): the grid lies outside the correlated "
                            "region",
                            options.grid_rows, region));
  }
  for (double y : rows) {
    for (double x : cols) {
      std::size_t found = kin.subsets;
      for (std::size_t i = 0; i < kin.subsets && found == kin.subsets; ++i)
        if (std::abs(kin.x_mm[i] - x) <= tol && std::abs(kin.y_mm[i] - y) <= tol) found = i;
      if (found == kin.subsets) {
        throw Error(ErrorKind::kInvalidValue, "momentum grid",
                    fmt::format("no correlated subset at x = {:.3f} mm, y = {:.3f} mm", x, y),
                    "a complete grid of correlated subsets: the grid lies outside the "
                    "correlated region (" +
                        region + ")");
      }
      grid.subset_ids.push_back(found);
    }
  }
  grid.cols = options.grid_cols;
  grid.rows = options.grid_rows;
  grid.rect_mm = {cols.front() - 0.5 * sx, rows.front() - 0.5 * sy, cols.back() + 0.5 * sx,
                  rows.back() + 0.5 * sy};
  grid.area_m2 = static_cast<double>(grid.subset_ids.size()) * sx * sy * 1e-6;
  return grid;
}

}  // namespace

MomentumGrid SelectMomentumGrid(const KinematicsResult& kin, const MomentumOptions& options) {
  options.Check();
  CheckValue(kin.subsets >= 1 && kin.x_mm.size() == kin.subsets, "kinematics",
             fmt::format("{} subsets", kin.subsets), "a correlated grid");
  const GridLayout layout = LayoutOf(kin);
  MomentumGrid grid = options.rect_mm ? GridInRectangle(kin, options, layout)
                                      : GridUnderFootprint(kin, options, layout);
  grid.mass_kg = options.density_kg_m3 * grid.area_m2 * options.depth_m;
  return grid;
}

namespace {

// "3-5, 9, 12-20" for sorted frame indices.
std::string IndexRanges(const std::vector<std::size_t>& sorted) {
  std::string out;
  for (std::size_t i = 0; i < sorted.size();) {
    std::size_t j = i;
    while (j + 1 < sorted.size() && sorted[j + 1] == sorted[j] + 1) ++j;
    out += (out.empty() ? "" : ", ") +
           (j == i ? fmt::format("{}", sorted[i]) : fmt::format("{}-{}", sorted[i], sorted[j]));
    i = j + 1;
  }
  return out;
}

// The grid means per frame (v_sand, a_sand, valid counts) and the momenta. A frame with fewer
// valid grid subsets than options.min_valid_fraction asks for is unmeasured: v_sand, a_sand,
// p_gran and p_tot are NaN there (a warning names them).
void GridMomentum(const KinematicsResult& kin, const MomentumOptions& options, MomentumResult* r) {
  MomentumSummary& s = r->summary;
  const std::size_t nf = kin.frames, ns = kin.subsets, grid = s.grid.subset_ids.size();
  const std::size_t min_valid = std::max<std::size_t>(
      1, static_cast<std::size_t>(std::ceil(options.min_valid_fraction * grid - 1e-9)));
  const double mp = options.pounder_mass_kg, ms = s.grid.mass_kg;
  r->v_sand_m_s.resize(nf);
  r->a_sand_m_s2.resize(nf);
  r->valid_subsets.resize(nf);
  r->p_pounder_kg_m_s.resize(nf);
  r->p_gran_kg_m_s.resize(nf);
  r->p_total_kg_m_s.resize(nf);
  std::vector<std::size_t> unmeasured;
  for (std::size_t k = 0; k < nf; ++k) {
    std::size_t count = 0, count_a = 0;
    const double v = 1e-3 * MeanOverSubsets(kin.vel_y_mm_s, ns, k, s.grid.subset_ids, &count);
    const double a = 1e-3 * MeanOverSubsets(kin.acc_y_mm_s2, ns, k, s.grid.subset_ids, &count_a);
    r->valid_subsets[k] = static_cast<double>(count);
    r->v_sand_m_s[k] = count >= min_valid ? v : kNaN;
    r->a_sand_m_s2[k] = count >= min_valid && count_a >= min_valid ? a : kNaN;
    if (count < min_valid) unmeasured.push_back(k);
    r->p_pounder_kg_m_s[k] = mp * r->v_pounder_m_s[k];
    r->p_gran_kg_m_s[k] = ms * r->v_sand_m_s[k];
    r->p_total_kg_m_s[k] = r->p_pounder_kg_m_s[k] + r->p_gran_kg_m_s[k];
  }
  s.unmeasured_frames = unmeasured.size();
  if (!unmeasured.empty()) {
    s.warnings.push_back(fmt::format(
        "{} of {} frames have fewer than {} of the {} momentum-grid subsets valid "
        "(momentum.min_valid_fraction = {}): p_gran is NaN there (frames {}, counted from "
        "the first analysed frame)",
        unmeasured.size(), nf, min_valid, grid, options.min_valid_fraction,
        IndexRanges(unmeasured)));
  }
}

// The peak stage is analysed from its start: the first analysed frame (the reference, where the
// soil is at rest) is exposed at or before the impact, to within one DAQ sample (the onset's
// resolution). Else (a dic.first_frame after the impact, a camera started late) t_e, the FIRST
// frame meeting its criteria, may lie before the first frame, and the soil's velocity there and
// its displacements are measured from a soil already in motion: false, *problem says why.
bool PeakStageStartAnalysed(const std::vector<double>& frame_time_s, const SensorSummary& sensor,
                            std::string* problem) {
  const double sample_s = sensor.sample_rate_hz > 0 ? 1 / sensor.sample_rate_hz : 0;
  if (frame_time_s.front() <= sensor.impact_time_s + sample_s) return true;
  *problem = fmt::format(
      "the first analysed frame, at {:.6f} s, is {:.3f} ms after the impact at {:.6f} s: the start "
      "of the peak stage was not analysed (the first frame correlated must be exposed at or "
      "before the impact; check dic.first_frame)",
      frame_time_s.front(), 1e3 * (frame_time_s.front() - sensor.impact_time_s),
      sensor.impact_time_s);
  return false;
}

// When no frame meets the t_e criteria (criteria_met false), the fallback (the frame of the
// maximum soil velocity) stands only if the analysed frames reach the pounder's stop: frames that
// end earlier (dic.last_frame, a short recording) may end inside the peak stage, where the soil's
// velocity still grows and its maximum is just the last frame. Else false, *problem says why.
bool FallbackInsideTheAnalysedFrames(const std::vector<double>& frame_time_s,
                                     const SensorSummary& sensor, bool criteria_met,
                                     std::string* problem) {
  const double last = frame_time_s.back();
  if (criteria_met || (std::isfinite(sensor.stop_time_s) && last >= sensor.stop_time_s))
    return true;
  *problem = fmt::format(
      "no analysed frame meets the t_e criteria, and the frames end at {:.6f} s, {}: the end of "
      "the peak stage may lie after the last frame (check dic.last_frame and the recording's "
      "length)",
      last,
      std::isfinite(sensor.stop_time_s)
          ? fmt::format("{:.3f} ms before the pounder stops at {:.6f} s",
                        1e3 * (sensor.stop_time_s - last), sensor.stop_time_s)
          : std::string("and the pounder does not stop inside the sensor record"));
  return false;
}

// The frame of t_e in [ki, kend] (file comment; *criteria_met: both criteria, not the fallback),
// or none (returns false, *problem says why).
bool FindEndOfPeakStage(const MomentumResult& r, std::size_t ki, std::size_t kend,
                        const MomentumOptions& options, std::size_t* ke_out, bool* criteria_met,
                        std::string* problem) {
  double a_max = 0;
  bool any_measured = false;
  for (std::size_t k = ki; k <= kend; ++k) {
    if (std::isfinite(r.a_sand_m_s2[k])) a_max = std::max(a_max, r.a_sand_m_s2[k]);
    any_measured = any_measured || std::isfinite(r.v_sand_m_s[k]);
  }
  if (!any_measured) {
    *problem = fmt::format(
        "no frame between the impact and the stop (frames {}-{}) has a measured p_gran (at least "
        "momentum.min_valid_fraction = {} of the grid's subsets valid)",
        ki, kend, options.min_valid_fraction);
    return false;
  }
  const double tol_a = options.sand_accel_tolerance * a_max;
  const double tol_v = options.velocity_match_tolerance * r.summary.v_p_max_m_s;
  // later_max[k]: the largest measured soil velocity after frame k (up to the stop).
  std::vector<double> later_max(kend + 2, -std::numeric_limits<double>::infinity());
  for (std::size_t k = kend; k-- > ki;) {
    const double v = r.v_sand_m_s[k + 1];
    later_max[k] = std::isfinite(v) ? std::max(later_max[k + 1], v) : later_max[k + 1];
  }
  std::size_t ke = kend + 1;
  for (std::size_t k = ki; k <= kend && ke > kend; ++k) {
    const double vs = r.v_sand_m_s[k];
    const bool stopped_accelerating = !(r.a_sand_m_s2[k] > tol_a) && later_max[k] <= vs + tol_v;
    if (std::isfinite(vs) && stopped_accelerating && r.v_pounder_m_s[k] - vs <= tol_v) ke = k;
  }
  *criteria_met = ke <= kend;
  if (ke > kend) {
    ke = ki;
    for (std::size_t k = ki; k <= kend; ++k)
      if (std::isfinite(r.v_sand_m_s[k]) && !(r.v_sand_m_s[k] <= r.v_sand_m_s[ke])) ke = k;
  }
  std::vector<std::size_t> gaps;
  for (std::size_t k = ki; k <= ke; ++k)
    if (!std::isfinite(r.v_sand_m_s[k])) gaps.push_back(k);
  if (!gaps.empty()) {
    *problem = fmt::format(
        "frames {} between the impact (frame {}) and the candidate t_e (frame {}) have no measured "
        "p_gran (fewer than momentum.min_valid_fraction = {} of the grid's subsets valid): t_e, "
        "the first frame meeting its criteria, may lie among them",
        IndexRanges(gaps), ki, ke, options.min_valid_fraction);
    return false;
  }
  *ke_out = ke;
  return true;
}

// Sub-frame t_e. Velocities at the frames are central differences, which smear the end of the
// peak stage over +-1 frame, while m_add(t) changes fast there; displacements are not smeared.
// The gap D(t) = z_p(t) - w_sand(t) (pounder penetration minus the grid's mean displacement)
// grows while v_p > v_sand and is constant once they move together; its growth rate
// v_p - v_sand closes about linearly, so D_e - D(t) ~ c (t_e - t)^2 just before t_e. From the
// two frames before ke: sqrt(D_e - D) is linear in t and its zero is t_e (kept in
// [t_{ke-1}, t_ke]). If instead D shrank over the last frame interval, the soil overtook the
// pounder (v_p - v_sand changed sign) and D has its maximum at the crossing: t_e is the vertex of
// the parabola through D at frames ke-2, ke-1, ke (v_p - v_sand linear across the crossing; kept
// in [t_{ke-1}, t_ke]). Where the soil's lead stops growing after the crossing, as in the DEM of
// docs/validation.md and the overtaking chain test, this comes late by ~1/3 frame. Returns where
// t_e lies between frames ke - 1 (0) and ke (1), for the series' values there.
double RefineEndOfPeakStage(const KinematicsResult& kin, const SensorResult& sensor,
                            const MomentumResult& r, std::size_t ki, std::size_t ke,
                            MomentumSummary* s) {
  const std::vector<double>& t = sensor.time_s;
  const std::vector<double>& frame_time_s = r.frame_time_s;
  const std::size_t nf = kin.frames, ns = kin.subsets;
  if (s->t_end_found && ke >= ki + 2 && sensor.penetration_m.size() == t.size() &&
      kin.disp_y_mm.size() == nf * ns) {
    auto gap = [&](std::size_t k) {
      const double w = 1e-3 * MeanOverSubsets(kin.disp_y_mm, ns, k, s->grid.subset_ids);
      const double z =
          SampleSeries(t, sensor.penetration_m, {frame_time_s[k]}, "pounder penetration")[0];
      return z - w;
    };
    const double d_e = gap(ke), d1 = gap(ke - 1), d2 = gap(ke - 2);
    const double t1 = frame_time_s[ke - 1], t2 = frame_time_s[ke - 2], t_ke = frame_time_s[ke];
    if (d_e < d1) {
      // The soil overtook the pounder: t_e is the gap's maximum (v_p = v_sand), the vertex of
      // the parabola through the three frames (v_p - v_sand linear across the crossing).
      const double m21 = (d1 - d2) / (t1 - t2), m1e = (d_e - d1) / (t_ke - t1);
      if (m21 > 0 && m1e < 0) {
        const double t_zero = 0.5 * (t1 + t2) + m21 * 0.5 * (t_ke - t2) / (m21 - m1e);
        s->t_end_peak_daq_s = std::clamp(t_zero, t1, t_ke);
        s->t_end_refined = true;
        return (s->t_end_peak_daq_s - t1) / (t_ke - t1);
      }
      return 1;
    }
    const double s1 = std::sqrt(std::max(d_e - d1, 0.0)), s2 = std::sqrt(std::max(d_e - d2, 0.0));
    if (std::isfinite(s1) && std::isfinite(s2) && s2 > s1 && s1 > 0) {
      const double t_zero = t1 + s1 * (t1 - t2) / (s2 - s1);
      s->t_end_peak_daq_s = std::clamp(t_zero, t1, frame_time_s[ke]);
      s->t_end_refined = true;
      return (s->t_end_peak_daq_s - t1) / (frame_time_s[ke] - t1);
    }
  }
  return 1;
}

// A per-frame series at t_e: interpolated between frames ke - 1 and ke at fraction w (1: frame
// ke's value).
double AtEndOfPeakStage(const std::vector<double>& series, std::size_t ke, double w) {
  return w >= 1 ? series[ke] : series[ke - 1] + w * (series[ke] - series[ke - 1]);
}

// Added mass at the DAQ rate from the impact to t_e, and the Eq. 5 fit.
void AddedMassAndFit(const SensorResult& sensor, const MomentumOptions& options,
                     MomentumResult* r) {
  MomentumSummary& s = r->summary;
  const SensorSummary& ss = sensor.summary;
  const std::vector<double>& t = sensor.time_s;
  const std::vector<double>& v = sensor.velocity_m_s;
  const std::size_t n = t.size();
  const double mp = options.pounder_mass_kg;
  for (std::size_t i = std::min(ss.impact_index, n - 1); i < n && t[i] <= s.t_end_peak_daq_s; ++i) {
    if (v[i] <= 0) continue;
    r->added_mass_time_after_impact_s.push_back(t[i] - ss.impact_time_s);
    r->added_mass_daq_kg.push_back(s.p_max_kg_m_s / v[i] - mp);
  }
  if (!options.fit_sigmoid) return;
  std::size_t stride = 1;
  if (ss.sample_rate_hz > 0 && ss.cutoff_hz > 0)
    stride = std::max<std::size_t>(
        1, static_cast<std::size_t>(std::lround(ss.sample_rate_hz / (2 * ss.cutoff_hz))));
  if (r->added_mass_daq_kg.size() < 6 * stride) stride = 1;
  // The thinned samples end at the last one before t_e and step back from there: the fit's data
  // always reach t_e. Stepping forward from the impact's sample instead would end anywhere in
  // the last stride before t_e, and as the onset's sample or t_e moved by a DAQ sample the fit
  // lost or gained its last point (up to 2 % of M on the small synthetic scene, where the data
  // end on the sigmoid's shoulder).
  std::vector<double> ft, fm;
  const std::size_t count = r->added_mass_daq_kg.size();
  for (std::size_t i = count > 0 ? (count - 1) % stride : 0; i < count; i += stride) {
    ft.push_back(r->added_mass_time_after_impact_s[i]);
    fm.push_back(r->added_mass_daq_kg[i]);
  }
  try {
    s.sigmoid = FitSigmoid(ft, fm, options.sigmoid);
    s.sigmoid_fitted = true;
    if (!s.sigmoid.converged) s.warnings.push_back("sigmoid fit: " + s.sigmoid.message);
  } catch (const Error& e) {
    s.warnings.push_back(std::string("sigmoid fit skipped: ") + e.what());
  }
}

}  // namespace

namespace internal {

MomentumResult AnalyzeMomentumOnGrid(const KinematicsResult& kin,
                                     const std::vector<double>& frame_time_s,
                                     const SensorResult& sensor, const MomentumOptions& options,
                                     const MomentumGrid& grid) {
  const std::size_t nf = kin.frames;
  const SensorSummary& ss = sensor.summary;
  MomentumResult r;
  MomentumSummary& s = r.summary;
  s.grid = grid;
  s.impact_velocity_m_s = ss.impact_velocity_m_s;
  const double mp = options.pounder_mass_kg;

  r.frame_time_s = frame_time_s;
  r.v_pounder_m_s = SampleSeries(sensor.time_s, sensor.velocity_m_s, frame_time_s,
                                 "pounder velocity at the frames");
  r.added_mass_kg.assign(nf, kNaN);
  GridMomentum(kin, options, &r);

  // p_max at the DAQ rate between the impact and the stop.
  const std::vector<double>& t = sensor.time_s;
  const std::vector<double>& v = sensor.velocity_m_s;
  const std::size_t n = t.size();
  std::size_t i_stop = std::isfinite(ss.stop_time_s)
                           ? static_cast<std::size_t>(
                                 std::lower_bound(t.begin(), t.end(), ss.stop_time_s) - t.begin())
                           : n - 1;
  i_stop = std::min(i_stop, n - 1);
  std::size_t i_max = std::min(ss.impact_index, n - 1);
  for (std::size_t i = i_max; i <= i_stop; ++i)
    if (v[i] > v[i_max]) i_max = i;
  s.v_p_max_m_s = v[i_max];
  s.p_max_kg_m_s = mp * v[i_max];
  s.t_p_max_s = t[i_max];

  // Frames of the peak stage: from the first frame at/after the impact to the last before stop.
  std::size_t ki = 0;
  while (ki < nf && frame_time_s[ki] < ss.impact_time_s) ++ki;
  if (ki >= nf) {
    throw Error(ErrorKind::kInvalidValue, "frame times",
                fmt::format("the last frame at {:.6g} s", frame_time_s.back()),
                fmt::format("frames after the impact at {:.6g} s", ss.impact_time_s));
  }
  std::size_t kend = nf - 1;
  if (std::isfinite(ss.stop_time_s))
    while (kend > ki && frame_time_s[kend] > ss.stop_time_s) --kend;
  if (kend <= ki + 1) {
    throw Error(ErrorKind::kInvalidValue, "frame times",
                fmt::format("{} frames between the impact ({:.6g} s) and the stop ({:.6g} s)",
                            kend + 1 - ki, ss.impact_time_s, ss.stop_time_s),
                "at least 3 frames in the peak and plateau stages");
  }
  std::size_t ke = nf;
  if (!PeakStageStartAnalysed(frame_time_s, ss, &s.t_end_problem) ||
      !FindEndOfPeakStage(r, ki, kend, options, &ke, &s.t_end_found, &s.t_end_problem) ||
      !FallbackInsideTheAnalysedFrames(frame_time_s, ss, s.t_end_found, &s.t_end_problem)) {
    s.t_end_found = false;
    s.warnings.push_back(
        "t_e is not measurable: " + s.t_end_problem +
        "; so t_e, the conservation error, m_add(t), m_add,max, the sigmoid fit, v_sand,max and "
        "the momentum ratio (Eq. 11) are NaN");
    return r;
  }
  // v_sand,max over the peak and plateau stages (the measured frames).
  for (std::size_t k = ki; k <= kend; ++k)
    if (std::isfinite(r.v_sand_m_s[k]) && !(r.v_sand_m_s[k] <= s.v_sand_max_m_s))  // NaN-safe max
      s.v_sand_max_m_s = r.v_sand_m_s[k];
  if (!s.t_end_found) {
    s.warnings.push_back(fmt::format(
        "no frame where the soil stops accelerating and moves with the pounder (within {:.0f} % "
        "of v_p,max); t_e is the frame of the maximum soil velocity",
        100 * options.velocity_match_tolerance));
  }
  s.end_frame = ke;
  s.t_end_peak_daq_s = frame_time_s[ke];
  const double w_te = RefineEndOfPeakStage(kin, sensor, r, ki, ke, &s);
  const double p_total_te = AtEndOfPeakStage(r.p_total_kg_m_s, ke, w_te);
  s.p_gran_te_kg_m_s = AtEndOfPeakStage(r.p_gran_kg_m_s, ke, w_te);
  s.v_sand_te_m_s = AtEndOfPeakStage(r.v_sand_m_s, ke, w_te);
  s.t_end_peak_s = s.t_end_peak_daq_s - ss.impact_time_s;
  s.momentum_conservation_error = std::abs(p_total_te - s.p_max_kg_m_s) / s.p_max_kg_m_s;
  for (std::size_t k = ki; k <= ke; ++k)
    if (r.v_pounder_m_s[k] > 0) r.added_mass_kg[k] = s.p_max_kg_m_s / r.v_pounder_m_s[k] - mp;
  // m_add,max = m_add(t_e) with the pounder velocity at t_e from the DAQ-rate record.
  const double v_te = SampleSeries(t, v, {s.t_end_peak_daq_s}, "pounder velocity at t_e")[0];
  s.added_mass_max_kg = v_te > 0 ? s.p_max_kg_m_s / v_te - mp : r.added_mass_kg[ke];
  s.momentum_ratio = s.added_mass_max_kg * s.v_sand_max_m_s / (mp * s.v_p_max_m_s);
  if (s.momentum_conservation_error > 0.1) {
    s.warnings.push_back(fmt::format("momentum is not conserved to 10 % at t_e (error {:.1f} %)",
                                     100 * s.momentum_conservation_error));
  }
  AddedMassAndFit(sensor, options, &r);
  return r;
}

}  // namespace internal

MomentumResult AnalyzeMomentum(const KinematicsResult& kin, const std::vector<double>& frame_time_s,
                               const SensorResult& sensor, const MomentumOptions& options) {
  WallTimer timer;
  options.Check();
  const std::size_t nf = kin.frames;
  CheckValue(frame_time_s.size() == nf, "frame times", fmt::format("{}", frame_time_s.size()),
             fmt::format("one per frame ({})", nf));
  CheckValue(std::isfinite(sensor.summary.impact_time_s) && !sensor.time_s.empty(),
             "sensor results", "no impact time", "a processed sensor record");
  const MomentumGrid grid = SelectMomentumGrid(kin, options);
  MomentumResult r = internal::AnalyzeMomentumOnGrid(kin, frame_time_s, sensor, options, grid);
  EstimateMomentumUncertainty(kin, sensor, options, &r);
  MomentumSummary& s = r.summary;
  s.seconds = timer.ElapsedSeconds();
  for (const auto& w : s.warnings) LogWarning("momentum: {}", w);
  return r;
}

std::string MomentumSummary::BriefReport() const {
  return fmt::format(
             "p_max = {:.4g} kg m/s, t_e = {:.3f} ms, conservation error = {:.2f} %, m_add,max = "
             "{:.4g} kg, momentum ratio = {:.4g}",
             p_max_kg_m_s, 1e3 * t_end_peak_s, 100 * momentum_conservation_error, added_mass_max_kg,
             momentum_ratio) +
         (t_end_problem.empty() ? "" : "; t_e is not measurable: " + t_end_problem);
}

std::string MomentumSummary::FullReport() const {
  std::string r;
  r += fmt::format("grid                  {} x {} subsets, area {:.6g} m^2, mass {:.4g} kg\n",
                   grid.cols, grid.rows, grid.area_m2, grid.mass_kg);
  r += fmt::format("p_max                 {:.5g} kg m/s (v_p,max {:.4f} m/s)\n", p_max_kg_m_s,
                   v_p_max_m_s);
  r += fmt::format("t_e                   {:.4f} ms after impact{}\n", 1e3 * t_end_peak_s,
                   !t_end_problem.empty() ? " (not measurable)"
                   : t_end_found          ? ""
                                          : " (fallback: max soil velocity)");
  r += fmt::format("conservation error    {:.3f} %\n", 100 * momentum_conservation_error);
  r += fmt::format("m_add,max             {:.5g} kg\n", added_mass_max_kg);
  r += fmt::format("v_sand,max            {:.4f} m/s\n", v_sand_max_m_s);
  r += fmt::format("momentum ratio        {:.4f}\n", momentum_ratio);
  if (sigmoid_fitted) r += "sigmoid (Eq. 5)       " + sigmoid.BriefReport() + "\n";
  for (const auto& w : warnings) r += "warning: " + w + "\n";
  return r;
}

JsonObject MomentumSummary::ToJson() const {
  JsonObject j;
  j.Add("p_max_kg_m_s", p_max_kg_m_s)
      .Add("t_end_peak_s", t_end_peak_s)
      .Add("momentum_conservation_error", momentum_conservation_error)
      .Add("added_mass_max_kg", added_mass_max_kg)
      .Add("sigmoid_b_per_s", sigmoid_fitted ? sigmoid.b_per_s : kNaN)
      .Add("sigmoid_T_s", sigmoid_fitted ? sigmoid.T_s : kNaN)
      .Add("momentum_ratio", momentum_ratio)
      .Add("v_sand_max_m_s", v_sand_max_m_s)
      .Add("sigmoid_M_kg", sigmoid_fitted ? sigmoid.M_kg : kNaN)
      .Add("grid_mass_kg", grid.mass_kg)
      .Add("grid_area_m2", grid.area_m2)
      .Add("t_end_found", t_end_found)
      .Add("t_end_problem", t_end_problem)
      .Add("warnings", warnings)
      .Add("impact_velocity_m_s", impact_velocity_m_s)
      .Add("p_gran_te_kg_m_s", p_gran_te_kg_m_s)
      .Add("v_sand_te_m_s", v_sand_te_m_s)
      .Add("uncertainty", UncertaintyJson(*this));
  return j;
}

}  // namespace impactdic
