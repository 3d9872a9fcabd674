// Internal: the built-in ODE methods (ode_stepper.h), one factory per file, listed in the
// table of ode.cc.
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
std::unique_ptr<OdeStepper> MakeDopri5Stepper();  // "dopri5"
std::unique_ptr<OdeStepper> MakeOde45Stepper();   // "ode45"
std::unique_ptr<OdeStepper> MakeRodas3Stepper();  // "rodas3" (ode_rodas3.cc)
std::unique_ptr<OdeStepper> MakeAutoStepper();    // "auto" (ode_auto.cc)

}  // namespace impactdic::internal

#endif  // IMPACTDIC_SRC_MODEL_ODE_STEPPERS_H_
