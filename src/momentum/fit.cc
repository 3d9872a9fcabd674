#include "impactdic/momentum/fit.h"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "impactdic/core/error.h"
#include "impactdic/core/numeric.h"
#include "impactdic/core/timer.h"
#include "impactdic/model/impact_model.h"

namespace impactdic {
namespace {

// Continued fraction of I_x(a, b) (valid for x < (a + 1) / (a + b + 2)).
double BetaContinuedFraction(double a, double b, double x) {
  const double tiny = 1e-300;
  double c = 1, d = 1 - (a + b) * x / (a + 1);
  if (std::abs(d) < tiny) d = tiny;
  d = 1 / d;
  double f = d;
  for (int m = 1; m <= 1000; ++m) {
    const double md = m;
    // Even term.
    double num = md * (b - md) * x / ((a + 2 * md - 1) * (a + 2 * md));
    d = 1 + num * d;
    if (std::abs(d) < tiny) d = tiny;
    c = 1 + num / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1 / d;
    f *= d * c;
    // Odd term.
    num = -(a + md) * (a + b + md) * x / ((a + 2 * md) * (a + 2 * md + 1));
    d = 1 + num * d;
    if (std::abs(d) < tiny) d = tiny;
    c = 1 + num / c;
    if (std::abs(c) < tiny) c = tiny;
    d = 1 / d;
    const double delta = d * c;
    f *= delta;
    if (std::abs(delta - 1) < 1e-15) break;
  }
  return f;
}

}  // namespace

double RegularizedIncompleteBeta(double a, double b, double x) {
  if (x <= 0) return 0;
  if (x >= 1) return 1;
  const double log_front =
      std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * std::log(x) + b * std::log1p(-x);
  if (x < (a + 1) / (a + b + 2)) return std::exp(log_front) * BetaContinuedFraction(a, b, x) / a;
  return 1 - std::exp(log_front) * BetaContinuedFraction(b, a, 1 - x) / b;
}

double StudentTCdf(double t, double dof) {
  const double tail = 0.5 * RegularizedIncompleteBeta(0.5 * dof, 0.5, dof / (dof + t * t));
  return t >= 0 ? 1 - tail : tail;
}

double StudentTQuantile(double p, double dof) {
  CheckValue(p > 0 && p < 1, "StudentTQuantile p", fmt::format("{}", p), "in (0, 1)");
  CheckValue(dof > 0, "StudentTQuantile dof", fmt::format("{}", dof), "> 0");
  if (p < 0.5) return -StudentTQuantile(1 - p, dof);
  double lo = 0, hi = 1;
  while (StudentTCdf(hi, dof) < p) hi *= 2;
  for (int i = 0; i < 200 && hi - lo > 1e-14 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (StudentTCdf(mid, dof) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

void SigmoidFitOptions::Check() const {
  CheckValue(max_iterations >= 1, "sigmoid.max_iterations", fmt::format("{}", max_iterations),
             ">= 1");
  CheckValue(step_tolerance > 0, "sigmoid.step_tolerance", fmt::format("{}", step_tolerance),
             "> 0");
  CheckValue(kConfidenceRange.Contains(confidence), "sigmoid.confidence",
             fmt::format("{}", confidence), "in (0, 1)");
}

std::string SigmoidFit::BriefReport() const {
  return fmt::format(
      "M = {:.4g} kg [{:.4g}, {:.4g}], b = {:.4g} 1/s [{:.4g}, {:.4g}], T = {:.4g} s [{:.4g}, "
      "{:.4g}], rms {:.3g} kg, {} points, {} iterations{}",
      M_kg, ci_M_kg[0], ci_M_kg[1], b_per_s, ci_b_per_s[0], ci_b_per_s[1], T_s, ci_T_s[0],
      ci_T_s[1], rms_residual_kg, points, iterations, converged ? "" : " (not converged)");
}

SigmoidFit FitSigmoid(const std::vector<double>& t_s, const std::vector<double>& m_kg,
                      const SigmoidFitOptions& options, const SigmoidFit* initial) {
  WallTimer timer;
  options.Check();
  CheckValue(t_s.size() == m_kg.size(), "FitSigmoid",
             fmt::format("{} times, {} values", t_s.size(), m_kg.size()), "equal lengths");
  std::vector<double> t, y;
  for (std::size_t i = 0; i < t_s.size(); ++i)
    if (std::isfinite(t_s[i]) && std::isfinite(m_kg[i])) {
      t.push_back(t_s[i]);
      y.push_back(m_kg[i]);
    }
  const std::size_t n = t.size();
  if (n < 4) {
    throw Error(ErrorKind::kNumerical, "sigmoid fit", fmt::format("{} finite points", n),
                "at least 4 points for 3 parameters");
  }
  // Initial guess.
  Eigen::Vector3d p;
  if (initial && initial->M_kg > 0) {
    p << initial->M_kg, initial->b_per_s, initial->T_s;
  } else {
    const double m0 = *std::max_element(y.begin(), y.end());
    auto crossing = [&](double level) {
      for (std::size_t i = 1; i < n; ++i)
        if (y[i - 1] < level && y[i] >= level)
          return t[i - 1] + (level - y[i - 1]) / (y[i] - y[i - 1]) * (t[i] - t[i - 1]);
      return kNaN;
    };
    const double span = t.back() - t.front();
    double T0 = crossing(0.5 * m0);
    if (!std::isfinite(T0)) T0 = t.front() + 0.5 * span;
    const double t12 = crossing(0.12 * m0), t88 = crossing(0.88 * m0);
    double b0 =
        (std::isfinite(t12) && std::isfinite(t88) && t88 > t12) ? 4 / (t88 - t12) : 8 / span;
    p << m0, b0, T0;
  }
  auto residuals = [&](const Eigen::Vector3d& q, Eigen::VectorXd* r, Eigen::MatrixXd* jac) {
    r->resize(static_cast<Eigen::Index>(n));
    if (jac) jac->resize(static_cast<Eigen::Index>(n), 3);
    for (std::size_t i = 0; i < n; ++i) {
      const auto ii = static_cast<Eigen::Index>(i);
      const double s = AddedMassAt(1.0, q[1], q[2], t[i]).m_add_kg;  // Eq. 5 with M = 1
      (*r)[ii] = y[i] - q[0] * s;
      if (jac) {  // Jacobian of the model (the residual's is its negative).
        const double ds = s * (1 - s);
        (*jac)(ii, 0) = s;
        (*jac)(ii, 1) = q[0] * ds * (t[i] - q[2]);
        (*jac)(ii, 2) = -q[0] * ds * q[1];
      }
    }
    return r->squaredNorm();
  };
  SigmoidFit fit;
  Eigen::VectorXd r, r_new;
  Eigen::MatrixXd jac;
  double cost = residuals(p, &r, &jac);
  double lambda = 1e-3;
  fit.message = "maximum iterations reached";
  int it = 0;
  for (; it < options.max_iterations; ++it) {
    const Eigen::Matrix3d a = jac.transpose() * jac;
    const Eigen::Vector3d g = jac.transpose() * r;
    bool accepted = false;
    while (lambda < 1e20) {
      Eigen::Matrix3d damped = a;
      for (int k = 0; k < 3; ++k) damped(k, k) += lambda * std::max(a(k, k), 1e-300);
      const Eigen::Vector3d step = damped.ldlt().solve(g);
      const Eigen::Vector3d q = p + step;
      const double c_new = residuals(q, &r_new, nullptr);
      if (std::isfinite(c_new) && c_new <= cost) {
        const bool small =
            (step.array().abs() <= options.step_tolerance * (p.array().abs() + 1e-300)).all();
        p = q;
        cost = residuals(p, &r, &jac);
        lambda = std::max(lambda / 10, 1e-12);
        accepted = true;
        if (small) {
          fit.converged = true;
          fit.message = "parameter steps below tolerance";
        }
        break;
      }
      lambda *= 10;
    }
    if (!accepted) {
      // No decrease possible at any damping: a minimum to rounding precision.
      fit.converged = true;
      fit.message = "no further decrease (minimum to rounding)";
      break;
    }
    if (fit.converged) {
      ++it;
      break;
    }
  }
  fit.iterations = it;
  fit.M_kg = p[0];
  fit.b_per_s = p[1];
  fit.T_s = p[2];
  fit.points = n;
  fit.rms_residual_kg = std::sqrt(cost / static_cast<double>(n));
  const Eigen::Matrix3d a = jac.transpose() * jac;
  const double s2 = cost / static_cast<double>(n - 3);
  const Eigen::Matrix3d cov = s2 * a.inverse();
  const double tq = StudentTQuantile(0.5 * (1 + options.confidence), static_cast<double>(n - 3));
  fit.se_M_kg = std::sqrt(cov(0, 0));
  fit.se_b_per_s = std::sqrt(cov(1, 1));
  fit.se_T_s = std::sqrt(cov(2, 2));
  fit.ci_M_kg = {fit.M_kg - tq * fit.se_M_kg, fit.M_kg + tq * fit.se_M_kg};
  fit.ci_b_per_s = {fit.b_per_s - tq * fit.se_b_per_s, fit.b_per_s + tq * fit.se_b_per_s};
  fit.ci_T_s = {fit.T_s - tq * fit.se_T_s, fit.T_s + tq * fit.se_T_s};
  if (!std::isfinite(fit.se_M_kg + fit.se_b_per_s + fit.se_T_s)) {
    fit.converged = false;
    fit.message += "; singular normal matrix (parameters not identifiable from these data)";
  }
  fit.seconds = timer.ElapsedSeconds();
  return fit;
}

std::string PowerLawFit::BriefReport() const {
  return fmt::format(
      "m_add,max = {:.4g} m_p^{:.3f} v^{:.3f} A^{:.3f} (n = {}, R^2 = {:.4f}); {:.0f} % CI: c "
      "[{:.4g}, {:.4g}], a [{:.3f}, {:.3f}], b [{:.3f}, {:.3f}], g [{:.3f}, {:.3f}]",
      c, a, b, g, n, r_squared, 100 * confidence, ci_c[0], ci_c[1], ci_a[0], ci_a[1], ci_b[0],
      ci_b[1], ci_g[0], ci_g[1]);
}

PowerLawFit FitPowerLaw(const std::vector<PowerLawSample>& samples, double confidence) {
  CheckValue(kConfidenceRange.Contains(confidence), "confidence", fmt::format("{}", confidence),
             "in (0, 1)");
  const std::size_t n = samples.size();
  CheckValue(n >= 5, "power-law regression", fmt::format("{} tests", n),
             "at least 5 tests for 4 coefficients");
  Eigen::MatrixXd x(static_cast<Eigen::Index>(n), 4);
  Eigen::VectorXd y(static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) {
    const auto& s = samples[i];
    const bool ok = s.mass_kg > 0 && s.velocity_m_s > 0 && s.area_m2 > 0 && s.added_mass_kg > 0 &&
                    std::isfinite(s.mass_kg + s.velocity_m_s + s.area_m2 + s.added_mass_kg);
    CheckValue(ok, fmt::format("power-law test {}", i),
               fmt::format("m_p = {}, v = {}, A = {}, m_add = {}", s.mass_kg, s.velocity_m_s,
                           s.area_m2, s.added_mass_kg),
               "positive finite values (logarithms are taken)");
    const auto ii = static_cast<Eigen::Index>(i);
    x(ii, 0) = 1;
    x(ii, 1) = std::log(s.mass_kg);
    x(ii, 2) = std::log(s.velocity_m_s);
    x(ii, 3) = std::log(s.area_m2);
    y[ii] = std::log(s.added_mass_kg);
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(x);
  if (qr.rank() < 4) {
    throw Error(ErrorKind::kNumerical, "power-law regression",
                fmt::format("rank {} design", qr.rank()),
                "tests that vary mass, velocity and area independently");
  }
  const Eigen::Vector4d beta = qr.solve(y);
  const Eigen::VectorXd res = y - x * beta;
  PowerLawFit f;
  f.n = n;
  f.dof = n - 4;
  f.confidence = confidence;
  const double sse = res.squaredNorm();
  const double mean = y.mean();
  const double sst = (y.array() - mean).square().sum();
  f.r_squared = sst > 0 ? 1 - sse / sst : 1;
  const double s2 = f.dof > 0 ? sse / static_cast<double>(f.dof) : 0;
  f.residual_sd = std::sqrt(s2);
  const Eigen::Matrix4d cov = s2 * (x.transpose() * x).inverse();
  f.c = std::exp(beta[0]);
  f.a = beta[1];
  f.b = beta[2];
  f.g = beta[3];
  f.se_log_c = std::sqrt(cov(0, 0));
  f.se_a = std::sqrt(cov(1, 1));
  f.se_b = std::sqrt(cov(2, 2));
  f.se_g = std::sqrt(cov(3, 3));
  const double tq = f.dof > 0 ? StudentTQuantile(0.5 * (1 + confidence), static_cast<double>(f.dof))
                              : std::numeric_limits<double>::infinity();
  f.ci_c = {std::exp(beta[0] - tq * f.se_log_c), std::exp(beta[0] + tq * f.se_log_c)};
  f.ci_a = {f.a - tq * f.se_a, f.a + tq * f.se_a};
  f.ci_b = {f.b - tq * f.se_b, f.b + tq * f.se_b};
  f.ci_g = {f.g - tq * f.se_g, f.g + tq * f.se_g};
  return f;
}

}  // namespace impactdic
