// Exactly band-limited translations of a pixel image and the sharp speckle used to study
// sub-pixel bias (docs/dic_accuracy.md, "Sub-pixel bias"): the DIC Challenge 1.0 translation
// samples (Reu et al., "DIC Challenge: developing images and guidelines for evaluating accuracy and
// resolution of 2D analyses", Exp. Mech. 58 (2018) 1067, doi:10.1007/s11340-017-0349-0) were
// made this way, by a Fourier shift of one camera image, then 8-bit rounding and noise.
//
//   cv::Mat base = SharpSpeckle(256, 256, /*dot_radius_px=*/1.5, /*seed=*/1);  // [0, 1]
//   cv::Mat ref = QuantiseWithNoise(FourierShift(base, 0, 0) * 200 + 20, 2.0, 8, 1);
//   cv::Mat def = QuantiseWithNoise(FourierShift(base, 0.3, 0) * 200 + 20, 2.0, 8, 2);
#ifndef IMPACTDIC_SYNTH_FOURIER_SHIFT_H_
#define IMPACTDIC_SYNTH_FOURIER_SHIFT_H_

#include <cstdint>
#include <opencv2/core.hpp>

namespace impactdic {

// The image (one channel, any depth) translated by (dx_px, dy_px): out(x, y) = in(x - dx, y - dy)
// for the band-limited (trigonometric) interpolant of the image extended by mirror symmetry to
// twice its size in each direction (a periodic, continuous extension, so the shift does not ring
// at the borders as a plain periodic one would). The spectrum of the extension is multiplied by
// exp(-2 pi i (fx dx + fy dy)); the Nyquist bins by cos(pi dx) (resp. dy), the real part, so the
// result is real. CV_64F, same size. A shift by an integer reproduces the image exactly inside
// it (up to round-off), away from the borders by that integer.
cv::Mat FourierShift(const cv::Mat& image, double dx_px, double dy_px);

// A painted-style speckle [0, 1], CV_64F: black dots with sharp edges on white, the analytic blob
// speckle (synth/speckle.h: blob sigma dot_radius_px / 2, coverage 1.2) thresholded at its
// median on a 4x finer grid, then averaged over each pixel's area (what a sharp lens and a
// sensor with full fill factor record). Its spectrum reaches the Nyquist frequency, unlike the
// smooth blob speckle.
cv::Mat SharpSpeckle(int width, int height, double dot_radius_px, std::uint64_t seed);

// grey + N(0, noise_sigma^2) per pixel (seeded per row like RenderImage: independent of the
// thread count), rounded and clamped to `bits` (8: CV_8U, 16: CV_16U).
cv::Mat QuantiseWithNoise(const cv::Mat& grey, double noise_sigma, int bits,
                          std::uint64_t noise_seed);

}  // namespace impactdic

#endif  // IMPACTDIC_SYNTH_FOURIER_SHIFT_H_
