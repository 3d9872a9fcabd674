#include "impactdic/preprocess/nyquist_bias.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstddef>
#include <numbers>

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

// A Hann window of side n, separable.
cv::Mat HannWindow(int n) {
  cv::Mat w(n, n, CV_64F);
  std::vector<double> h(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) h[i] = 0.5 - 0.5 * std::cos(2 * kPi * (i + 0.5) / n);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) w.at<double>(y, x) = h[y] * h[x];
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
  std::vector<double> px(static_cast<std::size_t>(n / 2 + 1), 0.0), py = px;
  cv::Mat tile, spectrum;
  for (int y0 : ys) {
    for (int x0 : xs) {
      image(cv::Rect(roi.x + x0, roi.y + y0, n, n)).convertTo(tile, CV_64F);
      tile -= cv::mean(tile)[0];
      tile = tile.mul(window);
      cv::dft(tile, spectrum, cv::DFT_COMPLEX_OUTPUT);
      for (int v = 0; v < n; ++v) {
        const int fv = v <= n / 2 ? v : n - v;
        const cv::Vec2d* row = spectrum.ptr<cv::Vec2d>(v);
        for (int u = 0; u < n; ++u) {
          const int fu = u <= n / 2 ? u : n - u;
          const double p = row[u][0] * row[u][0] + row[u][1] * row[u][1];
          px[static_cast<std::size_t>(fu)] += p;
          py[static_cast<std::size_t>(fv)] += p;
        }
      }
      ++out.tiles;
    }
  }
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

}  // namespace impactdic
