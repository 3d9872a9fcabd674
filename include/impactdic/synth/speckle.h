// Analytic speckle patterns and exact rendering of deformed images (docs/synth.md).
//
// The pattern is a sum of Gaussian blobs defined in material coordinates (X, Y) [px of the
// reference image]. A deformed image is rendered EXACTLY from a known displacement field: for every
// pixel x of the deformed image the material point X with x = X + u(X) is found by Newton iteration
// and the analytic intensity at X is evaluated (averaged over the pixel area with a fixed
// supersampling), never by interpolating the reference image.
//
//   SpeckleOptions speckle;               // blob radius, density, contrast, seed
//   SpecklePattern pattern(speckle, /*width=*/512, /*height=*/512);
//   cv::Mat ref = RenderImage(pattern, 512, 512, ZeroField(), render);
//   cv::Mat def = RenderImage(pattern, 512, 512, Translation(0.3, -0.7), render);
#ifndef IMPACTDIC_SYNTH_SPECKLE_H_
#define IMPACTDIC_SYNTH_SPECKLE_H_

#include <cstdint>
#include <functional>
#include <memory>
#include <opencv2/core.hpp>

namespace impactdic {

struct SpeckleOptions {
  double blob_radius_px = 2.5;  // Gaussian sigma of each blob [px], > 0.
  double density = 0.5;         // Blobs per pixel area times pi r^2 (coverage), in (0, 5].
  double contrast = 1.0;        // Peak blob amplitude relative to full scale (0, 1].
  double background = 0.15;     // Background level as a fraction of full scale [0, 1).
  std::uint64_t seed = 1;       // Seed of the blob positions and amplitudes.
  void Check() const;
};

// A displacement field u(X) [px] in material (reference-image) coordinates, with its Jacobian
// du/dX, needed by the Newton inversion of x = X + u(X).
struct DisplacementField {
  // Returns (u, v) at material point (X, Y).
  std::function<cv::Vec2d(double X, double Y)> u;
  // Returns (du/dX, du/dY, dv/dX, dv/dY) at (X, Y).
  std::function<cv::Vec4d(double X, double Y)> gradient;
};

// Fields used by the tests (see fields.h for more).
DisplacementField ZeroField();
DisplacementField Translation(double u_px, double v_px);

// Evaluates the analytic intensity I(X, Y) in [0, 1] (normalised grey level).
class SpecklePattern {
 public:
  // The blobs cover [-margin, width + margin] x [-margin, height + margin] of material space.
  SpecklePattern(const SpeckleOptions& options, int width, int height, double margin_px = 64);
  double Intensity(double X, double Y) const;

 private:
  struct Impl;
  std::shared_ptr<const Impl> impl_;
};

struct RenderOptions {
  int bits = 8;            // 8 or 16 (output CV_8U or CV_16U).
  double noise_sigma = 0;  // Gaussian noise sigma in grey levels of the output depth, >= 0.
  double gain = 1.0;       // Brightness/contrast change: I' = gain * I + offset (normalised).
  double offset = 0.0;
  int supersampling = 3;         // Samples per pixel side (pixel-area integration), >= 1.
  std::uint64_t noise_seed = 7;  // Seed of the noise.
  void Check() const;
};

// Renders the deformed image of `pattern` under `field` (x = X + u(X)), width x height pixels.
// Pixel (c, r) has its centre at x = c, y = r.
cv::Mat RenderImage(const SpecklePattern& pattern, int width, int height,
                    const DisplacementField& field, const RenderOptions& options);

// Inverts x = X + u(X) by Newton iteration starting from X = x; returns false if it does not
// converge (the returned point is then the last iterate).
bool InvertField(const DisplacementField& field, double x, double y, double* X, double* Y);

}  // namespace impactdic

#endif  // IMPACTDIC_SYNTH_SPECKLE_H_
