// Internal: small vector helpers and error norms shared by the ODE methods.
#ifndef IMPACTDIC_SRC_MODEL_ODE_NORMS_H_
#define IMPACTDIC_SRC_MODEL_ODE_NORMS_H_

#include <algorithm>
#include <cmath>

#include "impactdic/model/ode.h"

namespace impactdic::internal {

inline Vec2 Axpy(const Vec2& y, double a, const Vec2& k) {
  return {y[0] + a * k[0], y[1] + a * k[1]};
}

inline bool Finite(const Vec2& v) { return std::isfinite(v[0]) && std::isfinite(v[1]); }

// Hairer's RMS norm of err scaled by atol + rtol max(|y0|, |y1|).
inline double RmsNorm(const Vec2& err, const Vec2& y0, const Vec2& y1, double rtol, double atol) {
  double sum = 0.0;
  for (int i = 0; i < 2; ++i) {
    const double sk = atol + rtol * std::max(std::abs(y0[i]), std::abs(y1[i]));
    sum += (err[i] / sk) * (err[i] / sk);
  }
  return std::sqrt(sum / 2.0);
}

// ode45's norm: max_i |err_i| / max(|y0_i|, |y1_i|, threshold), threshold = AbsTol / RelTol.
inline double Ode45Norm(const Vec2& err, const Vec2& y0, const Vec2& y1, double threshold) {
  double m = 0.0;
  for (int i = 0; i < 2; ++i) {
    const double sk = std::max({std::abs(y0[i]), std::abs(y1[i]), threshold});
    m = std::max(m, std::abs(err[i]) / sk);
  }
  return m;
}

}  // namespace impactdic::internal

#endif  // IMPACTDIC_SRC_MODEL_ODE_NORMS_H_
