// The inverse of the small symmetric positive definite matrices of IC-GN (the Hessian of every
// subset, the uncertainty's corrected Hessian) in plain loops: for n <= 12, Eigen's dynamic-size
// LLT and solve cost several times the arithmetic (measured on the 1920x1440 benchmark pair of
// docs/dic_speed.md: 9 ms of the reference stage's 56 ms on one thread), and the loops' results
// do not depend on where the buffers lie.
#include <cassert>
#include <cmath>

#include "icgn.h"

namespace impactdic::internal {
namespace {

// kN > 0: the size known when compiling (the loops unrolled; the same operations in the same
// order as with kN = 0), else n.
template <int kN>
bool CholeskyInverse(const double* a, int n_runtime, double* inv) {
  const int n = kN > 0 ? kN : n_runtime;
  // Only the lower triangles are read; sized for kN (not 12 x 12 zeroed for every 6 x 6 matrix).
  constexpr int kCells = kN > 0 ? kN * kN : 144;
  double l[kCells] = {}, m[kCells] = {};
  for (int j = 0; j < n; ++j) {  // A = L L^T.
    double d = a[j * n + j];
    for (int k = 0; k < j; ++k) d -= l[j * n + k] * l[j * n + k];
    if (!(a[j * n + j] > 0) || !(d > 1e-10 * a[j * n + j])) return false;
    const double ljj = std::sqrt(d);
    l[j * n + j] = ljj;
    for (int i = j + 1; i < n; ++i) {
      double v = a[i * n + j];
      for (int k = 0; k < j; ++k) v -= l[i * n + k] * l[j * n + k];
      l[i * n + j] = v / ljj;
    }
  }
  for (int j = 0; j < n; ++j) {  // m = L^-1 (lower triangular).
    m[j * n + j] = 1 / l[j * n + j];
    for (int i = j + 1; i < n; ++i) {
      double v = 0;
      for (int k = j; k < i; ++k) v -= l[i * n + k] * m[k * n + j];
      m[i * n + j] = v / l[i * n + i];
    }
  }
  for (int i = 0; i < n; ++i) {  // inv = m^T m.
    for (int j = 0; j <= i; ++j) {
      double v = 0;
      for (int k = i; k < n; ++k) v += m[k * n + i] * m[k * n + j];
      inv[i * n + j] = inv[j * n + i] = v;
    }
  }
  return true;
}

}  // namespace

bool InvertSpd(const double* a, int n, double* inv) {
  assert(n >= 1 && n <= 12);
  if (n == 6) return CholeskyInverse<6>(a, n, inv);    // Affine.
  if (n == 12) return CholeskyInverse<12>(a, n, inv);  // Quadratic.
  return CholeskyInverse<0>(a, n, inv);
}

}  // namespace impactdic::internal
