// Post-check of straddling subsets (see continuity_check.h).
#include "impactdic/dic/continuity_check.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>

#include "impactdic/core/error.h"
#include "impactdic/core/numeric.h"
#include "impactdic/dic/options.h"

namespace impactdic {

namespace {

constexpr int kReach = 3;  // The neighbourhood of the local medians: 7 x 7 subsets.
constexpr double kNaNd = std::numeric_limits<double>::quiet_NaN();

bool Valid(const FrameResult& r, int i) { return r.status[i] == SubsetStatus::kConverged; }

// flag[i] = q[i] > max(floor, ratio x the median of q over the finite values of the 7 x 7
// neighbourhood, itself excluded); no flag with fewer than 6 such neighbours or a NaN q[i].
// ratio = +inf: q[i] > floor alone.
std::vector<std::uint8_t> AboveLocalMedian(const std::vector<double>& q, int cols, int rows,
                                           double floor, double ratio) {
  const int n = cols * rows;
  std::vector<std::uint8_t> flag(n, 0);
  if (!std::isfinite(floor)) return flag;
  // Each subset on its own (in parallel): the flags do not depend on the order.
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 256), [&](const tbb::blocked_range<int>& range) {
    std::vector<double> near;
    for (int i = range.begin(); i < range.end(); ++i) {
      if (!(q[i] > floor)) continue;
      if (!std::isfinite(ratio)) {
        flag[i] = 1;
        continue;
      }
      near.clear();
      const int row = i / cols, col = i % cols;
      for (int rr = std::max(0, row - kReach); rr <= std::min(rows - 1, row + kReach); ++rr) {
        for (int cc = std::max(0, col - kReach); cc <= std::min(cols - 1, col + kReach); ++cc) {
          const int j = rr * cols + cc;
          if (j != i && std::isfinite(q[j])) near.push_back(q[j]);
        }
      }
      if (near.size() < 6) continue;
      std::nth_element(near.begin(), near.begin() + near.size() / 2, near.end());
      flag[i] = q[i] > ratio * near[near.size() / 2];
    }
  });
  return flag;
}

// Per converged subset and grid direction (0: along its row, 1: along its column): the second
// difference of (u, v) (both neighbours converged) and the largest difference to a converged
// adjacent subset [px]; NaN where not defined. Kept per direction so that a strong gradient along
// one direction (the core under the pounder, whose displacement decays with depth) does not hide
// a jump across the other (a vertical shear band).
void Differences(const FrameResult& r, int cols, int rows, std::vector<double> second[2],
                 std::vector<double> jump[2]) {
  const int n = cols * rows;
  const auto dist = [&r](int i, double u, double v) {
    return PixelDistance(r.u_px[i] - u, r.v_px[i] - v);
  };
  for (int d = 0; d < 2; ++d) {
    second[d].assign(n, kNaNd);
    jump[d].assign(n, kNaNd);
  }
  // Each subset on its own (in parallel).
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 256), [&](const tbb::blocked_range<int>& range) {
    for (int i = range.begin(); i < range.end(); ++i) {
      if (!Valid(r, i)) continue;
      const int row = i / cols, col = i % cols;
      const int pairs[2][2][2] = {{{row, col - 1}, {row, col + 1}},
                                  {{row - 1, col}, {row + 1, col}}};
      for (int d = 0; d < 2; ++d) {
        const auto& p = pairs[d];
        const bool a_in = p[0][0] >= 0 && p[0][1] >= 0, b_in = p[1][0] < rows && p[1][1] < cols;
        const int a = a_in ? p[0][0] * cols + p[0][1] : -1;
        const int b = b_in ? p[1][0] * cols + p[1][1] : -1;
        for (const int j : {a, b}) {
          if (j >= 0 && Valid(r, j))
            jump[d][i] = std::fmax(jump[d][i], dist(i, r.u_px[j], r.v_px[j]));
        }
        if (a < 0 || b < 0 || !Valid(r, a) || !Valid(r, b)) continue;
        second[d][i] = dist(i, 0.5 * (r.u_px[a] + r.u_px[b]), 0.5 * (r.v_px[a] + r.v_px[b]));
      }
    }
  });
}

}  // namespace

ContinuityFlags CheckContinuity(const FrameResult& result, int cols, int rows,
                                const ContinuityCheckOptions& options) {
  options.Check();
  CheckValue(cols > 0 && rows > 0 && static_cast<std::size_t>(cols) * rows == result.status.size(),
             "CheckContinuity grid", std::to_string(cols) + "x" + std::to_string(rows),
             "cols x rows == the frame's subsets");
  const int n = cols * rows;
  std::vector<double> misfit(n, kNaNd), second[2], jump[2];
  for (int i = 0; i < n; ++i)
    if (Valid(result, i)) misfit[i] = 1.0 - result.zncc[i];
  Differences(result, cols, rows, second, jump);
  ContinuityFlags flags;
  // The median is taken at least 1e-6 (a perfect fit).
  const double misfit_floor = std::max(options.min_misfit, options.misfit_ratio * 1e-6);
  flags.misfit = std::isfinite(options.misfit_ratio)
                     ? AboveLocalMedian(misfit, cols, rows, misfit_floor, options.misfit_ratio)
                     : std::vector<std::uint8_t>(n, 0);
  flags.discontinuous.assign(n, 0);
  for (int d = 0; d < 2; ++d) {
    const std::vector<std::uint8_t> s2 = AboveLocalMedian(
        second[d], cols, rows, options.max_second_difference_px, options.local_ratio);
    const std::vector<std::uint8_t> jp = AboveLocalMedian(
        jump[d], cols, rows, options.max_neighbour_difference_px, options.local_ratio);
    for (int i = 0; i < n; ++i) flags.discontinuous[i] |= s2[i] | jp[i];
  }
  for (int i = 0; i < n; ++i) {
    flags.flagged += flags.misfit[i] || flags.discontinuous[i];
  }
  return flags;
}

void ApplyContinuityFlags(const ContinuityFlags& flags, FrameResult* result) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t i = 0; i < flags.misfit.size(); ++i) {
    if (!(flags.misfit[i] || flags.discontinuous[i])) continue;
    result->status[i] = SubsetStatus::kDiscontinuous;
    result->u_px[i] = result->v_px[i] = nan;
    if (i < result->sigma_px.size()) {
      result->sigma_u_px[i] = result->sigma_v_px[i] = result->sigma_px[i] =
          std::numeric_limits<float>::quiet_NaN();
    }
  }
}

}  // namespace impactdic
