// The front in the DIC field (momentum/wave_front.h) on analytic kinematics: a radial pulse
// u = A exp(-r / lambda) S((t - r / c) / tau) e_r sampled like a correlation (subsets on a grid,
// frames dt apart, velocity by the kinematics' differences) recovers c and, along the centre line
// once the pulse has passed, lambda (ln u is exactly linear in depth there); degenerate inputs
// give NaN with the reason, and summary.json's "wave" has no NaN.
#include "impactdic/momentum/wave_front.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "impactdic/io/json.h"
#include "impactdic/kinematics/kinematics.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/sensor/sensor.h"

namespace impactdic {
namespace {

constexpr double kC = 80;        // [m/s]
constexpr double kLambda = 150;  // [mm]
constexpr double kTau = 1e-3;    // [s]
constexpr double kDt = 1e-4;     // [s]
constexpr double kSurface = 50;  // Panel y of the surface [mm].
constexpr double kCentre = 300;  // Panel x of the centre line [mm].
constexpr double kWidth = 150;   // D [mm].

double Step(double x) { return x <= 0 ? 0 : x >= 1 ? 1 : x * x * x * (10 - 15 * x + 6 * x * x); }

// Subsets on the centre line (x = kCentre) and in columns outside the footprint, every 30 mm
// down to 300 mm; `amplitude_mm` 0 = no motion. Frames from -0.6 ms every kDt for `frames`.
// `bump_mm` > 0 lifts the near-surface row (15 mm deep) by that much from 4.75 ms over 0.5 ms (a
// reflection: an upward velocity pulse of 1.875 bump / 0.5 ms at its peak).
KinematicsResult Pulse(double amplitude_mm, int frames, bool centre_line = true,
                       double bump_mm = 0) {
  KinematicsResult k;
  std::vector<double> xs = {kCentre - 210, kCentre - 150, kCentre + 120, kCentre + 180};
  if (centre_line) xs.push_back(kCentre);
  for (double x : xs)
    for (double y = kSurface + 15; y <= kSurface + 300; y += 30) {
      k.x_mm.push_back(x);
      k.y_mm.push_back(y);
    }
  k.subsets = k.x_mm.size();
  k.frames = static_cast<std::size_t>(frames);
  for (int f = 0; f < frames; ++f) k.time_s.push_back(f * kDt);
  k.disp_y_mm.resize(k.frames * k.subsets);
  for (std::size_t f = 0; f < k.frames; ++f) {
    const double t = -6e-4 + static_cast<double>(f) * kDt;
    for (std::size_t s = 0; s < k.subsets; ++s) {
      const double X = k.x_mm[s] - kCentre, Y = k.y_mm[s] - kSurface, r = std::hypot(X, Y);
      // A deterministic +-1 um "noise" so the pre-impact standard deviation is not zero.
      const double noise = 1e-3 * std::sin(1.7 * static_cast<double>(f * 31 + s * 7));
      const double bump = Y < 20 ? -bump_mm * Step((t - 4.75e-3) / 5e-4) : 0;
      k.disp_y_mm[f * k.subsets + s] =
          amplitude_mm * std::exp(-r / kLambda) * Step((t - r / (1e3 * kC)) / kTau) * Y / r +
          noise + bump;
    }
  }
  k.vel_y_mm_s.resize(k.disp_y_mm.size());
  for (std::size_t s = 0; s < k.subsets; ++s) {
    std::vector<double> u(k.frames);
    for (std::size_t f = 0; f < k.frames; ++f) u[f] = k.disp_y_mm[f * k.subsets + s];
    const std::vector<double> v = FirstDerivative(u, kDt);
    for (std::size_t f = 0; f < k.frames; ++f) k.vel_y_mm_s[f * k.subsets + s] = v[f];
  }
  return k;
}

std::vector<double> FrameTimes(const KinematicsResult& k) {
  std::vector<double> t;
  for (std::size_t f = 0; f < k.frames; ++f) t.push_back(-6e-4 + static_cast<double>(f) * kDt);
  return t;
}

SensorResult Sensor() {
  SensorResult s;
  s.summary.impact_time_s = 0;
  s.summary.final_penetration_m = 0.05;
  s.time_s = {-1, 1};
  s.penetration_m = {0, 0};  // The pounder stays at the surface: depth below it = Y.
  return s;
}

WaveFrontOptions Options() {
  WaveFrontOptions o;
  o.pounder_center_x_mm = kCentre;
  o.surface_y_mm = kSurface;
  o.pounder_width_mm = kWidth;
  return o;
}

TEST(WaveFront, RecoversSpeedAndDecayOfAnAnalyticPulse) {
  const KinematicsResult k = Pulse(/*amplitude_mm=*/2, /*frames=*/80);
  const WaveFront w =
      AnalyzeWaveFront(k, FrameTimes(k), Sensor(), /*t_end_peak_s=*/3e-3, Options());
  ASSERT_TRUE(w.computed);
  EXPECT_TRUE(w.problem.empty()) << w.problem;
  // The threshold crossing lies at a fixed phase of the pulse (f = 0.5 of the peak velocity:
  // 30 xi^2 (1 - xi)^2 = 0.9375, xi = 0.229), so the arrival is r / c + 0.229 tau up to the
  // linear interpolation between frames (dt = tau / 10) and the central difference: the slope is
  // 1 / c within that error (measured: 80.05 m/s, 0.07 %).
  EXPECT_NEAR(w.speed_m_s, kC, 0.01 * kC);
  EXPECT_LT(w.speed_ci_m_s[0], kC);
  EXPECT_GT(w.speed_ci_m_s[1], kC);
  EXPECT_NEAR(w.intercept_s, 0.229 * kTau, 0.02e-3);
  // At the last frame (7.3 ms) the pulse has passed every centre-line subset (r / c + tau <= 4.8
  // ms): u = A exp(-z / lambda) exactly, up to the 1 um noise.
  EXPECT_TRUE(w.displacement_end.problem.empty()) << w.displacement_end.problem;
  EXPECT_NEAR(w.displacement_end.decay_length_mm, kLambda, 0.01 * kLambda);
  EXPECT_NEAR(w.displacement_end.surface_value, 2, 0.02);
  EXPECT_NEAR(w.displacement_end.depth_of_influence_mm, kLambda * std::log(10), 0.01 * 345);
  EXPECT_LT(w.displacement_end.decay_length_ci_mm[0], kLambda);
  EXPECT_GT(w.displacement_end.decay_length_ci_mm[1], kLambda);
  // The velocity at the end is the noise's alone: not determined, with the reason.
  EXPECT_TRUE(std::isnan(w.velocity_end.decay_length_mm));
  EXPECT_NE(w.velocity_end.problem.find("noise standard deviations"), std::string::npos);
  EXPECT_DOUBLE_EQ(w.crater_depth_mm, 50);
}

TEST(WaveFront, NoMotionGivesNullWithTheReason) {
  const KinematicsResult k = Pulse(/*amplitude_mm=*/0, /*frames=*/80);
  const WaveFront w = AnalyzeWaveFront(k, FrameTimes(k), Sensor(), 3e-3, Options());
  EXPECT_TRUE(std::isnan(w.speed_m_s));
  EXPECT_NE(w.problem.find("have an arrival"), std::string::npos) << w.problem;
  EXPECT_EQ(w.fit_subsets, 0u);
  EXPECT_TRUE(std::isnan(w.displacement_te.decay_length_mm));
  EXPECT_FALSE(w.displacement_te.problem.empty());
  WaveResult r;
  r.front = w;
  const std::string json = WaveJson(r).Dump();
  EXPECT_EQ(json.find("nan"), std::string::npos) << json;
  EXPECT_EQ(json.find("NaN"), std::string::npos);
  EXPECT_NE(json.find("\"speed_m_s\": null"), std::string::npos) << json;
}

TEST(WaveFront, TooFewCentreLineSubsetsGiveNullDecayWithTheReason) {
  const KinematicsResult k = Pulse(2, 80, /*centre_line=*/false);
  const WaveFront w = AnalyzeWaveFront(k, FrameTimes(k), Sensor(), 3e-3, Options());
  EXPECT_NEAR(w.speed_m_s, kC, 0.01 * kC);  // The front needs no centre line.
  EXPECT_EQ(w.centre_line_subsets, 0u);
  for (const DepthDecayFit* d : {&w.displacement_te, &w.velocity_te, &w.displacement_end})
    EXPECT_NE(d->problem.find("0 centre-line subsets"), std::string::npos) << d->problem;
}

TEST(WaveFront, NoFramesBeforeTheImpactGiveNullWithTheReason) {
  const KinematicsResult k = Pulse(2, 80);
  std::vector<double> t = FrameTimes(k);
  for (double& x : t) x += 6e-4;  // Frame 0 at the impact: no noise frames.
  const WaveFront w = AnalyzeWaveFront(k, t, Sensor(), 3e-3, Options());
  EXPECT_TRUE(std::isnan(w.speed_m_s));
  EXPECT_NE(w.problem.find("frames before the impact"), std::string::npos) << w.problem;
}

TEST(WaveFront, UnknownPounderPositionGivesNullWithTheReason) {
  const KinematicsResult k = Pulse(2, 80);
  WaveFrontOptions o = Options();
  o.pounder_center_x_mm = kNaN;
  const WaveFront w = AnalyzeWaveFront(k, FrameTimes(k), Sensor(), 3e-3, o);
  EXPECT_FALSE(w.computed);
  EXPECT_NE(w.problem.find("pounder_center_x_px"), std::string::npos);
}

// The DIC half of the reflection check: the near-surface row's mean velocity in a window around
// the return time. A 0.05 mm lift of the row at 4.75-5.25 ms (a 190 mm/s upward pulse) shows in
// a window over it and not in one after it; without it none shows; a window the frames do not
// reach, or no window, is not checked, with the reason.
TEST(DicReflection, FindsALiftOfTheNearSurfaceSoilAroundTheReturnTime) {
  const auto check = [](const KinematicsResult& k, std::array<double, 2> window) {
    std::vector<WaveChannel> channels(1);
    channels[0].reflection.window_s = window;
    CheckDicReflections(k, FrameTimes(k), Sensor(), Options(), &channels);
    return channels[0].dic_reflection;
  };
  const KinematicsResult lifted = Pulse(2, 80, true, /*bump_mm=*/0.05);
  const DicReflectionCheck hit = check(lifted, {4e-3, 6e-3});
  ASSERT_TRUE(hit.checked) << hit.note;
  EXPECT_EQ(hit.subsets, 4u);  // The four columns outside the footprint; not the centre line.
  EXPECT_TRUE(hit.local_maximum);
  EXPECT_NEAR(hit.prominence_mm_s, 1.875 * 0.05 / 5e-4, 20);
  EXPECT_GT(hit.threshold_mm_s, 0);
  const DicReflectionCheck after = check(lifted, {5.8e-3, 7.2e-3});
  ASSERT_TRUE(after.checked) << after.note;
  EXPECT_FALSE(after.local_maximum) << after.prominence_mm_s << " > " << after.threshold_mm_s;
  const DicReflectionCheck none = check(Pulse(2, 80), {4e-3, 6e-3});
  ASSERT_TRUE(none.checked) << none.note;
  EXPECT_FALSE(none.local_maximum) << none.prominence_mm_s << " > " << none.threshold_mm_s;
  EXPECT_LT(none.prominence_mm_s, 0.1 * hit.prominence_mm_s);

  const DicReflectionCheck late = check(lifted, {6e-3, 9e-3});
  EXPECT_FALSE(late.checked);
  EXPECT_NE(late.note.find("before the window's end"), std::string::npos) << late.note;
  const DicReflectionCheck no_window = check(lifted, {kNaN, kNaN});
  EXPECT_FALSE(no_window.checked);
  EXPECT_NE(no_window.note.find("no return time"), std::string::npos) << no_window.note;
}

TEST(WaveFrontOptions, DefaultsPassAndBadFieldsAreNamed) {
  EXPECT_NO_THROW(WaveFrontOptions{}.Check());
  WaveFrontOptions o;
  o.peak_fraction = 1;
  EXPECT_THROW(o.Check(), Error);
}

}  // namespace
}  // namespace impactdic
