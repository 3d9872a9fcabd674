// The IC-GN Hessian inversion (src/dic/spd_inverse.cc, internal to the dic module).
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "../../src/dic/icgn.h"

namespace impactdic::internal {
namespace {

// A = B^T B + I for a fixed B: symmetric positive definite, condition number ~1e2.
std::vector<double> SpdMatrix(int n) {
  std::vector<double> a(static_cast<std::size_t>(n) * n, 0.0);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      double s = i == j ? 1.0 : 0.0;
      for (int k = 0; k < n; ++k) s += std::sin(1.0 + k * n + i) * std::sin(1.0 + k * n + j);
      a[i * n + j] = s;
    }
  return a;
}

TEST(InvertSpd, ProductWithTheInverseIsTheIdentity) {
  for (int n : {1, 6, 12}) {
    const std::vector<double> a = SpdMatrix(n);
    std::vector<double> inv(a.size(), 0.0);
    ASSERT_TRUE(InvertSpd(a.data(), n, inv.data())) << n;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        double s = 0;
        for (int k = 0; k < n; ++k) s += a[i * n + k] * inv[k * n + j];
        EXPECT_NEAR(s, i == j ? 1.0 : 0.0, 1e-12) << n << " " << i << " " << j;
      }
  }
}

TEST(InvertSpd, RefusesSingularAndNearlySingularMatrices) {
  const int n = 6;
  std::vector<double> inv(n * n);
  // Rank one: v v^T.
  std::vector<double> a(n * n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) a[i * n + j] = (i + 1.0) * (j + 1.0);
  EXPECT_FALSE(InvertSpd(a.data(), n, inv.data()));
  // Positive definite, but the last pivot is 1e-12 of its diagonal entry: below the 1e-10
  // threshold (the subset's data cannot determine that warp parameter).
  a = SpdMatrix(n);
  std::vector<double> b = a;
  // Make row/column 5 = row/column 0 + 1e-6 e_5 (pivot ~1e-12 a_55).
  for (int i = 0; i < n; ++i) b[i * n + 5] = b[5 * n + i] = a[i * n + 0];
  b[5 * n + 5] = a[0] + 1e-12 * a[0];
  EXPECT_FALSE(InvertSpd(b.data(), n, inv.data()));
  // Not positive: a zero diagonal entry.
  a = SpdMatrix(n);
  a[2 * n + 2] = 0.0;
  EXPECT_FALSE(InvertSpd(a.data(), n, inv.data()));
}

}  // namespace
}  // namespace impactdic::internal
