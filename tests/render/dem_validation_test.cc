// Tests of the DEM validation comparison (render/dem_validation.h): a results file that equals the
// grains' truth plus known errors gives those errors back; the figures are drawn from results
// without frames and from a real run's results with the default frame preview.
#include "impactdic/render/dem_validation.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "../cli/cli_runner.h"
#include "../synth/dem_test_record.h"
#include "impactdic/io/csv.h"
#include "impactdic/io/dic_results.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/results_layout.h"
#include "impactdic/kinematics/kinematics_results.h"
#include "impactdic/momentum/momentum_results.h"
#include "impactdic/synth/dem_scene.h"
#include "impactdic/synth/impact_scene.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

// Writes a results.h5 as `impactdic run` lays it out (the groups' owners' writers), from the truth
// of `scene`: the analysed frames from the reference on, every DIC subset; velocities = truth +
// (dvx, 0) mm/s, p_gran = truth * gran_factor.
void WriteFakeResults(const DemScene& scene, const std::string& path, double dvx,
                      double gran_factor) {
  const DemTruth& t = scene.truth();
  const auto& grid = scene.base().dic_grid().centres_px;
  const std::size_t N = grid.size(), F = t.frame_time_s.size(), kr = t.reference_frame;
  std::vector<double> index, x, y, u, v, vx, vy, pg, pp, vs, madd;
  for (const auto& c : grid) x.push_back(c.x), y.push_back(c.y);
  for (std::size_t k = kr; k < F; ++k) {
    index.push_back(static_cast<double>(k));
    for (std::size_t i = 0; i < N; ++i) {
      const std::size_t j = k * N + i;
      u.push_back(t.u_px[j] - t.u_px[kr * N + i]);
      v.push_back(t.v_px[j] - t.v_px[kr * N + i]);
      vx.push_back(t.velocity_x_mm_s[j] + dvx);
      vy.push_back(t.velocity_y_mm_s[j]);
    }
    pg.push_back(gran_factor * t.p_gran_Ns[k]);
    pp.push_back(dem_test::kMass * scene.Pounder(t.frame_time_s[k]).v_m_s);
    vs.push_back(t.v_sand_m_s[k]);
    madd.push_back(std::nan(""));
  }
  const std::size_t Fa = index.size();
  H5Writer out(path);
  out.Write(results_layout::kTimeFrameIndex, index, Dims{Fa}, "1", "frame index");
  std::vector<double> t_ms, t_s;
  for (double k : index) t_s.push_back(t.frame_time_s[static_cast<std::size_t>(k)]);
  for (double ts : t_s) t_ms.push_back(1e3 * ts);
  out.Write(results_layout::kTimeMs, t_ms, Dims{Fa}, "ms", "time since the impact");
  // Each group by its owner's writer.
  DicResultsTable dic;
  dic.rows = Fa;
  dic.subsets = N;
  dic.x_px = x, dic.y_px = y, dic.u_px = u, dic.v_px = v;
  WriteDicResults(out, dic);
  KinematicsResult kin;
  kin.frames = Fa, kin.subsets = N;
  kin.time_s = t_s, kin.x_mm = x, kin.y_mm = y;
  kin.vel_x_mm_s = vx, kin.vel_y_mm_s = vy;
  kin.disp_x_mm = kin.disp_y_mm = kin.acc_x_mm_s2 = kin.acc_y_mm_s2 =
      std::vector<double>(Fa * N, 0.0);
  WriteKinematicsResults(out, kin, /*frame_time_daq_s=*/{});
  MomentumResult m;
  m.frame_time_s = t_s;
  m.p_gran_kg_m_s = pg, m.p_pounder_kg_m_s = pp, m.v_sand_m_s = vs, m.added_mass_kg = madd;
  for (std::size_t f = 0; f < Fa; ++f) {
    m.v_pounder_m_s.push_back(pp[f] / dem_test::kMass);
    m.p_total_kg_m_s.push_back(pp[f] + pg[f]);
  }
  m.a_sand_m_s2 = m.valid_subsets = std::vector<double>(Fa, 0.0);
  m.summary.p_max_kg_m_s = t.p_max_Ns;
  m.summary.t_end_peak_s = t.t_e_s;
  WriteMomentumResults(out, m, /*impact_time_s=*/0);
  out.Commit();
}

TEST(DemValidation, KnownErrorsComeBack) {
  const std::string dir = dem_test::MakeDemDir("validation");
  DemScene scene(ReadDemRecord(dir), dem_test::TinySpec());
  const std::string scene_dir = dir + "/scene";
  DemSceneReport report = WriteDemScene(scene, scene_dir);
  const std::string results = dir + "/results.h5";
  WriteFakeResults(scene, results, /*dvx=*/10, /*gran_factor=*/1.02);
  const DemValidation v = ValidateDemRun(report.truth_h5, results);
  EXPECT_GT(v.dic_samples, 100u);
  EXPECT_NEAR(v.dic_velocity_rms_mm_s, 10, 1e-9);
  EXPECT_NEAR(v.dic_displacement_rms_px, 0, 1e-9);
  // Uniform motion: a perfect DIC (central differences) equals the grains' velocity.
  EXPECT_NEAR(v.dic_velocity_rms_fd_mm_s, 10, 1e-3);
  const DemTruth& t = scene.truth();
  EXPECT_NEAR(v.p_gran_ratio_peak, 1.02, 1e-9);
  EXPECT_NEAR(v.p_gran_error_peak_Ns, 0.02 * t.grid_mass_kg * dem_test::kVGrain, 1e-9);
  EXPECT_NEAR(v.p_gran_error_peak_rel, 0.02 * t.grid_mass_kg * dem_test::kVGrain / t.p_max_Ns,
              1e-9);
  EXPECT_NEAR(v.p_max_truth_Ns, t.p_max_Ns, 1e-12);
  EXPECT_NEAR(v.t_e_truth_s, t.t_e_s, 1e-12);
  // No sigmoid in the results: Eq. 9 is not run, and the report says why.
  EXPECT_TRUE(std::isnan(v.model_peak_decel_g));
  ASSERT_FALSE(v.notes.empty());
  EXPECT_NE(v.notes.back().find("no sigmoid fit"), std::string::npos);
  // The DEM pounder's deceleration: F / (m_p g) - 1 in contact.
  EXPECT_NEAR(v.dem_peak_decel_g, dem_test::kForce / (dem_test::kMass * dem_test::kG) - 1, 1e-6);
  fs::remove_all(dir);
}

// A results file without camera frames (`outputs.frames: none`): the comparison figures that
// need no frame are drawn, the velocity-field figure is skipped with a note.
TEST(DemValidation, FiguresWithoutStoredFramesSkipTheVelocityField) {
  const std::string dir = dem_test::MakeDemDir("no_frames");
  DemScene scene(ReadDemRecord(dir), dem_test::TinySpec());
  DemSceneReport report = WriteDemScene(scene, dir + "/scene");
  const std::string results = dir + "/results.h5";
  WriteFakeResults(scene, results, /*dvx=*/0, /*gran_factor=*/1);
  const std::string figures = dir + "/figures";
  const DemValidation v = ValidateDemRun(report.truth_h5, results, figures);
  EXPECT_TRUE(fs::is_regular_file(fs::path(figures) / "momentum_compare.png"));
  EXPECT_TRUE(fs::is_regular_file(fs::path(figures) / "deceleration_compare.png"));
  EXPECT_FALSE(fs::exists(fs::path(figures) / "velocity_field_compare.png"));
  EXPECT_TRUE(std::any_of(v.notes.begin(), v.notes.end(), [](const std::string& n) {
    return n.find("no velocity-field figure") != std::string::npos;
  }));
  fs::remove_all(dir);
}

// The figures of a real `impactdic run` on DEM footage, written with the default outputs: its
// results.h5 stores a preview of the frames (outputs.frames: preview, <= 16 images of the
// analysed frames, /frames/row), not one per analysed frame. Until 2026-11 the velocity-field
// figure failed on such a file ("vx_mm_s/vy_mm_s ... got 11520 values; expected 2880"): only
// hand-written results with every frame had been compared.
TEST(DemValidation, FiguresFromARunWithTheDefaultFramePreview) {
  const std::string dir = dem_test::MakeDemDir("preview");
  // 1 mm/px: the 4.8 mm lattice grains are ~5 px wide, a texture the DIC can follow.
  ImpactSceneSpec spec = dem_test::TinySpec();
  spec.width = 320;
  spec.height = 160;
  spec.mm_per_px = 1.0;
  spec.subset_size = 21;
  spec.step = 12;
  DemScene scene(ReadDemRecord(dir), spec);
  const DemSceneReport report = WriteDemScene(scene, dir + "/scene");
  const std::string run = dir + "/run";
  const CliResult r = RunCli("run " + report.scene_yaml + " -o " + run);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string results = run + "/results.h5";
  {
    const H5Reader in(results);
    ASSERT_TRUE(in.Exists(results_layout::kFrameRows)) << "not a preview: the test needs one";
    EXPECT_LT(in.ReadDouble(results_layout::kFrameRows).size(),
              in.ReadDouble("/time/frame_index").size());
  }
  const std::string figures = dir + "/figures";
  const DemValidation v = ValidateDemRun(report.truth_h5, results, figures);
  EXPECT_GT(v.dic_samples, 100u);
  // The velocity field is drawn after the contact, at the stored frame nearest the grains' t_e.
  ASSERT_TRUE(std::isfinite(v.t_e_truth_s));
  EXPECT_GT(v.velocity_figure_t_s, 0);
  {
    const H5Reader in(results);
    double nearest = HUGE_VAL;
    const std::vector<double> rows = in.ReadDouble(results_layout::kFrameRows);
    for (double row : rows) {
      const double t = v.t_s.at(static_cast<std::size_t>(row));
      if (t > 0 && std::abs(t - v.t_e_truth_s) < std::abs(nearest - v.t_e_truth_s)) nearest = t;
    }
    EXPECT_EQ(v.velocity_figure_t_s, nearest);
  }
  for (const char* png : {"velocity_field_compare.png", "velocity_field_compare_small.png",
                          "frame_small.png", "momentum_compare.png", "deceleration_compare.png"})
    EXPECT_TRUE(fs::is_regular_file(fs::path(figures) / png)) << png;
  // The same through the command line, as docs/validation.md runs it.
  const CliResult cli = RunCli("validate-dem " + report.truth_h5 + " " + results + " --figures " +
                               dir + "/figures_cli");
  EXPECT_EQ(cli.exit_code, 0) << cli.output;
  EXPECT_TRUE(fs::is_regular_file(fs::path(dir) / "figures_cli/velocity_field_compare.png"));
  // Every frame stored (as validation/dem/run_case.sh runs it): the figure is within half a frame
  // interval of the grains' t_e, with no note about a preview.
  const CliResult all =
      RunCli("run " + report.scene_yaml + " --outputs.frames all -o " + run + "_all");
  ASSERT_EQ(all.exit_code, 0) << all.output;
  const DemValidation w =
      ValidateDemRun(report.truth_h5, run + "_all/results.h5", figures + "_all");
  const double interval = (w.t_s.back() - w.t_s.front()) / (w.t_s.size() - 1);
  EXPECT_NEAR(w.velocity_figure_t_s, w.t_e_truth_s, 0.5 * interval + 1e-12);
  EXPECT_FALSE(std::any_of(w.notes.begin(), w.notes.end(), [](const std::string& n) {
    return n.find("velocity-field figure is drawn") != std::string::npos;
  }));
  fs::remove_all(dir);
}

// The wave comparison of a real `impactdic run` on DEM footage with floor windows (the record's
// half-sine floor pulses, dem_test_record.h): validate-dem pairs each truth channel with the
// run's /wave channel of the same column, and the run measures the known pulses: the peak at
// the pulse's middle within 2 sigma_t, the onset on the rise, the stress ratio within 5 %: the
// zero-phase 1500 Hz filter lowers the half sine's peak by 2.6 % (its kinks at the start and
// end carry content above the cutoff), the pounder's constant contact force (its stress is the
// plateau's exactly) not at all. --wave-csv writes one row per channel.
TEST(DemValidation, WaveFiguresOfARunOnFloorWindows) {
  const std::string dir = dem_test::MakeDemDir("wave");
  dem_test::AddFloorRecord(dir);
  ImpactSceneSpec spec = dem_test::TinySpec();
  spec.width = 320;
  spec.height = 160;
  spec.mm_per_px = 1.0;
  spec.subset_size = 21;
  spec.step = 12;
  spec.base_sensors.noise_n = 0.05;
  DemScene scene(ReadDemRecord(dir), spec);
  const DemSceneReport report = WriteDemScene(scene, dir + "/scene");
  const std::string run = dir + "/run";
  const CliResult r = RunCli("run " + report.scene_yaml + " -o " + run);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string wave_csv = dir + "/wave.csv";
  const DemValidation v = ValidateDemFiles(report.truth_h5, run + "/results.h5", "", "", wave_csv);
  ASSERT_EQ(v.wave.size(), 2u);
  const H5Reader res(run + "/results.h5");
  const double sigma_t = res.ReadNumberAttribute("wave", "travel_time_sigma_s");
  const DemTruth& t = scene.truth();
  EXPECT_NEAR(v.pounder_peak_stress_truth_Pa, t.pounder_peak_stress_Pa, 1e-9);
  EXPECT_NEAR(v.pounder_peak_stress_tool_Pa, t.pounder_peak_stress_Pa,
              0.05 * t.pounder_peak_stress_Pa);
  std::printf("pounder peak stress: tool %.1f Pa, plateau %.1f Pa\n", v.pounder_peak_stress_tool_Pa,
              t.pounder_peak_stress_Pa);
  for (std::size_t w = 0; w < 2; ++w) {
    const DemWaveChannel& c = v.wave[w];
    SCOPED_TRACE(c.column);
    EXPECT_EQ(c.column, w == 0 ? "base_center_N" : "base_offset_N");
    EXPECT_EQ(c.peak_truth_s, t.base_peak_s[w]);
    EXPECT_EQ(c.stress_ratio_truth, t.base_stress_ratio[w]);
    const double middle = dem_test::kFloorStart[w] - dem_test::kContact + dem_test::kFloorPulse / 2;
    EXPECT_NEAR(c.peak_tool_s, middle, 2 * sigma_t);
    EXPECT_NEAR(c.stress_ratio_tool, c.stress_ratio_truth, 0.05 * c.stress_ratio_truth);
    std::printf("%s: peak %.4f ms (middle %.4f), onset %.4f ms (grains %.4f), ratio %.4f (%.4f)\n",
                c.column.c_str(), 1e3 * c.peak_tool_s, 1e3 * middle, 1e3 * c.onset_tool_s,
                1e3 * c.onset_truth_s, c.stress_ratio_tool, c.stress_ratio_truth);
    EXPECT_GE(c.onset_tool_s, c.onset_truth_s - (c.rise_50_truth_s - c.rise_10_truth_s));
    EXPECT_LE(c.onset_tool_s, c.onset_truth_s + 2 * sigma_t);
  }
  // No P-wave run in this record: its figures are NaN, not made up.
  EXPECT_TRUE(std::isnan(v.p_wave_speed_m_s));
  EXPECT_TRUE(std::isnan(v.wave[0].p_wave_travel_s));
  CsvReadOptions nan_ok;
  nan_ok.allow_non_finite = true;
  const CsvTable table = ReadCsv(wave_csv, nan_ok);
  EXPECT_EQ(table.names, DemValidationWaveCsvColumns());
  EXPECT_EQ(table.rows(), 2u);
  // The DIC front, the tool's and the grains': measured, or NaN with the reason (never a bare
  // NaN), and in the CSV as in the comparison.
  for (const auto& [name, f] : {std::pair<const char*, const DemFront&>{"tool", v.front_tool},
                                {"dem", v.front_grains},
                                {"dem_fd", v.front_grains_fd}}) {
    SCOPED_TRACE(name);
    EXPECT_EQ(std::isfinite(f.speed_m_s), f.problem.empty()) << f.problem;
    std::printf("front %s: %.2f m/s (%s)\n", name, f.speed_m_s, f.problem.c_str());
    const std::vector<double>& col = table.Column(std::string("front_speed_") + name + "_m_s");
    for (double x : col)
      EXPECT_TRUE(x == f.speed_m_s || (std::isnan(x) && std::isnan(f.speed_m_s))) << x;
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace impactdic
