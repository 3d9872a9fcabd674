// DEM impact scene: the truth measured on the grains and writing the scene (docs/validation.md).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/numeric.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/synth/dem_scene.h"
#include "impactdic/synth/impact_scene.h"
#include "scene_files.h"
#include "strain_truth.h"

namespace impactdic {
namespace {

// Index of the step x step cell (centred on a regular grid of centres) holding ideal pixel q, or
// -1. centres: row-major cols x rows, spacing `step`.
int CellOf(cv::Point2d q, const std::vector<cv::Point2d>& centres, int cols, int rows,
           double step) {
  if (centres.empty()) return -1;
  const int i = static_cast<int>(std::floor((q.x - centres[0].x) / step + 0.5));
  const int j = static_cast<int>(std::floor((q.y - centres[0].y) / step + 0.5));
  if (i < 0 || j < 0 || i >= cols || j >= rows) return -1;
  return j * cols + i;
}

// End of the peak stage on a series (see DemTruth::t_e_s); returns the index or npos.
std::size_t FindPeakEnd(const std::vector<double>& t, const std::vector<double>& v_p,
                        const std::vector<double>& v_sand, double t_pmax, double tol) {
  const std::size_t n = t.size();
  std::size_t last = n;  // the pounder's stop (v_p <= 0) bounds the search
  for (std::size_t i = 0; i < n; ++i)
    if (t[i] > t_pmax && v_p[i] <= 0) {
      last = i;
      break;
    }
  std::vector<double> later_max(n + 1, -std::numeric_limits<double>::infinity());
  for (std::size_t i = last; i-- > 0;) later_max[i] = std::max(later_max[i + 1], v_sand[i]);
  for (std::size_t i = 0; i < last; ++i) {
    if (t[i] < t_pmax) continue;
    if (v_p[i] - v_sand[i] <= tol && later_max[i + 1] <= v_sand[i] + tol) return i;
  }
  return std::string::npos;
}

// The grains (indices into the reference snapshot) whose reference centre q[i] lies in each
// subset's window |q - centre| <= half (x and y); centres row-major cols x rows, spacing `step`.
std::vector<std::vector<std::size_t>> GrainsPerWindow(const std::vector<cv::Point2d>& q,
                                                      const SceneDicGrid& dic, double step,
                                                      double half) {
  std::vector<std::vector<std::size_t>> in(dic.centres_px.size());
  if (dic.centres_px.empty()) return in;
  const cv::Point2d c0 = dic.centres_px[0];
  for (std::size_t g = 0; g < q.size(); ++g) {
    const int i0 = std::max(0, static_cast<int>(std::ceil((q[g].x - c0.x - half) / step)));
    const int i1 =
        std::min(dic.cols - 1, static_cast<int>(std::floor((q[g].x - c0.x + half) / step)));
    const int j0 = std::max(0, static_cast<int>(std::ceil((q[g].y - c0.y - half) / step)));
    const int j1 =
        std::min(dic.rows - 1, static_cast<int>(std::floor((q[g].y - c0.y + half) / step)));
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        const auto cell = static_cast<std::size_t>(j) * static_cast<std::size_t>(dic.cols) +
                          static_cast<std::size_t>(i);
        in[cell].push_back(g);
      }
  }
  return in;
}

// The gradient of the least-squares affine fit of the window grains' displacements (DemTruth::
// dudx): with the reference positions centred on their mean, H = S_ud S_dd^-1 (S the sums of
// outer products). NaN when fewer than 3 grains or det S_dd <= 1e-6 trace(S_dd)^2 (collinear).
void FitGrainGradients(const std::vector<std::vector<std::size_t>>& window,
                       const std::vector<cv::Point2d>& ref_px,
                       const std::vector<std::vector<cv::Point2d>>& px_of_frame, DemTruth& T) {
  const std::size_t N = window.size(), F = px_of_frame.size();
  for (auto* f : {&T.dudx, &T.dudy, &T.dvdx, &T.dvdy}) f->assign(F * N, kNaN);
  T.grains_per_subset.assign(N, 0);
  for (std::size_t c = 0; c < N; ++c) {
    const std::vector<std::size_t>& w = window[c];
    T.grains_per_subset[c] = static_cast<int>(w.size());
    if (w.size() < 3) continue;
    double mx = 0, my = 0;
    for (std::size_t g : w) mx += ref_px[g].x, my += ref_px[g].y;
    mx /= static_cast<double>(w.size()), my /= static_cast<double>(w.size());
    double sxx = 0, sxy = 0, syy = 0;
    for (std::size_t g : w) {
      const double dx = ref_px[g].x - mx, dy = ref_px[g].y - my;
      sxx += dx * dx, sxy += dx * dy, syy += dy * dy;
    }
    const double det = sxx * syy - sxy * sxy;
    if (!(det > 1e-6 * (sxx + syy) * (sxx + syy))) continue;
    for (std::size_t k = 0; k < F; ++k) {
      double sux = 0, suy = 0, svx = 0, svy = 0;  // displacement minus its mean: sums drop it
      for (std::size_t g : w) {
        const double dx = ref_px[g].x - mx, dy = ref_px[g].y - my;
        const double u = px_of_frame[k][g].x - ref_px[g].x, v = px_of_frame[k][g].y - ref_px[g].y;
        sux += u * dx, suy += u * dy, svx += v * dx, svy += v * dy;
      }
      const std::size_t o = k * N + c;
      T.dudx[o] = (sux * syy - suy * sxy) / det;
      T.dudy[o] = (suy * sxx - sux * sxy) / det;
      T.dvdx[o] = (svx * syy - svy * sxy) / det;
      T.dvdy[o] = (svy * sxx - svx * sxy) / det;
    }
  }
}

}  // namespace

void DemScene::ComputeTruth() {
  DemTruth& T = truth_;
  const DemMeta& m = record_.meta;
  const int F = frame_count();
  int kr = 0;
  while (kr + 1 < F && FrameTime(kr + 1) < 0) ++kr;
  T.reference_frame = kr;
  T.frame_time_s.resize(static_cast<std::size_t>(F));
  for (int k = 0; k < F; ++k) T.frame_time_s[static_cast<std::size_t>(k)] = FrameTime(k);
  const ImpactScene& b = *base_;
  const double sx = b.sx_mm_per_px(), sy = b.sy_mm_per_px(), step = spec_.step;
  const DemSnapshot& ref = record_.frames[static_cast<std::size_t>(kr)];
  const std::size_t G = ref.grains.size();

  // Cells of the DIC grid and of the momentum grid at the reference frame.
  const SceneDicGrid& dic = b.dic_grid();
  const SceneMomentumTruth& mt = b.momentum();
  std::vector<int> dic_cell(G), grid_cell(G);
  std::vector<cv::Point2d> ref_mm(G), ref_px(G);
  for (std::size_t i = 0; i < G; ++i) {
    ref_mm[i] = PanelFromDem(ref.grains[i].x_m, ref.grains[i].y_m);
    ref_px[i] = b.IdealFromPanel(ref_mm[i]);
    dic_cell[i] = CellOf(ref_px[i], dic.centres_px, dic.cols, dic.rows, step);
    grid_cell[i] = CellOf(ref_px[i], mt.centres_px, mt.cols, mt.rows, step);
  }
  std::vector<std::vector<cv::Point2d>> px_of_frame(static_cast<std::size_t>(F));
  const std::size_t N = dic.centres_px.size();
  T.grains_per_cell.assign(N, 0);
  std::vector<double> cell_mass(N, 0);
  for (std::size_t i = 0; i < G; ++i)
    if (dic_cell[i] >= 0) {
      ++T.grains_per_cell[static_cast<std::size_t>(dic_cell[i])];
      cell_mass[static_cast<std::size_t>(dic_cell[i])] += ref.grains[i].mass_kg;
    }
  T.u_px.assign(static_cast<std::size_t>(F) * N, 0);
  T.v_px = T.velocity_x_mm_s = T.velocity_y_mm_s = T.u_px;
  T.p_gran_Ns.assign(static_cast<std::size_t>(F), 0);
  std::vector<double> grid_y_m(static_cast<std::size_t>(F), 0);  // sum m y_down
  T.grid_mass_kg = 0;
  for (std::size_t i = 0; i < G; ++i)
    if (grid_cell[i] >= 0) T.grid_mass_kg += ref.grains[i].mass_kg;
  for (int k = 0; k < F; ++k) {
    const DemSnapshot& s = record_.frames[static_cast<std::size_t>(k)];
    const std::size_t o = static_cast<std::size_t>(k) * N;
    std::vector<cv::Point2d>& px = px_of_frame[static_cast<std::size_t>(k)];
    px.resize(G);
    for (std::size_t i = 0; i < G; ++i) {
      const DemGrain& g = s.grains[i];
      px[i] = b.IdealFromPanel(PanelFromDem(g.x_m, g.y_m));
      if (g.id != ref.grains[i].id)
        throw Error(ErrorKind::kFileFormat, "grains.dump", fmt::format("grain id {}", g.id),
                    fmt::format("the same ids in every snapshot (step {})", s.step));
      if (grid_cell[i] >= 0) {
        T.p_gran_Ns[static_cast<std::size_t>(k)] += -g.mass_kg * g.vy_m_s;
        grid_y_m[static_cast<std::size_t>(k)] += -g.mass_kg * g.y_m;
      }
      if (dic_cell[i] < 0) continue;
      const std::size_t c = o + static_cast<std::size_t>(dic_cell[i]);
      const cv::Point2d p = PanelFromDem(g.x_m, g.y_m);
      T.u_px[c] += g.mass_kg * (p.x - ref_mm[i].x) / sx;
      T.v_px[c] += g.mass_kg * (p.y - ref_mm[i].y) / sy;
      T.velocity_x_mm_s[c] += g.mass_kg * g.vx_m_s * 1000;
      T.velocity_y_mm_s[c] += -g.mass_kg * g.vy_m_s * 1000;
    }
    for (std::size_t c = 0; c < N; ++c)
      for (auto* field : {&T.u_px, &T.v_px, &T.velocity_x_mm_s, &T.velocity_y_mm_s})
        (*field)[o + c] = cell_mass[c] > 0 ? (*field)[o + c] / cell_mass[c] : kNaN;
  }
  FitGrainGradients(GrainsPerWindow(ref_px, dic, step, spec_.subset_size / 2.0), ref_px,
                    px_of_frame, T);
  T.bulk_density_kg_m3 = spec_.density_kg_m3;
  T.grid_mass_bulk_kg = spec_.density_kg_m3 * mt.grid_area_mm2 * 1e-6 * m.depth_m;
  T.p_gran_fd_Ns.assign(static_cast<std::size_t>(F), 0);
  for (int k = 0; k < F; ++k) {
    const std::size_t u = static_cast<std::size_t>(k);
    if (k == 0)
      T.p_gran_fd_Ns[u] = (-3 * grid_y_m[0] + 4 * grid_y_m[1] - grid_y_m[2]) /
                          (T.frame_time_s[2] - T.frame_time_s[0]);
    else if (k == F - 1)
      T.p_gran_fd_Ns[u] = (3 * grid_y_m[u] - 4 * grid_y_m[u - 1] + grid_y_m[u - 2]) /
                          (T.frame_time_s[u] - T.frame_time_s[u - 2]);
    else
      T.p_gran_fd_Ns[u] =
          (grid_y_m[u + 1] - grid_y_m[u - 1]) / (T.frame_time_s[u + 1] - T.frame_time_s[u - 1]);
  }
  T.v_sand_m_s.resize(T.p_gran_Ns.size());
  for (std::size_t k = 0; k < T.p_gran_Ns.size(); ++k)
    T.v_sand_m_s[k] = T.p_gran_Ns[k] / T.grid_mass_kg;

  std::unordered_map<std::int64_t, double> grid_mass_of;
  for (std::size_t i = 0; i < G; ++i)
    if (grid_cell[i] >= 0) grid_mass_of[ref.grains[i].id] = ref.grains[i].mass_kg;
  ComputePeakStageTruth(grid_mass_of);
  ComputeWaveTruth();
}

// The base force sensors' figures from the noise-free DAQ record (DemTruth::base_peak_s) and
// the bed's own P-wave speed.
void DemScene::ComputeWaveTruth() {
  DemTruth& T = truth_;
  if (!record_.pwave.empty()) {
    T.pwave = MeasurePWave(record_.pwave);
    if (!T.pwave.problem.empty()) T.notes.push_back("P-wave run: " + T.pwave.problem);
  }
  if (floor_windows() == 0) return;
  const ImpactScene::SensorRecord rec = MakeSensorRecord();
  const SceneBaseSensorOptions& b = spec_.base_sensors;
  const std::size_t n = rec.time_s.size();
  double peak_decel_g = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double t = rec.time_s[i] - rec.impact_daq_time_s;
    if (t >= 0 && rec.accel_true_g[i] - 1 > peak_decel_g)
      peak_decel_g = rec.accel_true_g[i] - 1, T.pounder_peak_decel_s = t;
  }
  T.pounder_peak_stress_Pa =
      spec_.pounder_mass_kg * spec_.g_m_s2 * peak_decel_g / (spec_.width_m * spec_.depth_m);
  for (std::size_t w = 0; w < floor_windows(); ++w) {
    const std::vector<double>& f = rec.base_force_true_n[w];
    std::size_t ip = n;
    for (std::size_t i = 0; i < n; ++i)
      if (rec.time_s[i] >= rec.impact_daq_time_s && (ip == n || f[i] > f[ip])) ip = i;
    double peak_t = kNaN, onset_t = kNaN, peak_f = kNaN, t10 = kNaN, t50 = kNaN;
    if (ip < n && f[ip] > 0) {
      peak_f = f[ip];
      peak_t = rec.time_s[ip] - rec.impact_daq_time_s;
      // The 50 % and 10 % crossings of the rise before the peak, linear between samples.
      auto crossing = [&](double level) {
        std::size_t j = ip;
        while (j > 0 && f[j] > level) --j;
        if (f[j] > level) return kNaN;
        return rec.time_s[j] +
               (level - f[j]) / (f[j + 1] - f[j]) * (rec.time_s[j + 1] - rec.time_s[j]) -
               rec.impact_daq_time_s;
      };
      t10 = crossing(0.1 * peak_f), t50 = crossing(0.5 * peak_f);
      onset_t = t10 - (t50 - t10) / 4;  // The line through both meets 0 there.
    }
    const double r_m = 1e-3 * std::hypot(b.offset_mm[w], b.depth_mm[w]);
    T.base_peak_s.push_back(peak_t);
    T.base_peak_force_N.push_back(peak_f);
    T.base_onset_s.push_back(onset_t);
    T.base_rise_10_s.push_back(t10);
    T.base_rise_50_s.push_back(t50);
    T.base_peak_speed_m_s.push_back(r_m / (peak_t - T.pounder_peak_decel_s));
    T.base_stress_ratio.push_back(peak_f / (1e-6 * b.area_mm2[w]) / T.pounder_peak_stress_Pa);
  }
}

// p_max, the fine series from near.dump and t_e by the paper's definition (DemTruth::t_e_s).
void DemScene::ComputePeakStageTruth(const std::unordered_map<std::int64_t, double>& grid_mass_of) {
  DemTruth& T = truth_;
  const DemMeta& m = record_.meta;
  // Pounder momentum maximum over the DEM samples after contact.
  const double mp = m.pounder_mass_kg;
  T.p_max_Ns = -std::numeric_limits<double>::infinity();
  for (const DemPounderSample& s : record_.pounder) {
    const double t = s.t_s - t_contact_s_;
    if (t >= 0 && -mp * s.vy_m_s > T.p_max_Ns) T.p_max_Ns = -mp * s.vy_m_s, T.t_pmax_s = t;
  }

  // Fine series from near.dump, if every grid grain is in it.
  bool fine = !record_.near.empty();
  for (const DemSnapshot& s : record_.near) {
    double p = 0;
    std::size_t found = 0;
    for (const DemGrain& g : s.grains) {
      auto it = grid_mass_of.find(g.id);
      if (it == grid_mass_of.end()) continue;
      ++found;
      p += -it->second * g.vy_m_s;
    }
    if (found != grid_mass_of.size()) {
      fine = false;
      T.notes.push_back(
          fmt::format("near.dump misses {} of the {} grid grains: t_e from the frames only",
                      grid_mass_of.size() - found, grid_mass_of.size()));
      break;
    }
    const double t = s.step * m.timestep_s - t_contact_s_;
    T.fine_t_s.push_back(t);
    T.fine_p_gran_Ns.push_back(p);
    T.fine_v_sand_m_s.push_back(p / T.grid_mass_kg);
    T.fine_v_p_m_s.push_back(Pounder(t).v_m_s);
    T.fine_p_p_Ns.push_back(mp * T.fine_v_p_m_s.back());
  }
  if (!fine) T.fine_t_s.clear(), T.fine_p_gran_Ns.clear(), T.fine_v_sand_m_s.clear();
  if (!fine) T.fine_v_p_m_s.clear(), T.fine_p_p_Ns.clear();

  // t_e from the grains.
  const double tol = options_.velocity_tolerance * T.p_max_Ns / mp;
  std::vector<double> t = T.fine_t_s, vs = T.fine_v_sand_m_s, vp = T.fine_v_p_m_s;
  if (!fine) {
    t = T.frame_time_s;
    vs = T.v_sand_m_s;
    vp.clear();
    for (double tk : t) vp.push_back(Pounder(tk).v_m_s);
  }
  const std::size_t ie = FindPeakEnd(t, vp, vs, T.t_pmax_s, tol);
  T.t_e_s = T.v_te_m_s = T.m_add_max_kg = T.conservation_error_te = T.conservation_error_peak =
      kNaN;
  if (ie == std::string::npos) {
    T.notes.push_back(fmt::format(
        "no time where the grid's grains stop accelerating and move with the pounder (within "
        "{:.3g} m/s): t_e is NaN",
        tol));
    return;
  }
  T.t_e_s = t[ie];
  T.v_te_m_s = vp[ie];
  T.m_add_max_kg = T.p_max_Ns / T.v_te_m_s - mp;
  T.conservation_error_te =
      std::abs(mp * vp[ie] + vs[ie] * T.grid_mass_kg - T.p_max_Ns) / T.p_max_Ns;
  T.conservation_error_peak = 0;
  for (std::size_t i = 0; i <= ie; ++i)
    if (t[i] >= T.t_pmax_s)
      T.conservation_error_peak =
          std::max(T.conservation_error_peak,
                   std::abs(mp * vp[i] + vs[i] * T.grid_mass_kg - T.p_max_Ns) / T.p_max_Ns);
}

std::string DemSceneReport::BriefReport() const {
  return fmt::format("synth (DEM): {} frames of {} grains in {} ({:.1f} s rendering)", frames,
                     grains, out_dir, render_seconds);
}

namespace {

// truth.h5 base_sensors/ (with floor.txt; the names of synth's where the meaning is the same,
// docs/synth.md) and p_wave/ (with the P-wave run).
void WriteDemWaveTruth(const DemScene& scene, const ImpactScene::SensorRecord& rec, H5Writer& out) {
  const DemTruth& T = scene.truth();
  const DemPWave& pw = T.pwave;
  const double c_p = pw.speed_m_s;
  if (!pw.layer_depth_m.empty()) {
    out.Write("p_wave/layer_depth_m", pw.layer_depth_m, "m", "layer centre below the bed top");
    out.Write("p_wave/half_peak_s", pw.half_peak_s, "s",
              "first time the layer's downward velocity reaches half its peak, after the pulse "
              "start (NaN: no pulse)");
    out.Write("p_wave/peak_s", pw.peak_s, "s", "the layer's peak time after the pulse start");
    out.Write("p_wave/peak_m_s", pw.peak_m_s, "m/s", "the layer's peak downward velocity");
    out.Write("p_wave/in_fit", pw.in_fit, Dims{pw.in_fit.size()}, "1",
              "1 = the layer is in the speed fits");
    auto scalar = [&](const std::string& name, double v, const std::string& units,
                      const std::string& what) {
      out.Write("p_wave/" + name, std::vector<double>{v}, units, what);
    };
    scalar("speed_m_s", c_p, "m/s",
           "small-strain P-wave speed: least squares of depth against the half-peak arrivals");
    scalar("speed_sigma_m_s", pw.speed_sigma_m_s, "m/s", "its standard error");
    scalar("speed_peak_m_s", pw.speed_peak_m_s, "m/s", "the same from the layers' peak times");
    scalar("speed_peak_sigma_m_s", pw.speed_peak_sigma_m_s, "m/s", "its standard error");
    scalar("rms_residual_s", pw.rms_residual_s, "s", "rms time residual of the half-peak fit");
    const DemPWaveRecord& pr = scene.record().pwave;
    out.SetAttribute("p_wave", "pulse_duration_s", pr.pulse_duration_s);
    out.SetAttribute("p_wave", "bed_top_m", pr.bed_top_m);
    out.SetAttribute("p_wave", "problem", pw.problem.empty() ? std::string("none") : pw.problem);
    out.SetAttribute("p_wave", "definition",
                     "validation/dem/pwave.in: a half-sine body-force pulse on the top band of "
                     "the settled bed; each layer's mean downward velocity with the pulse minus "
                     "without it; speeds fitted over the layers 0.15-0.85 of the bed depth "
                     "(synth/dem_scene.h, MeasurePWave)");
  }
  if (scene.floor_windows() == 0) return;
  const SceneBaseSensorOptions& b = scene.base().spec().base_sensors;
  std::vector<double> distance, peak_stress, p_wave_arrival, static_load;
  for (std::size_t w = 0; w < scene.floor_windows(); ++w) {
    distance.push_back(std::hypot(b.offset_mm[w], b.depth_mm[w]));
    peak_stress.push_back(T.base_peak_force_N[w] / (1e-6 * b.area_mm2[w]));
    p_wave_arrival.push_back(1e-3 * distance.back() / c_p);
    static_load.push_back(scene.floor_static_N(w));
    out.Write("base_sensors/force_true_N/" + b.columns[w], rec.base_force_true_n[w], "N",
              "noise-free dynamic floor force of the window (DAQ-interval average minus its "
              "mean before the contact); time axis: sensor.csv time_s");
  }
  out.Write("base_sensors/offset_mm", b.offset_mm, "mm", "horizontal offset from the pounder axis");
  out.Write("base_sensors/depth_mm", b.depth_mm, "mm", "depth of the floor below the surface");
  out.Write("base_sensors/area_mm2", b.area_mm2, "mm^2", "window width x t_z");
  out.Write("base_sensors/distance_mm", distance, "mm", "straight distance from the impact point");
  out.Write("base_sensors/static_load_N", static_load, "N", "mean floor force before the contact");
  out.Write("base_sensors/peak_s", T.base_peak_s, "s",
            "peak of the noise-free dynamic floor force after the contact (a sample time)");
  out.Write("base_sensors/peak_force_N", T.base_peak_force_N, "N", "its value");
  out.Write("base_sensors/peak_stress_Pa", peak_stress, "Pa", "peak force / area");
  out.Write("base_sensors/onset_s", T.base_onset_s, "s",
            "where the line through the rise's 10 % and 50 % of peak crossings meets zero");
  out.Write("base_sensors/rise_10_s", T.base_rise_10_s, "s",
            "last time before the peak that the force is at 10 % of the peak (linear)");
  out.Write("base_sensors/rise_50_s", T.base_rise_50_s, "s", "the same at 50 %");
  out.Write("base_sensors/speed_peak_m_s", T.base_peak_speed_m_s, "m/s",
            "distance / (peak_s - the pounder's peak deceleration time): the paper's definition "
            "on the noise-free records");
  out.Write("base_sensors/stress_ratio", T.base_stress_ratio, "1",
            "peak stress / the pounder's noise-free peak stress m_p a_peak / (D t_z) (the "
            "tool's definition, on the record's samples)");
  if (!pw.layer_depth_m.empty())
    out.Write("base_sensors/p_wave_travel_s", p_wave_arrival, "s",
              "distance / the bed's small-strain P-wave speed (p_wave/speed_m_s)");
  out.SetAttribute("base_sensors", "pounder_peak_stress_Pa", T.pounder_peak_stress_Pa);
  out.SetAttribute("base_sensors", "pounder_peak_s", T.pounder_peak_decel_s);
  out.SetAttribute("base_sensors", "columns", fmt::format("{}", fmt::join(b.columns, ",")));
  out.SetAttribute("base_sensors", "offset_n", b.offset_n);
  out.SetAttribute("base_sensors", "noise_n", b.noise_n);
  out.SetAttribute("base_sensors", "model",
                   "DEM floor force (validation/dem/impact.in floor.txt) in two windows: the "
                   "floor's contact force on the grains whose centres lie in the window");
}

void WriteDemTruth(const DemScene& scene, const ImpactScene::SensorRecord& rec,
                   const std::string& path, const std::string& spec_yaml) {
  const DemTruth& T = scene.truth();
  const ImpactScene& b = scene.base();
  const DemMeta& m = scene.record().meta;
  const SceneDicGrid& grid = b.dic_grid();
  const SceneMomentumTruth& mt = b.momentum();
  const auto F = static_cast<std::size_t>(scene.frame_count());
  H5Writer out(path);
  out.WriteProvenance(spec_yaml);
  out.SetAttribute("/", "generator", "impactdic synth (DEM footage: LAMMPS DEM, validation/dem)");
  out.SetAttribute("/", "conventions",
                   "t = 0 at contact; depths and velocities down positive; pixels are ideal "
                   "(undistorted) pixels of the first frame; panel mm origin at the pounder axis "
                   "on the pounder bottom at contact");
  std::vector<double> z(F), v(F), pp(F);
  for (std::size_t k = 0; k < F; ++k) {
    const PounderState ps = scene.Pounder(T.frame_time_s[k]);
    z[k] = ps.z_m, v[k] = ps.v_m_s, pp[k] = m.pounder_mass_kg * ps.v_m_s;
  }
  out.Write("frames/time_s", T.frame_time_s, "s", "frame time since contact");
  out.Write("pounder/z_m", z, "m", "pounder bottom below its position at contact, down +");
  out.Write("pounder/v_m_s", v, "m/s", "pounder velocity, down positive");
  const Dims gdims{static_cast<std::size_t>(grid.rows), static_cast<std::size_t>(grid.cols)};
  const Dims fdims{F, gdims[0], gdims[1]};
  std::vector<double> gx, gy;
  for (const auto& c : grid.centres_px) gx.push_back(c.x), gy.push_back(c.y);
  out.Write("soil/grid_x_px", gx, gdims, "px", "DIC subset centres (reference frame), x");
  out.Write("soil/grid_y_px", gy, gdims, "px", "DIC subset centres (reference frame), y");
  out.Write("soil/u_px", T.u_px, fdims, "px",
            "mass-weighted mean displacement of the cell's grains since the reference frame, x");
  out.Write("soil/v_px", T.v_px, fdims, "px", "the same, y down");
  out.Write("soil/velocity_x_mm_s", T.velocity_x_mm_s, fdims, "mm/s",
            "mass-weighted mean velocity of the cell's grains, x");
  out.Write("soil/velocity_y_mm_s", T.velocity_y_mm_s, fdims, "mm/s", "the same, y down");
  out.Write("soil/grains_per_cell", T.grains_per_cell, gdims, "1",
            "grains whose centre lies in the step x step cell at the reference frame");
  out.Write("soil/grains_per_subset", T.grains_per_subset, gdims, "1",
            "grains whose centre lies in the subset at the reference frame (the strain fit's)");
  synth_internal::WriteStrainTruth(
      synth_internal::GradientTruth{T.dudx, T.dudy, T.dvdx, T.dvdy}, fdims,
      "least-squares affine fit of the displacements of the subset's grains", out);
  out.SetAttribute("soil", "reference_frame", T.reference_frame);
  out.SetAttribute("soil", "step_px", scene.base().spec().step);
  out.SetAttribute("soil", "subset_size_px", scene.base().spec().subset_size);
  std::vector<double> mx, my;
  for (const auto& c : mt.centres_px) mx.push_back(c.x), my.push_back(c.y);
  const Dims mdims{static_cast<std::size_t>(mt.rows), static_cast<std::size_t>(mt.cols)};
  out.Write("momentum/grid_x_px", mx, mdims, "px", "default momentum grid centres, x");
  out.Write("momentum/grid_y_px", my, mdims, "px", "default momentum grid centres, y");
  out.Write("momentum/p_pounder_Ns", pp, "N s", "m_p v_p at the frames");
  out.Write("momentum/p_gran_Ns", T.p_gran_Ns, "N s", "sum m v_down of the grid's grains");
  out.Write("momentum/p_gran_fd_Ns", T.p_gran_fd_Ns, "N s",
            "grid mass x central difference of the grid grains' mean displacement (perfect DIC)");
  out.Write("momentum/v_sand_m_s", T.v_sand_m_s, "m/s", "p_gran / grid grain mass");
  auto scalar = [&](const std::string& name, double value, const std::string& units,
                    const std::string& what) {
    out.Write("momentum/" + name, std::vector<double>{value}, units, what);
  };
  scalar("p_max_Ns", T.p_max_Ns, "N s", "maximum pounder momentum (DEM samples)");
  scalar("t_pmax_s", T.t_pmax_s, "s", "its time");
  scalar("t_e_s", T.t_e_s, "s",
         "end of the peak stage from the grains: v_p - v_sand <= tol and no later rise of "
         "v_sand by more than tol");
  scalar("v_te_m_s", T.v_te_m_s, "m/s", "v_p(t_e)");
  scalar("m_add_max_kg", T.m_add_max_kg, "kg", "p_max / v_p(t_e) - m_p (Eq. 3)");
  scalar("grid_mass_kg", T.grid_mass_kg, "kg", "mass of the grid's grains");
  scalar("grid_mass_bulk_kg", T.grid_mass_bulk_kg, "kg", "rho_d * grid area * t_z");
  scalar("bulk_density_kg_m3", T.bulk_density_kg_m3, "kg/m^3",
         "grain mass per volume under the footprint, 5..105 mm deep");
  scalar("grid_area_mm2", mt.grid_area_mm2, "mm^2", "cols * rows * step^2 * s^2");
  scalar("conservation_error", T.conservation_error_te, "1",
         "|p_pounder + p_gran - p_max| / p_max at t_e (grains)");
  scalar("conservation_error_peak", T.conservation_error_peak, "1",
         "its maximum over [t_pmax, t_e]");
  std::string notes;
  for (const auto& n : T.notes) notes += n + "; ";
  out.SetAttribute("momentum", "notes", notes.empty() ? std::string("none") : notes);
  if (!T.fine_t_s.empty()) {
    out.Write("series/t_s", T.fine_t_s, "s", "time since contact (near.dump snapshots)");
    out.Write("series/p_gran_Ns", T.fine_p_gran_Ns, "N s", "sum m v_down of the grid's grains");
    out.Write("series/v_sand_m_s", T.fine_v_sand_m_s, "m/s", "grid grains' mean velocity");
    out.Write("series/v_m_s", T.fine_v_p_m_s, "m/s", "pounder velocity");
    out.Write("series/p_pounder_Ns", T.fine_p_p_Ns, "N s", "m_p v_p");
  }
  std::vector<double> st, sa;
  for (std::size_t i = 0; i < rec.time_s.size(); ++i) {
    const double ti = rec.time_s[i] - rec.impact_daq_time_s;
    if (ti < -0.002) continue;
    st.push_back(ti);
    sa.push_back(rec.accel_true_g[i]);
  }
  out.Write("sensor/t_s", st, "s", "DAQ sample time since contact");
  out.Write("sensor/accel_true_g", sa, "g", "noise-free reading from the DEM pounder (axis up)");
  out.SetAttribute("sensor", "frame0_daq_time_s", rec.frame0_daq_time_s);
  out.SetAttribute("sensor", "impact_daq_time_s", rec.impact_daq_time_s);
  out.SetAttribute("sensor", "release_daq_time_s", rec.release_daq_time_s);
  WriteDemWaveTruth(scene, rec, out);
  out.CreateGroup("dem");
  out.SetAttribute("dem", "pounder_mass_kg", m.pounder_mass_kg);
  out.SetAttribute("dem", "pounder_width_m", m.pounder_width_m);
  out.SetAttribute("dem", "depth_m", m.depth_m);
  out.SetAttribute("dem", "impact_velocity_m_s", scene.base().spec().impact_velocity_m_s);
  out.SetAttribute("dem", "timestep_s", m.timestep_s);
  out.SetAttribute("dem", "grains", static_cast<double>(scene.record().frames[0].grains.size()));
  out.SetAttribute("dem", "contact_time_s", scene.contact_time_s());
  out.CreateGroup("camera");
  out.SetAttribute("camera", "sx_mm_per_px", b.sx_mm_per_px());
  out.SetAttribute("camera", "sy_mm_per_px", b.sy_mm_per_px());
  out.SetAttribute("camera", "pounder_axis_x_px", b.axis_px());
  out.SetAttribute("camera", "surface_y_px", b.surface_px());
  out.SetAttribute("camera", "fps", b.spec().fps);
  out.Commit();
}

}  // namespace

DemSceneReport WriteDemScene(const DemScene& scene, const std::string& out_dir) {
  const ImpactScene::SensorRecord rec = scene.MakeSensorRecord();
  const synth_internal::SceneFiles files = synth_internal::WriteSceneFiles(
      scene.base(), scene.frame_count(), [&](int k) { return scene.RenderFrame(k); },
      "rendering DEM frames", rec,
      [&](const std::string& path, const std::string& spec_yaml) {
        WriteDemTruth(scene, rec, path, spec_yaml);
      },
      out_dir);
  DemSceneReport report;
  report.out_dir = out_dir;
  report.frames = scene.frame_count();
  report.grains = static_cast<int>(scene.record().frames[0].grains.size());
  report.render_seconds = files.render_seconds;
  report.calibration_yaml = files.calibration_yaml;
  report.sensor_csv = files.sensor_csv;
  report.truth_h5 = files.truth_h5;
  report.scene_yaml = files.scene_yaml;
  return report;
}

}  // namespace impactdic
