// The momentum analysis on a chosen grid, for AnalyzeMomentum and the Monte Carlo of its
// uncertainty (uncertainty.cc), which repeats it on perturbed inputs.
#ifndef IMPACTDIC_SRC_MOMENTUM_MOMENTUM_INTERNAL_H_
#define IMPACTDIC_SRC_MOMENTUM_MOMENTUM_INTERNAL_H_

#include <vector>

#include "impactdic/kinematics/kinematics.h"
#include "impactdic/momentum/momentum.h"
#include "impactdic/sensor/sensor.h"

namespace impactdic::internal {

// AnalyzeMomentum after the grid's selection (its warnings unlogged, no uncertainty). Uses of the
// sensor record: time_s, velocity_m_s, penetration_m and summary.
MomentumResult AnalyzeMomentumOnGrid(const KinematicsResult& kin,
                                     const std::vector<double>& frame_time_s,
                                     const SensorResult& sensor, const MomentumOptions& options,
                                     const MomentumGrid& grid);

}  // namespace impactdic::internal

#endif  // IMPACTDIC_SRC_MOMENTUM_MOMENTUM_INTERNAL_H_
