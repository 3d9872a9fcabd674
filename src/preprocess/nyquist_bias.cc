#include "impactdic/preprocess/nyquist_bias.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstddef>
#include <limits>
#include <numbers>
#include <opencv2/imgproc.hpp>
#include <optional>

namespace impactdic {
namespace {

constexpr double kPi = std::numbers::pi;

// The cubic B-spline beta3(x).
double Beta3(double x) {
  x = std::abs(x);
  if (x < 1) return 2.0 / 3.0 - x * x + 0.5 * x * x * x;
  if (x < 2) return (2 - x) * (2 - x) * (2 - x) / 6.0;
  return 0;
}

// A Hann window of side n, separable, its centre moved by (dx, dy) px.
cv::Mat HannWindow(int n, double dx = 0, double dy = 0) {
  cv::Mat w(n, n, CV_64F);
  std::vector<double> hx(static_cast<std::size_t>(n)), hy = hx;
  for (int i = 0; i < n; ++i) {
    hx[i] = 0.5 - 0.5 * std::cos(2 * kPi * (i + 0.5 - dx) / n);
    hy[i] = 0.5 - 0.5 * std::cos(2 * kPi * (i + 0.5 - dy) / n);
  }
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) w.at<double>(y, x) = hy[y] * hx[x];
  return w;
}

// Tile origins along an axis of `length` px: as many tiles of `side` as fit without overlap, at
// most `max_count`, spread evenly.
std::vector<int> TileOrigins(int length, int side, int max_count) {
  const int fit = length / side;
  const int count = std::min(fit, max_count);
  std::vector<int> origins;
  origins.reserve(static_cast<std::size_t>(std::max(count, 0)));
  for (int i = 0; i < count; ++i) {
    origins.push_back(
        count == 1 ? (length - side) / 2
                   : static_cast<int>(std::lround(double(i) * (length - side) / (count - 1))));
  }
  return origins;
}

}  // namespace

double PredictedBicubicBiasPx(const std::vector<double>& power, int n, double t) {
  double num = 0, den = 0;
  for (int k = 1; k <= n / 2 && k < static_cast<int>(power.size()); ++k) {
    const double w = 2 * kPi * k / n;
    const double b = (2 + std::cos(w)) / 3;  // B(w): the interpolation prefilter's response.
    std::complex<double> a = 0;
    for (int j = -2; j <= 2; ++j) a += Beta3(t - j) * std::polar(1.0, -w * (t - j));
    const std::complex<double> transfer = a / b;
    const double d = std::sin(w) / b;  // The B-spline gradient's response (up to i).
    const double weight = power[static_cast<std::size_t>(k)] * d * std::abs(transfer);
    num += weight * std::arg(transfer);
    den += weight * w;
  }
  return den > 0 ? -num / den : 0.0;
}

NyquistBias MeasureNyquistBias(const cv::Mat& image, cv::Rect roi) {
  NyquistBias out;
  if (roi.empty()) roi = cv::Rect(0, 0, image.cols, image.rows);
  roi &= cv::Rect(0, 0, image.cols, image.rows);
  int n = 64;
  while (n > 16 && (roi.width < n || roi.height < n)) n /= 2;
  if (roi.width < n || roi.height < n) return out;
  // At most kMaxNyquistTiles tiles: a square-ish grid of them.
  const int per_axis = std::max(1, static_cast<int>(std::sqrt(double(kMaxNyquistTiles))));
  const std::vector<int> xs = TileOrigins(roi.width, n, per_axis);
  const std::vector<int> ys = TileOrigins(roi.height, n, per_axis);
  const cv::Mat window = HannWindow(n);
  // The marginal spectra of each tile (tiles in parallel), then summed in the tiles' order: the
  // same figures for any number of threads.
  const std::size_t bins = static_cast<std::size_t>(n) / 2 + 1;
  const int tiles = static_cast<int>(xs.size() * ys.size());
  std::vector<double> marginals(static_cast<std::size_t>(tiles) * 2 * bins, 0.0);
  tbb::parallel_for(0, tiles, [&](int k) {
    const int x0 = xs[static_cast<std::size_t>(k) % xs.size()];
    const int y0 = ys[static_cast<std::size_t>(k) / xs.size()];
    double* tx = &marginals[static_cast<std::size_t>(k) * 2 * bins];
    double* ty = tx + bins;
    // The tile less its mean, times the window, in the thread's buffers.
    thread_local cv::Mat tile, spectrum;
    image(cv::Rect(roi.x + x0, roi.y + y0, n, n)).convertTo(tile, CV_64F);
    const double mean = cv::mean(tile)[0];
    for (int y = 0; y < n; ++y) {
      double* t = tile.ptr<double>(y);
      const double* w = window.ptr<double>(y);
      for (int x = 0; x < n; ++x) t[x] = (t[x] - mean) * w[x];
    }
    cv::dft(tile, spectrum, cv::DFT_COMPLEX_OUTPUT);
    for (int v = 0; v < n; ++v) {
      const int fv = v <= n / 2 ? v : n - v;
      const cv::Vec2d* row = spectrum.ptr<cv::Vec2d>(v);
      double row_power = 0;  // Added to ty once per row (not one dependent add per bin).
      for (int u = 0; u < n; ++u) {
        const int fu = u <= n / 2 ? u : n - u;
        const double p = row[u][0] * row[u][0] + row[u][1] * row[u][1];
        tx[fu] += p;
        row_power += p;
      }
      ty[fv] += row_power;
    }
  });
  std::vector<double> px(bins, 0.0), py = px;
  for (int k = 0; k < tiles; ++k) {
    const double* tx = &marginals[static_cast<std::size_t>(k) * 2 * bins];
    for (std::size_t b = 0; b < bins; ++b) {
      px[b] += tx[b];
      py[b] += tx[bins + b];
    }
  }
  out.tiles = tiles;
  out.tile_size = n;
  out.bias_x_px = out.bias_y_px = 0;
  for (int i = 1; i < 20; ++i) {
    const double t = 0.05 * i;
    out.bias_x_px = std::max(out.bias_x_px, std::abs(PredictedBicubicBiasPx(px, n, t)));
    out.bias_y_px = std::max(out.bias_y_px, std::abs(PredictedBicubicBiasPx(py, n, t)));
  }
  out.bias_px = std::max(out.bias_x_px, out.bias_y_px);
  return out;
}

namespace {

// The response of a symmetric 1-D kernel (odd length) at w: sum_j k_j cos(w j).
double KernelResponse(const cv::Mat& kernel, double w) {
  const int len = kernel.rows * kernel.cols, half = len / 2;
  double g = 0;
  for (int j = 0; j < len; ++j) g += kernel.at<double>(j) * std::cos(w * (j - half));
  return g;
}

// The max over t of |predicted bias| of a one-sided marginal spectrum.
double MaxBias(const std::vector<double>& power, int n) {
  double out = 0;
  for (int i = 1; i < 20; ++i)
    out = std::max(out, std::abs(PredictedBicubicBiasPx(power, n, 0.05 * i)));
  return out;
}

// var(u) (axis 0) or var(v) (axis 1) of the header's formula from the tiles' summed 2-D spectra
// of the reference (p) and of the pair's residual (r), n x n, with the filter's |G|^2 (g) or
// without it (g empty).
double RandomVariance(const cv::Mat& p, const cv::Mat& r, const cv::Mat& g, int axis,
                      int subset_px) {
  const int n = p.rows;
  double num = 0, den = 0;
  for (int v = 0; v < n; ++v) {
    for (int u = 0; u < n; ++u) {
      const int k = axis == 0 ? u : v;
      const double w = 2 * kPi * (k <= n / 2 ? k : k - n) / n;
      const double d = 3 * std::sin(w) / (2 + std::cos(w));
      const double gain = g.empty() ? 1.0 : g.at<double>(v, u);
      const double noise = r.at<double>(v, u);
      const double signal = std::max(p.at<double>(v, u) - 0.5 * noise, 0.0);
      const double sg = signal * d * d * gain;
      num += sg * noise * gain;
      den += sg;
    }
  }
  // The spectra's common scale (Parseval, the window, the tiles) cancels.
  return den > 0 ? double(n) * n / subset_px * num / (den * den)
                 : std::numeric_limits<double>::infinity();
}

}  // namespace

namespace {

// One tile of the first pair: the reference's spectrum and the residual spectrum
// F1 - F0 e^{-i w s} after the tile's shift s (complex, n x n), and its energy.
struct TradeTile {
  cv::Mat f0, d;
  double residual = 0;
};

// The angular frequency of DFT index k of n.
double Frequency(int k, int n) { return 2 * kPi * (k <= n / 2 ? k : k - n) / n; }

// The fractional shift (fx, fy) minimising sum |F1 - F0 e^{-i w f}|^2 by Gauss-Newton from the
// given start (phase correlation's own sub-pixel estimate is off by a few hundredths of a pixel,
// which would count |w f|^2 of the texture's power as noise). The deformed tile's window moves
// with its content (w(x - f)), else the window's edge counts as noise (on a 0.5 px shift of
// sharp speckle, 5 grey levels^2 of it); f1 receives the deformed tile's spectrum.
void FitShift(const cv::Mat& f0, const cv::Mat& t1, double* fx, double* fy, cv::Mat* f1) {
  const int n = f0.rows;
  for (int it = 0; it < 6; ++it) {
    if (it % 2 == 0) cv::dft(t1.mul(HannWindow(n, *fx, *fy)), *f1, cv::DFT_COMPLEX_OUTPUT);
    double jxx = 0, jxy = 0, jyy = 0, gx = 0, gy = 0;
    for (int v = 0; v < n; ++v) {
      const double wv = Frequency(v, n);
      const cv::Vec2d* a = f0.ptr<cv::Vec2d>(v);
      const cv::Vec2d* b = f1->ptr<cv::Vec2d>(v);
      for (int u = 0; u < n; ++u) {
        const double wu = Frequency(u, n);
        const std::complex<double> m =
            std::complex<double>(a[u][0], a[u][1]) * std::polar(1.0, -(wu * *fx + wv * *fy));
        const std::complex<double> r = std::complex<double>(b[u][0], b[u][1]) - m;
        const double p = std::norm(m);
        // dr/df = i w m: conj(i m) r = -i conj(m) r, real part = Im(conj(m) r).
        const double q = (std::conj(m) * r).imag();
        jxx += wu * wu * p, jxy += wu * wv * p, jyy += wv * wv * p;
        gx += wu * q, gy += wv * q;
      }
    }
    const double det = jxx * jyy - jxy * jxy;
    if (!(det > 0)) break;
    // Gauss-Newton: (J^H J) delta = -Re(J^H r).
    *fx -= (jyy * gx - jxy * gy) / det;
    *fy -= (jxx * gy - jxy * gx) / det;
  }
}

// The tile at r0 of the pair, or nothing when its shift takes it out of the image.
std::optional<TradeTile> MeasureTile(const cv::Mat& reference, const cv::Mat& next,
                                     const cv::Rect& r0, const cv::Mat& window) {
  const int n = r0.width;
  cv::Mat t0, t1;
  reference(r0).convertTo(t0, CV_64F);
  next(r0).convertTo(t1, CV_64F);
  // The tile's shift of the next image against the reference (content at x in the reference is
  // at x + s in the next one). phaseCorrelate windows its inputs in place.
  const cv::Point2d s = cv::phaseCorrelate(t0, t1, window);
  const cv::Point whole(static_cast<int>(std::lround(s.x)), static_cast<int>(std::lround(s.y)));
  const cv::Rect r1 = r0 + whole;
  if ((r1 & cv::Rect(0, 0, next.cols, next.rows)) != r1) return std::nullopt;
  next(r1).convertTo(t1, CV_64F);
  reference(r0).convertTo(t0, CV_64F);
  t0 -= cv::mean(t0)[0];
  t1 -= cv::mean(t1)[0];
  TradeTile tile;
  cv::dft(t0.mul(window), tile.f0, cv::DFT_COMPLEX_OUTPUT);
  double fx = s.x - whole.x, fy = s.y - whole.y;
  cv::Mat f1;
  FitShift(tile.f0, t1, &fx, &fy, &f1);
  tile.d.create(n, n, CV_64FC2);
  for (int v = 0; v < n; ++v) {
    const double wv = Frequency(v, n);
    const cv::Vec2d* a = tile.f0.ptr<cv::Vec2d>(v);
    const cv::Vec2d* b = f1.ptr<cv::Vec2d>(v);
    cv::Vec2d* d = tile.d.ptr<cv::Vec2d>(v);
    for (int u = 0; u < n; ++u) {
      // F1 = F0 e^{-i w s} for a shift s: undo the fractional part.
      const std::complex<double> shifted = std::complex<double>(a[u][0], a[u][1]) *
                                           std::polar(1.0, -(Frequency(u, n) * fx + wv * fy));
      const std::complex<double> r = std::complex<double>(b[u][0], b[u][1]) - shifted;
      d[u] = cv::Vec2d(r.real(), r.imag());
      tile.residual += std::norm(r);
    }
  }
  return tile;
}

// The sums over `tiles` (those with a residual at most twice the median: deformation and
// occlusion left out) of the reference's power spectrum (p2) and the residual's (r2), and the
// residual energy; the count of tiles used.
int SumSpectra(const std::vector<TradeTile>& tiles, cv::Mat* p2, cv::Mat* r2, double* energy) {
  std::vector<double> residuals;
  residuals.reserve(tiles.size());
  for (const TradeTile& t : tiles) residuals.push_back(t.residual);
  std::nth_element(residuals.begin(), residuals.begin() + residuals.size() / 2, residuals.end());
  const double limit = 2 * residuals[residuals.size() / 2];
  const int n = tiles.front().f0.rows;
  *p2 = cv::Mat::zeros(n, n, CV_64F);
  *r2 = cv::Mat::zeros(n, n, CV_64F);
  *energy = 0;
  int used = 0;
  for (const TradeTile& t : tiles) {
    if (t.residual > limit) continue;
    ++used;
    *energy += t.residual;
    for (int v = 0; v < n; ++v) {
      const cv::Vec2d* a = t.f0.ptr<cv::Vec2d>(v);
      const cv::Vec2d* d = t.d.ptr<cv::Vec2d>(v);
      double* pp = p2->ptr<double>(v);
      double* rr = r2->ptr<double>(v);
      for (int u = 0; u < n; ++u) {
        pp[u] += a[u][0] * a[u][0] + a[u][1] * a[u][1];
        rr[u] += d[u][0] * d[u][0] + d[u][1] * d[u][1];
      }
    }
  }
  return used;
}

}  // namespace

PrefilterTrade MeasurePrefilterTrade(const cv::Mat& reference, const cv::Mat& next, cv::Rect roi,
                                     const cv::Mat& kernel_in, int subset_size) {
  PrefilterTrade out;
  if (next.empty() || next.size() != reference.size() || subset_size < 1) return out;
  if (roi.empty()) roi = cv::Rect(0, 0, reference.cols, reference.rows);
  roi &= cv::Rect(0, 0, reference.cols, reference.rows);
  int n = 64;
  while (n > 32 && (roi.width < n || roi.height < n)) n /= 2;
  if (roi.width < n || roi.height < n) return out;
  cv::Mat kernel;
  kernel_in.convertTo(kernel, CV_64F);
  std::vector<double> g2(static_cast<std::size_t>(n));  // |G|^2 per DFT index.
  for (int u = 0; u < n; ++u) {
    const double gu = KernelResponse(kernel, Frequency(u, n));
    g2[static_cast<std::size_t>(u)] = gu * gu;
  }
  const int per_axis = std::max(1, static_cast<int>(std::sqrt(double(kMaxTradeTiles))));
  const std::vector<int> xs = TileOrigins(roi.width, n, per_axis);
  const std::vector<int> ys = TileOrigins(roi.height, n, per_axis);
  const cv::Mat window = HannWindow(n);
  std::vector<TradeTile> tiles;
  tiles.reserve(xs.size() * ys.size());
  for (int y0 : ys) {
    for (int x0 : xs) {
      std::optional<TradeTile> tile =
          MeasureTile(reference, next, cv::Rect(roi.x + x0, roi.y + y0, n, n), window);
      if (tile) tiles.push_back(std::move(*tile));
    }
  }
  if (tiles.empty()) return out;
  cv::Mat p2, r2;
  double noise_energy = 0;
  out.tiles = SumSpectra(tiles, &p2, &r2, &noise_energy);
  cv::Mat g(n, n, CV_64F);
  for (int v = 0; v < n; ++v)
    for (int u = 0; u < n; ++u)
      g.at<double>(v, u) = g2[static_cast<std::size_t>(u)] * g2[static_cast<std::size_t>(v)];
  // Per-pixel scale of the summed spectra (Parseval, the window's mean square, the tiles).
  const double window_ms = cv::mean(window.mul(window))[0];
  const double scale = 1.0 / (double(n) * n * n * n * window_ms * out.tiles);
  out.noise_grey = std::sqrt(noise_energy * scale / 2);
  // The bias from the axes' marginals of the reference spectrum (MeasureNyquistBias's model).
  std::vector<double> px(static_cast<std::size_t>(n / 2 + 1)), py = px, pgx = px, pgy = px;
  for (int v = 0; v < n; ++v) {
    const auto fv = static_cast<std::size_t>(v <= n / 2 ? v : n - v);
    for (int u = 0; u < n; ++u) {
      const auto fu = static_cast<std::size_t>(u <= n / 2 ? u : n - u);
      const double pw = p2.at<double>(v, u), pg = pw * g.at<double>(v, u);
      px[fu] += pw, py[fv] += pw, pgx[fu] += pg, pgy[fv] += pg;
    }
  }
  const int subset_px = subset_size * subset_size;
  out.bias_px = std::hypot(MaxBias(px, n), MaxBias(py, n));
  out.bias_filtered_px = std::hypot(MaxBias(pgx, n), MaxBias(pgy, n));
  out.random_px = std::sqrt(
      (RandomVariance(p2, r2, {}, 0, subset_px) + RandomVariance(p2, r2, {}, 1, subset_px)));
  out.random_filtered_px = std::sqrt(
      (RandomVariance(p2, r2, g, 0, subset_px) + RandomVariance(p2, r2, g, 1, subset_px)));
  return out;
}

}  // namespace impactdic
