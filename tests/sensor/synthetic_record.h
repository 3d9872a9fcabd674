// A closed-form pounder motion and the accelerometer record it produces (test ground truth).
//
// Rest (reading 1 g) until t_release, free fall (0 g) until t_impact = t_release + v0 / g, then a
// half-sine deceleration pulse a_down(tau) = g - a_pk sin(pi tau / T_d) (tau = t - t_impact) until
// the velocity
//   v(tau) = v0 + g tau - a_pk T_d / pi (1 - cos(pi tau / T_d))
// reaches 0 at tau_s, then rest again (1 g). Penetration
//   z(tau) = v0 tau + g tau^2 / 2 - a_pk T_d / pi (tau - T_d / pi sin(pi tau / T_d)).
// The reading is 1 - a_down / g (accelerometer axis up), plus a constant offset and white noise.
#ifndef IMPACTDIC_TESTS_SENSOR_SYNTHETIC_RECORD_H_
#define IMPACTDIC_TESTS_SENSOR_SYNTHETIC_RECORD_H_

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "impactdic/io/csv.h"

namespace impactdic::testing {

struct PulseMotion {
  double g = 9.81;
  double v0 = 3.7;           // Impact velocity [m/s].
  double a_pk = 100 * 9.81;  // Peak of the sine pulse [m/s^2].
  double t_d = 0.02;         // Pulse half-period [s].
  double t_release = 0.0201234;

  double t_impact() const { return t_release + v0 / g; }
  double V(double tau) const {
    const double w = std::numbers::pi / t_d;
    return v0 + g * tau - a_pk / w * (1 - std::cos(w * tau));
  }
  double Z(double tau) const {
    const double w = std::numbers::pi / t_d;
    return v0 * tau + 0.5 * g * tau * tau - a_pk / w * (tau - std::sin(w * tau) / w);
  }
  // Stop time after impact (v = 0), by bisection on the closed form.
  double TauStop() const {
    double lo = t_d / 100, hi = t_d;  // v(lo) > 0 > v(hi) for the parameters used.
    for (int i = 0; i < 200; ++i) {
      const double mid = 0.5 * (lo + hi);
      (V(mid) > 0 ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
  }
  double CraterDepth() const { return Z(TauStop()); }
  // Accelerometer reading [g] at time t.
  double Reading(double t) const {
    if (t < t_release) return 1;
    const double tau = t - t_impact();
    if (tau < 0) return 0;
    if (tau > TauStop()) return 1;
    return 1 - (g - a_pk * std::sin(std::numbers::pi * tau / t_d)) / g;
  }
};

struct SyntheticRecord {
  std::vector<double> time_s, accel_g, exposure;
  std::vector<double> frame_times;  // Exposure rising edges (truth).
};

// Samples at fs from 0 to t_end; exposure high for 40 % of each frame period starting at
// frame_offset + k / fps (while inside the record).
inline SyntheticRecord MakeRecord(const PulseMotion& motion, double fs, double t_end,
                                  double offset_g, double noise_g, unsigned seed, double fps = 1600,
                                  double frame_offset = 0.3712345) {
  SyntheticRecord r;
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, noise_g);
  for (int k = 0; frame_offset + k / fps < t_end; ++k)
    r.frame_times.push_back(frame_offset + k / fps);
  const auto n = static_cast<std::size_t>(t_end * fs);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) / fs;
    r.time_s.push_back(t);
    r.accel_g.push_back(motion.Reading(t) + offset_g + (noise_g > 0 ? noise(rng) : 0.0));
    double e = 0;
    if (t >= frame_offset) {
      const double phase = std::fmod(t - frame_offset, 1 / fps) * fps;
      e = phase < 0.4 ? 5.0 : 0.0;
    }
    r.exposure.push_back(e);
  }
  return r;
}

inline void WriteRecordCsv(const std::string& path, const SyntheticRecord& r,
                           bool with_exposure = true) {
  if (with_exposure) {
    WriteCsv(path, {"time_s", "accel_g", "exposure"}, {r.time_s, r.accel_g, r.exposure}, 12);
  } else {
    WriteCsv(path, {"time_s", "accel_g"}, {r.time_s, r.accel_g}, 12);
  }
}

}  // namespace impactdic::testing

#endif  // IMPACTDIC_TESTS_SENSOR_SYNTHETIC_RECORD_H_
