// A DEM record in LAMMPS's formats with a known answer, written by the tests of the DEM
// converter and of the DEM validation: a lattice of grains translating uniformly at 1 m/s down
// and a pounder in free fall that meets a constant contact force at DEM time kContact.
#ifndef IMPACTDIC_TESTS_SYNTH_DEM_TEST_RECORD_H_
#define IMPACTDIC_TESTS_SYNTH_DEM_TEST_RECORD_H_

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "impactdic/synth/impact_scene.h"

namespace impactdic::dem_test {

namespace fs = std::filesystem;

inline constexpr double kG = 9.81;
inline constexpr double kDt = 2.5e-6;       // DEM time step: 1/1600 s = 250 steps, 20 us = 8 steps
inline constexpr double kMass = 10;         // m_p [kg]
inline constexpr double kVStart = 2.0;      // pounder speed at DEM time 0 [m/s], down
inline constexpr double kContact = 1.0e-3;  // DEM time of the last contact-free sample [s]
inline constexpr double kForce = 1200;      // contact force after it [N], up
inline constexpr double kVGrain = 1.0;      // grains' speed [m/s], down
inline constexpr double kSurfaceY = 0.5;    // pounder bottom at contact (LAMMPS y) [m]
inline constexpr double kAxisX = 0.4;
inline constexpr double kOffset = 0.05;     // pounder centre of mass above its bottom [m]
inline constexpr double kSpacing = 0.005;   // grain lattice spacing [m]
inline constexpr double kGrainMass = 0.01;  // [kg]
inline constexpr double kDepth = 0.192;
inline constexpr long kSteps = 8000;  // 20 ms

// Pounder velocity (down) and bottom depth below the surface at DEM time t.
inline double PounderV(double t) {
  const double vc = kVStart + kG * kContact;
  return t <= kContact ? kVStart + kG * t : vc - (kForce / kMass - kG) * (t - kContact);
}
inline double PounderZ(double t) {
  const double zc = 0;  // the surface is the bottom at contact
  if (t <= kContact) {
    const double s = kContact - t;  // before contact, integrate backwards
    return zc - (PounderV(kContact) * s - 0.5 * kG * s * s);
  }
  const double s = t - kContact, a = kForce / kMass - kG;
  return zc + PounderV(kContact) * s - 0.5 * a * s * s;
}

// The record in a temporary folder. With stretch_x_per_s = c or shear_per_s = a, the grains
// also move sideways by t (c (x0 - kAxisX) + a (y0 - kSurfaceY)) (x0, y0 their lattice place): an
// affine field whose gradient since a reference time t_r is du/dX = c (t - t_r) / (1 + c t_r),
// du/dY = -a (t - t_r) / (1 + c t_r) (Y down), dv = 0.
inline std::string MakeDemDir(const std::string& name, double stretch_x_per_s = 0,
                              double shear_per_s = 0) {
  const fs::path dir =
      fs::temp_directory_path() / ("impactdic_dem_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream meta(dir / "meta.txt");
  meta << "pounder_mass_kg " << kMass << "\npounder_width_m 0.15\ndepth_m " << kDepth
       << "\nimpact_velocity_m_s 2.0\npounder_axis_x_m " << kAxisX << "\npounder_bottom_offset_m "
       << kOffset << "\nbed_top_m 0.5\nbox_width_m 0.8\n"
       << "timestep_s " << kDt << "\ngravity_m_s2 " << kG << "\n";
  std::ofstream pounder(dir / "pounder.txt");
  pounder.precision(12);
  pounder << "# Time-averaged data for fix prec\n# TimeStep v_t v_yc v_vy v_fy\n";
  for (long step = 0; step <= kSteps + 40; step += 8) {
    const double t = step * kDt;
    const double fy = t <= kContact + 1e-12 ? -kMass * kG : kForce - kMass * kG;
    pounder << step << " " << t << " " << kSurfaceY - PounderZ(t) + kOffset << " " << -PounderV(t)
            << " " << fy << "\n";
  }
  std::ofstream dump(dir / "grains.dump");
  dump.precision(12);
  for (long step = 0; step <= kSteps; step += 250) {
    const double t = step * kDt;
    std::vector<std::string> lines;
    long id = 0;
    for (int j = 0; j < 40; ++j)
      for (int i = 0; i < 120; ++i) {
        ++id;
        const double x0 = kAxisX - 0.3 + (i + 0.5) * kSpacing;
        const double y0 = kSurfaceY - 0.0025 - j * kSpacing;
        const double vx = stretch_x_per_s * (x0 - kAxisX) + shear_per_s * (y0 - kSurfaceY);
        const double x = x0 + vx * t, y = y0 - kVGrain * t;
        lines.push_back(std::to_string(id) + " " + std::to_string(x) + " " + std::to_string(y) +
                        " " + std::to_string(vx) + " " + std::to_string(-kVGrain) + " 0.0024 " +
                        std::to_string(kGrainMass));
      }
    dump << "ITEM: TIMESTEP\n"
         << step << "\nITEM: NUMBER OF ATOMS\n"
         << lines.size() << "\nITEM: BOX BOUNDS ff ff pp\n0 0.8\n0 1.2\n-0.005 0.005\n"
         << "ITEM: ATOMS id x y vx vy radius mass\n";
    for (const auto& l : lines) dump << l << "\n";
  }
  return dir.string();
}

// Floor windows (impact.in's floor.txt) for a record of MakeDemDir: window 0 under the axis,
// window 1 kFloorOffset beside it, each kFloorWidth wide; window w carries its static load
// kFloorStatic[w] plus a half sine of amplitude kFloorAmplitude[w] and duration kFloorPulse
// starting at DEM time kFloorStart[w]. Each line is the exact average of that force over its 8
// steps, as `fix ave/time 1 8 8` writes it.
inline constexpr double kFloorWidth = 0.05, kFloorOffset = 0.25, kFloorPulse = 2.0e-3;
inline constexpr double kFloorStatic[2] = {40, 35}, kFloorAmplitude[2] = {200, 100};
inline constexpr double kFloorStart[2] = {4.0e-3, 4.5e-3};
// Average of A sin(pi (t - t0) / T) (zero outside [t0, t0 + T]) over [a, b].
inline double HalfSineAverage(double A, double t0, double T, double a, double b) {
  const double pi = 3.14159265358979323846;
  const double lo = std::clamp(a, t0, t0 + T), hi = std::clamp(b, t0, t0 + T);
  return A * T / pi * (std::cos(pi * (lo - t0) / T) - std::cos(pi * (hi - t0) / T)) / (b - a);
}
inline void AddFloorRecord(const std::string& dir) {
  std::ofstream meta(fs::path(dir) / "meta.txt", std::ios::app);
  meta << "floor_window_width_m " << kFloorWidth << "\nfloor_window_center_x_m " << kAxisX
       << "\nfloor_window_offset_x_m " << kAxisX + kFloorOffset << "\n";
  std::ofstream floor(fs::path(dir) / "floor.txt");
  floor.precision(14);
  floor << "# Time-averaged data for fix frec\n# TimeStep c_fc c_fo\n";
  for (long step = 8; step <= kSteps + 40; step += 8) {
    floor << step;
    for (int w = 0; w < 2; ++w)
      floor << " "
            << kFloorStatic[w] + HalfSineAverage(kFloorAmplitude[w], kFloorStart[w], kFloorPulse,
                                                 (step - 8) * kDt, step * kDt);
    floor << "\n";
  }
}

// The tiny preset at 1600 fps without noise, offset or sensor noise.
inline ImpactSceneSpec TinySpec() {
  ImpactSceneSpec spec = ImpactScenePreset("tiny");
  spec.fps = 1600;
  spec.noise_sigma = 0;
  spec.sensor.noise_g = 0;
  spec.sensor.offset_g = 0;
  return spec;
}

}  // namespace impactdic::dem_test

#endif  // IMPACTDIC_TESTS_SYNTH_DEM_TEST_RECORD_H_
