#include "impactdic/dic/bspline.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/memory.h"

namespace impactdic {
namespace {

// Poles and gain of the B-spline interpolation prefilter (Unser et al. 1993).
struct Prefilter {
  double poles[2];
  int n_poles;
  double gain;
};

Prefilter PrefilterFor(Interpolation kind) {
  Prefilter p{};
  if (kind == Interpolation::kBicubic) {
    p.poles[0] = std::sqrt(3.0) - 2;
    p.n_poles = 1;
  } else {
    p.poles[0] = std::sqrt(135.0 / 2 - std::sqrt(17745.0 / 4)) + std::sqrt(105.0 / 4) - 6.5;
    p.poles[1] = std::sqrt(135.0 / 2 + std::sqrt(17745.0 / 4)) - std::sqrt(105.0 / 4) - 6.5;
    p.n_poles = 2;
  }
  p.gain = 1;
  for (int k = 0; k < p.n_poles; ++k) p.gain *= (1 - p.poles[k]) * (1 - 1 / p.poles[k]);
  return p;
}

// The prefilter (gain, then per pole a causal and an anti-causal first-order recursion with the
// mirror-boundary initial values) on kLanes interleaved lines at once: c[k * kLanes + l] is
// sample k of line l; the recursions run along k and are vectorised across the lines. Every line
// sees the same operations in the same order whatever kLanes is.
constexpr int kRowLanes = 8;
// Columns are filtered 32 at a time: two full cache lines of each row per pass.
constexpr int kColumnLanes = 32;
constexpr int kFloatsPerLine = 16;      // 64-byte cache lines.
constexpr int kColumnPrefetchRows = 8;  // Measured on 4096x3000: 4, 8 and 16 rows alike.

// Causal initial values for mirror boundary conditions (Unser et al. 1993), to this tolerance:
// the sum is cut after CausalHorizon(z) samples, |z|^horizon <= kCausalTolerance.
constexpr double kCausalTolerance = 1e-12;
int CausalHorizon(double z) {
  return static_cast<int>(std::ceil(std::log(kCausalTolerance) / std::log(std::abs(z))));
}
template <int kLanes>
void InitialCausalLanes(const double* c, int n, double z, double* out) {
  const int horizon = CausalHorizon(z);
  if (horizon < n) {
    double sum[kLanes];
    for (int l = 0; l < kLanes; ++l) sum[l] = c[l];
    double zn = z;
    for (int k = 1; k < horizon; ++k) {
      for (int l = 0; l < kLanes; ++l) sum[l] += zn * c[k * kLanes + l];
      zn *= z;
    }
    for (int l = 0; l < kLanes; ++l) out[l] = sum[l];
    return;
  }
  double zn = z;
  const double iz = 1 / z;
  double z2n = std::pow(z, n - 1);
  double sum[kLanes];
  for (int l = 0; l < kLanes; ++l) sum[l] = c[l] + z2n * c[(n - 1) * kLanes + l];
  z2n *= z2n * iz;
  for (int k = 1; k <= n - 2; ++k) {
    for (int l = 0; l < kLanes; ++l) sum[l] += (zn + z2n) * c[k * kLanes + l];
    zn *= z;
    z2n *= iz;
  }
  for (int l = 0; l < kLanes; ++l) out[l] = sum[l] / (1 - zn * zn);
}

// The prefilter on kLanes lines of n samples, fused with reading and writing them: load(k, c_k)
// writes sample k of every line, times p.gain, into c_k[0 .. kLanes); store(k, c_k) takes the
// filtered sample k. The first pole's causal recursion runs as the samples are loaded (the
// samples its initial value reads are loaded first), the last pole's anti-causal recursion as they
// are stored: the buffer c (n * kLanes doubles) is passed over twice per pole instead of four
// times, and every sample sees the same operations in the same order as in separate passes.
template <int kLanes, typename Load, typename Store>
void FilterLines(double* c, int n, const Prefilter& p, const Load& load, const Store& store) {
  if (n < 2) {
    for (int k = 0; k < n; ++k) load(k, c + static_cast<std::ptrdiff_t>(k) * kLanes);
    for (int k = 0; k < n; ++k) store(k, c + static_cast<std::ptrdiff_t>(k) * kLanes);
    return;
  }
  for (int j = 0; j < p.n_poles; ++j) {
    const bool first_pole = j == 0, last_pole = j + 1 == p.n_poles;
    const double z = p.poles[j];
    // The causal initial value reads the first CausalHorizon(z) samples (all of a short line).
    const int loaded = first_pole ? std::min(n, CausalHorizon(z)) : n;
    for (int k = 0; first_pole && k < loaded; ++k)
      load(k, c + static_cast<std::ptrdiff_t>(k) * kLanes);
    double first[kLanes];
    InitialCausalLanes<kLanes>(c, n, z, first);
    for (int l = 0; l < kLanes; ++l) c[l] = first[l];
    for (int k = 1; k < n; ++k) {
      double* ck = c + static_cast<std::ptrdiff_t>(k) * kLanes;
      if (k >= loaded) load(k, ck);
      const double* prev = ck - kLanes;
      for (int l = 0; l < kLanes; ++l) ck[l] += z * prev[l];
    }
    double* last = c + static_cast<std::ptrdiff_t>(n - 1) * kLanes;
    for (int l = 0; l < kLanes; ++l) last[l] = (z / (z * z - 1)) * (z * last[l - kLanes] + last[l]);
    if (last_pole) store(n - 1, last);
    for (int k = n - 2; k >= 0; --k) {
      double* ck = c + static_cast<std::ptrdiff_t>(k) * kLanes;
      const double* next = ck + kLanes;
      for (int l = 0; l < kLanes; ++l) ck[l] = z * (next[l] - ck[l]);
      if (last_pole) store(k, ck);
    }
  }
}

// Per-thread scratch of the prefilter (kept between calls: no allocation per line group).
double* Scratch(std::size_t count) {
  thread_local std::vector<double> buffer;
  if (buffer.size() < count) buffer.resize(count);
  return buffer.data();
}

int Mirror(int i, int n) {
  if (i >= 0 && i < n) return i;
  if (n == 1) return 0;
  const int period = 2 * (n - 1);
  i = std::abs(i) % period;
  return i < n ? i : period - i;
}

// B-spline of degree 3 or 5 and its derivative at signed distance d.
double Beta(int degree, double d) {
  const double x = std::abs(d);
  if (degree == 3) {
    if (x < 1) return 2.0 / 3 - x * x + 0.5 * x * x * x;
    if (x < 2) return (2 - x) * (2 - x) * (2 - x) / 6;
    return 0;
  }
  const double x2 = x * x, x4 = x2 * x2;
  if (x < 1) return (66 - 60 * x2 + 30 * x4 - 10 * x4 * x) / 120;
  if (x < 2) return (51 + 75 * x - 210 * x2 + 150 * x2 * x - 45 * x4 + 5 * x4 * x) / 120;
  if (x < 3) return std::pow(3 - x, 5) / 120;
  return 0;
}

double BetaDerivative(int degree, double d) {
  const double x = std::abs(d), sign = d < 0 ? -1 : 1;
  double r = 0;
  if (degree == 3) {
    if (x < 1)
      r = -2 * x + 1.5 * x * x;
    else if (x < 2)
      r = -0.5 * (2 - x) * (2 - x);
  } else {
    const double x2 = x * x;
    if (x < 1)
      r = (-120 * x + 120 * x2 * x - 50 * x2 * x2) / 120;
    else if (x < 2)
      r = (75 - 420 * x + 450 * x2 - 180 * x2 * x + 25 * x2 * x2) / 120;
    else if (x < 3)
      r = -5 * std::pow(3 - x, 4) / 120;
  }
  return sign * r;
}

}  // namespace

const char* ToString(Interpolation interpolation) {
  return kInterpolationNames.Name(interpolation);
}

Interpolation InterpolationFromString(const std::string& name) {
  return kInterpolationNames.Parse(name, "interpolation");
}

void BsplineImage::Build(const cv::Mat& image, Interpolation kind, cv::Rect region, int guard_px) {
  CheckValue(!image.empty() && image.channels() == 1, "BsplineImage image",
             image.empty() ? "empty image" : "multi-channel image", "a one-channel image");
  const int depth = image.depth();
  CheckValue(depth == CV_8U || depth == CV_16U || depth == CV_32F || depth == CV_64F,
             "BsplineImage image", "pixel depth " + std::to_string(depth),
             "8-bit or 16-bit unsigned, 32-bit or 64-bit float pixels");
  const cv::Rect full(0, 0, image.cols, image.rows);
  if (region.area() == 0) region = full;
  region = cv::Rect(region.x - guard_px, region.y - guard_px, region.width + 2 * guard_px,
                    region.height + 2 * guard_px) &
           full;
  CheckValue(region.width >= 8 && region.height >= 8, "BsplineImage region",
             std::to_string(region.width) + "x" + std::to_string(region.height),
             "a region of at least 8x8 px inside the image");
  kind_ = kind;
  region_ = region;
  const Prefilter prefilter = PrefilterFor(kind);
  const int w = region.width, h = region.height;
  // The buffer is kept from the last Build when it is large enough (no new pages to fault in
  // for every frame of a sequence).
  if (storage_.rows < h || storage_.cols < w) {
    storage_.create(std::max(h, storage_.rows), std::max(w, storage_.cols), CV_32F);
    AdviseHugePages(storage_.data, storage_.total() * storage_.elemSize());
  }
  coefficients_ = storage_(cv::Rect(0, 0, w, h));
  cv::Mat source = image(region);

  // Rows (in double), kRowLanes rows at a time (interleaved), groups in parallel. Each sample
  // of the kRowLanes rows is read and written in turn (one pass along the rows, each line of the
  // interleaved buffer touched once), times the prefilter's gain (FilterLines). The lanes past the
  // image's last row repeat it: their results are that row's, bit for bit.
  const double gain = prefilter.gain;
  const auto rows = [&]<typename T>(T /*depth*/) {
    tbb::parallel_for(0, (h + kRowLanes - 1) / kRowLanes, [&](int group) {
      constexpr int kLanes = kRowLanes;
      const int r0 = group * kLanes, lanes = std::min(kLanes, h - r0);
      std::array<const T*, kLanes> in;
      std::array<float*, kLanes> out;
      for (int l = 0; l < kLanes; ++l) {
        in[l] = source.ptr<T>(r0 + std::min(l, lanes - 1));
        out[l] = coefficients_.ptr<float>(r0 + std::min(l, lanes - 1));
      }
      FilterLines<kLanes>(
          Scratch(static_cast<std::size_t>(w) * kLanes), w, prefilter,
          [&](int k, double* b) {
            for (int l = 0; l < kLanes; ++l) b[l] = gain * in[l][k];
          },
          [&](int k, const double* b) {  // Repeated lanes write their row's own value again.
            for (int l = 0; l < kLanes; ++l) out[l][k] = static_cast<float>(b[l]);
          });
    });
  };
  switch (source.depth()) {
    case CV_8U: rows(std::uint8_t{}); break;
    case CV_16U: rows(std::uint16_t{}); break;
    case CV_32F: rows(float{}); break;
    default: rows(double{});
  }
  // Columns, kColumnLanes adjacent columns at a time (contiguous in each row), groups in parallel;
  // lanes past the last column are zeros (no denormals or NaN). The rows kColumnPrefetchRows ahead
  // are prefetched (down the columns while reading, up while writing): a row of the coefficients is
  // a page or more away from the next, where the hardware's prefetcher does not follow (4096x3000:
  // the column pass 2x faster).
  tbb::parallel_for(0, (w + kColumnLanes - 1) / kColumnLanes, [&](int group) {
    constexpr int kLanes = kColumnLanes;
    const int c0 = group * kLanes, lanes = std::min(kLanes, w - c0);
    const auto prefetch = [&](int r, bool write) {
      const float* row = coefficients_.ptr<float>(r) + c0;
      for (int l = 0; l < lanes; l += kFloatsPerLine) {
        if (write)
          __builtin_prefetch(row + l, /*rw=*/1);
        else
          __builtin_prefetch(row + l, /*rw=*/0);
      }
    };
    FilterLines<kLanes>(
        Scratch(static_cast<std::size_t>(h) * kLanes), h, prefilter,
        [&](int r, double* b) {
          if (r + kColumnPrefetchRows < h) prefetch(r + kColumnPrefetchRows, /*write=*/false);
          const float* in = coefficients_.ptr<float>(r) + c0;
          if (lanes == kLanes) {  // Whole groups with a fixed count (vectorised).
            for (int l = 0; l < kLanes; ++l) b[l] = gain * in[l];
          } else {
            for (int l = 0; l < lanes; ++l) b[l] = gain * in[l];
            for (int l = lanes; l < kLanes; ++l) b[l] = 0;
          }
        },
        [&](int r, const double* b) {
          if (r >= kColumnPrefetchRows) prefetch(r - kColumnPrefetchRows, /*write=*/true);
          float* out = coefficients_.ptr<float>(r) + c0;
          if (lanes == kLanes) {
            for (int l = 0; l < kLanes; ++l) out[l] = static_cast<float>(b[l]);
          } else {
            for (int l = 0; l < lanes; ++l) out[l] = static_cast<float>(b[l]);
          }
        });
  });
  // Evaluable domain: floor(x) - half_low >= 0 and floor(x) + half_high <= w - 1.
  const int low = kind == Interpolation::kBicubic ? 1 : 2;
  const int high = kind == Interpolation::kBicubic ? 2 : 3;
  x_min_ = region.x + low;
  x_max_ = region.x + w - high;  // floor(x) <= w - 1 - high  <=>  x < w - high.
  y_min_ = region.y + low;
  y_max_ = region.y + h - high;
}

double BsplineImage::Value(double x, double y) const {
  double v, gx, gy;
  ValueGradient(x, y, &v, &gx, &gy);
  return v;
}

void BsplineImage::ValueGradient(double x, double y, double* value, double* gx, double* gy) const {
  const int n = degree();
  const int low = n == 3 ? 1 : 2, taps = n + 1;
  const double lx = x - region_.x, ly = y - region_.y;
  const int ix = static_cast<int>(std::floor(lx)), iy = static_cast<int>(std::floor(ly));
  const double tx = lx - ix, ty = ly - iy;
  double wx[6], wy[6], dx[6], dy[6];
  for (int k = 0; k < taps; ++k) {
    wx[k] = Beta(n, tx - (k - low));
    wy[k] = Beta(n, ty - (k - low));
    dx[k] = BetaDerivative(n, tx - (k - low));
    dy[k] = BetaDerivative(n, ty - (k - low));
  }
  double v = 0, vx = 0, vy = 0;
  for (int j = 0; j < taps; ++j) {
    const float* row = coefficients_.ptr<float>(iy - low + j);
    double s = 0, sd = 0;
    for (int i = 0; i < taps; ++i) {
      const double c = row[ix - low + i];
      s += wx[i] * c;
      sd += dx[i] * c;
    }
    v += wy[j] * s;
    vx += wy[j] * sd;
    vy += dy[j] * s;
  }
  *value = v;
  *gx = vx;
  *gy = vy;
}

void BsplineImage::NodeGradients(cv::Mat* gx, cv::Mat* gy) const {
  for (cv::Mat* g : {gx, gy}) {
    if (g->rows == region_.height && g->cols == region_.width && g->type() == CV_32F) continue;
    g->create(region_.height, region_.width, CV_32F);
    AdviseHugePages(g->data, g->total() * g->elemSize());
  }
  NodeGradients(region_, gx, gy);
}

void BsplineImage::NodeGradients(const cv::Rect& rect, cv::Mat* gx, cv::Mat* gy) const {
  assert((rect & region_) == rect && "NodeGradients: rect outside the coefficient region");
  const int w = region_.width, h = region_.height;
  const bool cubic = kind_ == Interpolation::kBicubic;
  // Value and derivative weights of the spline at a node, offsets -2..2.
  const float value_w[5] = {cubic ? 0.0f : 1.0f / 120, cubic ? 1.0f / 6 : 26.0f / 120,
                            cubic ? 4.0f / 6 : 66.0f / 120, cubic ? 1.0f / 6 : 26.0f / 120,
                            cubic ? 0.0f : 1.0f / 120};
  const float deriv_w[5] = {cubic ? 0.0f : -1.0f / 24, cubic ? -0.5f : -10.0f / 24, 0,
                            cubic ? 0.5f : 10.0f / 24, cubic ? 0.0f : 1.0f / 24};
  const int reach = cubic ? 1 : 2;  // Taps -reach..reach are non-zero.
  gx->create(rect.height, rect.width, CV_32F);
  gy->create(rect.height, rect.width, CV_32F);
  // Columns x0..x1 of the region (local coordinates), with 2 columns either side (mirrored at
  // the region border).
  const int x0 = rect.x - region_.x, x1 = x0 + rect.width;
  // Separable: gx = value filter along y of the derivative filter along x, gy the transpose.
  // Per output row, the rows r - reach..r + reach (mirrored at the region border) are first
  // combined along y (value and derivative weights), then filtered along x. A column outside
  // the region takes the values of its mirror image, so every node's gradient is the same
  // whatever rectangle it is computed in.
  const auto row = [&](int r) {
    thread_local std::vector<float> buffer;  // v and d: no allocation per row.
    const std::size_t cols = static_cast<std::size_t>(rect.width) + 4;
    if (buffer.size() < 2 * cols) buffer.resize(2 * cols);
    float* v = buffer.data() + 2 - x0;  // v[x] for x in x0 - 2 .. x1 + 1.
    float* d = buffer.data() + cols + 2 - x0;
    const int in0 = std::max(x0 - 2, 0), in1 = std::min(x1 + 2, w);
    for (int x = in0; x < in1; ++x) v[x] = d[x] = 0;
    for (int k = -reach; k <= reach; ++k) {
      const float* c = coefficients_.ptr<float>(Mirror(r + k, h));
      const float a = value_w[k + 2], b = deriv_w[k + 2];
      for (int x = in0; x < in1; ++x) {
        v[x] += a * c[x];
        d[x] += b * c[x];
      }
    }
    // Mirrored padding for the filter along x.
    for (int x = x0 - 2; x < x1 + 2; ++x) {
      if (x >= in0 && x < in1) continue;
      const int m = Mirror(x, w);
      if (m >= in0 && m < in1) {
        v[x] = v[m];
        d[x] = d[m];
        continue;
      }
      float vm = 0, dm = 0;  // The mirror column is outside the computed range: compute it.
      for (int k = -reach; k <= reach; ++k) {
        const float c = coefficients_.ptr<float>(Mirror(r + k, h))[m];
        vm += value_w[k + 2] * c;
        dm += deriv_w[k + 2] * c;
      }
      v[x] = vm;
      d[x] = dm;
    }
    float* ox = gx->ptr<float>(r - (rect.y - region_.y)) - x0;
    float* oy = gy->ptr<float>(r - (rect.y - region_.y)) - x0;
    if (cubic) {
      for (int x = x0; x < x1; ++x) {
        ox[x] = deriv_w[3] * (v[x + 1] - v[x - 1]);
        oy[x] = value_w[1] * (d[x - 1] + d[x + 1]) + value_w[2] * d[x];
      }
    } else {
      for (int x = x0; x < x1; ++x) {
        ox[x] = deriv_w[3] * (v[x + 1] - v[x - 1]) + deriv_w[4] * (v[x + 2] - v[x - 2]);
        oy[x] = value_w[0] * (d[x - 2] + d[x + 2]) + value_w[1] * (d[x - 1] + d[x + 1]) +
                value_w[2] * d[x];
      }
    }
  };
  const int r0 = rect.y - region_.y, r1 = r0 + rect.height;
  if (rect.area() >= 64 * 1024) {
    tbb::parallel_for(r0, r1, row);
  } else {
    for (int r = r0; r < r1; ++r) row(r);
  }
}

}  // namespace impactdic
