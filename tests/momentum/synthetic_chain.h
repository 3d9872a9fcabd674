// Test helper: a synthetic impact with exact momentum conservation through the peak stage (the
// ground truth of the momentum tests and of the failed-stage fault tests).
#ifndef IMPACTDIC_TESTS_MOMENTUM_SYNTHETIC_CHAIN_H_
#define IMPACTDIC_TESTS_MOMENTUM_SYNTHETIC_CHAIN_H_

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <iterator>
#include <numbers>
#include <vector>

#include "impactdic/kinematics/kinematics.h"
#include "impactdic/momentum/momentum.h"
#include "impactdic/sensor/sensor.h"

namespace impactdic {

// A synthetic impact where momentum is conserved exactly through the peak stage:
//   m(tau) = M (s(tau) - s(0)), s = 1 / (1 + exp(-b (tau - T))), tau = t - t_impact;
//   v_p = p_max / (m_p + m),  v_sand = (p_max / m_s) m / (m_p + m)   for 0 <= tau <= tau_e,
// so p_p + p_gran = p_max and m_add = p_max / v_p - m_p = m exactly. The grid mass m_s is chosen
// as m(tau_e), which makes v_p = v_sand at tau_e. Afterwards pounder and soil decelerate together
// at d (> the soil's acceleration just before tau_e, so the soil acceleration turns negative at
// tau_e) until they stop. Subsets outside the grid move at half the grid's velocity.
//
// With 0 < tau_c < tau_e (an overtaking chain) m_s = m(tau_c): the soil overtakes the pounder at
// tau_c (v_p = v_sand there) and leads it at tau_e, where its acceleration ends; afterwards it
// decelerates at d_sand (> d) until it moves with the pounder again. Momentum is still conserved
// through the peak stage. tau_c <= 0: tau_c = tau_e (the chain above).
//
// bump_dv > 0 adds a late re-acceleration of the soil alone (as a wave reflected by the floor):
// v_sand += bump_dv (1 - cos(2 pi (tau - bump_tau) / bump_width)) / 2 on
// [bump_tau, bump_tau + bump_width], peak acceleration pi bump_dv / bump_width.
struct Chain {
  double mp = 10, M = 8, b = 2500, T = 0.002, v0 = 3.7, d = 600;
  double t_impact = 0.01, tau_e = 0.002 + 2 / 2500.0;
  double fs = 25000, fps = 10000, offset = 0.005;
  std::size_t frames = 120;
  double scale = 0.5;            // mm/px
  double tau_c = 0, d_sand = 0;  // Overtaking chain (above); d_sand used when tau_c > 0.
  double bump_dv = 0, bump_tau = 0, bump_width = 0;  // Late soil re-acceleration (above).
  double S(double tau) const { return 1 / (1 + std::exp(-b * (tau - T))); }
  double Madd(double tau) const { return M * (S(tau) - S(0)); }
  double PMax() const { return mp * v0; }
  double TauCross() const { return tau_c > 0 ? tau_c : tau_e; }
  double Ms() const { return Madd(TauCross()); }
  double Ve() const { return PMax() / (mp + Madd(tau_e)); }  // v_p(tau_e).
  double VsE() const { return PMax() / Ms() * Madd(tau_e) / (mp + Madd(tau_e)); }
  // Time after tau_e at which the soil moves with the pounder again.
  double TauJoin() const { return VsE() > Ve() ? (VsE() - Ve()) / (d_sand - d) : 0; }
  double TauStop() const { return tau_e + Ve() / d; }
  double Vp(double t) const {
    const double tau = t - t_impact;
    if (tau < 0) return v0;
    if (tau <= tau_e) return PMax() / (mp + Madd(tau));
    return std::max(0.0, Ve() - d * (tau - tau_e));
  }
  double Vs(double t) const {
    const double tau = t - t_impact;
    if (tau < 0) return 0;
    if (tau <= tau_e) return PMax() / Ms() * Madd(tau) / (mp + Madd(tau));
    double bump = 0;
    if (bump_dv > 0 && tau > bump_tau && tau < bump_tau + bump_width)
      bump = 0.5 * bump_dv * (1 - std::cos(2 * std::numbers::pi * (tau - bump_tau) / bump_width));
    if (tau < tau_e + TauJoin()) return VsE() - d_sand * (tau - tau_e) + bump;
    return std::max(0.0, Ve() - d * (tau - tau_e)) + bump;
  }
  // Soil displacement [m] since t0 = offset (frame 0): composite Simpson, 4000 panels per frame
  // interval and exact at the breakpoints (error < 1e-12 m).
  double Xs(double t) const {
    double x = 0;
    double breaks[] = {t_impact,
                       t_impact + tau_e,
                       t_impact + tau_e + TauJoin(),
                       t_impact + TauStop(),
                       t_impact + bump_tau,
                       t_impact + bump_tau + bump_width};
    std::sort(std::begin(breaks), std::end(breaks));
    double a = offset;
    auto integrate = [&](double lo, double hi) {
      const int n = 400;
      const double h = (hi - lo) / n;
      double s = Vs(lo) + Vs(hi);
      for (int i = 1; i < n; ++i) s += (i % 2 ? 4 : 2) * Vs(lo + i * h);
      return s * h / 3;
    };
    for (double br : breaks) {
      if (br > a && br < t) {
        x += integrate(a, br);
        a = br;
      }
    }
    return x + integrate(a, t);
  }
};

inline SensorResult MakeChainSensor(const Chain& c) {
  SensorResult s;
  for (int i = 0; i <= static_cast<int>(0.03 * c.fs); ++i) {
    const double t = i / c.fs;
    s.time_s.push_back(t);
    s.velocity_m_s.push_back(c.Vp(t));
  }
  s.summary.sample_rate_hz = c.fs;
  s.summary.cutoff_hz = 1500;
  s.summary.impact_time_s = c.t_impact;
  s.summary.impact_index = static_cast<std::size_t>(std::lround(c.t_impact * c.fs));
  s.summary.stop_time_s = c.t_impact + c.TauStop();
  s.summary.impact_velocity_m_s = c.v0;
  return s;
}

// The pounder penetration of the chain (since the impact, m) on the sensor's time base: what the
// sensor stage integrates; RefineEndOfPeakStage reads it (trapezoid over 100 sub-steps per
// sample: error < 1e-9 m).
inline void AddChainPenetration(const Chain& c, SensorResult* s) {
  s->penetration_m.assign(s->time_s.size(), 0);
  double z = 0;
  for (std::size_t i = 1; i < s->time_s.size(); ++i) {
    const double t0 = s->time_s[i - 1], h = (s->time_s[i] - t0) / 100;
    for (int j = 0; j < 100; ++j)
      z += 0.5 * h * (c.Vp(t0 + j * h) + c.Vp(t0 + (j + 1) * h)) * (t0 + j * h >= c.t_impact);
    s->penetration_m[i] = z;
  }
}

// 10 x 5 subsets, step 10 px = 5 mm; centres x = 50..95 mm, y = 150..170 mm; the momentum grid
// (ChainOptions) is the 6 x 2 subsets of columns 2..7 in rows 0..1.
inline CorrelationSeries MakeChainCorrelation(const Chain& c) {
  CorrelationSeries dic;
  dic.frames = c.frames;
  for (int j = 0; j < 5; ++j)
    for (int i = 0; i < 10; ++i) {
      dic.x_px.push_back(100 + 10 * i);
      dic.y_px.push_back(300 + 10 * j);
    }
  dic.subsets = dic.x_px.size();
  for (std::size_t k = 0; k < c.frames; ++k) {
    const double xs_px = c.Xs(c.offset + static_cast<double>(k) / c.fps) * 1e3 / c.scale;
    for (std::size_t s = 0; s < dic.subsets; ++s) {
      const bool in_grid = s % 10 >= 2 && s % 10 <= 7 && s / 10 <= 1;
      dic.u_px.push_back(0);
      dic.v_px.push_back(in_grid ? xs_px : 0.5 * xs_px);
    }
  }
  return dic;
}

inline MomentumOptions ChainOptions(const Chain& c) {
  MomentumOptions o;
  o.pounder_mass_kg = c.mp;
  o.footprint.x_left_mm = 58;
  o.footprint.x_right_mm = 87;
  o.footprint.bottom_y_mm = 148;
  const double area_m2 = 12 * 25e-6;
  o.density_kg_m3 = c.Ms() / (area_m2 * o.depth_m);
  return o;
}

}  // namespace impactdic

#endif  // IMPACTDIC_TESTS_MOMENTUM_SYNTHETIC_CHAIN_H_
