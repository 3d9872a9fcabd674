// The dic module is compiled for the build machine (-march=native); with AVX-512, GCC 12 reports
// false "may be used uninitialized" warnings inside Eigen's vectorised kernels (its intrinsics'
// __Y placeholders; "is used uninitialized" at -O1, the asan preset), so this file holds only the
// Eigen code and silences those two warnings.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wuninitialized"
#endif

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <cassert>

#include "icgn.h"

namespace impactdic::internal {

bool InvertSpd(const double* a, int n, double* inv) {
  assert(n >= 1 && n <= 12);
  using Matrix =
      Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor, /*MaxRows=*/12,
                    /*MaxCols=*/12>;
  const Eigen::Map<const Matrix> matrix(a, n, n);
  const Eigen::LLT<Matrix> llt(matrix);
  if (llt.info() != Eigen::Success) return false;
  const Matrix l = llt.matrixL();
  for (int j = 0; j < n; ++j)
    if (!(matrix(j, j) > 0) || !(l(j, j) * l(j, j) > 1e-10 * matrix(j, j))) return false;
  // Solved in a local matrix, then copied: Eigen's vectorised kernels take paths that depend on
  // the alignment of their operands, and `inv` may have any alignment, so solving in place there
  // would make the rounding (and the correlation results) depend on where the caller's buffer
  // happens to lie. The local matrices have fixed, aligned storage.
  const Matrix inverse = llt.solve(Matrix::Identity(n, n));
  Eigen::Map<Matrix>(inv, n, n) = inverse;
  return true;
}

}  // namespace impactdic::internal
