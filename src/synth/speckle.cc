// Analytic speckle pattern and exact rendering (see speckle.h).
//
// Intensity model: I(X) = background + (1 - background) * contrast * (1 - exp(-S(X))),
// S(X) = sum_i a_i exp(-|X - X_i|^2 / (2 s_i^2)). The saturating form keeps I in [0, 1) however
// many blobs overlap, so the analytic image never clips. Blobs are binned in a grid of cells of
// size R = 4 max(s_i); a point only sums the blobs of the cells within R (contributions beyond
// 4 sigma, < 3.4e-4 a_i, are dropped: this is part of the pattern's definition, identical for
// the reference and every deformed image, so it does not affect the ground truth).
#include "impactdic/synth/speckle.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "impactdic/core/error.h"
#include "random.h"

namespace impactdic {
namespace {

using synth_detail::Rng;

}  // namespace

void SpeckleOptions::Check() const {
  CheckValue(blob_radius_px > 0 && std::isfinite(blob_radius_px), "SpeckleOptions.blob_radius_px",
             std::to_string(blob_radius_px), "> 0");
  CheckValue(density > 0 && density <= 5, "SpeckleOptions.density", std::to_string(density),
             "in (0, 5]");
  CheckValue(contrast > 0 && contrast <= 1, "SpeckleOptions.contrast", std::to_string(contrast),
             "in (0, 1]");
  CheckValue(background >= 0 && background < 1, "SpeckleOptions.background",
             std::to_string(background), "in [0, 1)");
}

void RenderOptions::Check() const {
  CheckValue(bits == 8 || bits == 16, "RenderOptions.bits", std::to_string(bits), "8 or 16");
  CheckValue(noise_sigma >= 0 && std::isfinite(noise_sigma), "RenderOptions.noise_sigma",
             std::to_string(noise_sigma), ">= 0 grey levels");
  CheckValue(std::isfinite(gain) && gain > 0, "RenderOptions.gain", std::to_string(gain), "> 0");
  CheckValue(std::isfinite(offset), "RenderOptions.offset", std::to_string(offset), "finite");
  CheckValue(supersampling >= 1 && supersampling <= 16, "RenderOptions.supersampling",
             std::to_string(supersampling), "in [1, 16]");
}

struct SpecklePattern::Impl {
  SpeckleOptions options;
  double x0 = 0, y0 = 0;  // Material coordinates of the grid's corner.
  double cell = 1;        // Cell size [px] = cut-off radius.
  int cols = 0, rows = 0;
  // Blobs sorted by cell (CSR): cell c holds blobs [start[c], start[c + 1]).
  std::vector<int> start;
  std::vector<double> bx, by, amp, inv2s2;
  double scale = 1;  // (1 - background) * contrast.
};

SpecklePattern::SpecklePattern(const SpeckleOptions& options, int width, int height,
                               double margin_px) {
  options.Check();
  CheckValue(width > 0 && height > 0, "SpecklePattern size",
             std::to_string(width) + "x" + std::to_string(height), "positive width and height");
  CheckValue(margin_px >= 0, "SpecklePattern.margin_px", std::to_string(margin_px), ">= 0");
  auto impl = std::make_shared<Impl>();
  impl->options = options;
  const double r = options.blob_radius_px;
  const double max_sigma = 1.2 * r;
  impl->cell = 4 * max_sigma;
  impl->x0 = -margin_px - impl->cell;
  impl->y0 = -margin_px - impl->cell;
  const double span_x = width + 2 * margin_px + 2 * impl->cell;
  const double span_y = height + 2 * margin_px + 2 * impl->cell;
  impl->cols = static_cast<int>(std::ceil(span_x / impl->cell));
  impl->rows = static_cast<int>(std::ceil(span_y / impl->cell));
  const double area = span_x * span_y;
  const auto count =
      static_cast<std::size_t>(std::llround(options.density * area / (std::numbers::pi * r * r)));

  Rng rng(options.seed);
  struct Blob {
    int cell;
    double x, y, a, k;
  };
  std::vector<Blob> blobs(count);
  for (auto& b : blobs) {
    b.x = impl->x0 + rng.Uniform() * span_x;
    b.y = impl->y0 + rng.Uniform() * span_y;
    b.a = 0.6 + rng.Uniform();                         // Amplitude in [0.6, 1.6).
    const double s = r * (0.8 + 0.4 * rng.Uniform());  // Sigma in [0.8 r, 1.2 r).
    b.k = 1 / (2 * s * s);
    const int cx = std::clamp(static_cast<int>((b.x - impl->x0) / impl->cell), 0, impl->cols - 1);
    const int cy = std::clamp(static_cast<int>((b.y - impl->y0) / impl->cell), 0, impl->rows - 1);
    b.cell = cy * impl->cols + cx;
  }
  std::stable_sort(blobs.begin(), blobs.end(),
                   [](const Blob& a, const Blob& b) { return a.cell < b.cell; });
  impl->start.assign(static_cast<std::size_t>(impl->cols) * impl->rows + 1, 0);
  for (const auto& b : blobs) ++impl->start[b.cell + 1];
  for (std::size_t c = 1; c < impl->start.size(); ++c) impl->start[c] += impl->start[c - 1];
  for (const auto& b : blobs) {
    impl->bx.push_back(b.x);
    impl->by.push_back(b.y);
    impl->amp.push_back(b.a);
    impl->inv2s2.push_back(b.k);
  }
  impl->scale = (1 - options.background) * options.contrast;
  impl_ = std::move(impl);
}

double SpecklePattern::Intensity(double X, double Y) const {
  const Impl& p = *impl_;
  const double R = p.cell, R2 = R * R;
  const int cx0 = std::max(0, static_cast<int>(std::floor((X - R - p.x0) / R)));
  const int cx1 = std::min(p.cols - 1, static_cast<int>(std::floor((X + R - p.x0) / R)));
  const int cy0 = std::max(0, static_cast<int>(std::floor((Y - R - p.y0) / R)));
  const int cy1 = std::min(p.rows - 1, static_cast<int>(std::floor((Y + R - p.y0) / R)));
  double s = 0;
  for (int cy = cy0; cy <= cy1; ++cy) {
    for (int cx = cx0; cx <= cx1; ++cx) {
      const int c = cy * p.cols + cx;
      for (int i = p.start[c]; i < p.start[c + 1]; ++i) {
        const double dx = X - p.bx[i], dy = Y - p.by[i];
        const double d2 = dx * dx + dy * dy;
        if (d2 < R2) s += p.amp[i] * std::exp(-d2 * p.inv2s2[i]);
      }
    }
  }
  return p.options.background + p.scale * (1 - std::exp(-s));
}

bool InvertField(const DisplacementField& field, double x, double y, double* X, double* Y) {
  double px = x, py = y;
  for (int it = 0; it < 60; ++it) {
    const cv::Vec2d u = field.u(px, py);
    const double fx = px + u[0] - x, fy = py + u[1] - y;
    if (std::abs(fx) < 1e-11 && std::abs(fy) < 1e-11) {
      *X = px;
      *Y = py;
      return true;
    }
    const cv::Vec4d g = field.gradient(px, py);
    const double a = 1 + g[0], b = g[1], c = g[2], d = 1 + g[3];
    const double det = a * d - b * c;
    if (!(std::abs(det) > 1e-12)) break;
    px -= (d * fx - b * fy) / det;
    py -= (-c * fx + a * fy) / det;
    if (!std::isfinite(px) || !std::isfinite(py)) break;
  }
  *X = px;
  *Y = py;
  return false;
}

cv::Mat RenderImage(const SpecklePattern& pattern, int width, int height,
                    const DisplacementField& field, const RenderOptions& options) {
  options.Check();
  CheckValue(width > 0 && height > 0, "RenderImage size",
             std::to_string(width) + "x" + std::to_string(height), "positive width and height");
  const double full = options.bits == 8 ? 255.0 : 65535.0;
  cv::Mat image(height, width, options.bits == 8 ? CV_8U : CV_16U);
  const int ss = options.supersampling;
  tbb::parallel_for(0, height, [&](int r) {
    // Noise seeded per row: the image does not depend on the number of threads.
    Rng rng(options.noise_seed * 0x100000001B3ull + static_cast<std::uint64_t>(r));
    for (int c = 0; c < width; ++c) {
      double sum = 0;
      for (int sy = 0; sy < ss; ++sy) {
        for (int sx = 0; sx < ss; ++sx) {
          const double x = c + (sx + 0.5) / ss - 0.5, y = r + (sy + 0.5) / ss - 0.5;
          double X, Y;
          InvertField(field, x, y, &X, &Y);
          sum += pattern.Intensity(X, Y);
        }
      }
      double value = (options.gain * sum / (ss * ss) + options.offset) * full;
      if (options.noise_sigma > 0) value += options.noise_sigma * rng.Normal();
      value = std::clamp(std::round(value), 0.0, full);
      if (options.bits == 8) {
        image.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(value);
      } else {
        image.at<std::uint16_t>(r, c) = static_cast<std::uint16_t>(value);
      }
    }
  });
  return image;
}

}  // namespace impactdic
