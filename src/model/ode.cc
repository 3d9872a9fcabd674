// The adaptive step driver of IntegrateOde; the methods are OdeSteppers (ode_stepper.h), listed
// in ode_methods.def.
#include "impactdic/model/ode.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/core/strings.h"
#include "impactdic/model/ode_stepper.h"
#include "ode_norms.h"
#include "ode_steppers.h"

namespace impactdic {
namespace {

using internal::Axpy;
using internal::Finite;
using internal::RmsNorm;

// The built-in methods, in the order of ode_methods.def (the order messages list them). A new
// method adds one line there.
std::vector<std::pair<std::string, OdeStepperFactory>> BuiltinMethods() {
  return {
#define IMPACTDIC_ODE_METHOD(name, factory, file) {name, internal::factory},
#include "ode_methods.def"
#undef IMPACTDIC_ODE_METHOD
  };
}

struct MethodRegistry {
  std::mutex mutex;
  std::vector<std::pair<std::string, OdeStepperFactory>> methods = BuiltinMethods();
};

MethodRegistry& GetMethodRegistry() {
  static MethodRegistry registry;
  return registry;
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

// The landmarks strictly between x0 and x_end, then x_end, in the direction of integration.
std::vector<double> SortedLandmarks(const std::vector<double>& given, double x0, double x_end,
                                    double dir) {
  std::vector<double> landmarks;
  for (double l : given)
    if (std::isfinite(l) && (l - x0) * dir > 0 && (x_end - l) * dir > 0) landmarks.push_back(l);
  landmarks.push_back(x_end);
  std::sort(landmarks.begin(), landmarks.end(),
            [dir](double a, double b) { return a * dir < b * dir; });
  return landmarks;
}

// The adaptive loop: clip the proposed step, attempt it, reject (with the stepper's or a
// strong reduction) or accept, stop at x_end, a callback, a domain exit or a limit.
class Integrator {
 public:
  Integrator(const OdeSystem& system, const OdeOptions& options, std::vector<OdeStep>* steps)
      : opt_(options),
        steps_(steps),
        context_(system, options, &result_),
        stepper_(MakeOdeStepper(options.method)) {}

  OdeResult Run(double x0, const Vec2& y0, double x_end);

 private:
  // The step to attempt from x_: the proposed magnitude h_ clipped by the step limits and
  // stretched or shortened to end exactly on the next landmark. false (with result_.status set)
  // when the integration ends instead.
  bool NextTrialStep();
  // A trial that was not ok (non-finite, or outside the domain): ends the integration (false)
  // if the solution itself leaves the domain, else retries with a quarter of the step.
  bool HandleFailedTrial(const OdeTrial& trial);
  // Takes the accepted trial; false (with result_.status set) when the integration ends there.
  bool Accept(const OdeTrial& trial);

  const OdeOptions& opt_;
  std::vector<OdeStep>* steps_;
  OdeResult result_;
  OdeStepContext context_;
  std::unique_ptr<OdeStepper> stepper_;

  double dir_ = 1.0, x_end_ = 0.0;
  std::vector<double> landmarks_;
  std::size_t next_landmark_ = 0;
  double x_ = 0.0;
  Vec2 y_{}, f_{};
  double h_ = 0.0;  // Proposed step magnitude.
  bool last_rejected_ = false;
  int domain_exits_ = 0;  // Consecutive trial steps that left the domain.
  // The current trial step.
  double h_proposed_ = 0.0, hs_ = 0.0, x_target_ = 0.0;
  bool hits_landmark_ = false;
};

bool Integrator::NextTrialStep() {
  const double eps = std::numeric_limits<double>::epsilon();
  const double hmin = 16.0 * eps * std::max(std::abs(x_), 1e-300);
  h_proposed_ = h_;
  hs_ = std::min(h_, context_.StepLimit(x_));
  hits_landmark_ = false;
  while (next_landmark_ < landmarks_.size() && (landmarks_[next_landmark_] - x_) * dir_ <= hmin)
    ++next_landmark_;
  if (next_landmark_ == landmarks_.size()) {
    // Within round-off of x_end (a step landed a few ulps short of it): snap to it.
    x_ = x_end_;
    result_.x = x_;
    result_.status = OdeStatus::kReachedEnd;
    return false;
  }
  x_target_ = x_ + dir_ * hs_;
  const double dist = (landmarks_[next_landmark_] - x_) * dir_;
  // Stretch a step that would end just short of a landmark (never leave a sliver).
  if (hs_ >= dist * (1.0 - 1e-6)) {
    hs_ = dist;
    hits_landmark_ = true;
    x_target_ = landmarks_[next_landmark_];
  }
  if (hs_ < hmin) {
    result_.status = OdeStatus::kStepSizeUnderflow;
    return false;
  }
  return true;
}

bool Integrator::HandleFailedTrial(const OdeTrial& trial) {
  // A trial step can leave the domain because the solution does (the slope at the step's start
  // already carries it out) or because the step is too long for what lies ahead (a later stage
  // met a steep rise of the right-hand side, e.g. a sigmoid with a huge rate, while the slope at
  // the start stays inside): the latter is retried with shorter steps.
  if (opt_.stop_on_domain_exit && trial.domain_violation) {
    const Vec2 euler = Axpy(y_, x_target_ - x_, f_);
    if (!context_.InDomain(x_target_, euler) || ++domain_exits_ > opt_.domain_exit_retries) {
      result_.status = OdeStatus::kLeftDomain;
      return false;
    }
  }
  ++result_.rejected_steps;
  h_ = 0.25 * hs_;
  last_rejected_ = true;
  return true;
}

bool Integrator::Accept(const OdeTrial& trial) {
  ++result_.steps;
  domain_exits_ = 0;
  OdeStep step;
  step.x0 = x_;
  step.h = x_target_ - x_;
  step.y0 = y_;
  step.f0 = f_;
  step.y1 = trial.y1;
  step.f1 = trial.f1;
  step.local_error = trial.local_error;
  stepper_->Accepted(context_, trial, hs_, &step);
  if (steps_) steps_->push_back(step);

  double hnew = stepper_->AfterAcceptance(opt_, hs_, trial.error, last_rejected_);
  if (hits_landmark_) hnew = std::max(hnew, std::min(h_proposed_, 5.0 * hs_));
  h_ = hnew;
  last_rejected_ = false;

  x_ = x_target_;
  y_ = trial.y1;
  f_ = trial.f1;
  result_.x = x_;
  result_.y = y_;
  result_.f = f_;
  if (x_ == x_end_) {
    result_.status = OdeStatus::kReachedEnd;
    return false;
  }
  if (opt_.stop_after_step && opt_.stop_after_step(x_, y_, f_)) {
    result_.status = OdeStatus::kStoppedByCallback;
    return false;
  }
  return true;
}

OdeResult Integrator::Run(double x0, const Vec2& y0, double x_end) {
  dir_ = x_end >= x0 ? 1.0 : -1.0;
  x_end_ = x_end;
  landmarks_ = SortedLandmarks(opt_.landmarks, x0, x_end, dir_);
  x_ = x0;
  y_ = y0;
  f_ = context_.F(x_, y_);
  result_.x = x_;
  result_.y = y_;
  result_.f = f_;
  if (!Finite(f_) || !Finite(y_)) {
    result_.status = OdeStatus::kNonFiniteRhs;
    return result_;
  }
  if (x_ == x_end) return result_;
  h_ = opt_.initial_step > 0.0 ? opt_.initial_step
                               : stepper_->InitialStep(context_, x_, y_, f_, x_end, dir_);
  while (true) {
    if (result_.steps + result_.rejected_steps >= opt_.max_steps) {
      result_.status = OdeStatus::kMaxSteps;
      break;
    }
    if (!NextTrialStep()) break;
    const OdeTrial trial = stepper_->Attempt(context_, x_, y_, f_, x_target_ - x_, x_target_);
    if (!trial.ok) {
      if (!HandleFailedTrial(trial)) break;
      continue;
    }
    if (!stepper_->Accepts(opt_, trial.error)) {
      ++result_.rejected_steps;
      h_ = stepper_->AfterRejection(opt_, hs_, trial.error, last_rejected_);
      last_rejected_ = true;
      continue;
    }
    if (!Accept(trial)) break;
  }
  return result_;
}

}  // namespace

bool OdeStepContext::InDomain(double x, const Vec2& y) const {
  return Finite(y) && (!system_.in_domain || system_.in_domain(x, y));
}

double OdeStepContext::StepLimit(double x) const {
  double limit = options_.max_step;
  if (options_.max_step_at) limit = std::min(limit, options_.max_step_at(x));
  return limit;
}

double OdeStepper::InitialStep(OdeStepContext& c, double x, const Vec2& y, const Vec2& f,
                               double /*x_end*/, double dir) {
  // Hairer, Norsett, Wanner, sec. II.4 ("Starting step size").
  const OdeOptions& o = c.options();
  const double order = Order();
  const Vec2 zero{0.0, 0.0};
  const double dnf = RmsNorm(f, y, zero, o.rtol, o.atol);
  const double dny = RmsNorm(y, y, zero, o.rtol, o.atol);
  double h = (dnf <= 1e-5 || dny <= 1e-5) ? 1e-6 : 0.01 * dny / dnf;
  h = std::min(h, c.StepLimit(x));
  const Vec2 y1 = Axpy(y, dir * h, f);
  const Vec2 f1 = c.F(x + dir * h, y1);
  const Vec2 df{f1[0] - f[0], f1[1] - f[1]};
  double der2 = Finite(f1) ? RmsNorm(df, y, zero, o.rtol, o.atol) / h
                           : std::numeric_limits<double>::infinity();
  const double der12 = std::max(std::abs(der2), dnf);
  const double h1 = der12 <= 1e-15 ? std::max(1e-6, h * 1e-3) : std::pow(0.01 / der12, 1.0 / order);
  return std::min({100.0 * h, h1, c.StepLimit(x)});
}

bool OdeStepper::Accepts(const OdeOptions& /*options*/, double error) const { return error <= 1.0; }

void OdeStepper::Accepted(OdeStepContext& /*context*/, const OdeTrial& /*trial*/, double /*h_abs*/,
                          OdeStep* /*step*/) {}

std::unique_ptr<OdeStepper> MakeOdeStepper(const std::string& name) {
  MethodRegistry& registry = GetMethodRegistry();
  OdeStepperFactory make;
  {
    const std::lock_guard lock(registry.mutex);
    for (const auto& [n, f] : registry.methods)
      if (n == name) make = f;
  }
  if (!make)
    throw Error(ErrorKind::kInvalidValue, "OdeOptions.method", name, Join(OdeMethodNames(), ", "));
  return make();
}

std::vector<std::string> OdeMethodNames() {
  MethodRegistry& registry = GetMethodRegistry();
  const std::lock_guard lock(registry.mutex);
  std::vector<std::string> names;
  for (const auto& entry : registry.methods) names.push_back(entry.first);
  return names;
}

void RegisterOdeMethod(const std::string& name, OdeStepperFactory make) {
  CheckValue(!name.empty() && static_cast<bool>(make), "ODE method", name,
             "a non-empty name and a factory");
  MethodRegistry& registry = GetMethodRegistry();
  const std::lock_guard lock(registry.mutex);
  CheckValue(std::none_of(registry.methods.begin(), registry.methods.end(),
                          [&](const auto& entry) { return entry.first == name; }),
             "ODE method", name, "a name not yet registered");
  registry.methods.emplace_back(name, std::move(make));
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
