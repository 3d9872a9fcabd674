// ODE methods as an extension point of IntegrateOde (ode.h): a method is an OdeStepper that
// attempts one step with an error estimate and chooses the next step size; the driver in
// src/model/ode.cc does everything else (landmarks, step limits, domain exits, step counting,
// stopping). The built-in methods are "dopri5", "ode45", "rodas3" and "auto"
// (src/model/ode_*.cc). Adding one: a class deriving from OdeStepper in one new file and one line
// in the table of src/model/ode.cc (docs/development.md, "Extension points"); RegisterOdeMethod
// adds one at run time (tests/model/ode_test.cc, the Heun-Euler example).
#ifndef IMPACTDIC_MODEL_ODE_STEPPER_H_
#define IMPACTDIC_MODEL_ODE_STEPPER_H_

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "impactdic/model/ode.h"

namespace impactdic {

// What a stepper may use during an integration: the system's functions (counted in the result)
// and the options.
class OdeStepContext {
 public:
  OdeStepContext(const OdeSystem& system, const OdeOptions& options, OdeResult* result)
      : system_(system), options_(options), result_(result) {}

  // f(x, y), counted in OdeResult::rhs_evals.
  Vec2 F(double x, const Vec2& y) {
    ++result_->rhs_evals;
    return system_.rhs(x, y);
  }
  // df/dy and df/dx (OdeSystem::jacobian), counted in OdeResult::jacobian_evals.
  void Jacobian(double x, const Vec2& y, Mat2* dfdy, Vec2* dfdx) {
    ++result_->jacobian_evals;
    system_.jacobian(x, y, dfdy, dfdx);
  }
  // Finite and inside OdeSystem::in_domain.
  bool InDomain(double x, const Vec2& y) const;
  // Largest allowed step magnitude from x (OdeOptions::max_step, max_step_at).
  double StepLimit(double x) const;
  const OdeOptions& options() const { return options_; }
  // The result being built (a stepper records e.g. stiffness detection there).
  OdeResult& result() { return *result_; }

 private:
  const OdeSystem& system_;
  const OdeOptions& options_;
  OdeResult* result_;
};

// One attempted step.
struct OdeTrial {
  // false: a stage or the result is non-finite or outside the domain; the driver rejects the
  // step and retries with a quarter of it (domain_violation: the new state left the domain).
  bool ok = true;
  bool domain_violation = false;
  double x1 = 0.0;     // Where the step ends (the x_target of Attempt).
  Vec2 y1{}, f1{};     // The new state and f there (valid if ok).
  Vec2 local_error{};  // The embedded error estimate (absolute, per component).
  double error = 0.0;  // Its norm in the stepper's own scale (Accepts decides).
};

class OdeStepper {
 public:
  virtual ~OdeStepper() = default;

  // Order of the method (Hairer's starting-step rule uses it).
  virtual double Order() const = 0;
  // Initial step magnitude when OdeOptions::initial_step is not given; default: Hairer, Norsett,
  // Wanner, Solving ODEs I, sec. II.4, with Order().
  virtual double InitialStep(OdeStepContext& context, double x, const Vec2& y, const Vec2& f,
                             double x_end, double direction);
  // One step from (x, y), f = f(x, y), of signed length h, ending exactly at x_target.
  virtual OdeTrial Attempt(OdeStepContext& context, double x, const Vec2& y, const Vec2& f,
                           double h, double x_target) = 0;
  // Whether an ok trial is accepted; default error <= 1.
  virtual bool Accepts(const OdeOptions& options, double error) const;
  // The next step magnitude after rejecting an ok trial of magnitude h_abs.
  virtual double AfterRejection(const OdeOptions& options, double h_abs, double error,
                                bool last_rejected) = 0;
  // Called for an accepted trial (from x, magnitude h_abs): fills the dense output of `step`
  // (y0, y1, f0, f1 and h are set; default: cubic Hermite) and may record what it learnt.
  virtual void Accepted(OdeStepContext& context, const OdeTrial& trial, double h_abs,
                        OdeStep* step);
  // The next step magnitude after accepting a trial of magnitude h_abs.
  virtual double AfterAcceptance(const OdeOptions& options, double h_abs, double error,
                                 bool last_rejected) = 0;
};

// Makes a fresh stepper (one per integration; steppers keep state such as controller memory).
using OdeStepperFactory = std::function<std::unique_ptr<OdeStepper>()>;

// The stepper registered as `name` ("dopri5"); Error kInvalidValue naming the name and listing
// the registered methods otherwise.
std::unique_ptr<OdeStepper> MakeOdeStepper(const std::string& name);
// The registered names in registration order.
std::vector<std::string> OdeMethodNames();
// Adds a method (Error kInvalidValue if the name is empty or taken). Thread-safe.
void RegisterOdeMethod(const std::string& name, OdeStepperFactory make);

}  // namespace impactdic

#endif  // IMPACTDIC_MODEL_ODE_STEPPER_H_
