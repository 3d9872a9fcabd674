// One default simulation (m_p 10 kg, h 0.7 m, D 0.15 m, Table 2 parameters) at rtol 1e-6 and
// 1e-10 with each solver: wall time per run and the RHS evaluations as counters. The error
// estimate's companion run is switched off so the time is that of one solution.
#include <benchmark/benchmark.h>

#include <map>

#include "impactdic/model/impact_model.h"
#include "impactdic/model/work_precision.h"

namespace impactdic {
namespace {

void BM_DefaultSimulation(benchmark::State& state, const char* solver, double rtol) {
  const ImpactModelParameters params;
  ImpactSolverOptions options = SolverSetting(solver, rtol);
  options.error_estimator = ErrorEstimator::kLocalSum;
  ImpactSummary last;
  for (auto _ : state) {
    ImpactRun run = SimulateImpact(params, options);
    benchmark::DoNotOptimize(run.summary.crater_depth_m);
    last = run.summary;
  }
  state.counters["rhs_evals"] = static_cast<double>(last.rhs_evals);
  state.counters["steps"] = static_cast<double>(last.steps);
  state.counters["jacobian_evals"] = static_cast<double>(last.jacobian_evals);
}

BENCHMARK_CAPTURE(BM_DefaultSimulation, auto_rtol_1em6, "auto", 1e-6)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_DefaultSimulation, auto_rtol_1em10, "auto", 1e-10)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_DefaultSimulation, stiff_rtol_1em6, "stiff", 1e-6)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_DefaultSimulation, stiff_rtol_1em10, "stiff", 1e-10)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_DefaultSimulation, ode45_defaults, "ode45", 1e-3)
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace impactdic

BENCHMARK_MAIN();
