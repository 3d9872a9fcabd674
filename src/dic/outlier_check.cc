// The normalized median test on a correlated frame (see outlier_check.h).
#include "impactdic/dic/outlier_check.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>
#include <utility>

#include "impactdic/core/error.h"
#include "impactdic/core/numeric.h"

namespace impactdic {

namespace {

bool Valid(const FrameResult& r, int i) { return r.status[i] == SubsetStatus::kConverged; }

// One of each pair of opposite grid neighbours (row, column offsets).
constexpr std::array<std::pair<int, int>, 4> kHalfNeighbourhood{{{0, 1}, {1, -1}, {1, 0}, {1, 1}}};

// Median of the first n values (sorted in place by insertion; n <= 8 here, where that costs
// less than std::sort or nth_element): the middle one, or the mean of the two middle ones.
double Median(double* values, int n) {
  for (int i = 1; i < n; ++i) {
    const double v = values[i];
    int j = i;
    for (; j > 0 && values[j - 1] > v; --j) values[j] = values[j - 1];
    values[j] = v;
  }
  const double upper = values[n / 2];
  if (n % 2 == 1) return upper;
  return 0.5 * (upper + values[n / 2 - 1]);
}

// The normalized median test of subset i: flags->normalized_residual[i] and flags->outlier[i]
// (left as they are where the test does not apply).
void FlagOutlier(const FrameResult& result, int cols, int rows, const OutlierCheckOptions& options,
                 bool has_sigma, int i, OutlierFlags* flags) {
  if (!Valid(result, i)) return;
  const int row = i / cols, col = i % cols;
  // The neighbours in opposite pairs (both converged), so that a linear field's median is the
  // centre's value: a one-sided neighbourhood (a grid edge, a failed neighbour) would put the
  // median off by the local gradient and flag coherent motion.
  std::array<int, 8> near{};
  int count = 0;
  for (const auto& [dr, dc] : kHalfNeighbourhood) {
    const int r0 = row + dr, c0 = col + dc, r1 = row - dr, c1 = col - dc;
    if (r0 < 0 || r0 >= rows || c0 < 0 || c0 >= cols || r1 < 0 || r1 >= rows || c1 < 0 ||
        c1 >= cols)
      continue;
    const int a = r0 * cols + c0, b = r1 * cols + c1;
    if (!Valid(result, a) || !Valid(result, b)) continue;
    near[count++] = a;
    near[count++] = b;
  }
  if (count < options.min_neighbours) return;
  std::array<double, 8> u{}, v{}, r{};
  for (int k = 0; k < count; ++k) {
    u[k] = result.u_px[near[k]];
    v[k] = result.v_px[near[k]];
  }
  const double um = Median(u.data(), count), vm = Median(v.data(), count);
  for (int k = 0; k < count; ++k)
    r[k] = PixelDistance(result.u_px[near[k]] - um, result.v_px[near[k]] - vm);
  const double rm = Median(r.data(), count);
  const double deviation = PixelDistance(result.u_px[i] - um, result.v_px[i] - vm);
  const double normalized = deviation / (rm + options.noise_px);
  flags->normalized_residual[i] = normalized;
  double sigma = 0;
  if (has_sigma) {
    const double su = result.sigma_u_px[i], sv = result.sigma_v_px[i];
    if (std::isfinite(su) && std::isfinite(sv)) sigma = PixelDistance(su, sv);
  }
  if (normalized > options.threshold && deviation > options.sigma_factor * sigma)
    flags->outlier[i] = 1;
}

}  // namespace

OutlierFlags FindOutliers(const FrameResult& result, int cols, int rows,
                          const OutlierCheckOptions& options) {
  options.Check();
  CheckValue(cols > 0 && rows > 0 && static_cast<std::size_t>(cols) * rows == result.status.size(),
             "FindOutliers grid", std::to_string(cols) + "x" + std::to_string(rows),
             "cols x rows == the frame's subsets");
  const int n = cols * rows;
  OutlierFlags flags;
  flags.outlier.assign(n, 0);
  flags.normalized_residual.assign(n, std::numeric_limits<double>::quiet_NaN());
  const bool has_sigma = result.sigma_px.size() == static_cast<std::size_t>(n);
  // Each subset on its own (in parallel): the flags do not depend on the order.
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 256), [&](const tbb::blocked_range<int>& range) {
    for (int i = range.begin(); i < range.end(); ++i)
      FlagOutlier(result, cols, rows, options, has_sigma, i, &flags);
  });
  flags.flagged = static_cast<int>(std::count(flags.outlier.begin(), flags.outlier.end(), 1));
  return flags;
}

void ApplyOutlierFlags(const OutlierFlags& flags, FrameResult* result) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const float nanf = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t i = 0; i < flags.outlier.size(); ++i) {
    if (!flags.outlier[i]) continue;
    result->status[i] = SubsetStatus::kOutlier;
    result->u_px[i] = result->v_px[i] = nan;
    if (i < result->sigma_px.size())
      result->sigma_u_px[i] = result->sigma_v_px[i] = result->sigma_px[i] = nanf;
  }
}

}  // namespace impactdic
