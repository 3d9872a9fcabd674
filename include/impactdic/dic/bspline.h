// B-spline image interpolation (bicubic and biquintic) for sub-pixel DIC intensities.
//
// The interpolant is s(x, y) = sum_{k,l} c[l][k] b(x - k) b(y - l) with b the cubic or quintic
// B-spline; the coefficients c are computed ONCE per image by the recursive prefilter of Unser,
// Aldroubi & Eden, "B-spline signal processing: Part II", IEEE Trans. Signal Process. 41 (1993)
// 834-848, doi:10.1109/78.193221 (mirror boundary), and only over a region (the part of the image
// the subsets can reach, plus a guard band so that the truncated boundary does not change the
// values inside: the prefilter's boundary influence decays like |z|^d, z = -0.268 (cubic)).
// The interpolant passes through the pixel values and reproduces polynomials of degree <= 3
// (bicubic) or <= 5 (biquintic) in each variable exactly (away from the region border).
// Pixel (c, r) has its centre at x = c, y = r.
//
//   BsplineImage spline;
//   spline.Build(image, Interpolation::kBicubic, cv::Rect(100, 100, 400, 300));
//   double v, gx, gy;
//   spline.ValueGradient(150.3, 212.7, &v, &gx, &gy);
#ifndef IMPACTDIC_DIC_BSPLINE_H_
#define IMPACTDIC_DIC_BSPLINE_H_

#include <opencv2/core.hpp>
#include <string>

#include "impactdic/core/enum_names.h"

namespace impactdic {

enum class Interpolation { kBicubic, kBiquintic };
inline constexpr EnumNames<Interpolation, 2> kInterpolationNames{
    {{{Interpolation::kBicubic, "bicubic"}, {Interpolation::kBiquintic, "biquintic"}}}};
const char* ToString(Interpolation interpolation);
// A name of kInterpolationNames; Error(kInvalidValue) otherwise.
Interpolation InterpolationFromString(const std::string& name);

class BsplineImage {
 public:
  // Computes the coefficients of `image` (CV_8U, CV_16U, CV_32F or CV_64F, one channel) over
  // `region` (empty = whole image) grown by `guard_px` on every side and clipped to the image.
  // Reuses the memory of the last Build when it is large enough (a sequence's frames).
  void Build(const cv::Mat& image, Interpolation kind, cv::Rect region = cv::Rect(),
             int guard_px = 16);

  bool empty() const { return coefficients_.empty(); }
  Interpolation kind() const { return kind_; }
  int degree() const { return kind_ == Interpolation::kBicubic ? 3 : 5; }
  // The region the coefficients cover (image coordinates).
  const cv::Rect& region() const { return region_; }

  // True if (x, y) can be evaluated: all taps inside the coefficient region.
  bool Inside(double x, double y) const {
    return x >= x_min_ && x < x_max_ && y >= y_min_ && y < y_max_;
  }
  // Bounds of the evaluable domain: [x_min, x_max) x [y_min, y_max).
  double x_min() const { return x_min_; }
  double x_max() const { return x_max_; }
  double y_min() const { return y_min_; }
  double y_max() const { return y_max_; }

  // Value and gradient at (x, y) (must be Inside()).
  double Value(double x, double y) const;
  void ValueGradient(double x, double y, double* value, double* gx, double* gy) const;

  // Gradient images of the interpolant at the integer pixels of region() (exact derivatives of
  // the spline at the nodes, computed separably), CV_32F, region().size().
  void NodeGradients(cv::Mat* gx, cv::Mat* gy) const;
  // The same gradients over `rect` only (image coordinates, inside region()), into gx and gy
  // (created CV_32F, rect.size(), unless they already are, e.g. views into larger images): equal
  // to NodeGradients' values there, bit for bit. Costs rect.area(), not region().area().
  void NodeGradients(const cv::Rect& rect, cv::Mat* gx, cv::Mat* gy) const;

  // Raw coefficients (CV_32F, region().size(), rows not necessarily continuous); coefficient
  // (c, r) of the image is at (c - region().x, r - region().y).
  const cv::Mat& coefficients() const { return coefficients_; }

 private:
  Interpolation kind_ = Interpolation::kBicubic;
  cv::Rect region_;
  cv::Mat coefficients_;  // A view of storage_.
  cv::Mat storage_;
  double x_min_ = 0, x_max_ = 0, y_min_ = 0, y_max_ = 0;
};

// Cubic B-spline weights for taps floor(x) - 1 .. floor(x) + 2 at fractional part t in [0, 1).
inline void CubicWeights(float t, float w[4]) {
  const float s = 1 - t, t2 = t * t, t3 = t2 * t;
  w[0] = s * s * s * (1.0f / 6);
  w[1] = (2.0f / 3) - t2 + 0.5f * t3;
  w[3] = t3 * (1.0f / 6);
  w[2] = 1 - w[0] - w[1] - w[3];
}

}  // namespace impactdic

#endif  // IMPACTDIC_DIC_BSPLINE_H_
