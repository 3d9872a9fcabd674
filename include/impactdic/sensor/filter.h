// Zero-phase first-order Butterworth low-pass for the accelerometer and force channels.
//
// Design: the analogue prototype H(s) = 1 / (1 + s / w_c) mapped by the bilinear transform with
// frequency pre-warping, K = tan(pi f_c / f_s):
//   H(z) = K (1 + z^-1) / ((1 + K) + (K - 1) z^-1),
//   |H(f)|^2 = 1 / (1 + (tan(pi f / f_s) / K)^2)      (exact, every f < f_s / 2).
// Applied forward then backward (Gustafsson 1996, "Determining the initial states in
// forward-backward filtering", IEEE Trans. Signal Process. 44(4), doi:10.1109/78.492552), the
// response is |H|^2 with zero phase. Edges: the record is extended at both ends by odd reflection
// about its end samples (x_pad = 2 x_0 - x_k), which continues a local linear trend, and each pass
// starts in the steady state for its first padded sample (the role of scipy's lfilter_zi), so a
// constant or a straight line passes through unchanged up to the very ends (no ringing).
//
//   FirstOrderLowpass lp = DesignButterworthLowpass1(/*cutoff_hz=*/1500, /*sample_rate_hz=*/25000);
//   std::vector<double> smooth = FiltFilt(lp, raw);
#ifndef IMPACTDIC_SENSOR_FILTER_H_
#define IMPACTDIC_SENSOR_FILTER_H_

#include <cstddef>
#include <vector>

namespace impactdic {

// y[n] = b0 x[n] + b1 x[n-1] - a1 y[n-1]; DC gain (b0 + b1) / (1 + a1) = 1.
struct FirstOrderLowpass {
  double b0 = 1, b1 = 0, a1 = 0;
  double cutoff_hz = 0, sample_rate_hz = 0;
};

// Throws Error(kInvalidValue) unless 0 < cutoff_hz < sample_rate_hz / 2.
FirstOrderLowpass DesignButterworthLowpass1(double cutoff_hz, double sample_rate_hz);

// |H(f)|^2 of the single pass = gain of the forward-backward filter at frequency f [Hz].
double ZeroPhaseGain(const FirstOrderLowpass& filter, double f_hz);

// One causal pass, starting in the steady state for a constant input equal to x[0].
std::vector<double> FilterForward(const FirstOrderLowpass& filter, const std::vector<double>& x);

// Padding length used by FiltFilt when pad < 0: enough samples for the start-up transient to decay
// to 1e-12 (|a1|^pad <= 1e-12), at least 6, at most x.size() - 1.
int DefaultPadLength(const FirstOrderLowpass& filter, std::size_t n);

// Zero-phase forward-backward filtering with odd-reflection padding (see the file comment).
// Needs x.size() >= 2; pad < 0 = DefaultPadLength.
std::vector<double> FiltFilt(const FirstOrderLowpass& filter, const std::vector<double>& x,
                             int pad = -1);

}  // namespace impactdic

#endif  // IMPACTDIC_SENSOR_FILTER_H_
