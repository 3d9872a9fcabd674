// Tests of the DEM scene converter (synth/dem_scene.h) on a DEM record written by the test in
// LAMMPS's formats, with a known answer: a lattice of grains translating uniformly at 1 m/s down
// and a pounder in free fall that meets a constant contact force.
#include "impactdic/synth/dem_scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>

#include "dem_test_record.h"
#include "impactdic/core/error.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;
using namespace dem_test;  // NOLINT: the record's constants

TEST(DemScene, UniformGrainMotionGivesKnownCellVelocityAndMomentum) {
  const std::string dir = MakeDemDir("uniform");
  DemScene scene(ReadDemRecord(dir), TinySpec());
  const DemTruth& t = scene.truth();
  // Contact at the last force-free sample; the surface is the pounder bottom there.
  EXPECT_NEAR(scene.contact_time_s(), kContact, 1e-12);
  EXPECT_NEAR(scene.surface_y_m(), kSurfaceY, 1e-9);
  EXPECT_NEAR(scene.base().spec().impact_velocity_m_s, PounderV(kContact), 1e-9);
  // Bulk density: one grain per spacing^2 of the slab.
  EXPECT_NEAR(t.bulk_density_kg_m3, kGrainMass / (kSpacing * kSpacing * kDepth),
              0.03 * kGrainMass / (kSpacing * kSpacing * kDepth));
  // Every DIC cell holding grains moves with them: (0, 1000) mm/s, displacement v dt / s.
  const std::size_t n = scene.base().dic_grid().centres_px.size();
  const double s = scene.base().sy_mm_per_px();
  std::size_t checked = 0;
  for (int k = 0; k < scene.frame_count(); ++k)
    for (std::size_t c = 0; c < n; ++c) {
      const std::size_t j = static_cast<std::size_t>(k) * n + c;
      if (t.grains_per_cell[c] == 0) {
        EXPECT_TRUE(std::isnan(t.velocity_y_mm_s[j]));
        continue;
      }
      ++checked;
      EXPECT_NEAR(t.velocity_x_mm_s[j], 0, 1e-6);
      EXPECT_NEAR(t.velocity_y_mm_s[j], 1000 * kVGrain, 1e-6);
      const double dt = scene.FrameTime(k) - scene.FrameTime(t.reference_frame);
      EXPECT_NEAR(t.v_px[j], 1000 * kVGrain * dt / s, 1e-4);
      EXPECT_NEAR(t.u_px[j], 0, 1e-4);
    }
  EXPECT_GT(checked, 100u);
  // The 6 x 2 grid: 25 mm cells of a 5 mm lattice hold 25 grains each.
  EXPECT_NEAR(t.grid_mass_kg, 12 * 25 * kGrainMass, 1e-9);
  EXPECT_NEAR(t.grid_mass_bulk_kg, t.grid_mass_kg, 0.03 * t.grid_mass_kg);
  for (std::size_t k = 0; k < t.p_gran_Ns.size(); ++k) {
    EXPECT_NEAR(t.p_gran_Ns[k], t.grid_mass_kg * kVGrain, 1e-9);
    EXPECT_NEAR(t.p_gran_fd_Ns[k], t.grid_mass_kg * kVGrain, 1e-6);  // uniform motion: exact
    EXPECT_NEAR(t.v_sand_m_s[k], kVGrain, 1e-9);
  }
  // p_max at contact; t_e: the first frame where v_p - v_sand <= 2 % of v_p,max.
  const double vc = PounderV(kContact), a = kForce / kMass - kG;
  EXPECT_NEAR(t.p_max_Ns, kMass * vc, 1e-6);
  const double t_match = (vc - kVGrain - 0.02 * vc) / a;  // since contact
  int ke = 0;
  while (scene.FrameTime(ke) < t_match - 1e-12) ++ke;
  EXPECT_NEAR(t.t_e_s, scene.FrameTime(ke), 1e-12);
  EXPECT_NEAR(t.v_te_m_s, vc - a * scene.FrameTime(ke), 1e-6);
  EXPECT_NEAR(t.m_add_max_kg, t.p_max_Ns / t.v_te_m_s - kMass, 1e-6);
  fs::remove_all(dir);
}

// The strain truth (DemTruth::dudx ...): the least-squares affine fit of each subset's grains
// recovers the gradient of an affine grain motion (dem_test_record.h), in pixels (Y down).
TEST(DemScene, GrainFitGivesTheGradientOfAnAffineGrainMotion) {
  constexpr double kStretch = 2, kShear = 3;  // [1/s]
  const std::string dir = MakeDemDir("affine", kStretch, kShear);
  DemScene scene(ReadDemRecord(dir), TinySpec());
  const DemTruth& t = scene.truth();
  const std::size_t n = scene.base().dic_grid().centres_px.size();
  const double sx = scene.base().sx_mm_per_px(), sy = scene.base().sy_mm_per_px();
  const double t_r = scene.FrameTime(t.reference_frame);
  std::size_t checked = 0;
  for (int k = 0; k < scene.frame_count(); ++k) {
    // DEM time minus the reference's: the frame times differ from it by the contact time only.
    const double dt = scene.FrameTime(k) - t_r, tr = t_r + scene.contact_time_s();
    const double dudx = kStretch * dt / (1 + kStretch * tr);
    const double dudy = -kShear * dt / (1 + kStretch * tr) * sy / sx;
    for (std::size_t c = 0; c < n; ++c) {
      const std::size_t j = static_cast<std::size_t>(k) * n + c;
      if (t.grains_per_subset[c] < 3) {
        EXPECT_TRUE(std::isnan(t.dudx[j])) << "subset " << c << " with " << t.grains_per_subset[c];
        continue;
      }
      // Positions in the dump have 1 um steps (2e-4 px): over the 11 rows of grains of a full
      // subset that is below 1e-4 in the gradient; the edge subsets, with a row or two, are
      // looser (not checked).
      if (t.grains_per_subset[c] < 60) continue;
      ++checked;
      EXPECT_NEAR(t.dudx[j], dudx, 1e-4) << "frame " << k << " subset " << c;
      EXPECT_NEAR(t.dudy[j], dudy, 1e-4) << "frame " << k << " subset " << c;
      EXPECT_NEAR(t.dvdx[j], 0, 1e-4) << "frame " << k << " subset " << c;
      EXPECT_NEAR(t.dvdy[j], 0, 1e-4) << "frame " << k << " subset " << c;
    }
  }
  EXPECT_GT(checked, 100u);
  fs::remove_all(dir);
}

TEST(DemScene, SensorReadsHeldFreeFallAndContactForce) {
  const std::string dir = MakeDemDir("sensor");
  DemScene scene(ReadDemRecord(dir), TinySpec());
  const ImpactScene::SensorRecord rec = scene.MakeSensorRecord();
  const double h = 0.5 / scene.base().spec().sensor.rate_hz;
  std::size_t held = 0, falling = 0, contact = 0;
  for (std::size_t i = 0; i < rec.time_s.size(); ++i) {
    const double t = rec.time_s[i] - rec.impact_daq_time_s;  // since contact
    const double release = rec.release_daq_time_s - rec.impact_daq_time_s;
    if (t < release - h) {
      EXPECT_NEAR(rec.accel_g[i], 1, 1e-9) << t;
      ++held;
    } else if (t > release + h && t < -h) {
      EXPECT_NEAR(rec.accel_g[i], 0, 1e-6) << t;
      ++falling;
    } else if (t > h) {
      EXPECT_NEAR(rec.accel_g[i], kForce / (kMass * kG), 1e-6) << t;
      ++contact;
    }
  }
  EXPECT_GT(held, 100u);
  EXPECT_GT(falling, 100u);
  EXPECT_GT(contact, 100u);
  // One exposure pulse per frame: rising edges at the frame times.
  int edges = 0;
  for (std::size_t i = 1; i < rec.exposure.size(); ++i)
    if (rec.exposure[i] > 0.5 && rec.exposure[i - 1] < 0.5) ++edges;
  EXPECT_EQ(edges, scene.frame_count());
  fs::remove_all(dir);
}

TEST(DemScene, RendersGrainsAndPounder) {
  const std::string dir = MakeDemDir("render");
  DemScene scene(ReadDemRecord(dir), TinySpec());
  const cv::Mat img = scene.RenderFrame(0, /*with_noise=*/false);
  ASSERT_EQ(img.rows, 120);
  ASSERT_EQ(img.cols, 160);
  // Below the surface under the axis: grains (their levels vary), above the bed: pores or pounder.
  const cv::Point2d deep = scene.base().IdealFromPanel({-150, 60});
  const cv::Mat patch =
      img(cv::Rect(static_cast<int>(deep.x) - 5, static_cast<int>(deep.y) - 5, 10, 10));
  double lo = 0, hi = 0;
  cv::minMaxLoc(patch, &lo, &hi);
  EXPECT_GT(hi - lo, 40) << "the grains are the texture";
  fs::remove_all(dir);
}

TEST(DemScene, MalformedDumpNamesFileAndLine) {
  const std::string dir = MakeDemDir("malformed");
  {
    std::ofstream dump(dir + "/grains.dump");
    dump << "ITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n2\nITEM: BOX BOUNDS ff ff pp\n0 1\n0 1\n"
            "0 1\nITEM: ATOMS id x y vx vy radius mass\n1 0.1 0.2 0 0 0.002 0.01\n2 0.1 oops\n";
  }
  try {
    ReadLammpsDump(dir + "/grains.dump");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("grains.dump:11"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

// A DEM file is an input like any other (io/input_file.h): a folder in its place is named as one,
// not read as an empty or malformed dump.
TEST(DemScene, AFolderInPlaceOfADumpIsNamed) {
  const std::string dir = MakeDemDir("folder_dump");
  fs::remove(dir + "/grains.dump");
  fs::create_directory(dir + "/grains.dump");
  try {
    ReadDemRecord(dir);
    FAIL() << "no error";
  } catch (const Error& e) {
    const std::string text = e.what();
    EXPECT_NE(text.find("grains.dump"), std::string::npos) << text;
    EXPECT_NE(text.find("a folder"), std::string::npos) << text;
  }
  fs::remove_all(dir);
}

// The floor windows become the scene's base force channels: position, area, the DAQ record
// (each sample the force's average over its interval, the static load subtracted in the truth)
// and the truth's peak, onset and stress ratio, all of a known half-sine pulse.
TEST(DemScene, FloorWindowsBecomeBaseChannelsWithKnownTruth) {
  const std::string dir = MakeDemDir("floor");
  AddFloorRecord(dir);
  ImpactSceneSpec spec = TinySpec();
  spec.base_sensors.noise_n = 0;
  DemScene scene(ReadDemRecord(dir), spec);
  const SceneBaseSensorOptions& b = scene.base().spec().base_sensors;
  ASSERT_EQ(b.columns.size(), 2u);
  EXPECT_EQ(b.columns[0], "base_center_N");
  EXPECT_EQ(b.columns[1], "base_offset_N");
  EXPECT_NEAR(b.offset_mm[0], 0, 1e-9);
  EXPECT_NEAR(b.offset_mm[1], 1000 * kFloorOffset, 1e-9);
  for (int w = 0; w < 2; ++w) {
    EXPECT_NEAR(b.depth_mm[w], 1000 * kSurfaceY, 1e-6);  // the floor is y = 0
    EXPECT_NEAR(b.area_mm2[w], 1e6 * kFloorWidth * kDepth, 1e-6);
    EXPECT_NEAR(scene.floor_static_N(w), kFloorStatic[w], 1e-9);
  }
  const ImpactScene::SensorRecord rec = scene.MakeSensorRecord();
  ASSERT_EQ(rec.base_force_true_n.size(), 2u);
  const double dt = 1 / spec.sensor.rate_hz;
  const DemTruth& t = scene.truth();
  // The pounder's peak stress: its constant contact force less its weight over D t_z.
  const double pounder_stress = (kForce - kMass * kG) / (0.15 * kDepth);
  EXPECT_NEAR(t.pounder_peak_stress_Pa, pounder_stress, 1e-6 * pounder_stress);
  for (std::size_t w = 0; w < 2; ++w) {
    const double A = kFloorAmplitude[w], t0 = kFloorStart[w] - kContact;  // since contact
    for (std::size_t i = 0; i < rec.time_s.size(); ++i) {
      const double ti = rec.time_s[i] - rec.impact_daq_time_s;
      // The impulse is exact at the 8-step nodes and linear between them: a DAQ interval that
      // does not start on a node differs by the force's change over 20 us, < 0.5 % of A.
      const double expected = HalfSineAverage(A, t0, kFloorPulse, ti - dt / 2, ti + dt / 2);
      EXPECT_NEAR(rec.base_force_true_n[w][i], expected, 0.005 * A) << ti;
      EXPECT_NEAR(rec.base_force_n[w][i], kFloorStatic[w] + expected + spec.base_sensors.offset_n,
                  0.005 * A);
    }
    // Peak at the pulse's middle (to a DAQ sample), of height A (a 40 us average of the top of
    // the sine: 1 - (pi dt / T)^2 / 24 = 1 - 2.6e-5).
    EXPECT_NEAR(t.base_peak_s[w], t0 + kFloorPulse / 2, dt / 2 + 1e-9);
    EXPECT_NEAR(t.base_peak_force_N[w], A, 1e-3 * A);
    // Onset: the line through the 10 % and 50 % crossings, sin(pi tau / T) = 0.1 and 0.5,
    // meets 0 at tau10 - (tau50 - tau10) / 4; the crossings are interpolated linearly between
    // samples, within ~1 us here.
    const double pi = 3.14159265358979323846;
    const double tau10 = kFloorPulse / pi * std::asin(0.1), tau50 = kFloorPulse / 6;
    EXPECT_NEAR(t.base_rise_10_s[w], t0 + tau10, 5e-6);
    EXPECT_NEAR(t.base_rise_50_s[w], t0 + tau50, 5e-6);
    EXPECT_NEAR(t.base_onset_s[w], t0 + tau10 - (tau50 - tau10) / 4, 5e-6);
    const double ratio = t.base_peak_force_N[w] / (kFloorWidth * kDepth) / pounder_stress;
    EXPECT_NEAR(t.base_stress_ratio[w], ratio, 1e-9);
    const double r = std::hypot(b.offset_mm[w], b.depth_mm[w]) / 1000;
    EXPECT_NEAR(t.base_peak_speed_m_s[w], r / (t.base_peak_s[w] - t.pounder_peak_decel_s), 1e-9);
  }
  fs::remove_all(dir);
}

TEST(DemScene, FloorWindowKeysComeAllThreeOrNone) {
  const std::string dir = MakeDemDir("floor_keys");
  {
    std::ofstream meta(dir + "/meta.txt", std::ios::app);
    meta << "floor_window_width_m 0.05\n";
  }
  try {
    ReadDemRecord(dir);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("floor_window_center_x_m"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

TEST(DemScene, MalformedFloorLineNamesFileAndLine) {
  const std::string dir = MakeDemDir("floor_bad");
  AddFloorRecord(dir);
  {
    std::ofstream floor(dir + "/floor.txt", std::ios::app);
    floor << "99999 12\n";
  }
  try {
    ReadDemRecord(dir);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("floor.txt:"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

// A plane pulse of fixed shape (a Gaussian of width 0.15 ms) travelling at 80 m/s: both speeds
// come back to the fit's precision, the layers outside 0.15-0.85 of the depth stay out.
DemPWaveRecord KnownPlaneWave(double c_m_s) {
  DemPWaveRecord r;
  r.timestep_s = 2.5e-6;
  r.pulse_start_s = 5e-4;
  r.pulse_duration_s = 4e-4;
  r.bed_top_m = 0.3;
  for (int k = 1; k <= 14; ++k) r.layer_depth_m.push_back(0.02 * k);
  r.response_m_s.resize(r.layer_depth_m.size());
  for (std::int64_t step = 4; step <= 2400; step += 4) {
    r.step.push_back(step);
    const double t = static_cast<double>(step) * r.timestep_s - r.pulse_start_s;
    for (std::size_t k = 0; k < r.layer_depth_m.size(); ++k) {
      const double x = (t - 2e-4 - r.layer_depth_m[k] / c_m_s) / 1.5e-4;
      r.response_m_s[k].push_back(0.005 * std::exp(-x * x));
    }
  }
  return r;
}

TEST(DemPWave, DefaultOptionsPassAndBadFractionsAreNamed) {
  EXPECT_NO_THROW(DemPWaveOptions{}.Check());
  for (const auto& [lo, hi] : {std::pair{0.5, 0.5}, {-0.1, 0.8}, {0.2, 1.1}}) {
    DemPWaveOptions o;
    o.min_depth_fraction = lo;
    o.max_depth_fraction = hi;
    try {
      o.Check();
      FAIL() << lo << " " << hi;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("depth_fraction"), std::string::npos) << e.what();
    }
  }
}

TEST(DemPWave, KnownPlaneWaveSpeedComesBack) {
  const DemPWave w = MeasurePWave(KnownPlaneWave(80));
  EXPECT_TRUE(w.problem.empty()) << w.problem;
  EXPECT_NEAR(w.speed_m_s, 80, 0.1);
  EXPECT_NEAR(w.speed_peak_m_s, 80, 0.1);
  EXPECT_LT(w.speed_sigma_m_s, 0.1);
  ASSERT_EQ(w.in_fit.size(), 14u);
  for (std::size_t k = 0; k < 14; ++k) {
    const double z = w.layer_depth_m[k];
    EXPECT_EQ(w.in_fit[k], z >= 0.045 && z <= 0.255 ? 1 : 0) << z;
    // Half peak at the Gaussian's half width before its centre.
    EXPECT_NEAR(w.half_peak_s[k], 2e-4 + z / 80 - 1.5e-4 * std::sqrt(std::log(2.0)), 1e-6) << z;
  }
  // Without a pulse: no speed, and the reason.
  DemPWaveRecord flat = KnownPlaneWave(80);
  for (auto& layer : flat.response_m_s) std::fill(layer.begin(), layer.end(), 0.0);
  const DemPWave none = MeasurePWave(flat);
  EXPECT_TRUE(std::isnan(none.speed_m_s));
  EXPECT_NE(none.problem.find("0 layers"), std::string::npos) << none.problem;
}

// pwave.txt minus pwave_rest.txt: the settled grains' own motion (the same in both) drops out.
TEST(DemPWave, ReadSubtractsTheRunWithoutThePulse) {
  const std::string dir = MakeDemDir("pwave");
  const DemPWaveRecord known = KnownPlaneWave(80);
  {
    std::ofstream meta(dir + "/pwave_meta.txt");
    meta << "timestep_s 2.5e-06\npulse_start_s 0.0005\npulse_duration_s 0.0004\n"
         << "pulse_stress_Pa 2000\nbed_top_m 0.3\nlayer_thickness_m 0.02\n";
    for (double z : known.layer_depth_m) meta << "layer_depth_m " << z << "\n";
    std::ofstream with(dir + "/pwave.txt"), without(dir + "/pwave_rest.txt");
    with.precision(14);
    without.precision(14);
    with << "# Time-averaged data for fix rec\n# TimeStep c_L1 ...\n";
    for (std::size_t i = 0; i < known.step.size(); ++i) {
      with << known.step[i];
      without << known.step[i];
      for (std::size_t k = 0; k < known.layer_depth_m.size(); ++k) {
        const double background = 1e-3 * std::sin(0.01 * static_cast<double>(i * (k + 1)));
        with << " " << background - known.response_m_s[k][i];  // vy up
        without << " " << background;
      }
      with << "\n";
      without << "\n";
    }
  }
  const DemRecord record = ReadDemRecord(dir);
  ASSERT_EQ(record.pwave.layer_depth_m.size(), known.layer_depth_m.size());
  for (std::size_t k = 0; k < known.layer_depth_m.size(); ++k)
    for (std::size_t i = 0; i < known.step.size(); ++i)
      EXPECT_NEAR(record.pwave.response_m_s[k][i], known.response_m_s[k][i], 1e-12);
  // A rest run of another length is refused by name.
  {
    std::ofstream without(dir + "/pwave_rest.txt", std::ios::app);
    without << "999999";
    for (std::size_t k = 0; k < known.layer_depth_m.size(); ++k) without << " 0";
    without << "\n";
  }
  try {
    ReadDemPWave(dir);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("pwave_rest.txt"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

TEST(DemScene, FrameRateMismatchIsAnError) {
  const std::string dir = MakeDemDir("fps");
  ImpactSceneSpec spec = TinySpec();
  spec.fps = 2000;
  try {
    DemScene scene(ReadDemRecord(dir), spec);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("camera.fps"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace impactdic
