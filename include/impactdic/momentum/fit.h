// Least-squares fits of the momentum analysis: the sigmoid of Eq. 5 by Levenberg-Marquardt and the
// power law of Eq. 4 by log-linear least squares, both with standard errors and t-distribution
// confidence intervals.
//
//   SigmoidFit s = FitSigmoid(t_s, m_add_kg, SigmoidFitOptions{});   // M, b, T +- 95 % CI
//   PowerLawFit p = FitPowerLaw(samples);   // m_add,max = c m_p^a v^b A^g, CIs, R^2
#ifndef IMPACTDIC_MOMENTUM_FIT_H_
#define IMPACTDIC_MOMENTUM_FIT_H_

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "impactdic/core/range.h"

namespace impactdic {

// Regularised incomplete beta I_x(a, b), continued fraction by the modified Lentz method
// (Lentz 1976, doi:10.1364/AO.15.000668; Thompson & Barnett 1986,
// doi:10.1016/0021-9991(86)90046-X).
double RegularizedIncompleteBeta(double a, double b, double x);
// Student-t CDF and quantile with `dof` > 0 degrees of freedom; p in (0, 1).
double StudentTCdf(double t, double dof);
double StudentTQuantile(double p, double dof);

// The levels of the reported intervals (SigmoidFitOptions::confidence).
inline constexpr ValueRange kConfidenceRange{0, 1, "", /*min_open=*/true, /*max_open=*/true};

struct SigmoidFitOptions {
  int max_iterations = 200;       // Levenberg-Marquardt iterations, >= 1.
  double step_tolerance = 1e-10;  // Stop when every relative parameter step is below this, > 0.
  double confidence = 0.95;       // Level of the reported intervals, kConfidenceRange.
  void Check() const;
};

struct SigmoidFit {
  double M_kg = 0, b_per_s = 0, T_s = 0;
  double se_M_kg = 0, se_b_per_s = 0, se_T_s = 0;           // Standard errors.
  std::array<double, 2> ci_M_kg{}, ci_b_per_s{}, ci_T_s{};  // Confidence intervals.
  double rms_residual_kg = 0;
  std::size_t points = 0;
  int iterations = 0;
  bool converged = false;
  double seconds = 0;
  std::string message;  // Why it stopped.
  std::string BriefReport() const;
};

// Levenberg-Marquardt (Levenberg 1944; Marquardt 1963, doi:10.1137/0111030) with Marquardt's
// diagonal scaling, on Eigen. Residuals r_i = y_i - Sigmoid(t_i); analytic Jacobian. Start: M from
// the data's maximum, T at the half-height crossing, b from the 12 %-88 % rise time (or given by
// `initial` if its M > 0). Covariance s^2 (J^T J)^-1 with s^2 = SSE / (n - 3); intervals
// estimate +- t_{(1+conf)/2, n-3} se. Needs n >= 4 finite points.
SigmoidFit FitSigmoid(const std::vector<double>& t_s, const std::vector<double>& m_kg,
                      const SigmoidFitOptions& options, const SigmoidFit* initial = nullptr);

// One impact test for the Eq. 4 regression.
struct PowerLawSample {
  double mass_kg = 0;        // m_p > 0
  double velocity_m_s = 0;   // v0 > 0
  double area_m2 = 0;        // A > 0
  double added_mass_kg = 0;  // m_add,max > 0
};

struct PowerLawFit {
  // m_add,max = c m_p^a v^b A^g.
  double c = 0, a = 0, b = 0, g = 0;
  double se_log_c = 0, se_a = 0, se_b = 0, se_g = 0;
  std::array<double, 2> ci_c{}, ci_a{}, ci_b{}, ci_g{};  // ci_c = exp(ln c +- t se).
  double r_squared = 0;                                  // Of the log-linear fit.
  double residual_sd = 0;                                // Of ln m_add.
  std::size_t n = 0, dof = 0;
  double confidence = 0.95;
  std::string BriefReport() const;
};

// Ordinary least squares of ln m = ln c + a ln m_p + b ln v + g ln A (needs n >= 5 tests with
// non-degenerate spread in each variable).
PowerLawFit FitPowerLaw(const std::vector<PowerLawSample>& samples, double confidence = 0.95);

}  // namespace impactdic

#endif  // IMPACTDIC_MOMENTUM_FIT_H_
