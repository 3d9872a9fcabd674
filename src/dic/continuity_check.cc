// Post-check of straddling subsets (see continuity_check.h).
#include "impactdic/dic/continuity_check.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>

#include "impactdic/core/error.h"
#include "impactdic/dic/options.h"

namespace impactdic {

void ContinuityCheckOptions::Check() const {
  CheckValue(misfit_ratio > 1, "ContinuityCheckOptions.misfit_ratio", std::to_string(misfit_ratio),
             "> 1");
  CheckValue(max_neighbour_difference_px > 0, "ContinuityCheckOptions.max_neighbour_difference_px",
             std::to_string(max_neighbour_difference_px), "> 0 px");
  CheckValue(max_second_difference_px > 0, "ContinuityCheckOptions.max_second_difference_px",
             std::to_string(max_second_difference_px), "> 0 px");
}

namespace {

constexpr int kReach = 3;  // The misfit's neighbourhood: 7 x 7 subsets.

bool Valid(const FrameResult& r, int i) { return r.status[i] == SubsetStatus::kConverged; }

std::vector<std::uint8_t> Misfits(const FrameResult& r, int cols, int rows, double ratio) {
  const int n = cols * rows;
  std::vector<std::uint8_t> flag(n, 0);
  if (!std::isfinite(ratio)) return flag;
  std::vector<double> near;
  for (int i = 0; i < n; ++i) {
    if (!Valid(r, i)) continue;
    near.clear();
    const int row = i / cols, col = i % cols;
    for (int dr = -kReach; dr <= kReach; ++dr) {
      for (int dc = -kReach; dc <= kReach; ++dc) {
        const int rr = row + dr, cc = col + dc;
        if ((dr == 0 && dc == 0) || rr < 0 || rr >= rows || cc < 0 || cc >= cols) continue;
        if (Valid(r, rr * cols + cc)) near.push_back(1.0 - r.zncc[rr * cols + cc]);
      }
    }
    if (near.size() < 6) continue;
    std::nth_element(near.begin(), near.begin() + near.size() / 2, near.end());
    const double median = near[near.size() / 2];
    flag[i] = (1.0 - r.zncc[i]) > ratio * std::max(median, 1e-6);
  }
  return flag;
}

std::vector<std::uint8_t> Discontinuities(const FrameResult& r, int cols, int rows, double limit_px,
                                          double jump_px) {
  const int n = cols * rows;
  std::vector<std::uint8_t> flag(n, 0);

  for (int i = 0; i < n; ++i) {
    if (!Valid(r, i)) continue;
    const int row = i / cols, col = i % cols;
    const int pairs[2][2][2] = {{{row, col - 1}, {row, col + 1}}, {{row - 1, col}, {row + 1, col}}};
    for (const auto& p : pairs) {
      const int ra = p[0][0], ca = p[0][1], rb = p[1][0], cb = p[1][1];
      const bool a_in = ra >= 0 && ca >= 0, b_in = rb < rows && cb < cols;
      const int a = a_in ? ra * cols + ca : i, b = b_in ? rb * cols + cb : i;
      for (const int j : {a, b}) {
        if (Valid(r, j) && std::hypot(r.u_px[i] - r.u_px[j], r.v_px[i] - r.v_px[j]) > jump_px)
          flag[i] = 1;
      }
      if (!a_in || !b_in || !Valid(r, a) || !Valid(r, b)) continue;
      const double du = r.u_px[i] - 0.5 * (r.u_px[a] + r.u_px[b]);
      const double dv = r.v_px[i] - 0.5 * (r.v_px[a] + r.v_px[b]);
      if (std::hypot(du, dv) > limit_px) flag[i] = 1;
    }
  }
  return flag;
}

}  // namespace

ContinuityFlags CheckContinuity(const FrameResult& result, int cols, int rows,
                                const ContinuityCheckOptions& options) {
  options.Check();
  CheckValue(cols > 0 && rows > 0 && static_cast<std::size_t>(cols) * rows == result.status.size(),
             "CheckContinuity grid", std::to_string(cols) + "x" + std::to_string(rows),
             "cols x rows == the frame's subsets");
  ContinuityFlags flags;
  flags.misfit = Misfits(result, cols, rows, options.misfit_ratio);
  flags.discontinuous = Discontinuities(result, cols, rows, options.max_second_difference_px,
                                        options.max_neighbour_difference_px);
  for (std::size_t i = 0; i < flags.misfit.size(); ++i)
    flags.flagged += flags.misfit[i] || flags.discontinuous[i];
  return flags;
}

void ApplyContinuityFlags(const ContinuityFlags& flags, FrameResult* result) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t i = 0; i < flags.misfit.size(); ++i) {
    if (!(flags.misfit[i] || flags.discontinuous[i])) continue;
    result->status[i] = SubsetStatus::kLowCorrelation;
    result->u_px[i] = result->v_px[i] = nan;
    if (i < result->sigma_px.size()) {
      result->sigma_u_px[i] = result->sigma_v_px[i] = result->sigma_px[i] =
          std::numeric_limits<float>::quiet_NaN();
    }
  }
}

}  // namespace impactdic
