// The integrators on problems with known solutions.
#include "impactdic/model/ode.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/model/ode_stepper.h"

namespace impactdic {
namespace {

// y'' = -y with y(0) = 1, y'(0) = 0: y = cos x. Jacobian constant.
OdeSystem Oscillator() {
  OdeSystem sys;
  sys.rhs = [](double, const Vec2& y) { return Vec2{y[1], -y[0]}; };
  sys.jacobian = [](double, const Vec2&, Mat2* J, Vec2* fx) {
    *J = {0.0, 1.0, -1.0, 0.0};
    *fx = {0.0, 0.0};
  };
  return sys;
}

// A non-autonomous, nonlinear problem with a known solution:
// y0' = y1, y1' = -y0 + (y0 - sin x)^2 (solution y0 = sin x, y1 = cos x).
OdeSystem NonlinearForced() {
  OdeSystem sys;
  sys.rhs = [](double x, const Vec2& y) {
    const double d = y[0] - std::sin(x);
    return Vec2{y[1], -y[0] + d * d};
  };
  sys.jacobian = [](double x, const Vec2& y, Mat2* J, Vec2* fx) {
    const double d = y[0] - std::sin(x);
    *J = {0.0, 1.0, -1.0 + 2.0 * d, 0.0};
    *fx = {0.0, -2.0 * d * std::cos(x)};
  };
  return sys;
}

TEST(Ode, EveryMethodMeetsItsToleranceOnTheOscillator) {
  // Tolerance proportionality: over 10 time units the global error stays within 50x the
  // tolerance (error propagation over ~1.6 periods of a neutrally stable problem), and shrinks.
  for (const char* m : {"dopri5", "ode45", "rodas3", "auto"}) {
    double previous = 1.0;
    for (double tol : {1e-4, 1e-7, 1e-10}) {
      OdeOptions o;
      o.method = m;
      o.rtol = tol;
      o.atol = tol;
      const OdeResult r = IntegrateOde(Oscillator(), 0.0, {1.0, 0.0}, 10.0, o);
      ASSERT_EQ(r.status, OdeStatus::kReachedEnd) << m;
      EXPECT_EQ(r.x, 10.0);
      const double err = std::abs(r.y[0] - std::cos(10.0));
      EXPECT_LT(err, 50 * tol) << m << " tol " << tol;
      EXPECT_LT(err, previous) << m << " tol " << tol;
      previous = err;
    }
  }
}

TEST(Ode, Rodas3IsThirdOrderWithTheAnalyticJacobian) {
  // With a fixed step (huge tolerance, step cap) halving h divides the error by ~8.
  std::vector<double> errors;
  for (double h : {0.1, 0.05, 0.025}) {
    OdeOptions o;
    o.method = "rodas3";
    o.rtol = 1e-1;
    o.atol = 1e3;
    o.initial_step = h;
    o.max_step = h;
    const OdeResult r = IntegrateOde(NonlinearForced(), 0.0, {0.0, 1.0}, 2.0, o);
    errors.push_back(std::abs(r.y[0] - std::sin(2.0)));
  }
  const double order1 = std::log2(errors[0] / errors[1]);
  const double order2 = std::log2(errors[1] / errors[2]);
  EXPECT_NEAR(order1, 3.0, 0.4);
  EXPECT_NEAR(order2, 3.0, 0.4);
}

TEST(Ode, DormandPrinceIsFifthOrder) {
  // Fixed steps h = 0.1, 0.05, 0.025: the mean observed order over the two halvings is 5 +- 0.5
  // (measured 5.5: still slightly pre-asymptotic at h = 0.1).
  std::vector<double> errors;
  for (double h : {0.1, 0.05, 0.025}) {
    OdeOptions o;
    o.rtol = 1e-1;
    o.atol = 1e3;
    o.initial_step = h;
    o.max_step = h;
    const OdeResult r = IntegrateOde(NonlinearForced(), 0.0, {0.0, 1.0}, 2.0, o);
    EXPECT_EQ(r.steps, std::lround(2.0 / h));
    errors.push_back(std::abs(r.y[0] - std::sin(2.0)));
  }
  EXPECT_NEAR(0.5 * std::log2(errors[0] / errors[2]), 5.0, 0.5);
}

TEST(Ode, DenseOutputIsAccurateInsideSteps) {
  // Hairer's 4th-order continuous extension (DOPRI) and the cubic Hermite (Rodas3): the
  // interpolant's error at tol 1e-8 stays within 100x tol (interpolation order is one lower than
  // the step's).
  for (const char* m : {"dopri5", "rodas3"}) {
    OdeOptions o;
    o.method = m;
    o.rtol = 1e-8;
    o.atol = 1e-8;
    std::vector<OdeStep> steps;
    IntegrateOde(Oscillator(), 0.0, {1.0, 0.0}, 6.0, o, &steps);
    ASSERT_GT(steps.size(), 5u);
    double worst = 0.0;
    for (const OdeStep& s : steps)
      for (double theta : {0.25, 0.5, 0.75}) {
        const Vec2 y = s.Interpolate(theta);
        worst = std::max(worst, std::abs(y[0] - std::cos(s.x0 + theta * s.h)));
      }
    EXPECT_LT(worst, 100 * 1e-8) << m;
  }
}

TEST(Ode, LandmarksAreHitExactlyAndBackwardIntegrationWorks) {
  OdeOptions o;
  o.rtol = 1e-9;
  o.atol = 1e-12;
  o.landmarks = {0.3, 1.7};
  std::vector<OdeStep> steps;
  const OdeResult r =
      IntegrateOde(Oscillator(), 3.0, {std::cos(3.0), -std::sin(3.0)}, 0.0, o, &steps);
  ASSERT_EQ(r.status, OdeStatus::kReachedEnd);
  EXPECT_NEAR(r.y[0], 1.0, 1e-8);
  int hits = 0;
  for (const OdeStep& s : steps) {
    const double end = s.x0 + s.h;
    if (end == 0.3 || end == 1.7) ++hits;
    EXPECT_LT(s.h, 0.0);
  }
  EXPECT_EQ(hits, 2);
}

TEST(Ode, AutoSwitchesToRodas3OnAStiffProblem) {
  // y0' = -1e4 (y0 - cos x), y1' = y0: stiff once the transient has decayed. Hairer's stiffness
  // test must fire and the Rosenbrock method then needs far fewer steps than Dormand-Prince.
  OdeSystem sys;
  sys.rhs = [](double x, const Vec2& y) { return Vec2{-1e4 * (y[0] - std::cos(x)), y[0]}; };
  sys.jacobian = [](double x, const Vec2&, Mat2* J, Vec2* fx) {
    *J = {-1e4, 0.0, 1.0, 0.0};
    *fx = {-1e4 * std::sin(x), 0.0};
  };
  OdeOptions o;
  o.rtol = 1e-6;
  o.atol = 1e-9;
  o.method = "dopri5";
  const OdeResult explicit_run = IntegrateOde(sys, 0.0, {0.0, 0.0}, 2.0, o);
  o.method = "auto";
  const OdeResult auto_run = IntegrateOde(sys, 0.0, {0.0, 0.0}, 2.0, o);
  EXPECT_TRUE(auto_run.stiffness_detected);
  EXPECT_LT(auto_run.steps * 5, explicit_run.steps);
  EXPECT_NEAR(auto_run.y[1], std::sin(2.0), 1e-4);  // y1 ~ sin x after the 1e-4 transient
}

TEST(Ode, Ode45ModeFollowsMatlabsInitialStepAndGrowthRules) {
  // y' = (1, 2), y(0) = (1, 1) on [0, 10], RelTol 1e-3, AbsTol 1e-6, MaxStep 0.1 * 10 (ode45's
  // defaults). MATLAB's rule: threshold = AbsTol / RelTol = 1e-3,
  // rh = max|f ./ max(|y|, threshold)| / (0.8 RelTol^(1/5)) = 2 / (0.8 * 1e-3^0.2), and since
  // min(MaxStep, |tspan|) * rh > 1 the first step is 1 / rh. The step is exact (err = 0), so the
  // next one is 5 times longer, capped by MaxStep.
  OdeSystem sys;
  sys.rhs = [](double, const Vec2&) { return Vec2{1.0, 2.0}; };
  OdeOptions o;
  o.method = "ode45";
  o.rtol = 1e-3;
  o.atol = 1e-6;
  o.max_step = 1.0;
  std::vector<OdeStep> steps;
  const OdeResult r = IntegrateOde(sys, 0.0, {1.0, 1.0}, 10.0, o, &steps);
  ASSERT_EQ(r.status, OdeStatus::kReachedEnd);
  ASSERT_GE(steps.size(), 3u);
  const double h0 = 0.8 * std::pow(1e-3, 0.2) / 2.0;
  EXPECT_NEAR(steps[0].h, h0, 1e-15);
  EXPECT_NEAR(steps[1].h, std::min(5 * h0, 1.0), 1e-15);
  EXPECT_NEAR(steps[2].h, 1.0, 1e-15);
  EXPECT_EQ(r.rejected_steps, 0);
  EXPECT_NEAR(r.y[1], 21.0, 1e-12);
}

TEST(Ode, DomainExitStopsAtTheLastAcceptedPoint) {
  // y' = -1: leaves y > 0 at x = 1.
  OdeSystem sys;
  sys.rhs = [](double, const Vec2&) { return Vec2{-1.0, 0.0}; };
  sys.in_domain = [](double, const Vec2& y) { return y[0] > 0.0; };
  OdeOptions o;
  o.stop_on_domain_exit = true;
  o.initial_step = 0.3;
  const OdeResult r = IntegrateOde(sys, 0.0, {1.0, 0.0}, 5.0, o);
  EXPECT_EQ(r.status, OdeStatus::kLeftDomain);
  EXPECT_GT(r.y[0], 0.0);
  EXPECT_LT(r.x, 1.0);
  // The slope at the step's start carries it out: no retries.
  EXPECT_EQ(r.rejected_steps, 0);
}

TEST(Ode, ATooLongTrialStepLeavingTheDomainIsRetriedNotTakenAsTheExit) {
  // y' = -100 only for x > 0.95 (a steep drop ahead), 0 before: a long first step from x = 0
  // samples the drop and leaves y > 0, although the solution stays inside until x = 0.96. The
  // slope at the step's start stays inside, so the step is retried shorter; the integration goes
  // on to the drop and ends there (taking the first trial as the exit would end it at x = 0).
  OdeSystem sys;
  sys.rhs = [](double x, const Vec2&) { return Vec2{x > 0.95 ? -100.0 : 0.0, 0.0}; };
  sys.in_domain = [](double, const Vec2& y) { return y[0] > 0.0; };
  OdeOptions o;
  o.stop_on_domain_exit = true;
  o.initial_step = 2.0;
  const OdeResult r = IntegrateOde(sys, 0.0, {1.0, 0.0}, 5.0, o);
  EXPECT_EQ(r.status, OdeStatus::kLeftDomain);
  EXPECT_GT(r.x, 0.9);
  EXPECT_LT(r.x, 0.96);
  EXPECT_GT(r.rejected_steps, 0);
}

// The worked example of an ODE method added from outside the library (docs/architecture.md,
// "Extension points"): Heun's method with the embedded Euler step, order 2(1), an elementary
// controller h_new = h min(5, max(0.2, 0.9 err^(-1/2))). One class and one registration call.
class HeunEulerStepper final : public OdeStepper {
 public:
  double Order() const override { return 2.0; }
  OdeTrial Attempt(OdeStepContext& c, double /*x*/, const Vec2& y, const Vec2& f, double h,
                   double x_target) override {
    OdeTrial t;
    t.x1 = x_target;
    const Vec2 k2 = c.F(x_target, {y[0] + h * f[0], y[1] + h * f[1]});
    double sum = 0.0;
    for (int i = 0; i < 2; ++i) {
      t.y1[i] = y[i] + 0.5 * h * (f[i] + k2[i]);
      t.local_error[i] = 0.5 * h * (k2[i] - f[i]);
      const double scale =
          c.options().atol + c.options().rtol * std::max(std::abs(y[i]), std::abs(t.y1[i]));
      sum += (t.local_error[i] / scale) * (t.local_error[i] / scale);
    }
    t.error = std::sqrt(sum / 2.0);
    t.domain_violation = !c.InDomain(x_target, t.y1);
    t.ok = !t.domain_violation;
    if (t.ok) t.f1 = c.F(x_target, t.y1);
    return t;
  }
  double AfterRejection(const OdeOptions&, double h_abs, double error, bool) override {
    return h_abs * std::max(0.2, 0.9 / std::sqrt(error));
  }
  double AfterAcceptance(const OdeOptions&, double h_abs, double error, bool) override {
    return h_abs * std::min(5.0, std::max(0.2, 0.9 / std::sqrt(std::max(error, 1e-300))));
  }
};

void RegisterHeunEuler() {
  static const bool registered = [] {
    RegisterOdeMethod("heun-euler", [] { return std::make_unique<HeunEulerStepper>(); });
    return true;
  }();
  (void)registered;
}

TEST(OdeExtension, ATestOnlyMethodIsSelectedByNameAndMeetsItsTolerance) {
  RegisterHeunEuler();
  const std::vector<std::string> names = OdeMethodNames();
  EXPECT_NE(std::find(names.begin(), names.end(), "heun-euler"), names.end());
  OdeOptions o;
  o.method = "heun-euler";
  o.rtol = o.atol = 1e-6;
  std::vector<OdeStep> steps;
  const OdeResult r = IntegrateOde(Oscillator(), 0.0, {1.0, 0.0}, 10.0, o, &steps);
  ASSERT_EQ(r.status, OdeStatus::kReachedEnd);
  EXPECT_EQ(r.x, 10.0);
  // The same tolerance proportionality as the built-in methods.
  EXPECT_LT(std::abs(r.y[0] - std::cos(10.0)), 50 * o.rtol);
  // A second-order method needs far more steps than Dormand-Prince for the same tolerance.
  o.method = "dopri5";
  const OdeResult dopri = IntegrateOde(Oscillator(), 0.0, {1.0, 0.0}, 10.0, o);
  EXPECT_GT(r.steps, 5 * dopri.steps);
  // Its steps have the driver's cubic Hermite dense output (the default of Accepted).
  ASSERT_FALSE(steps.empty());
  EXPECT_FALSE(steps[0].dopri_dense);
  EXPECT_NEAR(steps[0].Interpolate(1.0)[0], steps[0].y1[0], 1e-15);
}

TEST(OdeExtension, UnknownMethodsAndDuplicateNamesAreRefused) {
  RegisterHeunEuler();
  OdeOptions o;
  o.method = "rk4";
  try {
    IntegrateOde(Oscillator(), 0.0, {1.0, 0.0}, 1.0, o);
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("rk4"), std::string::npos) << what;
    EXPECT_NE(what.find("dopri5, ode45, rodas3, auto"), std::string::npos) << what;
  }
  EXPECT_THROW(RegisterOdeMethod("dopri5", [] { return std::make_unique<HeunEulerStepper>(); }),
               Error);
}

}  // namespace
}  // namespace impactdic
