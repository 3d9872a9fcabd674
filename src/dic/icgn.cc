// IC-GN with the ZNSSD criterion (Pan, Li & Tong 2013, doi:10.1007/s11340-013-9717-6).
//
// With f the reference subset, g the warped deformed subset, J = grad f dW/dp the steepest-descent
// images at the reference pixels and H = sum J^T J (constant per reference subset), one
// Gauss-Newton step of min sum [(f(W(x; dp)) - f_m) / f_n - (g - g_m) / g_n]^2 is
//   dp = -H^-1 sum J^T [(f - f_m) - (f_n / g_n) (g - g_m)],
// followed by W(p) <- W(p) o W(dp)^-1. Expanding the sum,
//   sum J^T [...] = sum J (f - f_m) - (f_n / g_n) (sum J g' - g'_m sum J),   g' = g - f_m,
// where sum J (f - f_m) and sum J are per-subset constants: one pass over the pixels per
// iteration accumulates sum g', sum g'^2, sum f g' and sum J g' (the J of a pixel is its gradient
// times the shape monomials, so the per-row sums are combined with powers of eta after each row).
#include "icgn.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "icgn_kernels.h"

namespace impactdic::internal {
namespace {

constexpr int kMonoPx[6] = {0, 1, 0, 2, 1, 0};
constexpr int kMonoPy[6] = {0, 0, 1, 0, 1, 2};
constexpr double kMonoC[6] = {1, 1, 1, 0.5, 1, 0.5};

void Monomials(double xi, double eta, double m[6]) {
  m[0] = 1;
  m[1] = xi;
  m[2] = eta;
  m[3] = 0.5 * xi * xi;
  m[4] = xi * eta;
  m[5] = 0.5 * eta * eta;
}

}  // namespace

Shape MakeShape(ShapeFunction kind, int half) {
  Shape s;
  s.kind = kind;
  s.half = half;
  s.nm = kind == ShapeFunction::kAffine ? 3 : 6;
  s.n = 2 * s.nm;
  for (int j = -half; j <= half; ++j) {
    for (int i = -half; i <= half; ++i) {
      double m[6];
      Monomials(i, j, m);
      for (int q = 0; q < s.nm; ++q)
        for (int t = 0; t < s.nm; ++t) s.monomial_moments[q * 6 + t] += m[q] * m[t];
    }
  }
  if (kind == ShapeFunction::kQuadratic) {
    // Normal equations of the 5x5 sample grid in coordinates scaled by 1/half, then unscaled.
    double a[36] = {}, m[25][6];
    for (int k = 0; k < 25; ++k) {
      const int column = k % 5, row = k / 5;  // The 5x5 sample grid.
      const double xi = (column - 2) * 0.5, eta = (row - 2) * 0.5;
      Monomials(xi, eta, m[k]);
      for (int i = 0; i < 6; ++i)
        for (int j = 0; j < 6; ++j) a[i * 6 + j] += m[k][i] * m[k][j];
    }
    double inv[36];
    [[maybe_unused]] const bool invertible = InvertSpd(a, 6, inv);
    assert(invertible && "the 5x5 sample grid determines every quadratic coefficient");
    s.fit.assign(std::size_t{6} * 25, 0);
    const double scale[6] = {
        1, 1.0 / half, 1.0 / half, 1.0 / (half * half), 1.0 / (half * half), 1.0 / (half * half)};
    for (int i = 0; i < 6; ++i)
      for (int k = 0; k < 25; ++k) {
        double v = 0;
        for (int j = 0; j < 6; ++j) v += inv[i * 6 + j] * m[k][j];
        s.fit[i * 25 + k] = v * scale[i];
      }
  }
  return s;
}

void Displacement(const Shape& s, const Params& p, double xi, double eta, double* du, double* dv) {
  double m[6];
  Monomials(xi, eta, m);
  double a = 0, b = 0;
  for (int i = 0; i < s.nm; ++i) {
    a += p[i] * m[i];
    b += p[s.nm + i] * m[i];
  }
  *du = a;
  *dv = b;
}

Params Transfer(const Shape& s, const Params& p, double ox, double oy) {
  Params q = p;
  Displacement(s, p, ox, oy, &q[0], &q[s.nm]);
  if (s.kind == ShapeFunction::kQuadratic) {
    for (int c = 0; c < 2; ++c) {
      const int o = c * 6;
      q[o + 1] = p[o + 1] + p[o + 3] * ox + p[o + 4] * oy;
      q[o + 2] = p[o + 2] + p[o + 4] * ox + p[o + 5] * oy;
    }
  }
  return q;
}

Params ComposeInverse(const Shape& s, const Params& p, const Params& dp) {
  Params q{};
  if (s.kind == ShapeFunction::kAffine) {
    // 3x3 homogeneous matrices.
    const double a = 1 + dp[1], b = dp[2], c = dp[4], d = 1 + dp[5];
    const double det = a * d - b * c;
    const double ia = d / det, ib = -b / det, ic = -c / det, id = a / det;
    const double itx = -(ia * dp[0] + ib * dp[3]), ity = -(ic * dp[0] + id * dp[3]);
    const double A = 1 + p[1], B = p[2], C = p[4], D = 1 + p[5];
    q[1] = A * ia + B * ic - 1;
    q[2] = A * ib + B * id;
    q[0] = A * itx + B * ity + p[0];
    q[4] = C * ia + D * ic;
    q[5] = C * ib + D * id - 1;
    q[3] = C * itx + D * ity + p[3];
    return q;
  }
  const double h = s.half;
  double tu[25], tv[25];
  for (int k = 0; k < 25; ++k) {
    const int column = k % 5, row = k / 5;  // The 5x5 sample grid.
    const double xi = (column - 2) * 0.5 * h, eta = (row - 2) * 0.5 * h;
    // Invert x = X + d_dp(X) by fixed-point iteration (|grad d_dp| << 1).
    double X = xi, Y = eta;
    for (int it = 0; it < 6; ++it) {
      double du, dv;
      Displacement(s, dp, X, Y, &du, &dv);
      X = xi - du;
      Y = eta - dv;
    }
    double du, dv;
    Displacement(s, p, X, Y, &du, &dv);
    tu[k] = X + du - xi;
    tv[k] = Y + dv - eta;
  }
  for (int i = 0; i < 6; ++i) {
    double a = 0, b = 0;
    for (int k = 0; k < 25; ++k) {
      a += s.fit[i * 25 + k] * tu[k];
      b += s.fit[i * 25 + k] * tv[k];
    }
    q[i] = a;
    q[6 + i] = b;
  }
  return q;
}

namespace {

// The share of the estimated gradient noise taken off H: the full first-order correction is
// right on synthetic white noise (sigma / observed 0.98-1.08) but over-reports DIC Challenge
// Sample 14 by 1.36x; half keeps Sample 14 at 1.13-1.17, synthetic noise at 0.89-1.04 and the
// static real sand pair at 1.03-1.06 (docs/dic.md, "Uncertainty per subset").
constexpr double kGradientNoiseWeight = 0.5;

double NodeGradientNoiseRatio(Interpolation kind);

// The displacement standard deviation [px] the uncertainty model predicts for a subset of Hessian
// h (n x n) in noise of standard deviation `noise` [grey levels] in both images: the residuals
// carry the noise of both, 2 noise^2, on the inverse of the Hessian of the true gradients,
// h - s^2 M with s^2 the node gradients' noise variance (errors in variables, as the sigma model
// after correlation: TrueHessianInverse with its kGradientNoiseWeight, here without its bound).
// Infinite where the noise accounts for the whole gradient energy (h - s^2 M not positive
// definite): nothing to correlate.
double PredictedSigmaPx(const Shape& shape, const double* h, double noise, Interpolation kind) {
  const int n = shape.n, nm = shape.nm;
  const double s2 = kGradientNoiseWeight * noise * noise * 0.5 * NodeGradientNoiseRatio(kind);
  double ht[144], inv[144];
  for (int a = 0; a < n; ++a) {
    for (int b = 0; b < n; ++b) {
      ht[a * n + b] = h[a * n + b];
      if (a / nm == b / nm) ht[a * n + b] -= s2 * shape.monomial_moments[(a % nm) * 6 + b % nm];
    }
  }
  if (!InvertSpd(ht, n, inv)) return std::numeric_limits<double>::infinity();
  return std::sqrt(2 * noise * noise * std::max(inv[0], inv[nm * n + nm]));
}

// Whether PredictedSigmaPx is at most limit, from the inverse hinv of h without inverting
// h - s^2 M unless needed: the eigenvalues of s^2 h^-1 M are >= 0, so the largest, lambda, is at
// most their sum t, and when t < 1, (h - s^2 M)^-1 <= h^-1 / (1 - t): a subset whose bound is
// within the limit (nearly all) needs no second inverse.
bool PredictedSigmaWithin(const Shape& shape, const double* h, const double* hinv, double noise,
                          Interpolation kind, double limit) {
  if (!(noise > 0)) return true;
  const int n = shape.n, nm = shape.nm;
  const double s2 = kGradientNoiseWeight * noise * noise * 0.5 * NodeGradientNoiseRatio(kind);
  double t = 0;
  for (int a = 0; a < n; ++a) {
    for (int b = 0; b < n; ++b) {
      if (a / nm == b / nm) t += hinv[a * n + b] * shape.monomial_moments[(b % nm) * 6 + a % nm];
    }
  }
  t *= s2;
  const double bound2 = 2 * noise * noise * std::max(hinv[0], hinv[nm * n + nm]) / (1 - t);
  if (t < 1 && bound2 <= limit * limit) return true;
  return PredictedSigmaPx(shape, h, noise, kind) <= limit;
}

// The pointers of subset s's reference pixels for the kernels (f, gx and gy share their layout).
MomentInput RefMoments(const Shape& shape, const RefImages& ref, const SubsetRef& s) {
  assert(ref.gx.step1() == ref.f.step1() && ref.gy.step1() == ref.f.step1());
  const int h = shape.half;
  const cv::Point rc = RefCentre(ref, s);
  MomentInput in;
  in.half = h;
  in.stride = static_cast<std::ptrdiff_t>(ref.f.step1());
  const std::ptrdiff_t corner = static_cast<std::ptrdiff_t>(rc.y - h) * in.stride + (rc.x - h);
  in.f = ref.f.ptr<float>() + corner;
  in.gx = ref.gx.ptr<float>() + corner;
  in.gy = ref.gy.ptr<float>() + corner;
  in.full_scale = ref.full_scale;
  in.pmax = shape.kind == ShapeFunction::kAffine ? 2 : 4;
  return in;
}

}  // namespace

void PrepareSubset(const Shape& shape, const RefImages& ref, const IcgnOptions& options,
                   SubsetRef* s, double* hinv) {
  const int h = shape.half, size = 2 * h + 1, nm = shape.nm, n = shape.n;
  const cv::Rect box(s->cx - h, s->cy - h, size, size);
  if ((box & ref.region) != box) {
    s->status = SubsetStatus::kOutOfImage;
    return;
  }
  // Moments: gg[k][p][q] = sum g_a g_b xi^p eta^q (k: xx, xy, yy), gs[a][p][q] = sum g_a ...,
  // gf[a][p][q] = sum g_a (f - mean) ... (MomentSums).
  MomentSums moments;
  ActiveIcgnKernel().moments(RefMoments(shape, ref, *s), &moments);
  const double count = double(size) * size;
  const double mean = moments.mean, ss = moments.ss;
  const auto& gg = moments.gg;
  const auto& gs = moments.gs;
  const auto& gf = moments.gf;
  s->f_mean = static_cast<float>(mean);
  s->f_norm = static_cast<float>(std::sqrt(ss));
  if (moments.saturated > options.max_saturated_fraction * count) {
    s->status = SubsetStatus::kSaturated;
    return;
  }
  double H[144];
  for (int i = 0; i < n; ++i) {
    const int ai = i / nm, mi = i % nm;
    s->sum_j[i] = kMonoC[mi] * gs[ai][kMonoPx[mi]][kMonoPy[mi]];
    s->sum_jf[i] = kMonoC[mi] * gf[ai][kMonoPx[mi]][kMonoPy[mi]];
    for (int j = 0; j < n; ++j) {
      const int aj = j / nm, mj = j % nm;
      const int k = ai + aj;  // 0 xx, 1 xy, 2 yy.
      H[i * n + j] =
          kMonoC[mi] * kMonoC[mj] * gg[k][kMonoPx[mi] + kMonoPx[mj]][kMonoPy[mi] + kMonoPy[mj]];
    }
  }
  // Featureless: RMS gradient below 0.01 grey levels (8-bit scale) per px in x or y, or a Hessian
  // whose Cholesky factorisation breaks down (the data cannot determine some warp parameter).
  const double min_gradient2 = count * std::pow(0.01 * ref.full_scale / 255.0, 2);
  if (H[0] < min_gradient2 || H[nm * n + nm] < min_gradient2 || !InvertSpd(H, n, hinv)) {
    s->status = SubsetStatus::kSingularHessian;
    return;
  }
  // The grey-level limit is relative to the levels the frame uses (a short exposure fills a
  // fraction of the data's range), never wider than the data's full scale.
  const double range = ref.range > 0 ? std::min(ref.range, ref.full_scale) : ref.full_scale;
  const double contrast = std::sqrt(ss / count) * 255.0 / range;
  if (contrast < options.min_contrast ||
      !PredictedSigmaWithin(shape, H, hinv, ref.noise, options.interpolation,
                            options.max_predicted_uncertainty_px)) {
    s->status = SubsetStatus::kLowContrast;
    return;
  }
  s->status = SubsetStatus::kConverged;
}

namespace {

// The variance of the B-spline node gradient (BsplineImage::NodeGradients, the reference
// gradients of IC-GN) of unit white noise, divided by that of the central difference (1/2):
// measured once per interpolator on the spline of a unit impulse.
double NodeGradientNoiseRatio(Interpolation kind) {
  const auto gain = [](Interpolation k) {
    cv::Mat impulse = cv::Mat::zeros(65, 65, CV_32F);
    impulse.at<float>(32, 32) = 1;
    BsplineImage spline;
    spline.Build(impulse, k);
    cv::Mat gx, gy;
    spline.NodeGradients(&gx, &gy);
    return gx.dot(gx) / 0.5;
  };
  static const double cubic = gain(Interpolation::kBicubic);
  static const double quintic = gain(Interpolation::kBiquintic);
  return kind == Interpolation::kBicubic ? cubic : quintic;
}

// Standard deviations of the warp's translation (u, v) at the solution p, from the residuals
// r = (f - f_m) - (f_n / g_n) (g - g_m). They are those of the pass that converged, taken to p to
// first order: that pass sampled g at the warp before its increment dp, whose least-squares
// residuals are r + J dp (less their mean), so no pixel is sampled again (against sampling g at p:
// sigma within 1e-3 relative on the benchmark pair, docs/dic_speed.md "Speed"). The least-squares
// figure sigma_r sqrt(H^-1) assumes independent residuals and exact reference gradients; both fail
// on real images (2.4x too small on real sand before these corrections), so two corrections are
// made (docs/dic.md, "Uncertainty per subset"):
//  * Correlated residuals (noise after demosaicing, JPEG blocks or blur; texture the warp does
//    not follow): the translation's error is du = -sum_i a_i r_i with a_i = (H'^-1 J_i)_u, so
//    var(u) = sum_i sum_j a_i a_j cov(r_i, r_j). The residuals' covariance is taken as stationary
//    over the subset, cov(r_i, r_j) = sigma_r^2 rho(d), d = j - i, with rho(d) estimated from the
//    residual pairs at lag d for |dx|, |dy| <= kResidualLagPx (0 beyond), sigma_r^2 = sum r^2 /
//    (N - n): var(u) = sigma_r^2 sum_d rho(d) A(d), A(d) = sum_i a_i a_(i+d).
//  * Noise in the reference gradients (errors in variables): the Hessian H = sum J J^T of noisy
//    gradients exceeds that of the true gradients, H' = H - s_x^2 M_x - s_y^2 M_y (M the sums of
//    the shape monomials' products, s^2 the gradient noise variance), and IC-GN's fixed point
//    has the error H'^-1 sum J r. s^2 is estimated from the residuals, which carry the noise of
//    both images: half the variance of their central differences, times the node gradient's
//    noise gain relative to the central difference (NodeGradientNoiseRatio), weighted by
//    kGradientNoiseWeight. The correction is bounded: H' >= kMinTrueHessianFraction H (so it at
//    most doubles sigma).
// The variance is kept >= the least-squares sigma_r^2 (H^-1)_uu (the floor).
constexpr double kMinTrueHessianFraction = 0.25;

// Per-thread buffers of the uncertainty: the warped subset of the last IC-GN pass and the padded
// arrays of the residuals, the influences and the masks of the central differences (ResidualInput).
struct UncertaintyScratch {
  int size = 0;
  ResidualInput layout;
  std::vector<float> g, r, au, av, x_inside, y_inside;
  // Sized (and the padding zeroed) for subsets of `size` pixels per side.
  void Fit(int subset_size) {
    if (size == subset_size) return;
    size = subset_size;
    const int stride = size + kResidualLagPx;
    const auto round_up = [](int v) {
      return (v + kResidualLanes - 1) / kResidualLanes * kResidualLanes;
    };
    layout.stride = stride;
    layout.lead = round_up(stride);
    layout.length = round_up(size * stride);
    const std::size_t cells = static_cast<std::size_t>(layout.lead) + layout.length +
                              std::size_t{3} * stride + kResidualLanes;
    g.assign(static_cast<std::size_t>(size) * size, 0.0f);
    for (auto* v : {&r, &au, &av, &x_inside, &y_inside}) v->assign(cells, 0.0f);
    for (int j = 0; j < size; ++j) {
      for (int i = 0; i < size; ++i) {
        const std::size_t k = layout.lead + static_cast<std::size_t>(j) * stride + i;
        x_inside[k] = (i >= 1 && i + 1 < size) ? 1.0f : 0.0f;
        y_inside[k] = (j >= 1 && j + 1 < size) ? 1.0f : 0.0f;
      }
    }
    layout.x_inside = x_inside.data();
    layout.y_inside = y_inside.data();
  }
};

UncertaintyScratch& ThreadUncertaintyScratch(int size) {
  thread_local UncertaintyScratch scratch;
  scratch.Fit(size);
  return scratch;
}

// The variances of the reference gradients' noise in x and y from the sums of the squares of the
// residuals' central differences 2 dr/dx, 2 dr/dy (ResidualInput): half the variance of the
// central differences, times the node gradient's noise gain relative to the central difference,
// times kGradientNoiseWeight.
std::array<double, 2> GradientNoise(const double noise[2], int size, Interpolation kind) {
  const double pairs = double(size) * (size - 2);
  const double scale =
      kGradientNoiseWeight * 0.5 * NodeGradientNoiseRatio(kind) / pairs * 0.25;  // d = r'/2
  return {scale * noise[0], scale * noise[1]};
}

// The largest mu of N v = mu H v, i.e. the largest eigenvalue of H^-1 N (real, >= 0), by power
// iteration from the translation directions (n x n, row-major).
double LargestNoiseRatio(const double* hinv, const double* nn, int n, int nm) {
  double v[12], w[12], t[12], mu = 0;
  for (int a = 0; a < n; ++a) v[a] = (a % nm == 0) ? 1.0 : 0.0;
  for (int it = 0; it < 30; ++it) {
    for (int a = 0; a < n; ++a) {
      t[a] = 0;
      for (int b = 0; b < n; ++b) t[a] += nn[a * n + b] * v[b];
    }
    double norm = 0, dot = 0, vv = 0;
    for (int a = 0; a < n; ++a) {
      w[a] = 0;
      for (int b = 0; b < n; ++b) w[a] += hinv[a * n + b] * t[b];
      norm += w[a] * w[a];
      dot += w[a] * v[a];
      vv += v[a] * v[a];
    }
    mu = vv > 0 ? dot / vv : 0;
    norm = std::sqrt(norm);
    if (!(norm > 0)) break;
    for (int a = 0; a < n; ++a) v[a] = w[a] / norm;
  }
  return mu;
}

// H'^-1 into htinv, H' = H - lambda N with N = s_x^2 M_x + s_y^2 M_y (M the sums of the monomials'
// products over the subset) and lambda <= 1 the largest value that keeps
// H' >= kMinTrueHessianFraction H. Returns hinv itself when no correction applies.
const double* TrueHessianInverse(const Shape& shape, const double* hinv,
                                 const std::array<double, 2>& noise2, double* htinv) {
  const int n = shape.n, nm = shape.nm;
  double hh[144], nn[144], ht[144];
  if (!InvertSpd(hinv, n, hh)) return hinv;
  std::fill_n(nn, n * n, 0.0);
  for (int a = 0; a < n; ++a) {
    for (int b = 0; b < n; ++b) {
      if (a / nm == b / nm)
        nn[a * n + b] = noise2[a / nm] * shape.monomial_moments[(a % nm) * 6 + b % nm];
    }
  }
  // The eigenvalues of H^-1 N are real and >= 0, so the largest is at most their sum, the trace:
  // when that is <= 1 - kMinTrueHessianFraction (nearly always), lambda = 1 without the power
  // iteration.
  double trace = 0;
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) trace += hinv[a * n + b] * nn[b * n + a];
  if (!(trace > 0)) return hinv;
  double lambda = 1;
  if (trace > 1 - kMinTrueHessianFraction) {
    const double mu = LargestNoiseRatio(hinv, nn, n, nm);
    if (!(mu > 0)) return hinv;
    if (mu > 1 - kMinTrueHessianFraction) lambda = (1 - kMinTrueHessianFraction) / mu;
  }
  for (int a = 0; a < n * n; ++a) ht[a] = hh[a] - lambda * nn[a];
  return InvertSpd(ht, n, htinv) ? htinv : hinv;
}

// Along each row j of the subset (eta = j - half), the polynomials of xi sum_q w[t][q] m_q(xi, eta)
// of `terms` weight rows w[t] (nm each) into coef[3 (terms j + t) ..] as c0 + xi (c1 + xi c2):
// with m = (1, xi, eta, xi^2 / 2, xi eta, eta^2 / 2), c0 = w0 + w2 eta + w5 eta^2 / 2,
// c1 = w1 + w4 eta, c2 = w3 / 2 (affine: w0 + w2 eta, w1, 0). The influences a_i for u and v are
// those of the translation rows of H'^-1 (times the x and y gradient), J_i dp that of the
// increment's two halves.
void RowPolynomials(const Shape& shape, const double* const* w, int terms, float* coef) {
  const int h = shape.half, size = 2 * h + 1;
  const bool quad = shape.kind == ShapeFunction::kQuadratic;
  for (int j = 0; j < size; ++j) {
    const double eta = j - h;
    float* c = coef + static_cast<std::ptrdiff_t>(3) * terms * j;
    for (int t = 0; t < terms; ++t) {
      const double* wt = w[t];
      float* ct = c + static_cast<std::ptrdiff_t>(3) * t;
      ct[0] = static_cast<float>(wt[0] + wt[2] * eta + (quad ? 0.5 * wt[5] * eta * eta : 0.0));
      ct[1] = static_cast<float>(wt[1] + (quad ? wt[4] * eta : 0.0));
      ct[2] = static_cast<float>(quad ? 0.5 * wt[3] : 0.0);
    }
  }
}

// The uncertainty from the residuals of the pass that converged: its warped subset g' = g - f_m
// (in scratch.g), their mean g_mean and ratio = f_n / g_n.
void CorrelatedResidualSigma(const Shape& shape, const RefImages& ref, const SubsetRef& s,
                             const double* hinv, Interpolation kind, double g_mean, double ratio,
                             const Params& dp, double var_r, UncertaintyScratch* scratch,
                             float* sigma_u, float* sigma_v) {
  const int size = 2 * shape.half + 1, nm = shape.nm, n = shape.n;
  const IcgnKernel& kernel = ActiveIcgnKernel();
  const MomentInput ref_in = RefMoments(shape, ref, s);
  ResidualInput in = scratch->layout;
  in.half = shape.half;
  in.f = ref_in.f;
  in.gx = ref_in.gx;
  in.gy = ref_in.gy;
  in.ref_stride = ref_in.stride;
  // J dp less its mean (sum_j dp / N): the residuals keep a zero mean.
  double step_mean = 0;
  for (int q = 0; q < n; ++q) step_mean += s.sum_j[q] * dp[q];
  in.f_mean = static_cast<float>(s.f_mean + step_mean / (double(size) * size));
  in.g = scratch->g.data();
  in.g_mean = static_cast<float>(g_mean);
  in.ratio = static_cast<float>(ratio);
  thread_local std::vector<float> step, coef;
  step.resize(static_cast<std::size_t>(6) * size);
  coef.resize(static_cast<std::size_t>(12) * size);
  const double* dp_rows[2] = {dp.data(), dp.data() + nm};
  RowPolynomials(shape, dp_rows, /*terms=*/2, step.data());
  in.step = step.data();
  double noise[2];
  kernel.residuals(in, scratch->r.data(), noise);
  double htinv[144];
  const double* hi = TrueHessianInverse(shape, hinv, GradientNoise(noise, size, kind), htinv);
  const double* h_rows[4] = {hi, hi + nm, hi + static_cast<std::ptrdiff_t>(nm) * n,
                             hi + static_cast<std::ptrdiff_t>(nm) * n + nm};
  RowPolynomials(shape, h_rows, /*terms=*/4, coef.data());
  double sums[2];
  kernel.correlated_sums(in, scratch->r.data(), coef.data(), scratch->au.data(), scratch->av.data(),
                         sums);
  *sigma_u = static_cast<float>(std::sqrt(var_r * std::max(sums[0], hinv[0])));
  *sigma_v = static_cast<float>(std::sqrt(var_r * std::max(sums[1], hinv[nm * n + nm])));
}

// True when the warped subset, with a 1 px margin, lies inside the deformed image's valid region
// at every pixel it samples. An affine warp's extremes are at the corners; a quadratic warp along
// a pixel row is a parabola in xi, whose extremes are at the row's ends or at its vertex (which may
// lie inside the row, beyond the corners and edge midpoints).
bool WarpedSubsetInside(const Shape& shape, const SubsetRef& s, const Params& p,
                        const DeformedImage& def) {
  const auto at = [&](double xi, double eta, double* x, double* y) {
    double du, dv;
    Displacement(shape, p, xi, eta, &du, &dv);
    *x = s.cx + xi + du;
    *y = s.cy + eta + dv;
    return *x - 1 >= def.x_min && *x + 1 < def.x_max && *y - 1 >= def.y_min && *y + 1 < def.y_max;
  };
  const double h = shape.half;
  double x[3], y[3];
  if (shape.kind != ShapeFunction::kQuadratic) {
    return at(-h, -h, x, y) && at(h, -h, x, y) && at(-h, h, x, y) && at(h, h, x, y);
  }
  for (int row = -shape.half; row <= shape.half; ++row) {
    const double eta = row;
    if (!at(-h, eta, &x[0], &y[0]) || !at(0, eta, &x[1], &y[1]) || !at(h, eta, &x[2], &y[2])) {
      return false;
    }
    for (const double* f : {x, y}) {  // f(xi) = f1 + c1 xi + c2 xi^2 through the three samples.
      const double c2 = (f[2] + f[0] - 2 * f[1]) / (2 * h * h), c1 = (f[2] - f[0]) / (2 * h);
      const double vertex = c2 != 0 ? -c1 / (2 * c2) : 0;
      double vx, vy;
      if (std::abs(vertex) < h && !at(vertex, eta, &vx, &vy)) return false;
    }
  }
  return true;
}

}  // namespace

void PrefetchSubset(const Shape& shape, const RefImages& ref, const SubsetRef& s,
                    const DeformedImage& def, double u, double v) {
  if (s.status != SubsetStatus::kConverged) return;
  constexpr int kLine = 64;  // Bytes per cache line.
  const int h = shape.half, size = 2 * h + 1;
  const MomentInput in = RefMoments(shape, ref, s);
  // Every cache line of floats [p, p + floats).
  const auto row = [](const float* p, int floats) {
    const auto first = reinterpret_cast<std::uintptr_t>(p) & ~std::uintptr_t{kLine - 1};
    const auto end = reinterpret_cast<std::uintptr_t>(p + floats);
    for (std::uintptr_t a = first; a < end; a += kLine) {
      // NOLINTNEXTLINE(performance-no-int-to-ptr): addresses inside the caller's image rows
      __builtin_prefetch(reinterpret_cast<const void*>(a));
    }
  };
  for (int j = 0; j < size; ++j) {
    const std::ptrdiff_t o = j * in.stride;
    row(in.f + o, size);
    row(in.gx + o, size);
    row(in.gy + o, size);
  }
  const BsplineImage& spline = *def.spline;
  const cv::Mat& coef = spline.coefficients();
  const cv::Rect r = spline.region();
  if (!(std::abs(u) < 1e6 && std::abs(v) < 1e6)) return;  // A hint from a failed subset.
  const int margin = h + 3;  // The taps of a warped subset near a translation.
  const int x0 = static_cast<int>(std::lround(s.cx + u)) - margin - r.x;
  const int y0 = static_cast<int>(std::lround(s.cy + v)) - margin - r.y;
  const int cols = 2 * margin + 1;
  if (x0 < 0 || y0 < 0 || x0 + cols > coef.cols || y0 + cols > coef.rows) return;
  for (int j = 0; j < cols; ++j) row(coef.ptr<float>(y0 + j) + x0, cols);
}

IcgnResult RunIcgn(const Shape& shape, const RefImages& ref, const SubsetRef& s, const double* hinv,
                   const DeformedImage& def, const IcgnOptions& options, const Params& initial) {
  IcgnResult result;
  result.p = initial;
  const int h = shape.half, n = shape.n, nm = shape.nm;
  const double count = double(2 * h + 1) * (2 * h + 1);
  const BsplineImage& spline = *def.spline;
  const cv::Mat& coef = spline.coefficients();
  const int dcx = s.cx - spline.region().x, dcy = s.cy - spline.region().y;
  const auto pass = ActiveIcgnKernel().accumulate[spline.kind() == Interpolation::kBicubic ? 0 : 1]
                                                 [shape.kind == ShapeFunction::kQuadratic ? 1 : 0];
  // The pass's view of the subset (the warp's part is set per iteration).
  const MomentInput ref_in = RefMoments(shape, ref, s);
  PassInput in;
  in.half = h;
  in.f = ref_in.f;
  in.gx = ref_in.gx;
  in.gy = ref_in.gy;
  in.ref_stride = ref_in.stride;
  in.f_mean = s.f_mean;
  in.stride = static_cast<std::ptrdiff_t>(coef.step1());
  in.nm = nm;
  UncertaintyScratch& scratch = ThreadUncertaintyScratch(2 * h + 1);
  in.g_out = scratch.g.data();
  Params& p = result.p;
  // The standard deviation of a subset corner's displacement per unit residual standard deviation
  // (independent residuals), the largest over the four corners: sqrt(m^T H^-1_uu m + m^T H^-1_vv
  // m) with m the shape monomials at the corner. The convergence test compares the increment's
  // corner move with it.
  double corner_sd = 0;
  for (int k = 0; k < 4; ++k) {
    double m[6];
    Monomials((k & 1) ? h : -h, (k & 2) ? h : -h, m);
    double var = 0;
    for (int a = 0; a < 2; ++a) {
      for (int i = 0; i < nm; ++i)
        for (int j = 0; j < nm; ++j) var += m[i] * hinv[(a * nm + i) * n + a * nm + j] * m[j];
    }
    corner_sd = std::max(corner_sd, std::sqrt(std::max(0.0, var)));
  }
  for (int it = 1; it <= options.max_iterations; ++it) {
    result.iterations = it;
    // The warped subset (every sampled pixel, 1 px margin) must stay in the valid region.
    if (!WarpedSubsetInside(shape, s, p, def)) {
      result.status = SubsetStatus::kOutOfImage;
      return result;
    }
    // The integer part of the translation moves the centre, so local coordinates stay small.
    const int iu = static_cast<int>(std::lround(p[0])), iv = static_cast<int>(std::lround(p[nm]));
    in.centre = coef.ptr<float>() + static_cast<std::ptrdiff_t>(dcy + iv) * in.stride + (dcx + iu);
    in.p = p.data();
    in.u = p[0] - iu;
    in.v = p[nm] - iv;
    PassSums sums;
    pass(in, &sums);
    const double gm = sums.sg / count;
    const double gn2 = sums.sgg - count * gm * gm;
    if (!(gn2 > 1e-9 * count) || !(s.f_norm > 0)) {
      result.zncc = 0;
      result.status = SubsetStatus::kLowCorrelation;
      return result;
    }
    const double gn = std::sqrt(gn2);
    result.zncc = static_cast<float>((sums.sfg - s.f_mean * sums.sg) / (s.f_norm * gn));
    const double ratio = s.f_norm / gn;
    double b[12];
    for (int i = 0; i < n; ++i) {
      const int a = i / nm, m = i % nm;
      const double jg = kMonoC[m] * sums.a[a][kMonoPx[m]][kMonoPy[m]];
      b[i] = s.sum_jf[i] - ratio * (jg - gm * s.sum_j[i]);
    }
    Params dp{};
    for (int i = 0; i < n; ++i) {
      double v = 0;
      for (int j = 0; j < n; ++j) v -= hinv[i * n + j] * b[j];
      dp[i] = v;
    }
    // Convergence measure: largest displacement of a subset corner under the increment.
    double move = 0;
    for (int k = 0; k < 4; ++k) {
      double du, dv;
      Displacement(shape, dp, (k & 1) ? h : -h, (k & 2) ? h : -h, &du, &dv);
      move = std::max(move, std::sqrt(du * du + dv * dv));
    }
    if (!std::isfinite(move)) {
      result.status = SubsetStatus::kSingularHessian;
      return result;
    }
    p = ComposeInverse(shape, p, dp);
    // The residual variance sigma_r^2 = sum r^2 / (N - n), sum r^2 = f_n^2 * 2 (1 - ZNCC) (r in
    // reference grey levels). Converged once the increment moves no corner by more than
    // convergence_px, or by far less than the corners' own least-squares standard deviation
    // sigma_r corner_sd (IcgnOptions::convergence_sigma_fraction).
    const double r2 = double(s.f_norm) * s.f_norm * 2 * std::max(0.0, 1.0 - result.zncc);
    const double var_r = r2 / (count - n);
    if (move < std::max(options.convergence_px,
                        options.convergence_sigma_fraction * std::sqrt(var_r) * corner_sd)) {
      // The converged warp must stay in the valid region too (a quadratic subset's last step can
      // leave it).
      if (!WarpedSubsetInside(shape, s, p, def)) {
        result.status = SubsetStatus::kOutOfImage;
        return result;
      }
      // The uncertainty from the residuals of this last pass, at the warp before its increment
      // (which moved no corner by more than the convergence limit): var_r is theirs too.
      CorrelatedResidualSigma(shape, ref, s, hinv, spline.kind(), gm, ratio, dp, var_r, &scratch,
                              &result.sigma_u_px, &result.sigma_v_px);
      result.sigma_px = std::max(result.sigma_u_px, result.sigma_v_px);
      if (result.zncc < options.min_zncc) {
        result.status = SubsetStatus::kLowCorrelation;
      } else if (options.LimitsUncertainty() && !(result.sigma_px <= options.max_uncertainty_px)) {
        result.status = SubsetStatus::kUncertain;
      } else {
        result.status = SubsetStatus::kConverged;
      }
      return result;
    }
  }
  result.status = SubsetStatus::kMaxIterations;
  return result;
}

}  // namespace impactdic::internal
