#include "impactdic/model/ode.h"

#include <algorithm>
#include <cmath>

namespace impactdic {
namespace {

// Dormand-Prince 5(4) tableau (Dormand & Prince 1980; Hairer, Norsett, Wanner, Table II.5.2).
constexpr double kC2 = 1.0 / 5, kC3 = 3.0 / 10, kC4 = 4.0 / 5, kC5 = 8.0 / 9;
constexpr double kA21 = 1.0 / 5;
constexpr double kA31 = 3.0 / 40, kA32 = 9.0 / 40;
constexpr double kA41 = 44.0 / 45, kA42 = -56.0 / 15, kA43 = 32.0 / 9;
constexpr double kA51 = 19372.0 / 6561, kA52 = -25360.0 / 2187, kA53 = 64448.0 / 6561,
                 kA54 = -212.0 / 729;
constexpr double kA61 = 9017.0 / 3168, kA62 = -355.0 / 33, kA63 = 46732.0 / 5247, kA64 = 49.0 / 176,
                 kA65 = -5103.0 / 18656;
constexpr double kA71 = 35.0 / 384, kA73 = 500.0 / 1113, kA74 = 125.0 / 192, kA75 = -2187.0 / 6784,
                 kA76 = 11.0 / 84;
// Difference between the 5th- and the 4th-order weights (the local error estimate).
constexpr double kE1 = 71.0 / 57600, kE3 = -71.0 / 16695, kE4 = 71.0 / 1920,
                 kE5 = -17253.0 / 339200, kE6 = 22.0 / 525, kE7 = -1.0 / 40;
// Dense output of order 4 (Hairer, Norsett, Wanner, sec. II.6; the coefficients of DOPRI5's
// CONTD5).
constexpr double kD1 = -12715105075.0 / 11282082432, kD3 = 87487479700.0 / 32700410799,
                 kD4 = -10690763975.0 / 1880347072, kD5 = 701980252875.0 / 199316789632,
                 kD6 = -1453857185.0 / 822651844, kD7 = 69997945.0 / 29380423;

// Rodas3 (Sandu, Verwer, Blom, Spee, Carmichael, Potra, Atmos. Environ. 31 (1997) 3459-3472,
// doi:10.1016/S1352-2310(97)83212-8): 4 stages, order 3, stiffly accurate, embedded order 2, in
// the form
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

Vec2 Axpy(const Vec2& y, double a, const Vec2& k) { return {y[0] + a * k[0], y[1] + a * k[1]}; }

bool Finite(const Vec2& v) { return std::isfinite(v[0]) && std::isfinite(v[1]); }

// Hairer's RMS norm of err scaled by atol + rtol max(|y0|, |y1|).
double RmsNorm(const Vec2& err, const Vec2& y0, const Vec2& y1, double rtol, double atol) {
  double sum = 0.0;
  for (int i = 0; i < 2; ++i) {
    const double sk = atol + rtol * std::max(std::abs(y0[i]), std::abs(y1[i]));
    sum += (err[i] / sk) * (err[i] / sk);
  }
  return std::sqrt(sum / 2.0);
}

// ode45's norm: max_i |err_i| / max(|y0_i|, |y1_i|, threshold), threshold = AbsTol / RelTol.
double Ode45Norm(const Vec2& err, const Vec2& y0, const Vec2& y1, double threshold) {
  double m = 0.0;
  for (int i = 0; i < 2; ++i) {
    const double sk = std::max({std::abs(y0[i]), std::abs(y1[i]), threshold});
    m = std::max(m, std::abs(err[i]) / sk);
  }
  return m;
}

class Integrator {
 public:
  Integrator(const OdeSystem& system, const OdeOptions& options, std::vector<OdeStep>* steps)
      : sys_(system), opt_(options), steps_(steps) {}

  OdeResult Run(double x0, const Vec2& y0, double x_end);

 private:
  Vec2 F(double x, const Vec2& y) {
    ++result_.rhs_evals;
    return sys_.rhs(x, y);
  }
  bool InDomain(double x, const Vec2& y) const {
    return Finite(y) && (!sys_.in_domain || sys_.in_domain(x, y));
  }
  double InitialStepHairer(double x, const Vec2& y, const Vec2& f, double dir, double order);
  double InitialStepOde45(double x, const Vec2& y, const Vec2& f, double x_end);
  // Largest allowed magnitude of a step from x (max_step, max_step_at).
  double StepLimit(double x) const {
    double limit = opt_.max_step;
    if (opt_.max_step_at) limit = std::min(limit, opt_.max_step_at(x));
    return limit;
  }

  const OdeSystem& sys_;
  const OdeOptions& opt_;
  std::vector<OdeStep>* steps_;
  OdeResult result_;
};

double Integrator::InitialStepHairer(double x, const Vec2& y, const Vec2& f, double dir,
                                     double order) {
  // Hairer, Norsett, Wanner, sec. II.4 ("Starting step size").
  const Vec2 zero{0.0, 0.0};
  const double dnf = RmsNorm(f, y, zero, opt_.rtol, opt_.atol);
  const double dny = RmsNorm(y, y, zero, opt_.rtol, opt_.atol);
  double h = (dnf <= 1e-5 || dny <= 1e-5) ? 1e-6 : 0.01 * dny / dnf;
  h = std::min(h, StepLimit(x));
  const Vec2 y1 = Axpy(y, dir * h, f);
  const Vec2 f1 = F(x + dir * h, y1);
  const Vec2 df{f1[0] - f[0], f1[1] - f[1]};
  double der2 = Finite(f1) ? RmsNorm(df, y, zero, opt_.rtol, opt_.atol) / h
                           : std::numeric_limits<double>::infinity();
  const double der12 = std::max(std::abs(der2), dnf);
  const double h1 = der12 <= 1e-15 ? std::max(1e-6, h * 1e-3) : std::pow(0.01 / der12, 1.0 / order);
  return std::min({100.0 * h, h1, StepLimit(x)});
}

double Integrator::InitialStepOde45(double x, const Vec2& y, const Vec2& f, double x_end) {
  // Shampine & Reichelt 1997 / ode45: absh = min(hmax, |tspan|); rh = ||f ./ max(|y|, threshold)||
  // / (0.8 rtol^(1/5)); if absh * rh > 1 then absh = 1 / rh.
  const double threshold = opt_.atol / opt_.rtol;
  double absh = std::min(StepLimit(x), std::abs(x_end - x));
  double rh = 0.0;
  for (int i = 0; i < 2; ++i)
    rh = std::max(rh, std::abs(f[i]) / std::max(std::abs(y[i]), threshold));
  rh /= 0.8 * std::pow(opt_.rtol, 0.2);
  if (absh * rh > 1.0) absh = 1.0 / rh;
  return std::max(absh, 16.0 * std::numeric_limits<double>::epsilon() * std::abs(x));
}

Vec2 Hermite(const OdeStep& s, double theta) {
  const double t = theta, t2 = t * t, t3 = t2 * t;
  const double h00 = 2 * t3 - 3 * t2 + 1, h10 = t3 - 2 * t2 + t, h01 = -2 * t3 + 3 * t2,
               h11 = t3 - t2;
  Vec2 out;
  for (int i = 0; i < 2; ++i)
    out[i] = h00 * s.y0[i] + h10 * s.h * s.f0[i] + h01 * s.y1[i] + h11 * s.h * s.f1[i];
  return out;
}

OdeResult Integrator::Run(double x0, const Vec2& y0, double x_end) {
  const double dir = x_end >= x0 ? 1.0 : -1.0;
  OdeMethod method = opt_.method == OdeMethod::kAuto ? OdeMethod::kDopri5 : opt_.method;
  const bool detect_stiffness = opt_.method == OdeMethod::kAuto;

  std::vector<double> landmarks;
  for (double l : opt_.landmarks)
    if (std::isfinite(l) && (l - x0) * dir > 0 && (x_end - l) * dir > 0) landmarks.push_back(l);
  landmarks.push_back(x_end);
  std::sort(landmarks.begin(), landmarks.end(),
            [dir](double a, double b) { return a * dir < b * dir; });
  std::size_t next_landmark = 0;

  double x = x0;
  Vec2 y = y0;
  Vec2 f = F(x, y);
  result_.x = x;
  result_.y = y;
  result_.f = f;
  if (!Finite(f) || !Finite(y)) {
    result_.status = OdeStatus::kNonFiniteRhs;
    return result_;
  }
  if (x == x_end) return result_;

  const double order = method == OdeMethod::kRodas3 ? 3.0 : 5.0;
  double h;  // Proposed step magnitude.
  if (opt_.initial_step > 0.0) {
    h = opt_.initial_step;
  } else if (method == OdeMethod::kOde45) {
    h = InitialStepOde45(x, y, f, x_end);
  } else {
    h = InitialStepHairer(x, y, f, dir, order);
  }

  double facold = 1e-4;  // PI controller memory (Hairer's DOPRI5).
  bool last_rejected = false;
  int domain_exits = 0;       // Consecutive trial steps that left the domain.
  int iasti = 0, nonsti = 0;  // Stiffness test counters (Hairer's DOPRI5).
  Mat2 jac{};
  Vec2 dfdx{};
  bool have_jac = false;
  const double eps = std::numeric_limits<double>::epsilon();

  while (true) {
    if (result_.steps + result_.rejected_steps >= opt_.max_steps) {
      result_.status = OdeStatus::kMaxSteps;
      break;
    }
    const double hmin = 16.0 * eps * std::max(std::abs(x), 1e-300);
    // Clip the step: limits, then landmarks (end exactly on them).
    const double h_proposed = h;
    double hs = std::min(h, StepLimit(x));
    bool hits_landmark = false;
    while (next_landmark < landmarks.size() && (landmarks[next_landmark] - x) * dir <= hmin)
      ++next_landmark;
    if (next_landmark == landmarks.size()) {
      // Within round-off of x_end (a step landed a few ulps short of it): snap to it.
      x = x_end;
      result_.x = x;
      result_.status = OdeStatus::kReachedEnd;
      break;
    }
    double x_target = x + dir * hs;
    {
      const double dist = (landmarks[next_landmark] - x) * dir;
      // Stretch a step that would end just short of a landmark (never leave a sliver).
      if (hs >= dist * (1.0 - 1e-6)) {
        hs = dist;
        hits_landmark = true;
        x_target = landmarks[next_landmark];
      }
    }
    if (hs < hmin) {
      result_.status = OdeStatus::kStepSizeUnderflow;
      break;
    }
    const double hsigned = x_target - x;

    OdeStep step;
    step.x0 = x;
    step.h = hsigned;
    step.y0 = y;
    step.f0 = f;
    double err = 0.0;
    bool ok = true;
    bool domain_violation = false;
    Vec2 ynew{}, fnew{}, local{};
    // DOPRI stages kept for dense output and the stiffness test.
    Vec2 k2{}, k3{}, k4{}, k5{}, k6{}, ysti{};
    if (method == OdeMethod::kDopri5 || method == OdeMethod::kOde45) {
      const double hh = hsigned;
      const Vec2& k1 = f;
      Vec2 yt;
      for (int i = 0; i < 2; ++i) yt[i] = y[i] + hh * kA21 * k1[i];
      k2 = F(x + kC2 * hh, yt);
      for (int i = 0; i < 2; ++i) yt[i] = y[i] + hh * (kA31 * k1[i] + kA32 * k2[i]);
      k3 = F(x + kC3 * hh, yt);
      for (int i = 0; i < 2; ++i) yt[i] = y[i] + hh * (kA41 * k1[i] + kA42 * k2[i] + kA43 * k3[i]);
      k4 = F(x + kC4 * hh, yt);
      for (int i = 0; i < 2; ++i)
        yt[i] = y[i] + hh * (kA51 * k1[i] + kA52 * k2[i] + kA53 * k3[i] + kA54 * k4[i]);
      k5 = F(x + kC5 * hh, yt);
      for (int i = 0; i < 2; ++i)
        ysti[i] =
            y[i] + hh * (kA61 * k1[i] + kA62 * k2[i] + kA63 * k3[i] + kA64 * k4[i] + kA65 * k5[i]);
      k6 = F(x_target, ysti);
      for (int i = 0; i < 2; ++i)
        ynew[i] =
            y[i] + hh * (kA71 * k1[i] + kA73 * k3[i] + kA74 * k4[i] + kA75 * k5[i] + kA76 * k6[i]);
      domain_violation = Finite(ynew) && !InDomain(x_target, ynew);
      ok = !domain_violation && Finite(ynew);
      if (ok) {
        fnew = F(x_target, ynew);  // First stage of the next step (FSAL).
        for (int i = 0; i < 2; ++i)
          local[i] = hh * (kE1 * k1[i] + kE3 * k3[i] + kE4 * k4[i] + kE5 * k5[i] + kE6 * k6[i] +
                           kE7 * fnew[i]);
        ok = Finite(fnew) && Finite(local) && Finite(k2) && Finite(k3) && Finite(k4) &&
             Finite(k5) && Finite(k6);
      }
      if (ok) {
        err = method == OdeMethod::kOde45 ? Ode45Norm(local, y, ynew, opt_.atol / opt_.rtol)
                                          : RmsNorm(local, y, ynew, opt_.rtol, opt_.atol);
      }
    } else {  // Rodas3
      if (!have_jac) {
        sys_.jacobian(x, y, &jac, &dfdx);
        ++result_.jacobian_evals;
        have_jac = true;
      }
      const double hh = hsigned;
      const double d = 1.0 / (hh * kRosGamma);
      const double a00 = d - jac[0], a01 = -jac[1], a10 = -jac[2], a11 = d - jac[3];
      const double det = a00 * a11 - a01 * a10;
      auto solve = [&](const Vec2& r) {
        return Vec2{(a11 * r[0] - a01 * r[1]) / det, (a00 * r[1] - a10 * r[0]) / det};
      };
      ok = std::isfinite(det) && det != 0.0;
      Vec2 K1{}, K2{}, K3{}, K4{}, r{}, yt{};
      if (ok) {
        for (int i = 0; i < 2; ++i) r[i] = f[i] + hh * kRosGamma1 * dfdx[i];
        K1 = solve(r);
        for (int i = 0; i < 2; ++i) yt[i] = y[i] + kRosA21 * K1[i];
        const Vec2 F2 = F(x + kRosAlpha2 * hh, yt);
        for (int i = 0; i < 2; ++i) r[i] = F2[i] + kRosC21 / hh * K1[i] + hh * kRosGamma2 * dfdx[i];
        K2 = solve(r);
        for (int i = 0; i < 2; ++i) yt[i] = y[i] + kRosA31 * K1[i] + kRosA32 * K2[i];
        ok = Finite(yt) && Finite(F2);
      }
      if (ok) {
        const Vec2 F3 = F(x + kRosAlpha3 * hh, yt);
        for (int i = 0; i < 2; ++i)
          r[i] = F3[i] + (kRosC31 * K1[i] + kRosC32 * K2[i]) / hh + hh * kRosGamma3 * dfdx[i];
        K3 = solve(r);
        for (int i = 0; i < 2; ++i)
          yt[i] = y[i] + kRosA41 * K1[i] + kRosA42 * K2[i] + kRosA43 * K3[i];
        ok = Finite(yt) && Finite(F3);
      }
      if (ok) {
        const Vec2 F4 = F(x + kRosAlpha4 * hh, yt);
        for (int i = 0; i < 2; ++i)
          r[i] = F4[i] + (kRosC41 * K1[i] + kRosC42 * K2[i] + kRosC43 * K3[i]) / hh +
                 hh * kRosGamma4 * dfdx[i];
        K4 = solve(r);
        for (int i = 0; i < 2; ++i) {
          ynew[i] = y[i] + kRosM1 * K1[i] + kRosM2 * K2[i] + kRosM3 * K3[i] + kRosM4 * K4[i];
          local[i] = K4[i];
        }
        domain_violation = Finite(ynew) && !InDomain(x_target, ynew);
        ok = !domain_violation && Finite(ynew) && Finite(local) && Finite(F4);
        if (ok) {
          fnew = F(x_target, ynew);
          ok = Finite(fnew);
        }
      }
      if (ok) err = RmsNorm(local, y, ynew, opt_.rtol, opt_.atol);
    }

    if (!ok) {
      // Outside the domain or non-finite: reject with a strong reduction.
      // A trial step can leave the domain because the solution does (the slope at the step's
      // start already carries it out) or because the step is too long for what lies ahead (a
      // later stage met a steep rise of the right-hand side, e.g. a sigmoid with a huge rate,
      // while the slope at the start stays inside): the latter is retried with shorter steps.
      if (opt_.stop_on_domain_exit && domain_violation) {
        Vec2 euler;
        for (int i = 0; i < 2; ++i) euler[i] = y[i] + hsigned * f[i];
        if (!InDomain(x_target, euler) || ++domain_exits > opt_.domain_exit_retries) {
          result_.status = OdeStatus::kLeftDomain;
          break;
        }
      }
      ++result_.rejected_steps;
      h = 0.25 * hs;
      last_rejected = true;
      continue;
    }

    const bool accept = method == OdeMethod::kOde45 ? err <= opt_.rtol : err <= 1.0;
    if (!accept) {
      ++result_.rejected_steps;
      if (method == OdeMethod::kOde45) {
        // ode45: first failure in a step: max(0.1, 0.8 (rtol/err)^(1/5)); later failures: 0.5.
        h = last_rejected ? 0.5 * hs : hs * std::max(0.1, 0.8 * std::pow(opt_.rtol / err, 0.2));
      } else if (method == OdeMethod::kDopri5) {
        const double fac11 = std::pow(err, 0.2 - 0.04 * 0.75);
        h = hs / std::min(5.0, fac11 / 0.9);
      } else {
        h = hs / std::min(5.0, std::pow(err, 1.0 / 3.0) / 0.9);
      }
      last_rejected = true;
      continue;
    }

    // Accepted.
    ++result_.steps;
    domain_exits = 0;
    step.y1 = ynew;
    step.f1 = fnew;
    step.local_error = local;
    if (method == OdeMethod::kDopri5 || method == OdeMethod::kOde45) {
      step.dopri_dense = true;
      const double hh = hsigned;
      for (int i = 0; i < 2; ++i) {
        const double ydiff = ynew[i] - y[i];
        const double bspl = hh * f[i] - ydiff;
        step.rcont[0][i] = y[i];
        step.rcont[1][i] = ydiff;
        step.rcont[2][i] = bspl;
        step.rcont[3][i] = ydiff - hh * fnew[i] - bspl;
        step.rcont[4][i] = hh * (kD1 * f[i] + kD3 * k3[i] + kD4 * k4[i] + kD5 * k5[i] +
                                 kD6 * k6[i] + kD7 * fnew[i]);
      }
      if (detect_stiffness) {
        // Hairer's test: h * |lambda| ~ h ||k7 - k6|| / ||y_new - y_stage6||.
        double stnum = 0.0, stden = 0.0;
        for (int i = 0; i < 2; ++i) {
          stnum += (fnew[i] - k6[i]) * (fnew[i] - k6[i]);
          stden += (ynew[i] - ysti[i]) * (ynew[i] - ysti[i]);
        }
        if (stden > 0.0) {
          const double hlamb = hs * std::sqrt(stnum / stden);
          result_.max_h_lambda = std::max(result_.max_h_lambda, hlamb);
          if (hlamb > 3.25) {
            nonsti = 0;
            if (++iasti == 15) {
              result_.stiffness_detected = true;
              result_.stiffness_x = x_target;
              method = OdeMethod::kRodas3;
              have_jac = false;
            }
          } else if (++nonsti == 6) {
            iasti = 0;
          }
        }
      }
    }
    if (steps_) steps_->push_back(step);

    // Next step size.
    double hnew;
    if (method == OdeMethod::kOde45) {
      if (!last_rejected) {
        const double temp = 1.25 * std::pow(err / opt_.rtol, 0.2);
        hnew = temp > 0.2 ? hs / temp : 5.0 * hs;
      } else {
        hnew = hs;
      }
    } else if (method == OdeMethod::kDopri5) {
      const double fac11 = std::pow(std::max(err, 1e-300), 0.2 - 0.04 * 0.75);
      double fac = fac11 / std::pow(facold, 0.04);
      fac = std::max(0.1, std::min(5.0, fac / 0.9));
      hnew = hs / fac;
      facold = std::max(err, 1e-4);
      if (last_rejected) hnew = std::min(hnew, hs);
    } else {
      const double fac =
          std::max(1.0 / 6.0, std::min(5.0, std::pow(std::max(err, 1e-300), 1.0 / 3.0) / 0.9));
      hnew = hs / fac;
      if (last_rejected) hnew = std::min(hnew, hs);
      have_jac = false;
    }
    if (hits_landmark) hnew = std::max(hnew, std::min(h_proposed, 5.0 * hs));
    h = hnew;
    last_rejected = false;

    x = x_target;
    y = ynew;
    f = fnew;
    result_.x = x;
    result_.y = y;
    result_.f = f;
    if (x == x_end) {
      result_.status = OdeStatus::kReachedEnd;
      break;
    }
    if (opt_.stop_after_step && opt_.stop_after_step(x, y, f)) {
      result_.status = OdeStatus::kStoppedByCallback;
      break;
    }
  }
  return result_;
}

}  // namespace

const char* ToString(OdeMethod method) {
  switch (method) {
    case OdeMethod::kDopri5: return "dopri5";
    case OdeMethod::kOde45: return "ode45";
    case OdeMethod::kRodas3: return "rodas3";
    case OdeMethod::kAuto: return "auto";
  }
  return "?";
}

const char* ToString(OdeStatus status) {
  switch (status) {
    case OdeStatus::kReachedEnd: return "reached end";
    case OdeStatus::kStoppedByCallback: return "stopped by callback";
    case OdeStatus::kLeftDomain: return "left domain";
    case OdeStatus::kStepSizeUnderflow: return "step size underflow";
    case OdeStatus::kMaxSteps: return "maximum number of steps";
    case OdeStatus::kNonFiniteRhs: return "non-finite right-hand side at the start";
  }
  return "?";
}

Vec2 OdeStep::Interpolate(double theta) const {
  if (!dopri_dense) return Hermite(*this, theta);
  const double t1 = 1.0 - theta;
  Vec2 out;
  for (int i = 0; i < 2; ++i)
    out[i] = rcont[0][i] +
             theta * (rcont[1][i] + t1 * (rcont[2][i] + theta * (rcont[3][i] + t1 * rcont[4][i])));
  return out;
}

OdeResult IntegrateOde(const OdeSystem& system, double x0, const Vec2& y0, double x_end,
                       const OdeOptions& options, std::vector<OdeStep>* steps) {
  Integrator integrator(system, options, steps);
  return integrator.Run(x0, y0, x_end);
}

}  // namespace impactdic
