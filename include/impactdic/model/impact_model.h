// The added-mass impact model (Eq. 9 of Loewe, Thiele, Kanty, Kirstein: "Experimental
// investigation and modeling of impact stages during dynamic compaction"; equations in
// docs/model.md), SI units, z downward positive, t = 0 at contact:
//   (m_p + m_add) dv/dt = -(dm_add/dt) v + F_dyn + F_fr + F_g,
//   m_add = M / (1 + exp(-b (t - T)))                          (Eq. 5, 6)
//   F_g = (m_p + m_add) g,  F_fr = -k z,  F_dyn = -k z (u - 1) / v^n,  k = K rho_d g A  (Eq. 7, 8)
//   M = 425 m_p^0.1 v0^0.2 A^1.3 unless given                  (Eq. 4)
// simulated until v = 0 (the crater depth). The end is singular (v ~ (t_end - t)^(1/(1+n))): after
// the sigmoid has passed and once v is falling, the solver changes the independent variable to
// s = v^n (s = v if there is no v^-n term), integrating t(s) and z(s) down to s = 0, where the
// right-hand side is smooth; so t_end and the crater depth converge like any regular problem.
//
//   ImpactModelParameters p;             // Table 2 defaults, m_p = 10 kg, h = 0.7 m, D = 0.15 m
//   ImpactSolverOptions o;  o.rtol = 1e-8;
//   ImpactRun run = SimulateImpact(p, o);
//   std::cout << run.summary.BriefReport();
//   ImpactState s = run.solution.StateAt(0.005);   // dense output, any t in [0, t_end]
#ifndef IMPACTDIC_MODEL_IMPACT_MODEL_H_
#define IMPACTDIC_MODEL_IMPACT_MODEL_H_

#include <algorithm>
#include <cstddef>
#include <string>
#include <vector>

#include "impactdic/core/enum_names.h"
#include "impactdic/core/numeric.h"
#include "impactdic/core/range.h"
#include "impactdic/io/json.h"
#include "impactdic/model/ode.h"

namespace impactdic {

// v0 = sqrt(2 g h) for a free fall from height h (m) with gravity g (m/s^2).
double ImpactVelocityFromHeight(double height_m, double g_m_s2 = 9.81);

// Eq. 4: m_add,max = 425 m_p^0.1 v0^0.2 A^1.3 (kg; m_p in kg, v0 in m/s, A in m^2).
double AddedMassMaxEq4(double pounder_mass_kg, double impact_velocity_m_s, double area_m2);

struct ImpactModelParameters {
  // The k...Range limits are in core/range.h (shared with scene files and the CLI).
  double pounder_mass_kg = 10.0;  // m_p (kg), kPounderMassRange.
  // v0 (m/s), kImpactVelocityRange. Default: free fall from 0.7 m with g = 9.81.
  double impact_velocity_m_s = 3.7059411760037424;
  double width_m = 0.15;   // D (m), kPounderSizeRange.
  double depth_m = 0.192;  // t_z, out-of-plane depth (m), kPounderSizeRange; A = D t_z.
  // M = m_add,max (kg), kAddedMassRange; NaN: Eq. 4.
  double added_mass_kg = kNaN;
  double friction_K = 50.0;              // K, kFrictionKRange (dimensionless), Table 2.
  double damping_exponent_n = 0.2;       // n, in [0, 1], Table 2.
  double damping_factor_u = 1.9;         // u, kDampingFactorURange (F_dyn resists), Table 2.
  double sigmoid_delay_T_s = 0.002;      // T, kSigmoidDelayRange (s), Table 2.
  double sigmoid_rate_b_per_s = 2500.0;  // b, in (0, 1e12] (1/s), Table 2.
  double density_kg_m3 = 1550.0;         // rho_d, kSoilDensityRange.
  double gravity_m_s2 = 9.81;            // g, kGravityRange (0 for exact-solution checks).
  double bed_height_m = 0.6;             // For the "beyond the bed" warning, kBedHeightRange.

  // Throws Error(kInvalidValue) naming the first broken field and its allowed range (the ranges
  // of core/range.h: every force of Eq. 9 stays finite inside them).
  void Check() const;
  double ContactArea_m2() const { return width_m * depth_m; }
  double AddedMassMax_kg() const;  // M: the given value or Eq. 4.
  double Stiffness_N_m() const;    // k = K rho_d g A.
  // Whether the v^-n term is present (n > 0, k > 0, u > 1): the stop at v = 0 is then singular.
  bool SingularEnd() const;
};

// The added mass and its derivatives, overflow-safe for any b |t - T|.
struct AddedMass {
  double m_add_kg = 0.0;       // M sigma(x), x = b (t - T)
  double dm_dt_kg_s = 0.0;     // M b sigma (1 - sigma)
  double d2m_dt2_kg_s2 = 0.0;  // M b^2 sigma (1 - sigma) (1 - 2 sigma)
};
AddedMass AddedMassAt(double M_kg, double b_per_s, double T_s, double t_s);

// Every term of Eq. 9 at (t, z, v). For v <= 0 the v^-n term uses max(|v|, 1e-300) (the model is
// only meaningful for v > 0; this keeps trial stages finite).
struct ImpactForces {
  AddedMass added;
  double inertia_N = 0.0;   // -(dm_add/dt) v
  double dynamic_N = 0.0;   // F_dyn
  double friction_N = 0.0;  // F_fr
  double gravity_N = 0.0;   // F_g
  double dv_dt_m_s2 = 0.0;  // the sum over (m_p + m_add)
};
ImpactForces EvaluateImpactForces(const ImpactModelParameters& p, double M_kg, double t_s,
                                  double z_m, double v_m_s);

enum class ImpactSolver {
  kAuto,    // Dormand-Prince with stiffness detection, switching to Rodas3 if it fires.
  kDopri5,  // Dormand-Prince 5(4).
  kStiff,   // Rosenbrock Rodas3 with the analytic Jacobian.
};
inline constexpr EnumNames<ImpactSolver, 3> kImpactSolverNames{{{{ImpactSolver::kAuto, "auto"},
                                                                 {ImpactSolver::kDopri5, "dopri5"},
                                                                 {ImpactSolver::kStiff, "stiff"}}}};
const char* ToString(ImpactSolver solver);
// A name of kImpactSolverNames; Error(kInvalidValue) otherwise.
ImpactSolver ImpactSolverFromString(const std::string& name);

// How a run estimates its own error (ImpactSummary::error_estimate).
enum class ErrorEstimator {
  // A companion run at rtol / 10, atol / 10: error ~ |Q(tol) - Q(tol / 10)| / 0.9 (tolerance
  // proportionality; a Richardson-type estimate of the global error). Costs one more run. When
  // atol exceeds rtol times the solution's smallest scale (crater depth, v0, t_end), atol alone
  // governs the step control and tightening it tenfold may change nothing (atol = 1e300: both
  // runs take the same steps, and the difference is 0 whatever the true error): the companion's
  // atol is then rtol / 10 times that scale, so it is really ten times tighter, and a warning
  // says so.
  kCompanion,
  // The local error estimates summed over the steps, weighted by the sensitivity of the result
  // (a velocity error at t moves the crater depth by ~ (t_end - t) times it). Free, but it bounds
  // the error of the lower-order embedded solution, so it overestimates (see docs/model.md).
  kLocalSum,
};
inline constexpr EnumNames<ErrorEstimator, 2> kErrorEstimatorNames{
    {{{ErrorEstimator::kCompanion, "companion"}, {ErrorEstimator::kLocalSum, "local"}}}};
const char* ToString(ErrorEstimator estimator);
ErrorEstimator ErrorEstimatorFromString(const std::string& name);

// The relative tolerances the solver accepts (ImpactSolverOptions::rtol; the scene's model.rtol).
inline constexpr ValueRange kRelativeToleranceRange{1e-14, 0.1, ""};

struct ImpactSolverOptions {
  ImpactSolver solver = ImpactSolver::kAuto;
  // Relative tolerance, in kRelativeToleranceRange; NaN: 1e-6 (1e-3 with ode45_defaults).
  double rtol = kNaN;
  // Absolute tolerance (m, m/s; s in the end phase), > 0; NaN: 1e-3 * rtol (ode45's ratio).
  double atol = kNaN;
  ErrorEstimator error_estimator = ErrorEstimator::kCompanion;
  // MATLAB ode45's rules (error norm, initial step, step factors) on the Dormand-Prince pair;
  // with rtol/atol left at their defaults RelTol = 1e-3, AbsTol = 1e-6 (the paper's setting).
  // Only with solver kDopri5 or kAuto (then no stiffness switching).
  bool ode45_defaults = false;
  double t_max_s = 10.0;  // Give up (warning) if v has not reached 0 by then, > 0 (s).
  // The sigmoid is never stepped over: within |t - T| < window / b the step is at most
  // sigmoid_step / b, and no step jumps across the window start.
  double sigmoid_window = 8.0;  // > 0
  double sigmoid_step = 0.5;    // > 0
  // Switch to the end-phase variable once t > T + window / b, dv/dt < 0 and v < this fraction of
  // the largest velocity so far; in (0, 1].
  double switch_velocity_fraction = 0.25;
  long max_steps = 2000000;  // Per phase, > 0.
  // "tolerance not met" warning when the error estimate exceeds this factor times rtol; >= 1.
  double error_warning_factor = 10.0;

  void Check() const;
  // The tolerances actually used (ode45 defaults / the atol rule applied).
  double EffectiveRtol() const;
  double EffectiveAtol() const;
};

// The state at one time, from the dense output.
struct ImpactState {
  double t_s = 0.0, z_m = 0.0, v_m_s = 0.0;
};

// The trajectory as solver steps with their dense output (time phase: y = (z, v) over t; end
// phase: y = (t, z) over s, v = s^(1/p), p = n or 1).
class ImpactSolution {
 public:
  std::vector<OdeStep> time_steps;
  std::vector<OdeStep> end_steps;
  double end_exponent_p = 1.0;  // s = v^p in the end phase.
  double t_end_s = 0.0;         // Last time covered.
  double z_end_m = 0.0, v_end_m_s = 0.0;

  // State at t in [0, t_end_s] (clamped), by dense output (root-finding in the end phase).
  ImpactState StateAt(double t_s) const;
  // Number of samples along the trajectory: 0..N-1 = step ends (first: t = 0).
  std::vector<ImpactState> StepStates() const;
  // State at a continuous coordinate u in [0, time_steps + end_steps]: step index + theta.
  ImpactState AtCoordinate(double u) const;
  double CoordinateEnd() const { return static_cast<double>(time_steps.size() + end_steps.size()); }
};

struct ImpactSummary {
  double t_end_s = kNaN;
  double crater_depth_m = kNaN;
  double relative_penetration = kNaN;  // Eq. 10
  double added_mass_max_kg = kNaN;     // M
  double peak_deceleration_g = kNaN;   // -dv/dt / g
  double t_peak_s = kNaN;
  double plateau_deceleration_g = kNaN;  // v(t1)/(t_end-t1)/g
  double momentum_ratio = kNaN;          // m_add(t1) v(t1)/(m_p v0)
  double t1_s = kNaN;                    // T + 4 / b
  double v_t1_m_s = kNaN;
  bool stopped = false;  // v reached 0 before t_max.
  // Why the solve ended: "v = 0 reached" when stopped, else what stopped it (t_max reached,
  // step size underflow, step budget, a non-finite right-hand side ...). Without a stop, t_end_s,
  // the crater depth, the plateau deceleration and the momentum ratio are NaN.
  std::string stop_reason;
  double t_reached_s = kNaN;  // Last time covered.
  // "dopri5", "rodas3", "auto(dopri5)", "auto(dopri5->rodas3)", "ode45(dopri5)".
  std::string solver;
  std::string solver_reason;
  long steps = 0, rejected_steps = 0, rhs_evals = 0, jacobian_evals = 0;
  long end_phase_steps = 0;  // Of `steps`, those in the end-phase variable s.
  double t_switch_s = kNaN;  // Start of the end phase.
  // Relative global error estimate of the crater depth and t_end (max of the two): the local
  // error estimates, weighted by the sensitivity of the result to them (a velocity error at t
  // shifts the crater depth by ~ (t_end - t) times it), summed over the steps.
  // The estimate of `error_estimator` (see ErrorEstimator); both are always filled in when the
  // companion run was made. Never 0 unless the true error is: at least the round-off of the
  // steps (2 eps sqrt(steps)); +inf when the tolerance could not be met (step size underflow,
  // step budget); NaN when the solve never started.
  double error_estimate = kNaN;
  double error_estimate_local = kNaN;
  double error_estimate_companion = kNaN;
  std::string error_estimator;       // "companion" or "local"
  long companion_rhs_evals = 0;      // Cost of the companion run (not in rhs_evals).
  double wall_time_s = 0.0;          // Everything, the companion run included.
  double primary_wall_time_s = 0.0;  // The primary run alone.
  std::vector<std::string> warnings;

  bool IsUsable() const;
  std::string BriefReport() const;  // One line.
  std::string FullReport() const;   // Several lines.
  // The summary as JSON (`impactdic model --format json`), with the run's impact velocity and
  // effective tolerances (`params`, `options`: the run's).
  JsonObject ToJson(const ImpactModelParameters& params, const ImpactSolverOptions& options) const;
};

// Time series at the steps (t, z, v, dv/dt, m_add, dm_add/dt and each force term). At v = 0 the
// v^-n term and dv/dt are unbounded: they are NaN in the last row.
struct ImpactSeries {
  std::vector<double> t_s, z_m, v_m_s, dv_dt_m_s2, m_add_kg, dm_add_dt_kg_s, inertia_N, dynamic_N,
      friction_N, gravity_N;
  std::size_t size() const { return t_s.size(); }
};

struct ImpactRun {
  ImpactSummary summary;
  ImpactSolution solution;
};

// Runs the model. Throws Error(kInvalidValue) for bad parameters/options.
ImpactRun SimulateImpact(const ImpactModelParameters& params, const ImpactSolverOptions& options);

ImpactSeries MakeImpactSeries(const ImpactModelParameters& params, const ImpactRun& run);

// Writes the series as CSV (columns t_s, z_m, v_m_s, dv_dt_m_s2, m_add_kg, dm_add_dt_kg_s,
// inertia_N, dynamic_N, friction_N, gravity_N) or HDF5 (the /model group of a run's results.h5,
// model/model_results.h WriteModelResults; other groups of an existing file are kept), chosen by
// the extension (.csv, .h5/.hdf5).
void WriteImpactSeries(const std::string& path, const ImpactModelParameters& params,
                       const ImpactRun& run);
// The columns of WriteImpactSeries' CSV, in order.
std::vector<std::string> ImpactSeriesColumns();

// The exact solutions of docs/model.md (used by the tests and the work-precision study).
// (a) K = 0, g = 0: (m_p + m_add(t)) v(t) = (m_p + m_add(0)) v0; z(t) in closed form.
ImpactState ExactConservedMomentum(const ImpactModelParameters& p, double t_s);
// (b) M = 0, u = 1 (no added mass, no damping): m_p z'' = m_p g - k z. Stop time and depth.
struct HarmonicStop {
  double t_end_s, crater_depth_m;
};
HarmonicStop ExactHarmonicStop(const ImpactModelParameters& p);

}  // namespace impactdic

#endif  // IMPACTDIC_MODEL_IMPACT_MODEL_H_
