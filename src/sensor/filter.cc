#include "impactdic/sensor/filter.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "impactdic/core/error.h"

namespace impactdic {

FirstOrderLowpass DesignButterworthLowpass1(double cutoff_hz, double sample_rate_hz) {
  CheckValue(std::isfinite(sample_rate_hz) && sample_rate_hz > 0, "sample_rate_hz",
             fmt::format("{}", sample_rate_hz), "a positive sample rate");
  CheckValue(std::isfinite(cutoff_hz) && cutoff_hz > 0 && cutoff_hz < 0.5 * sample_rate_hz,
             "cutoff_hz", fmt::format("{} Hz", cutoff_hz),
             fmt::format("0 < cutoff < Nyquist = {} Hz", 0.5 * sample_rate_hz));
  // Pre-warped bilinear transform of 1 / (1 + s / w_c).
  const double k = std::tan(std::numbers::pi * cutoff_hz / sample_rate_hz);
  FirstOrderLowpass f;
  f.b0 = k / (1 + k);
  f.b1 = f.b0;
  f.a1 = (k - 1) / (k + 1);
  f.cutoff_hz = cutoff_hz;
  f.sample_rate_hz = sample_rate_hz;
  return f;
}

double ZeroPhaseGain(const FirstOrderLowpass& filter, double f_hz) {
  const double k = std::tan(std::numbers::pi * filter.cutoff_hz / filter.sample_rate_hz);
  const double r = std::tan(std::numbers::pi * f_hz / filter.sample_rate_hz) / k;
  return 1 / (1 + r * r);
}

std::vector<double> FilterForward(const FirstOrderLowpass& filter, const std::vector<double>& x) {
  std::vector<double> y(x.size());
  if (x.empty()) return y;
  // Steady state for a constant input x[0]: y = x[0] (unit DC gain), previous input x[0].
  double x_prev = x[0], y_prev = x[0];
  for (std::size_t n = 0; n < x.size(); ++n) {
    const double yn = filter.b0 * x[n] + filter.b1 * x_prev - filter.a1 * y_prev;
    y[n] = yn;
    x_prev = x[n];
    y_prev = yn;
  }
  return y;
}

int DefaultPadLength(const FirstOrderLowpass& filter, std::size_t n) {
  const double pole = std::abs(filter.a1);
  int pad = 6;
  if (pole > 0 && pole < 1)
    pad = std::max(pad, static_cast<int>(std::ceil(std::log(1e-12) / std::log(pole))));
  return static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(pad), n - 1));
}

std::vector<double> FiltFilt(const FirstOrderLowpass& filter, const std::vector<double>& x,
                             int pad) {
  CheckValue(x.size() >= 2, "FiltFilt input", fmt::format("{} samples", x.size()),
             "at least 2 samples");
  const std::size_t n = x.size();
  if (pad < 0) pad = DefaultPadLength(filter, n);
  const std::size_t p = std::min<std::size_t>(static_cast<std::size_t>(pad), n - 1);
  // Odd reflection about both end samples.
  std::vector<double> ext(n + 2 * p);
  for (std::size_t i = 0; i < p; ++i) ext[i] = 2 * x[0] - x[p - i];
  std::copy(x.begin(), x.end(), ext.begin() + static_cast<std::ptrdiff_t>(p));
  for (std::size_t i = 0; i < p; ++i) ext[p + n + i] = 2 * x[n - 1] - x[n - 2 - i];
  std::vector<double> y = FilterForward(filter, ext);
  std::reverse(y.begin(), y.end());
  y = FilterForward(filter, y);
  std::reverse(y.begin(), y.end());
  return std::vector<double>(y.begin() + static_cast<std::ptrdiff_t>(p),
                             y.begin() + static_cast<std::ptrdiff_t>(p + n));
}

}  // namespace impactdic
