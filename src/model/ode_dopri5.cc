// Dormand-Prince 5(4) with local extrapolation, Hairer's PI step control, 4th-order dense output
// and stiffness test (Dormand & Prince 1980, doi:10.1016/0771-050X(80)90013-3; Hairer, Norsett,
// Wanner, Solving ODEs I, sec. II.5 and IV.2), or under MATLAB ode45's rules (Shampine &
// Reichelt 1997, doi:10.1137/S1064827594276424).
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>

#include "impactdic/model/ode.h"
#include "impactdic/model/ode_stepper.h"
#include "ode_norms.h"
#include "ode_steppers.h"

namespace impactdic::internal {
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

class Dopri5Stepper final : public OdeStepper {
 public:
  Dopri5Stepper(bool ode45_rules, bool detect_stiffness)
      : ode45_(ode45_rules), detect_stiffness_(detect_stiffness) {}

  double Order() const override { return 5.0; }

  double InitialStep(OdeStepContext& c, double x, const Vec2& y, const Vec2& f, double x_end,
                     double direction) override {
    if (!ode45_) return OdeStepper::InitialStep(c, x, y, f, x_end, direction);
    // Shampine & Reichelt 1997 / ode45: absh = min(hmax, |tspan|); rh = ||f ./ max(|y|,
    // threshold)|| / (0.8 rtol^(1/5)); if absh * rh > 1 then absh = 1 / rh.
    const OdeOptions& o = c.options();
    const double threshold = o.atol / o.rtol;
    double absh = std::min(c.StepLimit(x), std::abs(x_end - x));
    double rh = 0.0;
    for (int i = 0; i < 2; ++i)
      rh = std::max(rh, std::abs(f[i]) / std::max(std::abs(y[i]), threshold));
    rh /= 0.8 * std::pow(o.rtol, 0.2);
    if (absh * rh > 1.0) absh = 1.0 / rh;
    return std::max(absh, 16.0 * std::numeric_limits<double>::epsilon() * std::abs(x));
  }

  OdeTrial Attempt(OdeStepContext& c, double x, const Vec2& y, const Vec2& f, double hh,
                   double x_target) override {
    OdeTrial t;
    t.x1 = x_target;
    const Vec2& k1 = f;
    Vec2 yt;
    for (int i = 0; i < 2; ++i) yt[i] = y[i] + hh * kA21 * k1[i];
    k2_ = c.F(x + kC2 * hh, yt);
    for (int i = 0; i < 2; ++i) yt[i] = y[i] + hh * (kA31 * k1[i] + kA32 * k2_[i]);
    k3_ = c.F(x + kC3 * hh, yt);
    for (int i = 0; i < 2; ++i) yt[i] = y[i] + hh * (kA41 * k1[i] + kA42 * k2_[i] + kA43 * k3_[i]);
    k4_ = c.F(x + kC4 * hh, yt);
    for (int i = 0; i < 2; ++i)
      yt[i] = y[i] + hh * (kA51 * k1[i] + kA52 * k2_[i] + kA53 * k3_[i] + kA54 * k4_[i]);
    k5_ = c.F(x + kC5 * hh, yt);
    for (int i = 0; i < 2; ++i)
      ysti_[i] = y[i] + hh * (kA61 * k1[i] + kA62 * k2_[i] + kA63 * k3_[i] + kA64 * k4_[i] +
                              kA65 * k5_[i]);
    k6_ = c.F(x_target, ysti_);
    for (int i = 0; i < 2; ++i)
      t.y1[i] = y[i] +
                hh * (kA71 * k1[i] + kA73 * k3_[i] + kA74 * k4_[i] + kA75 * k5_[i] + kA76 * k6_[i]);
    t.domain_violation = Finite(t.y1) && !c.InDomain(x_target, t.y1);
    t.ok = !t.domain_violation && Finite(t.y1);
    if (t.ok) {
      t.f1 = c.F(x_target, t.y1);  // First stage of the next step (FSAL).
      for (int i = 0; i < 2; ++i)
        t.local_error[i] = hh * (kE1 * k1[i] + kE3 * k3_[i] + kE4 * k4_[i] + kE5 * k5_[i] +
                                 kE6 * k6_[i] + kE7 * t.f1[i]);
      t.ok = Finite(t.f1) && Finite(t.local_error) && Finite(k2_) && Finite(k3_) && Finite(k4_) &&
             Finite(k5_) && Finite(k6_);
    }
    if (t.ok) {
      const OdeOptions& o = c.options();
      t.error = ode45_ ? Ode45Norm(t.local_error, y, t.y1, o.atol / o.rtol)
                       : RmsNorm(t.local_error, y, t.y1, o.rtol, o.atol);
    }
    return t;
  }

  bool Accepts(const OdeOptions& o, double error) const override {
    return ode45_ ? error <= o.rtol : error <= 1.0;
  }

  double AfterRejection(const OdeOptions& o, double hs, double err, bool last_rejected) override {
    if (ode45_) {
      // ode45: first failure in a step: max(0.1, 0.8 (rtol/err)^(1/5)); later failures: 0.5.
      return last_rejected ? 0.5 * hs : hs * std::max(0.1, 0.8 * std::pow(o.rtol / err, 0.2));
    }
    const double fac11 = std::pow(err, 0.2 - 0.04 * 0.75);
    return hs / std::min(5.0, fac11 / 0.9);
  }

  void Accepted(OdeStepContext& c, const OdeTrial& t, double hs, OdeStep* step) override {
    step->dopri_dense = true;
    const double hh = step->h;
    const Vec2& y = step->y0;
    const Vec2& f = step->f0;
    for (int i = 0; i < 2; ++i) {
      const double ydiff = t.y1[i] - y[i];
      const double bspl = hh * f[i] - ydiff;
      step->rcont[0][i] = y[i];
      step->rcont[1][i] = ydiff;
      step->rcont[2][i] = bspl;
      step->rcont[3][i] = ydiff - hh * t.f1[i] - bspl;
      step->rcont[4][i] = hh * (kD1 * f[i] + kD3 * k3_[i] + kD4 * k4_[i] + kD5 * k5_[i] +
                                kD6 * k6_[i] + kD7 * t.f1[i]);
    }
    if (detect_stiffness_) StiffnessTest(c, t, hs);
  }

  double AfterAcceptance(const OdeOptions& o, double hs, double err, bool last_rejected) override {
    if (ode45_) {
      if (last_rejected) return hs;
      const double temp = 1.25 * std::pow(err / o.rtol, 0.2);
      return temp > 0.2 ? hs / temp : 5.0 * hs;
    }
    const double fac11 = std::pow(std::max(err, 1e-300), 0.2 - 0.04 * 0.75);
    double fac = fac11 / std::pow(facold_, 0.04);
    fac = std::max(0.1, std::min(5.0, fac / 0.9));
    double hnew = hs / fac;
    facold_ = std::max(err, 1e-4);
    if (last_rejected) hnew = std::min(hnew, hs);
    return hnew;
  }

  bool stiff() const { return stiff_; }

 private:
  // Hairer's test: h |lambda| ~ h ||k7 - k6|| / ||y_new - y_stage6||; fires after 15 accepted
  // steps above 3.25 without 6 below it.
  void StiffnessTest(OdeStepContext& c, const OdeTrial& t, double hs) {
    double stnum = 0.0, stden = 0.0;
    for (int i = 0; i < 2; ++i) {
      stnum += (t.f1[i] - k6_[i]) * (t.f1[i] - k6_[i]);
      stden += (t.y1[i] - ysti_[i]) * (t.y1[i] - ysti_[i]);
    }
    if (!(stden > 0.0)) return;
    OdeResult& r = c.result();
    const double hlamb = hs * std::sqrt(stnum / stden);
    r.max_h_lambda = std::max(r.max_h_lambda, hlamb);
    if (hlamb > 3.25) {
      nonsti_ = 0;
      if (++iasti_ == 15) {
        r.stiffness_detected = true;
        r.stiffness_x = t.x1;
        stiff_ = true;
      }
    } else if (++nonsti_ == 6) {
      iasti_ = 0;
    }
  }

  bool ode45_, detect_stiffness_;
  double facold_ = 1e-4;        // PI controller memory (Hairer's DOPRI5).
  int iasti_ = 0, nonsti_ = 0;  // Stiffness test counters (Hairer's DOPRI5).
  bool stiff_ = false;
  // Stages of the last attempt, for the dense output and the stiffness test.
  Vec2 k2_{}, k3_{}, k4_{}, k5_{}, k6_{}, ysti_{};
};

}  // namespace

std::unique_ptr<OdeStepper> MakeDopri5(bool ode45_rules, bool detect_stiffness) {
  return std::make_unique<Dopri5Stepper>(ode45_rules, detect_stiffness);
}

bool StiffnessDetected(const OdeStepper& dopri5) {
  return static_cast<const Dopri5Stepper&>(dopri5).stiff();
}

std::unique_ptr<OdeStepper> MakeDopri5Stepper() {
  return MakeDopri5(/*ode45_rules=*/false, /*detect_stiffness=*/false);
}

std::unique_ptr<OdeStepper> MakeOde45Stepper() {
  return MakeDopri5(/*ode45_rules=*/true, /*detect_stiffness=*/false);
}

}  // namespace impactdic::internal
