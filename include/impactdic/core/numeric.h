// Small numerical building blocks shared by every module: the NaN constant ("not measured") and
// a golden-section search for the maximum of a unimodal function.
//
//   const double t_peak = GoldenSectionMaximize([&](double t) { return Deceleration(t); },
//                                               /*lo=*/0.0, /*hi=*/0.01, {.max_iterations = 200});
#ifndef IMPACTDIC_CORE_NUMERIC_H_
#define IMPACTDIC_CORE_NUMERIC_H_

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

namespace impactdic {

// "Not measured" / "not defined": every module's figures that could not be computed.
inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline constexpr float kNaNf = std::numeric_limits<float>::quiet_NaN();

struct GoldenSectionOptions {
  // Upper bound on the number of interval reductions (each shrinks the bracket by 0.618).
  int max_iterations = 200;
  // Stop once hi - lo <= relative_tolerance * max(1, |hi|); 0 runs all max_iterations.
  double relative_tolerance = 0.0;
};

// The abscissa of the maximum of f on [lo, hi] by golden-section search (Kiefer 1953, "Sequential
// minimax search for a maximum", Proc. AMS 4(3), 502-506): the bracket [lo, hi] shrinks by the
// inverse golden ratio r = (sqrt(5) - 1) / 2 per step, reusing one interior evaluation, until the
// options' tolerance or iteration limit; returns the midpoint of the final bracket. f must be
// unimodal on [lo, hi] for the result to be the global maximum there; ties keep the right part.
// Costs max_iterations + 2 evaluations of f at most.
template <typename F>
double GoldenSectionMaximize(F&& f, double lo, double hi,
                             const GoldenSectionOptions& options = {}) {
  assert(lo <= hi);
  const double r = (std::sqrt(5.0) - 1.0) / 2.0;
  double a = lo, b = hi;
  double c = b - r * (b - a), d = a + r * (b - a);
  double fc = f(c), fd = f(d);
  for (int it = 0; it < options.max_iterations &&
                   b - a > options.relative_tolerance * std::max(1.0, std::abs(b));
       ++it) {
    if (fc > fd) {
      b = d;
      d = c;
      fd = fc;
      c = b - r * (b - a);
      fc = f(c);
    } else {
      a = c;
      c = d;
      fc = fd;
      d = a + r * (b - a);
      fd = f(d);
    }
  }
  return 0.5 * (a + b);
}

// The distinct values of v, sorted; values closer than tol to the previous kept one are the same
// (grid coordinates of subset centres).
inline std::vector<double> UniqueSorted(std::vector<double> v, double tol) {
  std::sort(v.begin(), v.end());
  std::vector<double> out;
  for (double x : v)
    if (out.empty() || x - out.back() > tol) out.push_back(x);
  return out;
}

// The median difference of consecutive entries of a sorted vector (a grid step); NaN for fewer
// than two entries.
inline double MedianStep(const std::vector<double>& sorted) {
  if (sorted.size() < 2) return kNaN;
  std::vector<double> d;
  for (std::size_t i = 1; i < sorted.size(); ++i) d.push_back(sorted[i] - sorted[i - 1]);
  std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
  return d[d.size() / 2];
}

// The length of a displacement difference (du, dv) in pixels: sqrt(du^2 + dv^2). Such values
// neither overflow nor underflow, so std::hypot's guard (several times the cost; the post-checks
// take ~10 of these per subset) is not needed. Differs from std::hypot in the last bit at most.
inline double PixelDistance(double du, double dv) { return std::sqrt(du * du + dv * dv); }

}  // namespace impactdic

#endif  // IMPACTDIC_CORE_NUMERIC_H_
