// Our own adaptive integrators for small (2-component) ODE systems y' = f(x, y):
//  - Dormand-Prince 5(4) with local extrapolation, PI step control and Hairer's 4th-order dense
//    output and stiffness test (J. R. Dormand, P. J. Prince, J. Comput. Appl. Math. 6 (1980) 19-26,
//    doi:10.1016/0771-050X(80)90013-3; E. Hairer, S. P. Norsett, G. Wanner, Solving ODEs I,
//    2nd ed., Springer 1993, sec. II.5 and IV.2 (stiffness detection),
//    doi:10.1007/978-3-540-78862-1);
//  - the same pair under MATLAB ode45's documented rules (max-norm of |err| / max(|y|, |ynew|,
//    AbsTol/RelTol), the initial step guess, the 0.8 / 1.25 step factors: L. F. Shampine,
//    M. W. Reichelt, "The MATLAB ODE Suite", SIAM J. Sci. Comput. 18 (1997) 1-22,
//    doi:10.1137/S1064827594276424);
//  - the linearly implicit Rosenbrock method Rodas3 (4 stages, order 3, stiffly accurate, embedded
//    order 2) with the analytic Jacobian (A. Sandu et al., Atmos. Environ. 31 (1997) 3459-3472,
//    doi:10.1016/S1352-2310(97)83212-8; Hairer & Wanner, Solving ODEs II, sec. IV.7), cubic
//    Hermite dense output;
//  - `auto`: Dormand-Prince with the stiffness test; when it fires the rest of the interval is
//    integrated by Rodas3.
// The integration can run backwards (x_end < x0), clips steps at `landmarks` so a step ends exactly
// there, honours a position-dependent maximum step (used to never step over a steep sigmoid), and
// rejects trial steps that leave a domain (e.g. v > 0).
//
//   OdeSystem sys;
//   sys.rhs = [](double x, const Vec2& y) { return Vec2{y[1], -y[0]}; };
//   OdeOptions opts;  opts.rtol = 1e-8;
//   std::vector<OdeStep> steps;
//   OdeResult r = IntegrateOde(sys, 0.0, {1.0, 0.0}, 10.0, opts, &steps);
#ifndef IMPACTDIC_MODEL_ODE_H_
#define IMPACTDIC_MODEL_ODE_H_

#include <array>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "impactdic/core/numeric.h"

namespace impactdic {

using Vec2 = std::array<double, 2>;
// Row-major 2x2 matrix: m[0] = d f0/d y0, m[1] = d f0/d y1, m[2] = d f1/d y0, m[3] = d f1/d y1.
using Mat2 = std::array<double, 4>;

struct OdeSystem {
  std::function<Vec2(double x, const Vec2& y)> rhs;
  // Analytic Jacobian df/dy and df/dx (needed by the Rosenbrock method only).
  std::function<void(double x, const Vec2& y, Mat2* dfdy, Vec2* dfdx)> jacobian;
  // Optional: false for states outside the domain of f (the trial step is rejected).
  std::function<bool(double x, const Vec2& y)> in_domain;
};

struct OdeOptions {
  // A registered method (ode_stepper.h): "dopri5" (Dormand-Prince 5(4), Hairer's controller and
  // RMS error norm), "ode45" (the same pair with MATLAB ode45's norm, initial step and step
  // factors), "rodas3" (Rosenbrock Rodas3, analytic Jacobian) or "auto" (dopri5 with stiffness
  // detection, switching to rodas3 when it fires).
  std::string method = "dopri5";
  double rtol = 1e-6;  // Relative tolerance, > 0.
  double atol = 1e-9;  // Absolute tolerance, > 0 (same for both components).
  // Initial step magnitude; <= 0 or NaN: automatic (Hairer's or ode45's rule).
  double initial_step = 0.0;
  double max_step = std::numeric_limits<double>::infinity();  // Magnitude.
  // Optional position-dependent step limit (magnitude) for a step starting at x.
  std::function<double(double x)> max_step_at;
  // Positions a step must end on exactly (e.g. a window start, t1 of the plateau).
  std::vector<double> landmarks;
  long max_steps = 2000000;  // Accepted + rejected steps.
  // Called after every accepted step; returning true ends the integration there.
  std::function<bool(double x, const Vec2& y, const Vec2& f)> stop_after_step;
  // A trial state outside the domain is rejected and retried with a quarter of the step. If
  // stop_on_domain_exit, the integration ends at the last accepted point (status kLeftDomain)
  // when the slope at the step's start carries the solution out too (y + h f outside), or
  // after domain_exit_retries retries that left the domain since the last accepted step.
  bool stop_on_domain_exit = false;
  int domain_exit_retries = 3;
};

enum class OdeStatus {
  kReachedEnd,
  kStoppedByCallback,
  kLeftDomain,
  kStepSizeUnderflow,
  kMaxSteps,
  kNonFiniteRhs,  // f(x0, y0) is not finite: no step can be taken (e.g. overflowing inputs).
};
const char* ToString(OdeStatus status);

// One accepted step, enough to evaluate the dense output anywhere inside it.
struct OdeStep {
  double x0 = 0.0, h = 0.0;  // The step covers [x0, x0 + h] (h < 0 backwards).
  Vec2 y0{}, y1{}, f0{}, f1{};
  bool dopri_dense = false;     // true: 4th-order Dormand-Prince dense output in `rcont`.
  std::array<Vec2, 5> rcont{};  // Hairer's continuous-extension coefficients.
  Vec2 local_error{};           // The embedded local error estimate (absolute, per component).
  // y at x0 + theta h, theta in [0, 1].
  Vec2 Interpolate(double theta) const;
};

struct OdeResult {
  OdeStatus status = OdeStatus::kReachedEnd;
  double x = 0.0;  // Where the integration ended.
  Vec2 y{};
  Vec2 f{};  // f(x, y).
  long steps = 0, rejected_steps = 0, rhs_evals = 0, jacobian_evals = 0;
  bool stiffness_detected = false;  // "auto": switched to Rodas3.
  double stiffness_x = kNaN;        // Where it switched.
  double max_h_lambda = 0.0;        // Largest stiffness indicator h|lambda| seen by the DOPRI test.
};

// Integrates from (x0, y0) towards x_end. Accepted steps are appended to `steps` if not null.
OdeResult IntegrateOde(const OdeSystem& system, double x0, const Vec2& y0, double x_end,
                       const OdeOptions& options, std::vector<OdeStep>* steps = nullptr);

}  // namespace impactdic

#endif  // IMPACTDIC_MODEL_ODE_H_
