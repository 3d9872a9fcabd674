#include "impactdic/sensor/filter.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "impactdic/core/error.h"

namespace impactdic {
namespace {

constexpr double kFs = 25000, kFc = 1500;

// Least-squares amplitude of sin and cos components of y over samples [b, e) at frequency f.
void FitSinCos(const std::vector<double>& y, double f, std::size_t b, std::size_t e, double* s,
               double* c) {
  double ss = 0, cc = 0, sc = 0, ys = 0, yc = 0;
  for (std::size_t i = b; i < e; ++i) {
    const double ph = 2 * std::numbers::pi * f * static_cast<double>(i) / kFs;
    const double si = std::sin(ph), ci = std::cos(ph);
    ss += si * si;
    cc += ci * ci;
    sc += si * ci;
    ys += y[i] * si;
    yc += y[i] * ci;
  }
  const double det = ss * cc - sc * sc;
  *s = (ys * cc - yc * sc) / det;
  *c = (yc * ss - ys * sc) / det;
}

TEST(Butterworth, DesignMatchesBilinearFormula) {
  const FirstOrderLowpass lp = DesignButterworthLowpass1(kFc, kFs);
  EXPECT_NEAR((lp.b0 + lp.b1) / (1 + lp.a1), 1.0, 1e-15);  // Unit DC gain.
  EXPECT_NEAR(ZeroPhaseGain(lp, kFc), 0.5, 1e-15);         // -3 dB of |H| at f_c.
  EXPECT_NEAR(ZeroPhaseGain(lp, 0), 1.0, 1e-15);
}

// Gain of the forward-backward filter for sinusoids, measured away from the ends, equals |H|^2 of
// the bilinear first-order Butterworth to 1e-3 (the tolerance asked for; the measurement is exact
// up to the ~1e-12 start-up transient) and the quadrature (phase) component is zero.
TEST(Butterworth, ZeroPhaseGainEqualsSquaredMagnitude) {
  const FirstOrderLowpass lp = DesignButterworthLowpass1(kFc, kFs);
  const std::size_t n = 5000;
  for (double f : {50.0, 300.0, 1000.0, 1500.0, 2500.0, 5000.0, 10000.0}) {
    std::vector<double> x(n);
    for (std::size_t i = 0; i < n; ++i)
      x[i] = std::sin(2 * std::numbers::pi * f * static_cast<double>(i) / kFs);
    const std::vector<double> y = FiltFilt(lp, x);
    double s, c;
    FitSinCos(y, f, 500, n - 500, &s, &c);
    const double k = std::tan(std::numbers::pi * kFc / kFs);
    const double r = std::tan(std::numbers::pi * f / kFs) / k;
    EXPECT_NEAR(s, 1 / (1 + r * r), 1e-3) << "f = " << f;
    EXPECT_NEAR(c, 0.0, 1e-3) << "phase at f = " << f;
    EXPECT_NEAR(s, ZeroPhaseGain(lp, f), 1e-9) << "f = " << f;
  }
}

// A step in the middle: the output equals the theoretical step response of the zero-phase filter
// (the running sum of the symmetric kernel h * h(-n), computed from the impulse response) and the
// constant ends stay exactly constant (no start/end transient).
TEST(Butterworth, StepHasNoEdgeTransient) {
  const FirstOrderLowpass lp = DesignButterworthLowpass1(kFc, kFs);
  const std::size_t n = 2000, n0 = 1000;
  std::vector<double> x(n, 0.0);
  for (std::size_t i = n0; i < n; ++i) x[i] = 1;
  const std::vector<double> y = FiltFilt(lp, x);
  // Causal impulse response h[k] of one pass.
  const int len = 400;
  std::vector<double> h(len);
  double y_prev = 0;
  for (int k = 0; k < len; ++k) {
    const double xk = k == 0 ? 1 : 0, xk1 = k == 1 ? 1 : 0;
    h[k] = lp.b0 * xk + lp.b1 * xk1 - lp.a1 * y_prev;
    y_prev = h[k];
  }
  // Zero-phase kernel r[m] = sum_k h[k] h[k + |m|]; step response s[j] = sum_{m <= j} r[m].
  auto r = [&](int m) {
    m = std::abs(m);
    double acc = 0;
    for (int k = 0; k + m < len; ++k) acc += h[k] * h[k + m];
    return acc;
  };
  for (std::size_t i = 0; i < n; ++i) {
    const int j = static_cast<int>(i) - static_cast<int>(n0);
    double theory = 0;
    for (int m = -len + 1; m <= std::min(j, len - 1); ++m) theory += r(m);
    if (j >= len) theory = 1;
    EXPECT_NEAR(y[i], theory, 1e-10) << "sample " << i;
  }
  EXPECT_NEAR(y.front(), 0.0, 1e-12);
  EXPECT_NEAR(y.back(), 1.0, 1e-12);
}

// Odd reflection continues a straight line, so a ramp passes through unchanged to the very ends.
TEST(Butterworth, RampReproducedUpToTheEnds) {
  const FirstOrderLowpass lp = DesignButterworthLowpass1(kFc, kFs);
  std::vector<double> x(300);
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = 2.5 - 0.01 * static_cast<double>(i);
  const std::vector<double> y = FiltFilt(lp, x);
  for (std::size_t i = 0; i < x.size(); ++i) EXPECT_NEAR(y[i], x[i], 1e-9) << i;
}

TEST(Butterworth, RejectsCutoffAboveNyquist) {
  try {
    DesignButterworthLowpass1(13000, kFs);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("cutoff_hz"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("Nyquist"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace impactdic
