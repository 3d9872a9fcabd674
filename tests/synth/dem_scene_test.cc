// Tests of the DEM scene converter (synth/dem_scene.h) on a DEM record written by the test in
// LAMMPS's formats, with a known answer: a lattice of grains translating uniformly at 1 m/s down
// and a pounder in free fall that meets a constant contact force.
#include "impactdic/synth/dem_scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <filesystem>
#include <fstream>

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
