// "auto": Dormand-Prince 5(4) with Hairer's stiffness test; when it fires, the rest of the
// interval is integrated by Rodas3 (Hairer, Norsett, Wanner, Solving ODEs I, sec. IV.2).
#include <memory>

#include "impactdic/model/ode.h"
#include "impactdic/model/ode_stepper.h"
#include "ode_steppers.h"

namespace impactdic::internal {
namespace {

class AutoStepper final : public OdeStepper {
 public:
  AutoStepper()
      : dopri5_(MakeDopri5(/*ode45_rules=*/false, /*detect_stiffness=*/true)),
        rodas3_(MakeRodas3Stepper()) {}

  double Order() const override { return current().Order(); }
  double InitialStep(OdeStepContext& c, double x, const Vec2& y, const Vec2& f, double x_end,
                     double direction) override {
    return current().InitialStep(c, x, y, f, x_end, direction);
  }
  OdeTrial Attempt(OdeStepContext& c, double x, const Vec2& y, const Vec2& f, double h,
                   double x_target) override {
    return current().Attempt(c, x, y, f, h, x_target);
  }
  bool Accepts(const OdeOptions& o, double error) const override {
    return current().Accepts(o, error);
  }
  double AfterRejection(const OdeOptions& o, double h_abs, double error,
                        bool last_rejected) override {
    return current().AfterRejection(o, h_abs, error, last_rejected);
  }
  void Accepted(OdeStepContext& c, const OdeTrial& trial, double h_abs, OdeStep* step) override {
    current().Accepted(c, trial, h_abs, step);
    // The step size after the switching step already follows Rodas3's controller.
    if (!stiff_ && StiffnessDetected(*dopri5_)) stiff_ = true;
  }
  double AfterAcceptance(const OdeOptions& o, double h_abs, double error,
                         bool last_rejected) override {
    return current().AfterAcceptance(o, h_abs, error, last_rejected);
  }

 private:
  OdeStepper& current() const { return stiff_ ? *rodas3_ : *dopri5_; }

  std::unique_ptr<OdeStepper> dopri5_;
  std::unique_ptr<OdeStepper> rodas3_;
  bool stiff_ = false;
};

}  // namespace

std::unique_ptr<OdeStepper> MakeAutoStepper() { return std::make_unique<AutoStepper>(); }

}  // namespace impactdic::internal
