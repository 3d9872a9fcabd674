// Allowed ranges of physical inputs, defined once and shared by the scene file, the CLI options
// and the library's Check() methods, so that a physically absurd value (a 1e308 kg pounder) is
// refused up front with the allowed range instead of failing somewhere deep in a stage.
//
//   CheckRange(mass, kPounderMassRange, "--mass", "a pounder mass");
//   // --mass: invalid value (got 1e+308); expected a pounder mass in [0.01, 1e+05] kg
//
// The ranges are generous: they hold every real drop test and the extreme cases the model must
// run (docs/model.md, extreme cases: m_p = 0.1 .. 1000 kg, 18 m drops, D = 0.001 m, v0 = 0.01 m/s).
#ifndef IMPACTDIC_CORE_RANGE_H_
#define IMPACTDIC_CORE_RANGE_H_

#include <string>

namespace impactdic {

// The interval from min to max in `unit`, closed unless an end is marked open; NaN and
// infinities are never inside.
struct ValueRange {
  double min = 0;
  double max = 0;
  const char* unit = "";
  bool min_open = false;  // (min, ...: min itself is outside.
  bool max_open = false;  // ..., max): max itself is outside.

  bool Contains(double value) const {
    return (min_open ? value > min : value >= min) && (max_open ? value < max : value <= max);
  }
  // "[0.01, 1e+05] kg", "(0, 1)"
  std::string Text() const;
};

// "a pounder mass in [0.01, 1e+05] kg"; a range without an upper end (max >= 1e300) reads
// "a grid step >= 1 px", one without either end "a time [s]".
std::string ExpectedText(const std::string& what, const ValueRange& range);

// Error(kInvalidValue, where, value, ExpectedText(what, range)) unless range.Contains(value).
void CheckRange(double value, const ValueRange& range, const std::string& where,
                const std::string& what);

// --- A drop test (scene `test.*`, `impactdic model`, synthetic scene specs) ----------------------
// Pounder mass m_p: the paper's 7-13 kg, the model's extremes 0.1 and 1000 kg, up to 100 t
// (heavy tamping in the field uses 10-40 t).
inline constexpr ValueRange kPounderMassRange{0.01, 1e5, "kg"};
// Drop height h: 0 (impact velocity given instead) up to 100 m (field tamping: <= 40 m).
inline constexpr ValueRange kDropHeightRange{0, 100, "m"};
// Impact velocity v0: the model's slow extreme 0.01 m/s, up to 100 m/s (a 500 m free fall).
inline constexpr ValueRange kImpactVelocityRange{1e-3, 100, "m/s"};
// Pounder width D and out-of-plane depth t_z: 0.1 mm (the model's extreme is 1 mm) to 10 m.
inline constexpr ValueRange kPounderSizeRange{1e-4, 10, "m"};
// Dry density of the soil rho_d (sand ~1550). Wide: synthetic checks choose rho_d to give a
// grid a round mass (tests/momentum uses ~1.2e5).
inline constexpr ValueRange kSoilDensityRange{1, 1e6, "kg/m^3"};
// Height of the sand bed.
inline constexpr ValueRange kBedHeightRange{1e-3, 100, "m"};
// Gravitational acceleration (0 only for the model's exact-solution checks).
inline constexpr ValueRange kGravityRange{0, 100, "m/s^2"};
// Added mass M = m_add,max (given instead of Eq. 4).
inline constexpr ValueRange kAddedMassRange{0, 1e6, "kg"};
// The model's soil parameters (Eq. 7-9; Table 2: K = 50, u = 1.9, T = 2 ms). With every range
// of this file respected, no force of Eq. 9 can overflow: k = K rho_d g A <= 1e18 N/m.
inline constexpr ValueRange kFrictionKRange{0, 1e6, ""};
inline constexpr ValueRange kDampingFactorURange{1, 1e3, ""};
inline constexpr ValueRange kSigmoidDelayRange{0, 1e3, "s"};
// Damping exponent n (Eq. 8) and sigmoid rate b (Eq. 6; Table 2: n = 0.2, b = 2500 1/s).
inline constexpr ValueRange kDampingExponentNRange{0, 1, ""};
inline constexpr ValueRange kSigmoidRateRange{0, 1e12, "1/s", /*min_open=*/true};

// --- The camera (scene `inputs.*`, synthetic scene specs) ----------------------------------------
// Recording frame rate: 1/s up to 10 million frames per second (the fastest cameras).
inline constexpr ValueRange kCameraFpsRange{1, 1e7, "1/s"};
// Image scale on the panel: 0.1 um to 10 m per pixel.
inline constexpr ValueRange kMmPerPxRange{1e-4, 1e4, "mm/px"};

}  // namespace impactdic

#endif  // IMPACTDIC_CORE_RANGE_H_
