#include "impactdic/strain/strain.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "impactdic/core/error.h"

namespace impactdic {
namespace {

// The subsets of a correlation on its regular grid: rows and columns of the reference centres,
// one step in x and in y, holes allowed (-1).
struct GridIndex {
  double x0 = 0, y0 = 0;  // Top-left grid point [px].
  double sx = 1, sy = 1;  // Steps [px] (the other one's when a single column or row).
  std::ptrdiff_t cols = 1, rows = 1;
  std::vector<std::ptrdiff_t> id;              // [rows x cols] subset id or -1 (hole).
  std::vector<std::ptrdiff_t> row_of, col_of;  // Per subset.

  std::ptrdiff_t At(std::ptrdiff_t r, std::ptrdiff_t c) const {
    if (r < 0 || c < 0 || r >= rows || c >= cols) return -1;
    return id[static_cast<std::size_t>(r * cols + c)];
  }
};

GridIndex IndexGrid(const CorrelationSeries& dic) {
  CheckValue(dic.subsets >= 1 && dic.x_px.size() == dic.subsets && dic.y_px.size() == dic.subsets,
             "strain: correlation grid", fmt::format("{} positions", dic.x_px.size()),
             fmt::format("one position per subset ({})", dic.subsets));
  const auto [xmin, xmax] = std::minmax_element(dic.x_px.begin(), dic.x_px.end());
  const auto [ymin, ymax] = std::minmax_element(dic.y_px.begin(), dic.y_px.end());
  const double tol = 1e-6 * std::max({1.0, *xmax - *xmin, *ymax - *ymin});
  const std::vector<double> xs = UniqueSorted(dic.x_px, tol), ys = UniqueSorted(dic.y_px, tol);
  GridIndex g;
  g.x0 = xs.front();
  g.y0 = ys.front();
  g.sx = MedianStep(xs);
  g.sy = MedianStep(ys);
  if (std::isnan(g.sx)) g.sx = std::isnan(g.sy) ? 1 : g.sy;
  if (std::isnan(g.sy)) g.sy = g.sx;
  g.cols = std::lround((xs.back() - g.x0) / g.sx) + 1;
  g.rows = std::lround((ys.back() - g.y0) / g.sy) + 1;
  g.id.assign(static_cast<std::size_t>(g.rows * g.cols), -1);
  g.row_of.resize(dic.subsets);
  g.col_of.resize(dic.subsets);
  for (std::size_t i = 0; i < dic.subsets; ++i) {
    const double fc = (dic.x_px[i] - g.x0) / g.sx, fr = (dic.y_px[i] - g.y0) / g.sy;
    const std::ptrdiff_t c = std::lround(fc), r = std::lround(fr);
    CheckValue(
        std::abs(fc - static_cast<double>(c)) < 1e-3 &&
            std::abs(fr - static_cast<double>(r)) < 1e-3,
        "strain: correlation grid",
        fmt::format("subset {} at ({}, {}) px off the grid of steps {} x {} px from ({}, {})", i,
                    dic.x_px[i], dic.y_px[i], g.sx, g.sy, g.x0, g.y0),
        "subset centres on a regular grid (one step in x and one in y)");
    std::ptrdiff_t& slot = g.id[static_cast<std::size_t>(r * g.cols + c)];
    CheckValue(slot < 0, "strain: correlation grid",
               fmt::format("subsets {} and {} at the same centre ({}, {}) px", slot, i, dic.x_px[i],
                           dic.y_px[i]),
               "one subset per grid point");
    slot = static_cast<std::ptrdiff_t>(i);
    g.row_of[i] = r;
    g.col_of[i] = c;
  }
  return g;
}

bool SampleValid(const CorrelationSeries& dic, std::size_t j) {
  return (dic.valid.empty() || dic.valid[j] != 0) && std::isfinite(dic.u_px[j]) &&
         std::isfinite(dic.v_px[j]);
}

// Calls visit(k) for the valid samples k of the window x window neighbourhood of subset i in the
// frame whose samples start at `row`.
template <typename Visit>
void ForEachNeighbour(const CorrelationSeries& dic, const GridIndex& g, std::size_t row,
                      std::size_t i, std::ptrdiff_t half, Visit&& visit) {
  for (std::ptrdiff_t dr = -half; dr <= half; ++dr) {
    for (std::ptrdiff_t dc = -half; dc <= half; ++dc) {
      const std::ptrdiff_t k = g.At(g.row_of[i] + dr, g.col_of[i] + dc);
      if (k >= 0 && SampleValid(dic, row + static_cast<std::size_t>(k)))
        visit(static_cast<std::size_t>(k));
    }
  }
}

// Least-squares gradient of u and v (planes through the window's valid samples, centred on their
// mean) in the frame whose samples start at `row`; false when fewer than 3 samples or (nearly)
// collinear ones.
bool FitAt(const CorrelationSeries& dic, const GridIndex& g, std::size_t row, std::size_t i,
           std::ptrdiff_t half, std::array<double, 4>* h) {
  std::size_t count = 0;
  double mx = 0, my = 0, mu = 0, mv = 0;
  ForEachNeighbour(dic, g, row, i, half, [&](std::size_t k) {
    ++count;
    mx += dic.x_px[k];
    my += dic.y_px[k];
    mu += dic.u_px[row + k];
    mv += dic.v_px[row + k];
  });
  if (count < 3) return false;
  const auto n = static_cast<double>(count);
  mx /= n;
  my /= n;
  mu /= n;
  mv /= n;
  double sxx = 0, sxy = 0, syy = 0, sxu = 0, syu = 0, sxv = 0, syv = 0;
  ForEachNeighbour(dic, g, row, i, half, [&](std::size_t k) {
    const double dx = dic.x_px[k] - mx, dy = dic.y_px[k] - my;
    const double du = dic.u_px[row + k] - mu, dv = dic.v_px[row + k] - mv;
    sxx += dx * dx;
    sxy += dx * dy;
    syy += dy * dy;
    sxu += dx * du;
    syu += dy * du;
    sxv += dx * dv;
    syv += dy * dv;
  });
  const double det = sxx * syy - sxy * sxy;
  if (!(det > 1e-9 * (sxx + syy) * (sxx + syy))) return false;  // Collinear samples.
  (*h)[0] = (syy * sxu - sxy * syu) / det;                      // du/dX
  (*h)[1] = (sxx * syu - sxy * sxu) / det;                      // du/dY
  (*h)[2] = (syy * sxv - sxy * syv) / det;                      // dv/dX
  (*h)[3] = (sxx * syv - sxy * sxv) / det;                      // dv/dY
  return true;
}

// The grid neighbours' offsets along the four directions of ShearBands.
constexpr std::array<std::array<int, 2>, 4> kRidgeDirections{{{0, 1}, {1, 0}, {1, 1}, {1, -1}}};

}  // namespace

void StrainOptions::Check() const {
  CheckValue(window >= 3 && window % 2 == 1, "strain.window", fmt::format("{}", window),
             "an odd number of grid points >= 3");
  CheckValue(
      std::isfinite(compaction_threshold) && compaction_threshold >= 0 && compaction_threshold < 1,
      "strain.compaction_threshold", fmt::format("{}", compaction_threshold),
      "a volumetric strain in [0, 1) (compression positive)");
  CheckValue(std::isfinite(shear_band_threshold) && shear_band_threshold >= 0,
             "strain.shear_band_threshold", fmt::format("{}", shear_band_threshold),
             "a finite shear strain >= 0");
}

DisplacementGradient FitDisplacementGradient(const CorrelationSeries& dic, int window) {
  CheckValue(window >= 3 && window % 2 == 1, "strain.window", fmt::format("{}", window),
             "an odd number of grid points >= 3");
  const std::size_t n = dic.frames * dic.subsets;
  CheckValue(dic.u_px.size() == n && dic.v_px.size() == n, "strain: u_px / v_px",
             fmt::format("{} / {} entries", dic.u_px.size(), dic.v_px.size()),
             fmt::format("frames x subsets = {}", n));
  CheckValue(dic.valid.empty() || dic.valid.size() == n, "strain: valid",
             fmt::format("{} entries", dic.valid.size()),
             fmt::format("empty or frames x subsets = {}", n));
  const GridIndex g = IndexGrid(dic);
  // The window must fit inside the grid in both directions (strain.h, FitDisplacementGradient).
  const std::ptrdiff_t side = std::min(g.cols, g.rows), largest = side % 2 == 1 ? side : side - 1;
  CheckValue(window <= side, "strain.window",
             fmt::format("{} on a subset grid of {} columns x {} rows", window, g.cols, g.rows),
             largest >= 3 ? fmt::format("at most {} (the grid's smaller side), so that each fit "
                                        "stays local; or a smaller dic.step",
                                        largest)
                          : std::string("a grid of at least 3 x 3 subsets for strain.gradient: "
                                        "fit (a smaller dic.step), or strain.gradient: warp"));
  DisplacementGradient out;
  out.frames = dic.frames;
  out.subsets = dic.subsets;
  out.dudx.assign(n, kNaN);
  out.dudy.assign(n, kNaN);
  out.dvdx.assign(n, kNaN);
  out.dvdy.assign(n, kNaN);
  const std::ptrdiff_t half = window / 2;
  for (std::size_t f = 0; f < dic.frames; ++f) {
    const std::size_t row = f * dic.subsets;
    for (std::size_t i = 0; i < dic.subsets; ++i) {
      std::array<double, 4> h{};
      if (!SampleValid(dic, row + i) || !FitAt(dic, g, row, i, half, &h)) continue;
      out.dudx[row + i] = h[0];
      out.dudy[row + i] = h[1];
      out.dvdx[row + i] = h[2];
      out.dvdy[row + i] = h[3];
    }
  }
  return out;
}

StrainAtPoint StrainFromGradient(double dudx, double dudy, double dvdx, double dvdy) {
  StrainAtPoint s;
  s.exx = dudx;
  s.eyy = dvdy;
  s.exy = 0.5 * (dudy + dvdx);
  // E = (H + H^T + H^T H) / 2, (H^T H)_ij = sum_k H_ki H_kj.
  s.gxx = dudx + 0.5 * (dudx * dudx + dvdx * dvdx);
  s.gyy = dvdy + 0.5 * (dudy * dudy + dvdy * dvdy);
  s.gxy = 0.5 * (dudy + dvdx) + 0.5 * (dudx * dudy + dvdx * dvdy);
  s.eps_v = 0.0 - (s.exx + s.eyy);  // +0 (not -0) without strain.
  const double centre = 0.5 * (s.exx + s.eyy);
  const double radius = std::hypot(0.5 * (s.exx - s.eyy), s.exy);
  s.eps_1 = centre + radius;
  s.eps_2 = centre - radius;
  s.gamma_max = 2 * radius;
  // atan2 in (-pi, pi] -> theta in (-pi/2, pi/2]; 0 for an isotropic strain.
  s.theta_1_rad = 0.5 * std::atan2(2 * s.exy, s.exx - s.eyy);
  return s;
}

StrainField ComputeStrain(const DisplacementGradient& gradient, double fps) {
  CheckValue(std::isfinite(fps) && fps > 0, "strain: fps", fmt::format("{}", fps), "> 0 1/s");
  const std::size_t n = gradient.frames * gradient.subsets;
  CheckValue(gradient.dudx.size() == n && gradient.dudy.size() == n && gradient.dvdx.size() == n &&
                 gradient.dvdy.size() == n,
             "strain: displacement gradient", fmt::format("{} entries", gradient.dudx.size()),
             fmt::format("frames x subsets = {} in each of dudx, dudy, dvdx, dvdy", n));
  StrainField s;
  s.frames = gradient.frames;
  s.subsets = gradient.subsets;
  for (std::vector<double>* v : {&s.exx, &s.eyy, &s.exy, &s.gxx, &s.gyy, &s.gxy, &s.eps_v, &s.eps_1,
                                 &s.eps_2, &s.theta_1_rad, &s.gamma_max, &s.exx_rate, &s.eyy_rate,
                                 &s.exy_rate, &s.eps_v_rate, &s.gamma_max_rate})
    v->assign(n, kNaN);
  for (std::size_t j = 0; j < n; ++j) {
    const double a = gradient.dudx[j], b = gradient.dudy[j], c = gradient.dvdx[j],
                 d = gradient.dvdy[j];
    if (!(std::isfinite(a) && std::isfinite(b) && std::isfinite(c) && std::isfinite(d))) continue;
    const StrainAtPoint p = StrainFromGradient(a, b, c, d);
    s.exx[j] = p.exx;
    s.eyy[j] = p.eyy;
    s.exy[j] = p.exy;
    s.gxx[j] = p.gxx;
    s.gyy[j] = p.gyy;
    s.gxy[j] = p.gxy;
    s.eps_v[j] = p.eps_v;
    s.eps_1[j] = p.eps_1;
    s.eps_2[j] = p.eps_2;
    s.theta_1_rad[j] = p.theta_1_rad;
    s.gamma_max[j] = p.gamma_max;
  }
  if (s.frames < 3) return s;  // Rates need 3 frames: NaN.
  const double dt = 1 / fps;
  const std::array<std::pair<const std::vector<double>*, std::vector<double>*>, 5> rates{
      {{&s.exx, &s.exx_rate},
       {&s.eyy, &s.eyy_rate},
       {&s.exy, &s.exy_rate},
       {&s.eps_v, &s.eps_v_rate},
       {&s.gamma_max, &s.gamma_max_rate}}};
  std::vector<double> series(s.frames);
  for (const auto& [value, rate] : rates) {
    for (std::size_t i = 0; i < s.subsets; ++i) {
      for (std::size_t f = 0; f < s.frames; ++f) series[f] = (*value)[f * s.subsets + i];
      const std::vector<double> d = FirstDerivative(series, dt);
      for (std::size_t f = 0; f < s.frames; ++f) (*rate)[f * s.subsets + i] = d[f];
    }
  }
  return s;
}

std::vector<double> DensityField(const StrainField& strain, double dry_density_kg_m3) {
  CheckValue(std::isfinite(dry_density_kg_m3) && dry_density_kg_m3 > 0,
             "strain: dry density (test.density_kg_m3)", fmt::format("{}", dry_density_kg_m3),
             "> 0 kg/m^3");
  std::vector<double> rho(strain.eps_v.size(), kNaN);
  for (std::size_t j = 0; j < rho.size(); ++j) {
    const double e = strain.eps_v[j];
    if (std::isfinite(e) && e < 1) rho[j] = dry_density_kg_m3 / (1 - e);
  }
  return rho;
}

CompactedZone FindCompactedZone(const StrainField& strain, const CorrelationSeries& dic,
                                std::size_t frame, const StrainOptions& options, double mm_per_px,
                                double surface_y_px) {
  options.Check();
  CheckValue(std::isfinite(mm_per_px) && mm_per_px > 0, "strain: mm_per_px",
             fmt::format("{}", mm_per_px), "> 0 mm/px");
  CheckValue(frame < strain.frames && strain.subsets == dic.subsets &&
                 strain.eps_v.size() == strain.frames * strain.subsets,
             "strain: compacted zone frame",
             fmt::format("frame {} of a field of {} frames x {} subsets ({} correlated)", frame,
                         strain.frames, strain.subsets, dic.subsets),
             "a frame of the strain field, with one subset per correlated subset");
  const GridIndex g = IndexGrid(dic);
  const double top = std::isfinite(surface_y_px) ? surface_y_px : g.y0;
  CompactedZone z;
  z.frame = frame;
  double deepest = top;
  const std::size_t row = frame * strain.subsets;
  bool measured = false;  // Any finite eps_v in the frame.
  for (std::size_t i = 0; i < strain.subsets; ++i) {
    const double e = strain.eps_v[row + i];
    measured = measured || std::isfinite(e);
    if (!(std::isfinite(e) && e > options.compaction_threshold)) continue;
    ++z.samples;
    deepest = std::max(deepest, dic.y_px[i]);
  }
  if (!measured) {
    z.area_mm2 = z.depth_mm = kNaN;
    return z;
  }
  z.area_mm2 = static_cast<double>(z.samples) * g.sx * g.sy * mm_per_px * mm_per_px;
  z.depth_mm = (deepest - top) * mm_per_px;
  return z;
}

std::vector<std::uint8_t> ShearBands(const StrainField& strain, const CorrelationSeries& dic,
                                     const StrainOptions& options) {
  options.Check();
  CheckValue(
      strain.subsets == dic.subsets && strain.gamma_max.size() == strain.frames * strain.subsets,
      "strain: shear bands",
      fmt::format("a field of {} subsets ({} correlated)", strain.subsets, dic.subsets),
      "one subset per correlated subset");
  const GridIndex g = IndexGrid(dic);
  std::vector<std::uint8_t> band(strain.gamma_max.size(), 0);
  for (std::size_t f = 0; f < strain.frames; ++f) {
    const std::size_t row = f * strain.subsets;
    for (std::size_t i = 0; i < strain.subsets; ++i) {
      const double v = strain.gamma_max[row + i];
      if (!(std::isfinite(v) && v > options.shear_band_threshold)) continue;
      for (const auto& [dr, dc] : kRidgeDirections) {
        const std::ptrdiff_t a = g.At(g.row_of[i] + dr, g.col_of[i] + dc);
        const std::ptrdiff_t b = g.At(g.row_of[i] - dr, g.col_of[i] - dc);
        if (a < 0 || b < 0) continue;  // A hole or the edge: this direction cannot tell.
        const double va = strain.gamma_max[row + static_cast<std::size_t>(a)];
        const double vb = strain.gamma_max[row + static_cast<std::size_t>(b)];
        // NaN neighbours compare false: undecided.
        if (v > va && v > vb) {
          band[row + i] = 1;
          break;
        }
      }
    }
  }
  return band;
}

}  // namespace impactdic
