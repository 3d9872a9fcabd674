// Internal: the built-in ODE methods (ode_stepper.h), one factory each, declared from the list
// ode_methods.def.
#ifndef IMPACTDIC_SRC_MODEL_ODE_STEPPERS_H_
#define IMPACTDIC_SRC_MODEL_ODE_STEPPERS_H_

#include <memory>

#include "impactdic/model/ode_stepper.h"

namespace impactdic::internal {

// Dormand-Prince 5(4): Hairer's controller and RMS norm ("dopri5"), or MATLAB ode45's norm,
// initial step and step factors ("ode45"); with Hairer's stiffness test if detect_stiffness.
std::unique_ptr<OdeStepper> MakeDopri5(bool ode45_rules, bool detect_stiffness);
// Whether the stiffness test of a stepper made by MakeDopri5 with detect_stiffness has fired.
bool StiffnessDetected(const OdeStepper& dopri5);

#define IMPACTDIC_ODE_METHOD(name, factory, file) std::unique_ptr<OdeStepper> factory();
#include "ode_methods.def"
#undef IMPACTDIC_ODE_METHOD

}  // namespace impactdic::internal

#endif  // IMPACTDIC_SRC_MODEL_ODE_STEPPERS_H_
