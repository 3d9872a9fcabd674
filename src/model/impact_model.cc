#include "impactdic/model/impact_model.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <numbers>

#include "impactdic/core/error.h"
#include "impactdic/core/numeric.h"
#include "impactdic/core/range.h"
#include "impactdic/core/timer.h"

namespace impactdic {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::string Num(double v) { return fmt::format("{:.6g}", v); }

// The relative round-off accumulated over `steps` steps: 2 eps sqrt(steps) (a random walk of one
// rounding per step and component), the least error a result can honestly claim.
double RoundOffFloor(long steps) {
  return 2 * std::numeric_limits<double>::epsilon() * std::sqrt(static_cast<double>(steps) + 1);
}

// Names the field and the rule when `ok` is false.
void Require(bool ok, const char* field, double value, const char* allowed) {
  CheckValue(ok, field, Num(value), allowed);
}

}  // namespace

double ImpactVelocityFromHeight(double height_m, double g_m_s2) {
  return std::sqrt(2.0 * g_m_s2 * height_m);
}

double AddedMassMaxEq4(double pounder_mass_kg, double impact_velocity_m_s, double area_m2) {
  return 425.0 * std::pow(pounder_mass_kg, 0.1) * std::pow(impact_velocity_m_s, 0.2) *
         std::pow(area_m2, 1.3);
}

void ImpactModelParameters::Check() const {
  // The ranges of a drop test, shared with scene files and the CLI (core/range.h).
  CheckRange(pounder_mass_kg, kPounderMassRange, "pounder_mass_kg", "a pounder mass");
  CheckRange(impact_velocity_m_s, kImpactVelocityRange, "impact_velocity_m_s",
             "an impact velocity");
  CheckRange(width_m, kPounderSizeRange, "width_m", "a pounder width D");
  CheckRange(depth_m, kPounderSizeRange, "depth_m", "an out-of-plane depth t_z");
  if (!std::isnan(added_mass_kg))
    CheckRange(added_mass_kg, kAddedMassRange, "added_mass_kg",
               "an added mass M (or unset: Eq. 4)");
  CheckRange(friction_K, kFrictionKRange, "friction_K", "a friction coefficient K");
  Require(std::isfinite(damping_exponent_n) && damping_exponent_n >= 0 && damping_exponent_n <= 1,
          "damping_exponent_n", damping_exponent_n, "n in [0, 1]");
  CheckRange(damping_factor_u, kDampingFactorURange, "damping_factor_u",
             "a damping factor u (>= 1: F_dyn must resist the motion)");
  CheckRange(sigmoid_delay_T_s, kSigmoidDelayRange, "sigmoid_delay_T_s", "a sigmoid delay T");
  Require(std::isfinite(sigmoid_rate_b_per_s) && sigmoid_rate_b_per_s > 0 &&
              sigmoid_rate_b_per_s <= 1e12,
          "sigmoid_rate_b_per_s", sigmoid_rate_b_per_s, "b in (0, 1e12] 1/s");
  CheckRange(density_kg_m3, kSoilDensityRange, "density_kg_m3", "a dry density");
  CheckRange(gravity_m_s2, kGravityRange, "gravity_m_s2", "a gravitational acceleration");
  CheckRange(bed_height_m, kBedHeightRange, "bed_height_m", "a bed height");
}

double ImpactModelParameters::AddedMassMax_kg() const {
  if (!std::isnan(added_mass_kg)) return added_mass_kg;
  return AddedMassMaxEq4(pounder_mass_kg, impact_velocity_m_s, ContactArea_m2());
}

double ImpactModelParameters::Stiffness_N_m() const {
  return friction_K * density_kg_m3 * gravity_m_s2 * ContactArea_m2();
}

bool ImpactModelParameters::SingularEnd() const {
  return damping_exponent_n > 0 && Stiffness_N_m() > 0 && damping_factor_u > 1;
}

AddedMass AddedMassAt(double M_kg, double b_per_s, double T_s, double t_s) {
  // sigma(x) = 1 / (1 + e^-x) written with e^-|x| only (never overflows);
  // sigma (1 - sigma) = e^-|x| / (1 + e^-|x|)^2; 1 - 2 sigma = -tanh(x / 2).
  const double x = b_per_s * (t_s - T_s);
  const double e = std::exp(-std::abs(x));
  const double sigma = x >= 0 ? 1.0 / (1.0 + e) : e / (1.0 + e);
  const double s1s = e / ((1.0 + e) * (1.0 + e));
  AddedMass out;
  out.m_add_kg = M_kg * sigma;
  out.dm_dt_kg_s = M_kg * b_per_s * s1s;
  // tanh(x / 2) = sign(x) (1 - e^-|x|) / (1 + e^-|x|), from the same exponential.
  const double tanh_half = (x >= 0 ? 1.0 : -1.0) * (1.0 - e) / (1.0 + e);
  out.d2m_dt2_kg_s2 = -M_kg * b_per_s * b_per_s * s1s * tanh_half;
  return out;
}

ImpactForces EvaluateImpactForces(const ImpactModelParameters& p, double M_kg, double t_s,
                                  double z_m, double v_m_s) {
  ImpactForces f;
  f.added = AddedMassAt(M_kg, p.sigmoid_rate_b_per_s, p.sigmoid_delay_T_s, t_s);
  const double m = p.pounder_mass_kg + f.added.m_add_kg;
  const double k = p.Stiffness_N_m();
  f.inertia_N = -f.added.dm_dt_kg_s * v_m_s;
  const double vn = p.damping_exponent_n == 0
                        ? 1.0
                        : std::pow(std::max(std::abs(v_m_s), 1e-300), p.damping_exponent_n);
  f.dynamic_N = -k * z_m * (p.damping_factor_u - 1.0) / vn;
  f.friction_N = -k * z_m;
  f.gravity_N = m * p.gravity_m_s2;
  f.dv_dt_m_s2 = (f.inertia_N + f.dynamic_N + f.friction_N + f.gravity_N) / m;
  return f;
}

const char* ToString(ImpactSolver solver) { return kImpactSolverNames.Name(solver); }

ImpactSolver ImpactSolverFromString(const std::string& name) {
  return kImpactSolverNames.Parse(name, "solver");
}

const char* ToString(ErrorEstimator estimator) { return kErrorEstimatorNames.Name(estimator); }

ErrorEstimator ErrorEstimatorFromString(const std::string& name) {
  return kErrorEstimatorNames.Parse(name, "error_estimator");
}

void ImpactSolverOptions::Check() const {
  CheckValue(std::isnan(rtol) || kRelativeToleranceRange.Contains(rtol), "rtol", Num(rtol),
             "a relative tolerance in " + kRelativeToleranceRange.Text() + " (or unset: 1e-6)");
  Require(std::isnan(atol) || (std::isfinite(atol) && atol > 0), "atol", atol,
          "an absolute tolerance > 0 (or unset: 1e-3 * rtol)");
  Require(std::isfinite(t_max_s) && t_max_s > 0, "t_max_s", t_max_s, "a time > 0 s");
  Require(std::isfinite(sigmoid_window) && sigmoid_window > 0, "sigmoid_window", sigmoid_window,
          "> 0");
  Require(std::isfinite(sigmoid_step) && sigmoid_step > 0, "sigmoid_step", sigmoid_step, "> 0");
  Require(switch_velocity_fraction > 0 && switch_velocity_fraction <= 1, "switch_velocity_fraction",
          switch_velocity_fraction, "a fraction in (0, 1]");
  Require(max_steps > 0, "max_steps", static_cast<double>(max_steps), "> 0");
  Require(error_warning_factor >= 1, "error_warning_factor", error_warning_factor, ">= 1");
  if (ode45_defaults && solver == ImpactSolver::kStiff)
    throw Error(ErrorKind::kInvalidValue, "ode45_defaults", "with solver stiff",
                "ode45 rules apply to the Dormand-Prince pair: solver auto or dopri5");
}

double ImpactSolverOptions::EffectiveRtol() const {
  if (!std::isnan(rtol)) return rtol;
  return ode45_defaults ? 1e-3 : 1e-6;
}

double ImpactSolverOptions::EffectiveAtol() const {
  if (!std::isnan(atol)) return atol;
  return 1e-3 * EffectiveRtol();  // ode45: RelTol 1e-3, AbsTol 1e-6
}

// ---------------------------------------------------------------------------------------------
// Dense output.

ImpactState ImpactSolution::AtCoordinate(double u) const {
  const double n_time = static_cast<double>(time_steps.size());
  u = std::clamp(u, 0.0, CoordinateEnd());
  ImpactState s;
  if (u < n_time || end_steps.empty()) {
    if (time_steps.empty()) return ImpactState{0.0, z_end_m, v_end_m_s};
    std::size_t i = std::min(static_cast<std::size_t>(u), time_steps.size() - 1);
    const OdeStep& st = time_steps[i];
    const double theta = std::clamp(u - static_cast<double>(i), 0.0, 1.0);
    const Vec2 y = theta == 1.0 ? st.y1 : st.Interpolate(theta);
    s.t_s = st.x0 + theta * st.h;
    s.z_m = y[0];
    s.v_m_s = y[1];
    return s;
  }
  std::size_t i = std::min(static_cast<std::size_t>(u - n_time), end_steps.size() - 1);
  const OdeStep& st = end_steps[i];
  const double theta = std::clamp(u - n_time - static_cast<double>(i), 0.0, 1.0);
  const Vec2 y = theta == 1.0 ? st.y1 : st.Interpolate(theta);
  const double sv = std::max(0.0, st.x0 + theta * st.h);
  s.t_s = y[0];
  s.z_m = y[1];
  s.v_m_s = std::pow(sv, 1.0 / end_exponent_p);
  return s;
}

ImpactState ImpactSolution::StateAt(double t_s) const {
  if (!time_steps.empty() && t_s <= time_steps.front().x0)
    return {time_steps.front().x0, time_steps.front().y0[0], time_steps.front().y0[1]};
  if (t_s >= t_end_s) return {t_end_s, z_end_m, v_end_m_s};
  // Time phase: find the step by binary search.
  if (!time_steps.empty() && t_s <= time_steps.back().x0 + time_steps.back().h) {
    auto it = std::upper_bound(time_steps.begin(), time_steps.end(), t_s,
                               [](double t, const OdeStep& s) { return t < s.x0; });
    const std::size_t i = (it == time_steps.begin()) ? 0 : (it - time_steps.begin()) - 1;
    const OdeStep& st = time_steps[i];
    const double theta = std::clamp((t_s - st.x0) / st.h, 0.0, 1.0);
    const Vec2 y = st.Interpolate(theta);
    return {t_s, y[0], y[1]};
  }
  // End phase: t increases along the steps; bisection on theta.
  auto it = std::upper_bound(end_steps.begin(), end_steps.end(), t_s,
                             [](double t, const OdeStep& s) { return t < s.y0[0]; });
  const std::size_t i = (it == end_steps.begin()) ? 0 : (it - end_steps.begin()) - 1;
  if (i >= end_steps.size()) return {t_end_s, z_end_m, v_end_m_s};
  const OdeStep& st = end_steps[i];
  double lo = 0.0, hi = 1.0;
  for (int iter = 0; iter < 200 && hi - lo > 1e-17; ++iter) {
    const double mid = 0.5 * (lo + hi);
    if (st.Interpolate(mid)[0] < t_s)
      lo = mid;
    else
      hi = mid;
  }
  const double theta = 0.5 * (lo + hi);
  const Vec2 y = st.Interpolate(theta);
  const double sv = std::max(0.0, st.x0 + theta * st.h);
  return {t_s, y[1], std::pow(sv, 1.0 / end_exponent_p)};
}

std::vector<ImpactState> ImpactSolution::StepStates() const {
  std::vector<ImpactState> out;
  if (!time_steps.empty())
    out.push_back({time_steps.front().x0, time_steps.front().y0[0], time_steps.front().y0[1]});
  for (const OdeStep& st : time_steps) out.push_back({st.x0 + st.h, st.y1[0], st.y1[1]});
  for (const OdeStep& st : end_steps) {
    const double sv = std::max(0.0, st.x0 + st.h);
    out.push_back({st.y1[0], st.y1[1], std::pow(sv, 1.0 / end_exponent_p)});
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// The simulation.

namespace {

struct PeakResult {
  double value = kNaN;  // -dv/dt (m/s^2)
  double t = kNaN;
};

// The largest distinct interior local maximum of -dv/dt along the trajectory: sampled at 4
// points per time-phase step and 2 per end-phase step (-dv/dt grows monotonically there),
// candidates are positive samples (a deceleration) larger than both neighbours whose
// topographic prominence exceeds 1e-3 of their value; each candidate is refined by
// golden-section search on the dense output over its two neighbouring samples.
PeakResult FindPeak(const ImpactModelParameters& p, double M, const ImpactSolution& sol) {
  auto decel = [&](double u) {
    const ImpactState s = sol.AtCoordinate(u);
    if (s.v_m_s <= 0.0) return kInf;
    return -EvaluateImpactForces(p, M, s.t_s, s.z_m, s.v_m_s).dv_dt_m_s2;
  };
  std::vector<double> us;
  for (std::size_t i = 0; i < sol.time_steps.size(); ++i)
    for (int j = 0; j < 4; ++j) us.push_back(static_cast<double>(i) + 0.25 * j);
  const double n_time = static_cast<double>(sol.time_steps.size());
  for (std::size_t i = 0; i < sol.end_steps.size(); ++i)
    for (int j = 0; j < 2; ++j) us.push_back(n_time + static_cast<double>(i) + 0.5 * j);
  us.push_back(sol.CoordinateEnd());
  const int n = static_cast<int>(us.size()) - 1;
  if (n < 3) return {};
  std::vector<double> g(n + 1);
  for (int i = 0; i <= n; ++i) g[i] = decel(us[i]);
  PeakResult best;
  for (int i = 1; i < n; ++i) {
    if (!(g[i] > g[i - 1] && g[i] >= g[i + 1])) continue;
    double left_min = g[i], right_min = g[i];
    for (int j = i - 1; j >= 0 && g[j] <= g[i]; --j) left_min = std::min(left_min, g[j]);
    for (int j = i + 1; j <= n && g[j] <= g[i]; ++j) right_min = std::min(right_min, g[j]);
    const double prominence = g[i] - std::max(left_min, right_min);
    // A peak of deceleration: positive, and distinct from the numerical ripple.
    if (!(g[i] > 0.0) || !(prominence > 1e-3 * std::abs(g[i]) + 1e-9)) continue;
    // Golden-section search for the maximum in [u_{i-1}, u_{i+1}].
    const double u = GoldenSectionMaximize(decel, us[i - 1], us[i + 1],
                                           {.max_iterations = 200, .relative_tolerance = 1e-10});
    const double value = std::max(decel(u), g[i]);
    if (std::isnan(best.value) || value > best.value) {
      best.value = value;
      best.t = decel(u) >= g[i] ? sol.AtCoordinate(u).t_s : sol.AtCoordinate(us[i]).t_s;
    }
  }
  return best;
}

}  // namespace

namespace {

// The constants of one simulation, derived once from the parameters and the solver options.
struct Simulation {
  const ImpactModelParameters& p;
  const ImpactSolverOptions& options;
  double M, k, mp, g, u1, n, b, T;
  bool singular;      // The v^-n damping term makes v = 0 a singular end (SingularEnd()).
  double pexp;        // s = v^pexp in the end phase.
  double rtol, atol;  // Effective tolerances.
  double t1;          // Start of the plateau, T + 4 / b.
  double tw0, tw1;    // The sigmoid window where steps are limited to h_window.
  double h_window;
  std::string method;  // The ODE method (ode_stepper.h).

  Simulation(const ImpactModelParameters& params, const ImpactSolverOptions& solver_options)
      : p(params), options(solver_options) {
    M = p.AddedMassMax_kg();
    k = p.Stiffness_N_m();
    mp = p.pounder_mass_kg;
    g = p.gravity_m_s2;
    u1 = p.damping_factor_u - 1.0;
    n = p.damping_exponent_n;
    b = p.sigmoid_rate_b_per_s;
    T = p.sigmoid_delay_T_s;
    singular = p.SingularEnd();
    pexp = singular ? n : 1.0;
    rtol = options.EffectiveRtol();
    atol = options.EffectiveAtol();
    t1 = T + 4.0 / b;
    tw0 = T - options.sigmoid_window / b;
    tw1 = T + options.sigmoid_window / b;
    h_window = options.sigmoid_step / b;
    method = options.ode45_defaults                   ? "ode45"
             : options.solver == ImpactSolver::kStiff ? "rodas3"
             : options.solver == ImpactSolver::kAuto  ? "auto"
                                                      : "dopri5";
  }
};

// What the integrations report beyond the solution.
struct IntegrationNotes {
  bool stiff_switch = false;  // "auto" switched to Rodas3 ...
  double stiff_at = kNaN;     // ... at this time [s].
  double max_h_lambda = 0.0;  // Largest stiffness indicator of the Dormand-Prince steps.
  bool tolerance_trouble = false;
};

// Time phase: y = (z, v), x = t, Eq. 9 with its analytic Jacobian; v > 0 is the domain.
OdeSystem TimePhaseSystem(const Simulation& c) {
  OdeSystem sys;
  sys.rhs = [&c](double t, const Vec2& y) {
    return Vec2{y[1], EvaluateImpactForces(c.p, c.M, t, y[0], y[1]).dv_dt_m_s2};
  };
  sys.jacobian = [&c](double t, const Vec2& y, Mat2* J, Vec2* ft) {
    const ImpactForces f = EvaluateImpactForces(c.p, c.M, t, y[0], y[1]);
    const double m = c.mp + f.added.m_add_kg;
    const double v = std::max(std::abs(y[1]), 1e-300);
    const double vn = c.n == 0 ? 1.0 : std::pow(v, c.n);
    const double a_z = (-c.k * c.u1 / vn - c.k) / m;
    const double a_v = (-f.added.dm_dt_kg_s + c.n * c.k * y[0] * c.u1 / (vn * v)) / m;
    const double a_t = (-f.added.d2m_dt2_kg_s2 * y[1] + f.added.dm_dt_kg_s * c.g -
                        f.dv_dt_m_s2 * f.added.dm_dt_kg_s) /
                       m;
    *J = {0.0, 1.0, a_z, a_v};
    *ft = {0.0, a_t};
  };
  sys.in_domain = [](double, const Vec2& y) { return y[1] > 0.0; };
  return sys;
}

// Integrates the time phase until the switch to the end phase (v has fallen below
// switch_velocity_fraction of its maximum after the sigmoid window, and v = 0 can be reached).
OdeResult IntegrateTimePhase(const Simulation& c, ImpactRun* run) {
  const OdeSystem time_sys = TimePhaseSystem(c);
  double vmax = c.p.impact_velocity_m_s;
  auto end_phase_ready = [&](double t, const Vec2& y, double a) {
    if (!(a < 0.0)) return false;
    if (c.singular) return c.k * y[0] * c.u1 > 0.0;
    // Regular end: dv/dt at v = 0 must be negative for v to reach 0.
    return EvaluateImpactForces(c.p, c.M, t, y[0], 0.0).dv_dt_m_s2 < 0.0;
  };
  OdeOptions to;
  to.method = c.method;
  to.rtol = c.rtol;
  to.atol = c.atol;
  to.max_steps = c.options.max_steps;
  to.landmarks = {c.tw0, c.tw1, c.t1};
  to.max_step_at = [&](double t) { return (t >= c.tw0 && t < c.tw1) ? c.h_window : kInf; };
  if (c.method == "ode45") to.max_step = 0.1 * c.options.t_max_s;  // ode45's MaxStep rule
  to.stop_on_domain_exit = true;
  to.stop_after_step = [&](double t, const Vec2& y, const Vec2& f) {
    vmax = std::max(vmax, y[1]);
    return t >= c.tw1 && y[1] <= c.options.switch_velocity_fraction * vmax &&
           end_phase_ready(t, y, f[1]);
  };
  return IntegrateOde(time_sys, 0.0, {0.0, c.p.impact_velocity_m_s}, c.options.t_max_s, to,
                      &run->solution.time_steps);
}

// Records how the time phase ended; true if the end phase should follow.
bool TimePhaseEnded(const Simulation& c, const OdeResult& r1, ImpactSummary* sum,
                    IntegrationNotes* notes) {
  switch (r1.status) {
    case OdeStatus::kReachedEnd:
      sum->stop_reason =
          fmt::format("v did not reach 0 by t_max = {} s (v = {} m/s, z = {} m): no crater depth",
                      Num(c.options.t_max_s), Num(r1.y[1]), Num(r1.y[0]));
      sum->warnings.push_back(sum->stop_reason);
      return false;
    case OdeStatus::kStoppedByCallback: return true;
    case OdeStatus::kLeftDomain:
      if (r1.f[1] < 0.0) return true;
      sum->stop_reason = fmt::format(
          "a step would have made v <= 0 at t = {} s while dv/dt >= 0; stopped there", Num(r1.x));
      sum->warnings.push_back(sum->stop_reason);
      return false;
    case OdeStatus::kStepSizeUnderflow:
    case OdeStatus::kMaxSteps:
      notes->tolerance_trouble = true;
      sum->stop_reason = fmt::format("tolerance not met: {} at t = {} s in the time phase",
                                     ToString(r1.status), Num(r1.x));
      sum->warnings.push_back(sum->stop_reason);
      return r1.f[1] < 0.0 && r1.y[1] > 0.0;
    case OdeStatus::kNonFiniteRhs:
      sum->stop_reason = fmt::format(
          "dv/dt is not finite at t = 0 (z = 0, v = {} m/s): the parameters overflow Eq. 9",
          Num(r1.y[1]));
      sum->warnings.push_back(sum->stop_reason);
      return false;
  }
  return false;
}

// End phase: q = v^n dv/dt (singular end) or dv/dt (regular end) at (s, y = (t, z)), and its
// partial derivatives.
struct QTerms {
  double q, q_t, q_z, q_s, v, dv_ds;
};

QTerms EndPhaseTerms(const Simulation& c, double s, const Vec2& y) {
  QTerms r{};
  const double t = y[0], z = y[1];
  const double sv = std::max(s, 0.0);
  const AddedMass am = AddedMassAt(c.M, c.b, c.T, t);
  const double m = c.mp + am.m_add_kg;
  const double n = c.n, k = c.k, u1 = c.u1, g = c.g;
  if (c.singular) {
    r.v = std::pow(sv, 1.0 / n);
    r.dv_ds = std::pow(sv, 1.0 / n - 1.0) / n;
    const double G = -am.dm_dt_kg_s * r.v - k * z + m * g;
    const double P = sv * G - k * z * u1;
    r.q = P / m;
    const double P_t = sv * (-am.d2m_dt2_kg_s2 * r.v + am.dm_dt_kg_s * g);
    r.q_t = P_t / m - P * am.dm_dt_kg_s / (m * m);
    r.q_z = (-sv * k - k * u1) / m;
    r.q_s = (G - am.dm_dt_kg_s * r.v / n) / m;
  } else {
    r.v = sv;
    r.dv_ds = 1.0;
    const ImpactForces f = EvaluateImpactForces(c.p, c.M, t, z, sv);
    r.q = f.dv_dt_m_s2;
    const double vn = n == 0 ? 1.0 : std::pow(std::max(sv, 1e-300), n);
    r.q_z = (-k * u1 / vn - k) / m;
    r.q_s = (-am.dm_dt_kg_s) / m;  // no v^-n term here (regular end)
    r.q_t = (-am.d2m_dt2_kg_s2 * sv + am.dm_dt_kg_s * g - r.q * am.dm_dt_kg_s) / m;
  }
  return r;
}

// End phase: y = (t, z), x = s = v^pexp, integrated from s0 down to 0; q < 0 is the domain.
OdeSystem EndPhaseSystem(const Simulation& c) {
  OdeSystem sys;
  sys.rhs = [&c](double s, const Vec2& y) {
    const QTerms q = EndPhaseTerms(c, s, y);
    // singular: dt/ds = (dv/ds) / a = v / (n q); regular: dt/ds = 1 / a.
    const double dtds = c.singular ? q.v / (c.n * q.q) : 1.0 / q.q;
    return Vec2{dtds, q.v * dtds};
  };
  sys.jacobian = [&c](double s, const Vec2& y, Mat2* J, Vec2* fs) {
    const QTerms q = EndPhaseTerms(c, s, y);
    double f1, f1_t, f1_z, f1_s;
    if (c.singular) {
      f1 = q.v / (c.n * q.q);
      const double d = -q.v / (c.n * q.q * q.q);
      f1_t = d * q.q_t;
      f1_z = d * q.q_z;
      f1_s = q.dv_ds / (c.n * q.q) + d * q.q_s;
    } else {
      f1 = 1.0 / q.q;
      const double d = -1.0 / (q.q * q.q);
      f1_t = d * q.q_t;
      f1_z = d * q.q_z;
      f1_s = d * q.q_s;
    }
    *J = {f1_t, f1_z, q.v * f1_t, q.v * f1_z};
    *fs = {f1_s, q.dv_ds * f1 + q.v * f1_s};
  };
  sys.in_domain = [&c](double s, const Vec2& y) {
    const double q = EndPhaseTerms(c, s, y).q;
    return q < 0.0 && std::isfinite(q);
  };
  return sys;
}

// Integrates the end phase from where the time phase stopped (r1) to v = 0.
void IntegrateEndPhase(const Simulation& c, const OdeResult& r1, ImpactRun* run,
                       IntegrationNotes* notes) {
  ImpactSummary& sum = run->summary;
  ImpactSolution& sol = run->solution;
  sum.t_switch_s = r1.x;
  const OdeSystem end_sys = EndPhaseSystem(c);
  double last_t = r1.x;
  double last_dtds = 0.0;
  OdeOptions eo;
  eo.method = (c.method == "auto" && notes->stiff_switch) ? "rodas3" : c.method;
  eo.rtol = c.rtol;
  eo.atol = c.atol;
  eo.max_steps = c.options.max_steps;
  // Never step over the sigmoid in time either (only matters if the switch came early).
  eo.max_step_at = [&](double) {
    if (last_t < c.tw1 && last_dtds != 0.0) return c.h_window / std::abs(last_dtds);
    return kInf;
  };
  eo.stop_after_step = [&](double, const Vec2& y, const Vec2& f) {
    last_t = y[0];
    last_dtds = f[0];
    return false;
  };
  const double s0 = std::pow(r1.y[1], c.pexp);
  last_dtds = end_sys.rhs(s0, {r1.x, r1.y[0]})[0];
  const OdeResult r2 = IntegrateOde(end_sys, s0, {r1.x, r1.y[0]}, 0.0, eo, &sol.end_steps);
  sum.steps += r2.steps;
  sum.end_phase_steps = r2.steps;
  sum.rejected_steps += r2.rejected_steps;
  sum.rhs_evals += r2.rhs_evals + 1;
  sum.jacobian_evals += r2.jacobian_evals;
  if (r2.stiffness_detected && !notes->stiff_switch) {
    notes->stiff_switch = true;
    notes->stiff_at = r2.y[0];
  }
  notes->max_h_lambda = std::max(notes->max_h_lambda, r2.max_h_lambda);
  sol.t_end_s = r2.y[0];
  sol.z_end_m = r2.y[1];
  sol.v_end_m_s = std::pow(std::max(r2.x, 0.0), 1.0 / c.pexp);
  if (r2.status == OdeStatus::kReachedEnd) {
    sum.stopped = true;
    sol.v_end_m_s = 0.0;
  } else {
    notes->tolerance_trouble = true;
    sum.stop_reason = fmt::format(
        "tolerance not met: {} in the end phase at v = {} m/s (t = {} s); v = 0 not reached",
        ToString(r2.status), Num(sol.v_end_m_s), Num(r2.y[0]));
    sum.warnings.push_back(sum.stop_reason);
  }
}

// Error estimate: sensitivity-weighted sum of the local error estimates.
void EstimateErrorFromLocalErrors(const ImpactSolution& sol, ImpactSummary* sum) {
  double ez = 0.0, et = 0.0;
  const double t_end = sol.t_end_s;
  for (const OdeStep& st : sol.time_steps) {
    const double te = st.x0 + st.h;
    const double remaining = std::max(t_end - te, 0.0);
    const double v = std::max(st.y1[1], 1e-300);
    ez += std::abs(st.local_error[0]) + std::abs(st.local_error[1]) * remaining;
    et += std::abs(st.local_error[1]) * remaining / v;
  }
  for (const OdeStep& st : sol.end_steps) {
    et += std::abs(st.local_error[0]);
    ez += std::abs(st.local_error[1]);
  }
  const double zref = std::abs(sol.z_end_m), tref = std::abs(t_end);
  sum->error_estimate_local =
      std::max({zref > 0 ? ez / zref : 0.0, tref > 0 && sum->stopped ? et / tref : 0.0,
                RoundOffFloor(sum->steps)});
  sum->error_estimate = sum->error_estimate_local;
  sum->error_estimator = "local";
}

// Peak deceleration (FindPeak), plateau deceleration and momentum ratio at t1.
void AddKeyFigures(const Simulation& c, const ImpactSolution& sol, double g_unit,
                   ImpactSummary* sum) {
  const PeakResult peak = FindPeak(c.p, c.M, sol);
  sum->peak_deceleration_g = peak.value / g_unit;
  sum->t_peak_s = peak.t;
  if (std::isnan(peak.value) && !sol.time_steps.empty()) {
    sum->warnings.push_back(
        sum->stopped
            ? "no distinct peak: -dv/dt has no interior local maximum on (0, t_end) (the pounder "
              "is still accelerating during the peak stage); peak deceleration is NaN"
            : fmt::format("no distinct peak: -dv/dt has no interior local maximum on the part "
                          "solved, (0, {} s); peak deceleration is NaN",
                          Num(sol.t_end_s)));
  }
  const double t1 = c.t1;
  if (sum->stopped && t1 < sol.t_end_s) {
    ImpactState s1;
    bool exact = false;
    for (const OdeStep& st : sol.time_steps) {
      if (st.x0 + st.h == t1) {
        s1 = {t1, st.y1[0], st.y1[1]};
        exact = true;
        break;
      }
    }
    if (!exact) s1 = sol.StateAt(t1);
    sum->v_t1_m_s = s1.v_m_s;
    sum->plateau_deceleration_g = s1.v_m_s / (sol.t_end_s - t1) / g_unit;
    sum->momentum_ratio =
        AddedMassAt(c.M, c.b, c.T, t1).m_add_kg * s1.v_m_s / (c.mp * c.p.impact_velocity_m_s);
  } else if (sum->stopped) {
    sum->warnings.push_back(fmt::format(
        "the pounder stopped at t_end = {} s before t1 = T + 4/b = {} s: no plateau deceleration "
        "or momentum ratio",
        Num(sol.t_end_s), Num(t1)));
  }
}

// Physical warnings: stopped only by the damping term, penetration beyond the bed.
void AddPhysicalWarnings(const Simulation& c, const ImpactSolution& sol, ImpactSummary* sum) {
  if (sum->stopped && c.singular) {
    const double m_end = c.mp + AddedMassAt(c.M, c.b, c.T, sol.t_end_s).m_add_kg;
    const double friction = c.k * sol.z_end_m, weight = m_end * c.g;
    if (friction < weight)
      sum->warnings.push_back(fmt::format(
          "stopped only by the v^-n damping term: friction k z = {} N is below the weight "
          "(m_p + m_add) g = {} N at v = 0",
          Num(friction), Num(weight)));
  }
  const double z_final = sum->stopped ? sum->crater_depth_m : sol.z_end_m;
  if (z_final > c.p.bed_height_m)
    sum->warnings.push_back(fmt::format(
        "penetration {} m is beyond the bed height {} m (the model's soil is unbounded below)",
        Num(z_final), Num(c.p.bed_height_m)));
}

// Which solver ran and why.
void DescribeSolver(const Simulation& c, const IntegrationNotes& notes, ImpactSummary* sum) {
  if (c.method == "ode45") {
    sum->solver = "ode45(dopri5)";
    sum->solver_reason = fmt::format(
        "requested ode45_defaults: Dormand-Prince 5(4) with MATLAB ode45's error norm, initial "
        "step and step factors, RelTol {}, AbsTol {}",
        Num(c.rtol), Num(c.atol));
  } else if (c.method == "rodas3") {
    sum->solver = "rodas3";
    sum->solver_reason = "requested: stiff solver (Rosenbrock Rodas3, analytic Jacobian)";
  } else if (c.method == "dopri5") {
    sum->solver = "dopri5";
    sum->solver_reason = "requested: Dormand-Prince 5(4)";
  } else if (notes.stiff_switch) {
    sum->solver = "auto(dopri5->rodas3)";
    sum->solver_reason = fmt::format(
        "Hairer's stiffness test fired (h|lambda| > 3.25 on 15 accepted Dormand-Prince steps) at "
        "t = {} s; the rest was integrated by Rodas3",
        Num(notes.stiff_at));
  } else {
    sum->solver = "auto(dopri5)";
    sum->solver_reason = fmt::format(
        "no stiffness detected (Hairer's test did not fire: it needs h|lambda| > 3.25 on 15 "
        "accepted Dormand-Prince steps without 6 below it; largest h|lambda| {:.3g}): the step "
        "limit {} s near the sigmoid keeps Dormand-Prince stable",
        notes.max_h_lambda, Num(c.h_window));
  }
}

// One run with the local-sum estimate (no companion run, no tolerance warning): the time phase,
// the end phase in s = v^pexp when the pounder is about to stop, then the key figures.
ImpactRun SimulateOnce(const ImpactModelParameters& params, const ImpactSolverOptions& options) {
  WallTimer timer;
  const Simulation c(params, options);
  ImpactRun run;
  ImpactSummary& sum = run.summary;
  ImpactSolution& sol = run.solution;
  sol.end_exponent_p = c.pexp;
  sum.added_mass_max_kg = c.M;
  sum.t1_s = c.t1;

  const OdeResult r1 = IntegrateTimePhase(c, &run);
  sum.steps = r1.steps;
  sum.rejected_steps = r1.rejected_steps;
  sum.rhs_evals = r1.rhs_evals;
  sum.jacobian_evals = r1.jacobian_evals;
  IntegrationNotes notes;
  notes.stiff_switch = r1.stiffness_detected;
  notes.stiff_at = r1.stiffness_x;
  notes.max_h_lambda = r1.max_h_lambda;
  sol.t_end_s = r1.x;
  sol.z_end_m = r1.y[0];
  sol.v_end_m_s = r1.y[1];
  if (TimePhaseEnded(c, r1, &sum, &notes)) IntegrateEndPhase(c, r1, &run, &notes);

  if (sum.stopped) sum.stop_reason = "v = 0 reached";
  if (sum.stop_reason.empty()) sum.stop_reason = "v = 0 not reached";
  sum.t_reached_s = sol.t_end_s;
  sum.t_end_s = sum.stopped ? sol.t_end_s : kNaN;
  const double g_unit = c.g > 0 ? c.g : 9.81;
  if (sum.stopped) {
    sum.crater_depth_m = sol.z_end_m;
    sum.relative_penetration = sol.z_end_m / params.width_m;
  }
  EstimateErrorFromLocalErrors(sol, &sum);
  AddKeyFigures(c, sol, g_unit, &sum);
  AddPhysicalWarnings(c, sol, &sum);
  if (notes.tolerance_trouble) sum.error_estimate = std::numeric_limits<double>::infinity();
  DescribeSolver(c, notes, &sum);
  sum.wall_time_s = timer.ElapsedSeconds();
  sum.primary_wall_time_s = sum.wall_time_s;
  return run;
}

}  // namespace

namespace {

// The companion run's atol (ErrorEstimator::kCompanion): atol / 10, but at most rtol / 10 times
// the solution's smallest scale (crater depth or depth reached, v0, t_end), so that the companion
// is ten times tighter even where atol alone governed the primary run's steps (then a warning).
double CompanionAtol(const ImpactModelParameters& p, const ImpactSolverOptions& options,
                     const ImpactRun& primary, std::vector<std::string>* warnings) {
  const double rtol = options.EffectiveRtol(), atol = options.EffectiveAtol();
  double scale = p.impact_velocity_m_s;
  for (double x : {std::abs(primary.solution.z_end_m), primary.solution.t_end_s})
    if (x > 0 && std::isfinite(x)) scale = std::min(scale, x);
  if (atol <= rtol * scale) return atol / 10.0;
  warnings->push_back(fmt::format(
      "atol {} exceeds rtol x the solution's smallest scale ({} x {} = {}): atol governs the step "
      "control, so the error estimate's companion run uses atol {} (rtol / 10 x that scale) "
      "instead of atol / 10",
      Num(atol), Num(rtol), Num(scale), Num(rtol * scale), Num(rtol * scale / 10.0)));
  return rtol * scale / 10.0;
}

}  // namespace

ImpactRun SimulateImpact(const ImpactModelParameters& params, const ImpactSolverOptions& options) {
  params.Check();
  options.Check();
  WallTimer timer;
  ImpactRun run = SimulateOnce(params, options);
  ImpactSummary& sum = run.summary;
  const double rtol = options.EffectiveRtol();
  if (sum.steps == 0) {
    // Nothing was integrated (e.g. a non-finite right-hand side at the start): no estimate.
    sum.error_estimate = sum.error_estimate_local = kNaN;
  } else if (options.error_estimator == ErrorEstimator::kCompanion) {
    ImpactSolverOptions tighter = options;
    tighter.rtol = rtol / 10.0;
    tighter.atol = CompanionAtol(params, options, run, &sum.warnings);
    const ImpactRun companion = SimulateOnce(params, tighter);
    sum.companion_rhs_evals = companion.summary.rhs_evals;
    auto rel = [](double a, double b) { return std::abs(a - b) / std::max(std::abs(b), 1e-300); };
    double diff;
    if (sum.stopped && companion.summary.stopped) {
      diff = std::max(rel(sum.crater_depth_m, companion.summary.crater_depth_m),
                      rel(sum.t_end_s, companion.summary.t_end_s));
    } else {
      diff = std::max(
          rel(run.solution.z_end_m, companion.solution.z_end_m),
          rel(run.solution.v_end_m_s, companion.solution.v_end_m_s) * (sum.stopped ? 0.0 : 1.0));
    }
    // Under tolerance proportionality err(tol) ~ C tol, so Q(tol) - Q(tol/10) ~ 0.9 err(tol);
    // never below the round-off of the steps (the runs can agree to the last bit).
    sum.error_estimate_companion = std::max(diff / 0.9, RoundOffFloor(sum.steps));
    if (std::isfinite(sum.error_estimate))  // not already infinite (tolerance trouble)
      sum.error_estimate = sum.error_estimate_companion;
    sum.error_estimator = "companion";
  }
  if (std::isfinite(sum.error_estimate) && sum.error_estimate > options.error_warning_factor * rtol)
    sum.warnings.push_back(
        fmt::format("tolerance not met: the error estimate ({}) {} exceeds {} x rtol = {}",
                    sum.error_estimator, Num(sum.error_estimate), Num(options.error_warning_factor),
                    Num(options.error_warning_factor * rtol)));
  sum.wall_time_s = timer.ElapsedSeconds();
  return run;
}

// ---------------------------------------------------------------------------------------------

JsonObject ImpactSummary::ToJson(const ImpactModelParameters& params,
                                 const ImpactSolverOptions& options) const {
  JsonObject j;
  j.Add("t_end_s", t_end_s)
      .Add("crater_depth_m", crater_depth_m)
      .Add("relative_penetration", relative_penetration)
      .Add("added_mass_max_kg", added_mass_max_kg)
      .Add("peak_deceleration_g", peak_deceleration_g)
      .Add("t_peak_s", t_peak_s)
      .Add("plateau_deceleration_g", plateau_deceleration_g)
      .Add("momentum_ratio", momentum_ratio)
      .Add("solver", solver)
      .Add("steps", static_cast<std::int64_t>(steps))
      .Add("rejected_steps", static_cast<std::int64_t>(rejected_steps))
      .Add("rhs_evals", static_cast<std::int64_t>(rhs_evals))
      .Add("jacobian_evals", static_cast<std::int64_t>(jacobian_evals))
      .Add("error_estimate", error_estimate)
      .Add("wall_time_s", wall_time_s)
      .Add("warnings", warnings)
      .Add("solver_reason", solver_reason)
      .Add("error_estimator", error_estimator)
      .Add("error_estimate_local", error_estimate_local)
      .Add("impact_velocity_m_s", params.impact_velocity_m_s)
      .Add("rtol", options.EffectiveRtol())
      .Add("atol", options.EffectiveAtol())
      .Add("stopped", stopped)
      .Add("stop_reason", stop_reason)
      .Add("t_reached_s", t_reached_s);
  return j;
}

bool ImpactSummary::IsUsable() const {
  return stopped && std::isfinite(crater_depth_m) && std::isfinite(t_end_s);
}

std::string ImpactSummary::BriefReport() const {
  return fmt::format(
      "t_end {:.6g} s, crater depth {:.6g} m ({:.4g} D), peak {:.5g} g at {:.5g} s, plateau "
      "{:.5g} g, momentum ratio {:.4g}, solver {}, {} steps, error estimate {:.2g}",
      t_end_s, crater_depth_m, relative_penetration, peak_deceleration_g, t_peak_s,
      plateau_deceleration_g, momentum_ratio, solver, steps, error_estimate);
}

std::string ImpactSummary::FullReport() const {
  std::string out;
  if (!stopped)
    out += fmt::format("NOT STOPPED            {} (reached t = {:.10g} s)\n", stop_reason,
                       t_reached_s);
  out += fmt::format("t_end                  {:.10g} s\n", t_end_s);
  out += fmt::format("crater depth           {:.10g} m\n", crater_depth_m);
  out += fmt::format("relative penetration   {:.10g}\n", relative_penetration);
  out += fmt::format("added mass M           {:.10g} kg\n", added_mass_max_kg);
  out += fmt::format("peak deceleration      {:.10g} g at t = {:.10g} s\n", peak_deceleration_g,
                     t_peak_s);
  out += fmt::format("plateau deceleration   {:.10g} g (t1 = {:.6g} s, v(t1) = {:.10g} m/s)\n",
                     plateau_deceleration_g, t1_s, v_t1_m_s);
  out += fmt::format("momentum ratio         {:.10g}\n", momentum_ratio);
  out += fmt::format("solver                 {} ({})\n", solver, solver_reason);
  out += fmt::format(
      "cost                   {} steps ({} in the end phase from t = {:.6g} s), {} rejected, "
      "{} RHS, {} Jacobian evaluations, {:.3g} s\n",
      steps, end_phase_steps, t_switch_s, rejected_steps, rhs_evals, jacobian_evals, wall_time_s);
  out += fmt::format(
      "error estimate         {:.3g} ({}; relative, crater depth / t_end; local sum {:.3g})\n",
      error_estimate, error_estimator, error_estimate_local);
  for (const std::string& w : warnings) out += "warning: " + w + "\n";
  return out;
}

ImpactSeries MakeImpactSeries(const ImpactModelParameters& params, const ImpactRun& run) {
  ImpactSeries s;
  const double M = run.summary.added_mass_max_kg;
  for (const ImpactState& st : run.solution.StepStates()) {
    const ImpactForces f = EvaluateImpactForces(params, M, st.t_s, st.z_m, st.v_m_s);
    const bool singular_point = st.v_m_s <= 0.0;
    s.t_s.push_back(st.t_s);
    s.z_m.push_back(st.z_m);
    s.v_m_s.push_back(st.v_m_s);
    s.dv_dt_m_s2.push_back(singular_point ? kNaN : f.dv_dt_m_s2);
    s.m_add_kg.push_back(f.added.m_add_kg);
    s.dm_add_dt_kg_s.push_back(f.added.dm_dt_kg_s);
    s.inertia_N.push_back(f.inertia_N);
    s.dynamic_N.push_back(singular_point ? kNaN : f.dynamic_N);
    s.friction_N.push_back(f.friction_N);
    s.gravity_N.push_back(f.gravity_N);
  }
  return s;
}

ImpactState ExactConservedMomentum(const ImpactModelParameters& p, double t_s) {
  const double M = p.AddedMassMax_kg(), mp = p.pounder_mass_kg;
  const double b = p.sigmoid_rate_b_per_s, T = p.sigmoid_delay_T_s;
  const double p0 = (mp + AddedMassAt(M, b, T, 0.0).m_add_kg) * p.impact_velocity_m_s;
  // int dt / (m_p + M sigma(b (t - T))) with x = b (t - T):
  //   (1/b) [ x / a + M / (a c) (x - ln(a e^x + c)) ],  a = m_p + M, c = m_p.
  const double a = mp + M, c = mp;
  auto L = [&](double x) {
    return x > 0 ? x + std::log(a + c * std::exp(-x))
                 : std::log(c) + std::log1p(a * std::exp(x) / c);
  };
  const double x = b * (t_s - T), x0 = -b * T;
  const double integral = ((x - x0) / a + M / (a * c) * ((x - x0) - (L(x) - L(x0)))) / b;
  ImpactState s;
  s.t_s = t_s;
  s.z_m = p0 * integral;
  s.v_m_s = p0 / (mp + AddedMassAt(M, b, T, t_s).m_add_kg);
  return s;
}

HarmonicStop ExactHarmonicStop(const ImpactModelParameters& p) {
  const double k = p.Stiffness_N_m(), m = p.pounder_mass_kg, v0 = p.impact_velocity_m_s;
  const double omega = std::sqrt(k / m);
  const double delta = m * p.gravity_m_s2 / k;  // static deflection
  // z = delta (1 - cos wt) + (v0 / w) sin wt; v = 0 first at wt = pi - atan(v0 / (delta w)).
  const double theta = std::numbers::pi - std::atan2(v0, delta * omega);
  HarmonicStop out;
  out.t_end_s = theta / omega;
  out.crater_depth_m = delta + std::hypot(delta, v0 / omega);
  return out;
}

}  // namespace impactdic
