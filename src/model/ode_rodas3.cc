// The linearly implicit Rosenbrock method Rodas3 (Sandu, Verwer, Blom, Spee, Carmichael, Potra,
// Atmos. Environ. 31 (1997) 3459-3472, doi:10.1016/S1352-2310(97)83212-8; Hairer & Wanner,
// Solving ODEs II, sec. IV.7): 4 stages, order 3, stiffly accurate, embedded order 2, analytic
// Jacobian, cubic Hermite dense output.
#include <algorithm>
#include <cmath>
#include <memory>

#include "impactdic/model/ode.h"
#include "impactdic/model/ode_stepper.h"
#include "ode_norms.h"
#include "ode_steppers.h"

namespace impactdic::internal {
namespace {

// In the form
//   (I / (h gamma) - J) K_i = f(x + alpha_i h, y + sum_j a_ij K_j) + sum_j c_ij / h K_j
//                             + h gamma_i df/dx,
//   y_new = y + sum m_i K_i,   error estimate = K_4 (y_new minus the embedded solution).
// (We first tried ROS3P; its only order-2 embedded solution differs from y_new by a multiple of
// K_1 - K_2, which vanishes for linear autonomous problems, so its error estimate is blind there.)
constexpr double kRosGamma = 0.5;
constexpr double kRosA21 = 0.0, kRosA31 = 2.0, kRosA32 = 0.0, kRosA41 = 2.0, kRosA42 = 0.0,
                 kRosA43 = 1.0;
constexpr double kRosC21 = 4.0, kRosC31 = 1.0, kRosC32 = -1.0, kRosC41 = 1.0, kRosC42 = -1.0,
                 kRosC43 = -8.0 / 3.0;
constexpr double kRosM1 = 2.0, kRosM2 = 0.0, kRosM3 = 1.0, kRosM4 = 1.0;
constexpr double kRosAlpha2 = 0.0, kRosAlpha3 = 1.0, kRosAlpha4 = 1.0;
constexpr double kRosGamma1 = 0.5, kRosGamma2 = 1.5, kRosGamma3 = 0.0, kRosGamma4 = 0.0;

class Rodas3Stepper final : public OdeStepper {
 public:
  double Order() const override { return 3.0; }

  OdeTrial Attempt(OdeStepContext& c, double x, const Vec2& y, const Vec2& f, double hh,
                   double x_target) override {
    // The Jacobian at the step's start, reused by the retries of a rejected step.
    if (!have_jac_) {
      c.Jacobian(x, y, &jac_, &dfdx_);
      have_jac_ = true;
    }
    OdeTrial t;
    t.x1 = x_target;
    const double d = 1.0 / (hh * kRosGamma);
    const double a00 = d - jac_[0], a01 = -jac_[1], a10 = -jac_[2], a11 = d - jac_[3];
    const double det = a00 * a11 - a01 * a10;
    auto solve = [&](const Vec2& r) {
      return Vec2{(a11 * r[0] - a01 * r[1]) / det, (a00 * r[1] - a10 * r[0]) / det};
    };
    t.ok = std::isfinite(det) && det != 0.0;
    Vec2 K1{}, K2{}, K3{}, K4{}, r{}, yt{};
    if (t.ok) {
      for (int i = 0; i < 2; ++i) r[i] = f[i] + hh * kRosGamma1 * dfdx_[i];
      K1 = solve(r);
      for (int i = 0; i < 2; ++i) yt[i] = y[i] + kRosA21 * K1[i];
      const Vec2 F2 = c.F(x + kRosAlpha2 * hh, yt);
      for (int i = 0; i < 2; ++i) r[i] = F2[i] + kRosC21 / hh * K1[i] + hh * kRosGamma2 * dfdx_[i];
      K2 = solve(r);
      for (int i = 0; i < 2; ++i) yt[i] = y[i] + kRosA31 * K1[i] + kRosA32 * K2[i];
      t.ok = Finite(yt) && Finite(F2);
    }
    if (t.ok) {
      const Vec2 F3 = c.F(x + kRosAlpha3 * hh, yt);
      for (int i = 0; i < 2; ++i)
        r[i] = F3[i] + (kRosC31 * K1[i] + kRosC32 * K2[i]) / hh + hh * kRosGamma3 * dfdx_[i];
      K3 = solve(r);
      for (int i = 0; i < 2; ++i)
        yt[i] = y[i] + kRosA41 * K1[i] + kRosA42 * K2[i] + kRosA43 * K3[i];
      t.ok = Finite(yt) && Finite(F3);
    }
    if (t.ok) {
      const Vec2 F4 = c.F(x + kRosAlpha4 * hh, yt);
      for (int i = 0; i < 2; ++i)
        r[i] = F4[i] + (kRosC41 * K1[i] + kRosC42 * K2[i] + kRosC43 * K3[i]) / hh +
               hh * kRosGamma4 * dfdx_[i];
      K4 = solve(r);
      for (int i = 0; i < 2; ++i) {
        t.y1[i] = y[i] + kRosM1 * K1[i] + kRosM2 * K2[i] + kRosM3 * K3[i] + kRosM4 * K4[i];
        t.local_error[i] = K4[i];
      }
      t.domain_violation = Finite(t.y1) && !c.InDomain(x_target, t.y1);
      t.ok = !t.domain_violation && Finite(t.y1) && Finite(t.local_error) && Finite(F4);
      if (t.ok) {
        t.f1 = c.F(x_target, t.y1);
        t.ok = Finite(t.f1);
      }
    }
    if (t.ok) t.error = RmsNorm(t.local_error, y, t.y1, c.options().rtol, c.options().atol);
    return t;
  }

  double AfterRejection(const OdeOptions& /*options*/, double hs, double err,
                        bool /*last_rejected*/) override {
    return hs / std::min(5.0, std::pow(err, 1.0 / 3.0) / 0.9);
  }

  double AfterAcceptance(const OdeOptions& /*options*/, double hs, double err,
                         bool last_rejected) override {
    const double fac =
        std::max(1.0 / 6.0, std::min(5.0, std::pow(std::max(err, 1e-300), 1.0 / 3.0) / 0.9));
    double hnew = hs / fac;
    if (last_rejected) hnew = std::min(hnew, hs);
    have_jac_ = false;  // A new Jacobian at the next step's start.
    return hnew;
  }

 private:
  Mat2 jac_{};
  Vec2 dfdx_{};
  bool have_jac_ = false;
};

}  // namespace

std::unique_ptr<OdeStepper> MakeRodas3Stepper() { return std::make_unique<Rodas3Stepper>(); }

}  // namespace impactdic::internal
