// Realistic synthetic footage (see realistic.h).
//
// Grains: the texture is the matrix level composited with every grain in a fixed order
// (v += c_i (shade_i - v)), c_i the grain's coverage (1 inside, a smooth step over `kEdgePx` at
// its rim, 0 outside). Grains are binned in cells (CSR) of size >= their reach; the order of two
// overlapping grains is that of their cells and indices, the same at every point, so the texture
// is a continuous function of the material point.
#include "impactdic/synth/realistic.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <functional>
#include <numbers>
#include <string>
#include <tuple>
#include <utility>

#include "impactdic/core/error.h"
#include "impactdic/synth/speckle.h"
#include "random.h"

namespace impactdic {
namespace {

using synth_detail::Rng;

constexpr double kEdgePx = 0.4;       // Soft rim of a grain [px].
constexpr double kMatrixLevel = 0.3;  // Fine matrix between the grains.
constexpr double kGlareFlag = 0.2;    // Glare flag: added light >= this [full scale].

class GrainTexture {
 public:
  GrainTexture(double radius, double spread, double coverage, std::uint64_t seed, double x0,
               double y0, double x1, double y1) {
    const double r_max = radius * (1 + spread) + kEdgePx;
    cell_ = std::max(2 * r_max, 2.0);
    x0_ = x0 - cell_;
    y0_ = y0 - cell_;
    cols_ = static_cast<int>(std::ceil((x1 - x0_ + cell_) / cell_));
    rows_ = static_cast<int>(std::ceil((y1 - y0_ + cell_) / cell_));
    const double span_x = cols_ * cell_, span_y = rows_ * cell_;
    const auto count = static_cast<std::size_t>(
        std::llround(coverage * span_x * span_y / (std::numbers::pi * radius * radius)));
    Rng rng(seed);
    struct G {
      int cell;
      double x, y, r, b;
    };
    std::vector<G> grains(count);
    for (G& g : grains) {
      g.x = x0_ + rng.Uniform() * span_x;
      g.y = y0_ + rng.Uniform() * span_y;
      g.r = radius * (1 + spread * (2 * rng.Uniform() - 1));
      // 70 % light (quartz, feldspar), 30 % dark minerals.
      g.b = rng.Uniform() < 0.7 ? 0.62 + 0.33 * rng.Uniform() : 0.2 + 0.25 * rng.Uniform();
      const int cx = std::clamp(static_cast<int>((g.x - x0_) / cell_), 0, cols_ - 1);
      const int cy = std::clamp(static_cast<int>((g.y - y0_) / cell_), 0, rows_ - 1);
      g.cell = cy * cols_ + cx;
    }
    std::stable_sort(grains.begin(), grains.end(),
                     [](const G& a, const G& b) { return a.cell < b.cell; });
    start_.assign(static_cast<std::size_t>(cols_) * rows_ + 1, 0);
    for (const G& g : grains) ++start_[g.cell + 1];
    for (std::size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
    for (const G& g : grains) {
      gx_.push_back(g.x);
      gy_.push_back(g.y);
      gr_.push_back(g.r);
      gb_.push_back(g.b);
    }
    reach_ = r_max;
  }

  double Intensity(double X, double Y) const {
    const int cx0 = std::max(0, static_cast<int>(std::floor((X - reach_ - x0_) / cell_)));
    const int cx1 = std::min(cols_ - 1, static_cast<int>(std::floor((X + reach_ - x0_) / cell_)));
    const int cy0 = std::max(0, static_cast<int>(std::floor((Y - reach_ - y0_) / cell_)));
    const int cy1 = std::min(rows_ - 1, static_cast<int>(std::floor((Y + reach_ - y0_) / cell_)));
    double v = kMatrixLevel;
    for (int cy = cy0; cy <= cy1; ++cy) {
      for (int cx = cx0; cx <= cx1; ++cx) {
        const int c = cy * cols_ + cx;
        for (int i = start_[c]; i < start_[c + 1]; ++i) {
          const double dx = X - gx_[i], dy = Y - gy_[i];
          const double rr = gr_[i] + 0.5 * kEdgePx;
          const double d2 = dx * dx + dy * dy;
          if (d2 >= rr * rr) continue;
          const double d = std::sqrt(d2);
          const double e = std::clamp((gr_[i] + 0.5 * kEdgePx - d) / kEdgePx, 0.0, 1.0);
          const double coverage = e * e * (3 - 2 * e);
          // Lit from the upper left: brighter on that side, darker on the other.
          const double shade = gb_[i] * (1 - 0.25 * (dx + dy) / (gr_[i] * std::numbers::sqrt2));
          v += coverage * (shade - v);
        }
      }
    }
    return std::clamp(v, 0.0, 1.0);
  }

 private:
  double x0_ = 0, y0_ = 0, cell_ = 1, reach_ = 1;
  int cols_ = 0, rows_ = 0;
  std::vector<int> start_;
  std::vector<double> gx_, gy_, gr_, gb_;
};

double SmoothInside(double signed_distance, double width) {  // 1 inside (< 0), 0 outside.
  return 0.5 * (1 - std::tanh(signed_distance / width));
}

}  // namespace

void RealisticSceneSpec::Check() const {
  auto in = [](double v, double lo, double hi) { return std::isfinite(v) && v >= lo && v <= hi; };
  auto s = [](double v) { return std::to_string(v); };
  CheckValue(width >= 64 && width <= 8192, "realistic.width", s(width), "in [64, 8192] px");
  CheckValue(height >= 48 && height <= 8192, "realistic.height", s(height), "in [48, 8192] px");
  CheckValue(frames >= 2 && frames <= 10000, "realistic.frames", s(frames), "in [2, 10000]");
  CheckValue(std::isfinite(fps) && fps > 0, "realistic.fps", s(fps), "> 0");
  CheckValue(std::isfinite(exposure_s) && exposure_s > 0 && exposure_s <= 1 / fps,
             "realistic.exposure_s", s(exposure_s), "in (0, 1 / fps] s");
  CheckValue(blur_samples >= 1 && blur_samples <= 32, "realistic.blur_samples", s(blur_samples),
             "in [1, 32]");
  CheckValue(supersampling >= 1 && supersampling <= 8, "realistic.supersampling", s(supersampling),
             "in [1, 8]");
  CheckValue(in(noise_sigma, 0, 1e3), "realistic.noise_sigma", s(noise_sigma), ">= 0 grey levels");
  CheckValue(jpeg_quality >= 0 && jpeg_quality <= 100, "realistic.jpeg_quality", s(jpeg_quality),
             "in [1, 100], or 0 for PNG");
  CheckValue(in(grain_radius_px, 0.5, 20), "realistic.grain_radius_px", s(grain_radius_px),
             "in [0.5, 20] px");
  CheckValue(in(grain_radius_spread, 0, 0.9), "realistic.grain_radius_spread",
             s(grain_radius_spread), "in [0, 0.9]");
  CheckValue(in(grain_coverage, 1e-9, 5), "realistic.grain_coverage", s(grain_coverage),
             "in (0, 5]");
  CheckValue(in(light_falloff, 0, 0.9), "realistic.light_falloff", s(light_falloff), "in [0, 0.9]");
  CheckValue(in(light_drift_per_frame, -0.1, 0.1), "realistic.light_drift_per_frame",
             s(light_drift_per_frame), "in [-0.1, 0.1]");
  CheckValue(in(glare_level, 0, 10), "realistic.glare_level", s(glare_level), "in [0, 10]");
  CheckValue(in(glare_radius_px, 0, 1e5), "realistic.glare_radius_px", s(glare_radius_px),
             ">= 0 px");
  CheckValue(in(glare_x, 0, 1), "realistic.glare_x", s(glare_x), "in [0, 1]");
  CheckValue(in(glare_y, 0, 1), "realistic.glare_y", s(glare_y), "in [0, 1]");
  CheckValue(in(surface_fraction, 0.05, 0.8), "realistic.surface_fraction", s(surface_fraction),
             "in [0.05, 0.8]");
  CheckValue(in(pounder_width_fraction, 0.05, 0.8), "realistic.pounder_width_fraction",
             s(pounder_width_fraction), "in [0.05, 0.8]");
  CheckValue(in(penetration_px_per_frame, 0, 50), "realistic.penetration_px_per_frame",
             s(penetration_px_per_frame), "in [0, 50] px");
  CheckValue(in(shear_band_width_px, 0.1, 20), "realistic.shear_band_width_px",
             s(shear_band_width_px), "in [0.1, 20] px");
  CheckValue(in(core_decay_px, 0, 1e5), "realistic.core_decay_px", s(core_decay_px), ">= 0 px");
  CheckValue(in(heave_ratio, 0, 1), "realistic.heave_ratio", s(heave_ratio), "in [0, 1]");
  CheckValue(in(heave_decay_px, 0, 1e5), "realistic.heave_decay_px", s(heave_decay_px), ">= 0 px");
  CheckValue(subset_size >= 5 && subset_size <= 201 && subset_size % 2 == 1,
             "realistic.subset_size", s(subset_size), "odd, in [5, 201] px");
  CheckValue(step >= 1, "realistic.step", s(step), ">= 1 px");
}

std::vector<std::uint8_t> RealisticTruth::Flagged() const {
  std::vector<std::uint8_t> f(u_px.size());
  for (std::size_t i = 0; i < f.size(); ++i)
    f[i] = straddles_edge[i] || straddles_shear_band[i] || in_glare[i];
  return f;
}

struct RealisticScene::Impl {
  std::unique_ptr<GrainTexture> sand, pounder, wall;
  double b = 1, w = 1, core = 1, heave = 1, glare_sigma = 1;
  double speed_px_s = 0;
};

RealisticScene::RealisticScene(const RealisticSceneSpec& spec) : spec_(spec) {
  spec_.Check();
  auto impl = std::make_shared<Impl>();
  const double r = spec_.grain_radius_px, spread = spec_.grain_radius_spread;
  const double margin = 64 + 60 * spec_.penetration_px_per_frame;
  const double W = spec_.width, H = spec_.height;
  impl->sand = std::make_unique<GrainTexture>(r, spread, spec_.grain_coverage, spec_.seed, -margin,
                                              -margin, W + margin, H + margin);
  impl->pounder = std::make_unique<GrainTexture>(2 * r, 0.3, 0.8, spec_.seed + 101, -margin,
                                                 -margin - H, W + margin, H + margin);
  impl->wall =
      std::make_unique<GrainTexture>(3 * r, 0.5, 1.0, spec_.seed + 202, -1, -1, W + 1, H + 1);
  impl->b = half_width_px();
  impl->w = spec_.shear_band_width_px;
  impl->core = spec_.core_decay_px > 0 ? spec_.core_decay_px : 2 * impl->b;
  impl->heave = spec_.heave_decay_px > 0 ? spec_.heave_decay_px : impl->b;
  impl->glare_sigma = spec_.glare_radius_px > 0 ? spec_.glare_radius_px : W / 30;
  impl->speed_px_s = spec_.penetration_px_per_frame * spec_.fps;
  impl_ = std::move(impl);
}

double RealisticScene::Penetration(double t_s) const {
  return impl_->speed_px_s * std::max(t_s, 0.0);
}

cv::Vec2d RealisticScene::SoilDisplacement(double X, double Y, double t_s) const {
  const Impl& p = *impl_;
  const double s = Penetration(t_s);
  const double xi = X - axis_px(), eta = std::max(Y - surface_px(), 0.0);
  const double rho = std::abs(xi) - p.b;  // Signed distance to the band (< 0 under the pounder).
  const double inside = SmoothInside(rho, p.w);
  const double g = std::exp(-(eta / p.core) * (eta / p.core));
  const double v_core = s * inside * g;
  const double rho_out = std::max(rho, 0.0);
  const double decay = std::exp(-rho_out / p.heave) * std::exp(-eta / p.heave);
  const double h = spec_.heave_ratio * s * (1 - inside);
  const double v_heave = -h * decay;
  const double u_heave = (xi >= 0 ? 1 : -1) * h * (rho_out / p.heave) * decay;
  return {u_heave, v_core + v_heave};
}

double RealisticScene::SandIntensity(double X, double Y) const {
  return impl_->sand->Intensity(X, Y);
}

namespace {

// Field of one time with a central-difference gradient (for the Newton inversion).
DisplacementField FieldAt(const RealisticScene& scene, double t_s) {
  DisplacementField f;
  f.u = [&scene, t_s](double X, double Y) { return scene.SoilDisplacement(X, Y, t_s); };
  f.gradient = [&scene, t_s](double X, double Y) {
    constexpr double h = 1e-5;
    const cv::Vec2d ux =
        (scene.SoilDisplacement(X + h, Y, t_s) - scene.SoilDisplacement(X - h, Y, t_s)) / (2 * h);
    const cv::Vec2d uy =
        (scene.SoilDisplacement(X, Y + h, t_s) - scene.SoilDisplacement(X, Y - h, t_s)) / (2 * h);
    return cv::Vec4d(ux[0], uy[0], ux[1], uy[1]);
  };
  return f;
}

}  // namespace

cv::Mat RealisticScene::RenderFrame(int k, bool with_noise) const {
  CheckValue(k >= 0 && k < spec_.frames, "realistic frame", std::to_string(k),
             "in [0, frames - 1]");
  const Impl& p = *impl_;
  const int W = spec_.width, H = spec_.height, ss = spec_.supersampling;
  const int nb = spec_.blur_samples;
  std::vector<double> times(nb);
  std::vector<DisplacementField> fields;
  for (int j = 0; j < nb; ++j) {
    times[j] = k / spec_.fps + (j + 0.5) / nb * spec_.exposure_s;
    fields.push_back(FieldAt(*this, times[j]));
  }
  const double light_scale = 1 + spec_.light_drift_per_frame * k;
  const double lx = 0.3 * W, ly = 0.15 * H, diag2 = static_cast<double>(W) * W + H * H;
  const double gx = spec_.glare_x * W, gy = spec_.glare_y * H;
  cv::Mat image(H, W, CV_8U);
  tbb::parallel_for(0, H, [&](int r) {
    Rng rng(spec_.seed * 0x9E3779B97F4A7C15ull + 0x51ull * (k + 1) +
            static_cast<std::uint64_t>(r) * 0x100000001B3ull);
    for (int c = 0; c < W; ++c) {
      double sum = 0;
      for (int sy = 0; sy < ss; ++sy) {
        for (int sx = 0; sx < ss; ++sx) {
          const double x = c + (sx + 0.5) / ss - 0.5, y = r + (sy + 0.5) / ss - 0.5;
          const double light =
              light_scale *
              (1 - spec_.light_falloff * ((x - lx) * (x - lx) + (y - ly) * (y - ly)) / diag2);
          for (int j = 0; j < nb; ++j) {
            const double s = Penetration(times[j]);
            double value;
            if (std::abs(x - axis_px()) < p.b && y < surface_px() + s) {
              value = 0.08 + 0.3 * p.pounder->Intensity(x, y - s);  // Rigid steel pounder.
            } else {
              double X, Y;
              InvertField(fields[j], x, y, &X, &Y);
              value =
                  Y < surface_px() ? 0.35 + 0.4 * p.wall->Intensity(x, y) : p.sand->Intensity(X, Y);
            }
            sum += value * light;
          }
        }
      }
      const double d2 = (c - gx) * (c - gx) + (r - gy) * (r - gy);
      const double glare = spec_.glare_level * std::exp(-d2 / (2 * p.glare_sigma * p.glare_sigma));
      double value = (sum / (ss * ss * nb) + glare) * 255.0;
      if (with_noise && spec_.noise_sigma > 0) value += spec_.noise_sigma * rng.Normal();
      image.at<std::uint8_t>(r, c) =
          static_cast<std::uint8_t>(std::clamp(std::round(value), 0.0, 255.0));
    }
  });
  return image;
}

cv::Vec2d RealisticScene::MeanDisplacement(double X, double Y, int k) const {
  cv::Vec2d sum(0, 0);
  const int nb = spec_.blur_samples;
  for (int j = 0; j < nb; ++j)
    sum += SoilDisplacement(X, Y, k / spec_.fps + (j + 0.5) / nb * spec_.exposure_s);
  return sum / nb;
}

bool RealisticScene::ReferencePoint(double x, double y, double* X, double* Y) const {
  DisplacementField mean0;
  mean0.u = [this](double a, double b) { return MeanDisplacement(a, b, 0); };
  mean0.gradient = [this](double a, double b) {
    constexpr double h = 1e-5;
    const cv::Vec2d ux = (MeanDisplacement(a + h, b, 0) - MeanDisplacement(a - h, b, 0)) / (2 * h);
    const cv::Vec2d uy = (MeanDisplacement(a, b + h, 0) - MeanDisplacement(a, b - h, 0)) / (2 * h);
    return cv::Vec4d(ux[0], uy[0], ux[1], uy[1]);
  };
  return InvertField(mean0, x, y, X, Y);
}

RealisticTruth RealisticScene::Truth(const std::vector<cv::Point2d>& points, int k,
                                     double half_px) const {
  const Impl& p = *impl_;
  const std::size_t n = points.size();
  RealisticTruth t;
  t.u_px.assign(n, 0);
  t.v_px.assign(n, 0);
  t.straddles_edge.assign(n, 0);
  t.straddles_shear_band.assign(n, 0);
  t.in_glare.assign(n, 0);
  const double s_max = Penetration(k / spec_.fps + spec_.exposure_s);
  const double band_depth = s_max > 0.02 ? p.core * std::sqrt(std::log(s_max / 0.02)) : 0;
  const double gx = spec_.glare_x * spec_.width, gy = spec_.glare_y * spec_.height;
  const double glare_reach =
      spec_.glare_level > kGlareFlag
          ? p.glare_sigma * std::sqrt(2 * std::log(spec_.glare_level / kGlareFlag))
          : -1;
  // Pounder depth: exposure mean (truth) and extremes (flags) in frame 0 and frame k.
  double s_mean0 = 0, s_meank = 0;
  for (int j = 0; j < spec_.blur_samples; ++j) {
    const double dt = (j + 0.5) / spec_.blur_samples * spec_.exposure_s;
    s_mean0 += Penetration(dt) / spec_.blur_samples;
    s_meank += Penetration(k / spec_.fps + dt) / spec_.blur_samples;
  }
  const double s_min0 = Penetration(0), s_max0 = Penetration(spec_.exposure_s);
  const double s_mink = Penetration(k / spec_.fps);
  for (std::size_t i = 0; i < n; ++i) {
    const double x = points[i].x, y = points[i].y;
    // A subset entirely on the pounder (in frame 0 and frame k) moves with it.
    const bool on_pounder = std::abs(x - axis_px()) + half_px < p.b - 1 &&
                            y + half_px < surface_px() + std::min(s_min0, s_mink) - 1;
    // The centre on the pounder in frame 0: its truth is the pounder's motion (the subset is
    // flagged below unless it lies entirely on the pounder).
    const bool centre_on_pounder = std::abs(x - axis_px()) < p.b && y < surface_px() + s_mean0;
    if (on_pounder || centre_on_pounder) {
      t.u_px[i] = 0;
      t.v_px[i] = s_meank - s_mean0;
      t.straddles_edge[i] = !on_pounder;
      continue;
    }
    double X, Y;
    ReferencePoint(x, y, &X, &Y);
    // Above the surface the pixel sees the static wall, not sand.
    const bool wall = Y < surface_px();
    const cv::Vec2d d =
        wall ? cv::Vec2d(0, 0) : MeanDisplacement(X, Y, k) - MeanDisplacement(X, Y, 0);
    t.u_px[i] = d[0];
    t.v_px[i] = d[1];
    // Body edges: the sand surface (material), or the pounder covers part of the subset in frame
    // 0 or in frame k.
    const double eta0 = Y - half_px - surface_px(), eta1 = Y + half_px - surface_px();
    bool edge = eta0 < 1 && eta1 > -1;
    for (const auto& [cx, cy, s] :
         {std::tuple{x, y, s_max0}, std::tuple{x + d[0], y + d[1], s_max}}) {
      const bool x_overlap = std::abs(cx - axis_px()) < p.b + half_px + 1;
      if (x_overlap && cy - half_px < surface_px() + s + 1) edge = true;
    }
    t.straddles_edge[i] = edge;
    // Shear bands at |xi| = b, in the sand down to where the slip falls below 0.02 px.
    const double xi = X - axis_px();
    const bool near_band = std::abs(std::abs(xi) - p.b) < half_px + 3 * p.w ||
                           (std::abs(xi) < p.b + half_px && std::abs(xi) > p.b - half_px);
    t.straddles_shear_band[i] = near_band && eta1 > 0 && eta0 < band_depth;
    // Glare: the nearest point of the (frame k) subset to the glare centre.
    const double cx = points[i].x + d[0], cy = points[i].y + d[1];
    const double dx = std::max(std::abs(cx - gx) - half_px, 0.0);
    const double dy = std::max(std::abs(cy - gy) - half_px, 0.0);
    t.in_glare[i] = std::hypot(dx, dy) < glare_reach;
  }
  return t;
}

std::vector<cv::Point2d> RealisticScene::GridPoints(int* cols, int* rows) const {
  // The correlator's layout on the whole image: 4 px kept from the border.
  constexpr int kBorderPx = 4;
  const int size = spec_.subset_size, half = size / 2;
  const int w = spec_.width - 2 * kBorderPx, h = spec_.height - 2 * kBorderPx;
  *cols = (w - size) / spec_.step + 1;
  *rows = (h - size) / spec_.step + 1;
  std::vector<cv::Point2d> points;
  for (int r = 0; r < *rows; ++r)
    for (int c = 0; c < *cols; ++c)
      points.emplace_back(kBorderPx + half + c * spec_.step, kBorderPx + half + r * spec_.step);
  return points;
}

}  // namespace impactdic
