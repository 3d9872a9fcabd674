// How much of an image's content lies near the Nyquist frequency, expressed as the sub-pixel bias
// it would cause: the figure that decides the automatic Gaussian pre-filter (preprocess.h,
// GaussianMode::kAuto; docs/dic_accuracy.md, "Sub-pixel bias").
//
//   const NyquistBias b = MeasureNyquistBias(reference, roi);
//   if (b.measured() && b.bias_px > 0.0025) ...   // near-Nyquist content: pre-filter
//
// The model (Schreier, Braasch & Sutton, Opt. Eng. 39 (2000) 2915, doi:10.1117/1.1314593, for the
// B-spline's transfer function): a Fourier component e^{i w x} of the deformed image, shifted by
// t (the fractional part of the displacement), is reproduced by the cubic B-spline interpolant as
// T(w, t) e^{i w (x + t)}, T = A(w, t) / B(w) with A = sum_j beta3(t - j) e^{-i w (t - j)} and
// B = (2 + cos w) / 3; its phase error phi = arg T shifts that component by phi / w. IC-GN
// stops where the residual is orthogonal to the reference's B-spline gradient (transfer
// d(w) = 3 sin w / (2 + cos w)), so a translation is biased by
//
//     bias(t) = - sum_w P(w) d(w) |T| phi(w, t) / sum_w P(w) d(w) |T| w,
//
// P the image's power spectrum along the axis (the marginal of the 2-D spectrum over the other
// frequency). The figure is max over t in [0.05, 0.95] and the two axes of |bias(t)|, for the
// bicubic spline whatever interpolation the correlation uses (biquintic has about 0.6-0.8 times
// it). Measured on DIC Challenge 1.0 Sample 3: 0.0034 px predicted, 0.0041 px observed (bicubic).
// It is a property of the image alone, independent of its grey-level scale.
//
// P is estimated by Welch's method: tiles of 64 x 64 px (smaller for a small region, down to
// 16 px) with a Hann window and their mean removed, at most kMaxNyquistTiles of them spread evenly
// over the region, so the cost is bounded (~10 ms) whatever the image size. Noise is content
// too: white noise raises P near the Nyquist frequency, so a very noisy image reads higher than
// its signal alone would.
#ifndef IMPACTDIC_PREPROCESS_NYQUIST_BIAS_H_
#define IMPACTDIC_PREPROCESS_NYQUIST_BIAS_H_

#include <cmath>
#include <opencv2/core.hpp>
#include <vector>

namespace impactdic {

inline constexpr int kMaxNyquistTiles = 256;

struct NyquistBias {
  double bias_px = std::nan("");    // The figure: max |predicted bias| [px]; NaN if not measured.
  double bias_x_px = std::nan("");  // Its x (u) and y (v) parts [px].
  double bias_y_px = std::nan("");
  int tiles = 0;      // Tiles averaged.
  int tile_size = 0;  // Their side [px].
  bool measured() const { return !std::isnan(bias_px); }
};

// The figure of a single-channel image (8/16-bit or float) over `roi` (empty: the whole image;
// clipped to it). Not measured (NaN) when the region is smaller than 16 x 16 px; 0 for a flat
// region.
NyquistBias MeasureNyquistBias(const cv::Mat& image, cv::Rect roi = {});

// What a Gaussian pre-filter of both images trades for a subset of a given size: the predicted
// bias above (max over t, the u and v parts in quadrature) and the expected random error of the
// subset's translation (standard deviation, u and v in quadrature), without and with the filter.
// The random error is the least-squares one of IC-GN in stationary texture and noise, over the
// 2-D spectra (n x n bins) of the signal S and of the pair's residual noise N, for the subset's
// M pixels (a product of the axes' marginals would credit the filter with noise it removes where
// there is no signal):
//
//     var(u) = (n^2 / M) sum_k a_k b_k / (sum_k a_k)^2,   a = S d(w_x)^2 G^2,  b = N G^2,
//
// d the B-spline gradient's response, G the filter's (1 without it). N is measured from the
// first pair itself, so coloured noise (JPEG, demosaicing) counts as it is: per tile, the
// deformed tile is taken at the integer part of the tile's shift (phase correlation), its
// fractional part s fitted by Gauss-Newton on sum |F1 - F0 e^(-i w s)|^2 with the deformed
// tile's window moved by s (its content's position), and N = |F1 - F0 e^(-i w s)|^2 (both
// images' noise, and content that does not move as a shift, e.g. near the Nyquist frequency);
// tiles whose residual is over twice the median (deformation, occlusion) are left out.
// S = the reference's spectrum less half of N. The filter is worth it when the total error
// sqrt(bias^2 + random^2) falls. Sizes as MeasureNyquistBias (64 px tiles, here at most
// kMaxTradeTiles of them).
inline constexpr int kMaxTradeTiles = 64;
struct PrefilterTrade {
  double bias_px = std::nan(""), bias_filtered_px = std::nan("");
  double random_px = std::nan(""), random_filtered_px = std::nan("");
  double noise_grey = std::nan("");  // One image's noise standard deviation [grey levels].
  int tiles = 0;                     // Tiles used (of those that fit the region).
  bool measured() const { return !std::isnan(random_px) && !std::isnan(bias_px); }
  double Error(bool filtered) const {
    return filtered ? std::hypot(bias_filtered_px, random_filtered_px)
                    : std::hypot(bias_px, random_px);
  }
};

// The trade for the pair (reference, next) over roi (empty: the whole image), a 1-D filter
// kernel applied along both axes (cv::getGaussianKernel) and subsets of subset_size px per side.
// Not measured (NaN) when the region holds no 32 px tile or next is empty or of another size.
PrefilterTrade MeasurePrefilterTrade(const cv::Mat& reference, const cv::Mat& next, cv::Rect roi,
                                     const cv::Mat& kernel, int subset_size);

// The predicted bias [px] of a bicubic B-spline IC-GN translation at fractional shift t in (0, 1)
// for the one-sided marginal power spectrum power[k], k = 0..n/2, of an n-point axis (frequency
// w = 2 pi k / n; power[0], the mean, is ignored). Exposed for the tests.
double PredictedBicubicBiasPx(const std::vector<double>& power, int n, double t);

}  // namespace impactdic

#endif  // IMPACTDIC_PREPROCESS_NYQUIST_BIAS_H_
