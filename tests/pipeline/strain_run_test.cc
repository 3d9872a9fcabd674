// The strain stage through `run`: on the small synthesised scene, a run
// with strain.enabled writes /strain (datasets [F x N] with units, the conventions and the
// compacted zone as attributes), strain.csv and the summary's strain figures next to the crater
// depths; with strain.enabled false (the default) results.h5 has no /strain and the folder no
// extra file; without the momentum stage the t_e figures are NaN with the reason.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "../cli/cli_runner.h"
#include "../io/test_dir.h"
#include "impactdic/io/csv.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/results_layout.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/strain/strain_results.h"
#include "scene_text.h"
#include "small_scene_spec.h"

namespace impactdic {
namespace {
namespace fs = std::filesystem;
namespace L = results_layout;

std::set<std::string> FilesIn(const std::string& folder) {
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(folder)) names.insert(e.path().filename().string());
  return names;
}

// One synthesised scene for every case (rendering it is the slow part).
class StrainRun : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = std::make_unique<TestDir>("StrainRun");
    const CliResult synth = RunCli("-q synth " + dir_->Write("spec.yaml", kSmallSceneSpec) +
                                   " -o " + dir_->File("scene"));
    ASSERT_EQ(synth.exit_code, 0) << synth.output;
    // Figures and animation off: the test is about results.h5 and the tables.
    scene_text_ = Replace(
        Replace(ReadText(dir_->File("scene/scene.yaml")), "  figures: true", "  figures: false"),
        "  animation: true", "  animation: false");
  }
  static void TearDownTestSuite() { dir_.reset(); }

  // Runs the scene text (written beside the frames) into folder `out`.
  static PipelineSummary Run(const std::string& name, const std::string& text,
                             const std::string& out) {
    PipelineOptions options;
    options.output_folder = dir_->File(out);
    return RunScene(LoadScene(dir_->Write("scene/" + name, text)), options);
  }

  static std::unique_ptr<TestDir> dir_;
  static std::string scene_text_;
};
std::unique_ptr<TestDir> StrainRun::dir_;
std::string StrainRun::scene_text_;

const char* kStrainOn = "strain:\n  enabled: true\n";

TEST_F(StrainRun, EnabledWritesStrainWithItsAttributesTheCsvAndTheSummaryFigures) {
  const PipelineSummary s = Run("on.yaml", scene_text_ + kStrainOn, "on");
  ASSERT_TRUE(s.strain.has_value());
  const std::string out = dir_->File("on");
  EXPECT_EQ(FilesIn(out), (std::set<std::string>{".impactdic-output", "results.h5", "strain.csv",
                                                 "summary.csv", "summary.json", "timing.json"}));
  const H5Reader h5(out + "/results.h5");
  ASSERT_TRUE(h5.Exists(L::kStrainGroup));
  Dims dic_dims;
  h5.ReadDouble(L::kDicU, &dic_dims);
  for (const char* path : {L::kStrainEpsV, L::kStrainGxx, L::kStrainGammaMax, L::kStrainDensity,
                           L::kStrainEpsVRate, L::kStrainShearBand})
    EXPECT_EQ(h5.Dimensions(path), dic_dims) << path;
  EXPECT_EQ(h5.ReadStringAttribute(L::kStrainGroup, L::kStrainGradientAttr), "fit");
  EXPECT_NE(h5.ReadStringAttribute(L::kStrainGroup, L::kStrainConventionAttr)
                .find("COMPRESSION positive"),
            std::string::npos);
  EXPECT_EQ(h5.ReadStringAttribute(L::kStrainEpsVRate, "units"), "1/s");
  const StrainResult r = ReadStrainResults(h5, out + "/results.h5");
  // t_e from the momentum stage: its frame, and the zone at t_e and at the end on the panel.
  ASSERT_TRUE(r.te_known) << r.te_note;
  const double te_frame = h5.ReadNumberAttribute(L::kStrainGroup, "compacted_te_frame");
  EXPECT_EQ(static_cast<std::size_t>(te_frame), r.zone_te.frame);
  EXPECT_EQ(r.zone_end.frame, dic_dims[0] - 1);
  EXPECT_EQ(r.depth_from, "momentum.surface_y_px");
  EXPECT_EQ(r.surface_y_px, 59.5);
  EXPECT_EQ(r.dry_density_kg_m3, 1550);
  // The impact compacts the soil beneath the pounder: a zone at the end, below the surface.
  EXPECT_GT(r.zone_end.area_mm2, 0);
  EXPECT_GT(r.zone_end.depth_mm, 0);
  EXPECT_EQ(s.strain->compacted_depth_te_mm, r.zone_te.depth_mm);
  EXPECT_EQ(s.strain->compacted_area_end_mm2, r.zone_end.area_mm2);
  EXPECT_EQ(s.strain->crater_depth_model_mm, 1e3 * s.figures.crater_depth_model_m);
  EXPECT_EQ(s.strain->crater_depth_measured_mm, 1e3 * s.figures.crater_depth_measured_m);
  EXPECT_TRUE(std::isfinite(s.strain->crater_depth_measured_mm));
  // summary.json: the "strain" object; summary.csv: its columns.
  const std::string json = ReadText(out + "/summary.json");
  EXPECT_NE(json.find("\"strain\": {"), std::string::npos) << json;
  EXPECT_NE(json.find("\"compacted_depth_te_mm\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"crater_depth_model_mm\""), std::string::npos) << json;
  const CsvTable summary = ReadCsv(out + "/summary.csv", {.allow_non_finite = true});
  EXPECT_EQ(summary.Column("strain_compacted_depth_end_mm")[0], r.zone_end.depth_mm);
  // strain.csv: a row per frame and subset, the /strain values.
  const CsvTable csv = ReadCsv(out + "/strain.csv", {.allow_non_finite = true});
  ASSERT_EQ(csv.rows(), dic_dims[0] * dic_dims[1]);
  const std::size_t j = csv.rows() - 1;
  EXPECT_EQ(csv.Column("subset")[j], static_cast<double>(dic_dims[1] - 1));
  const double eps_v = r.field.eps_v[j];
  if (std::isnan(eps_v)) {
    EXPECT_TRUE(std::isnan(csv.Column("eps_v")[j]));
  } else {
    EXPECT_NEAR(csv.Column("eps_v")[j], eps_v, 1e-9 * std::max(1.0, std::abs(eps_v)));
  }
  EXPECT_EQ(csv.Column("shear_band")[j], r.shear_band[j]);
}

TEST_F(StrainRun, DisabledWritesNoStrainAndNoExtraFile) {
  const PipelineSummary s = Run("off.yaml", scene_text_, "off");
  EXPECT_FALSE(s.strain.has_value());
  const std::string out = dir_->File("off");
  EXPECT_EQ(FilesIn(out), (std::set<std::string>{".impactdic-output", "results.h5", "summary.csv",
                                                 "summary.json", "timing.json"}));
  const H5Reader h5(out + "/results.h5");
  EXPECT_FALSE(h5.Exists(L::kStrainGroup));
  EXPECT_EQ(ReadText(out + "/summary.json").find("strain"), std::string::npos);
  EXPECT_EQ(ReadText(out + "/summary.csv").find("strain"), std::string::npos);
  bool reported = false;
  for (const StageReport& r : s.stages) {
    if (r.name != "strain") continue;
    reported = true;
    EXPECT_FALSE(r.ran);
    EXPECT_EQ(r.note, "strain.enabled is false");
  }
  EXPECT_TRUE(reported);
}

TEST_F(StrainRun, WithoutTheMomentumStageTheTeFiguresAreNullWithTheReason) {
  // No sensor, momentum or pounder position: t_e unknown, depth from the grid's top row; no CSV.
  std::string text = Replace(scene_text_, "  sensor: sensor.csv\n", "");
  text = Replace(text, "  pounder_center_x_px: 160\n", "");
  text = Replace(text, "  surface_y_px: 59.5\n", "");
  text = Replace(text, "  csv: true", "  csv: false");
  const PipelineSummary s = Run("no_te.yaml", text + kStrainOn, "no_te");
  ASSERT_TRUE(s.strain.has_value());
  EXPECT_TRUE(std::isnan(s.strain->compacted_depth_te_mm));
  EXPECT_TRUE(std::isnan(s.strain->compacted_area_te_mm2));
  EXPECT_TRUE(std::isnan(s.strain->crater_depth_measured_mm));
  EXPECT_NE(s.strain->te_note.find("momentum stage did not run"), std::string::npos)
      << s.strain->te_note;
  EXPECT_EQ(s.strain->depth_from, "grid top row");
  const std::string out = dir_->File("no_te");
  EXPECT_EQ(FilesIn(out), (std::set<std::string>{".impactdic-output", "results.h5", "summary.json",
                                                 "timing.json"}));
  const std::string json = ReadText(out + "/summary.json");
  EXPECT_NE(json.find("\"compacted_depth_te_mm\": null"), std::string::npos) << json;
  EXPECT_NE(json.find("\"te_note\""), std::string::npos) << json;
  const H5Reader h5(out + "/results.h5");
  const StrainResult r = ReadStrainResults(h5, "results.h5");
  EXPECT_FALSE(r.te_known);
  EXPECT_EQ(r.depth_from, "grid top row");
  const std::vector<double> y = h5.ReadDouble(L::kDicY);
  EXPECT_EQ(r.surface_y_px, *std::min_element(y.begin(), y.end()));
}

TEST_F(StrainRun, WarpGradientIsTheCorrelationsSubsetWarpGradient) {
  // strain.gradient: warp makes the correlation keep the warp's gradient (/dic/*_warp) and the
  // strain stage use it as it is where the sample is valid.
  const PipelineSummary s =
      Run("warp.yaml", scene_text_ + "strain:\n  enabled: true\n  gradient: warp\n", "warp");
  ASSERT_TRUE(s.strain.has_value());
  EXPECT_EQ(s.strain->gradient, "warp");
  const H5Reader h5(dir_->File("warp/results.h5"));
  ASSERT_TRUE(h5.Exists(L::kDicDudxWarp));
  EXPECT_EQ(h5.ReadStringAttribute(L::kStrainGroup, L::kStrainGradientAttr), "warp");
  const std::vector<double> warp = h5.ReadDouble(L::kDicDvdyWarp);
  const std::vector<double> used = h5.ReadDouble(L::kStrainDvdy);
  const std::vector<double> u = h5.ReadDouble(L::kDicU);
  ASSERT_EQ(warp.size(), used.size());
  std::size_t finite = 0;
  for (std::size_t j = 0; j < used.size(); ++j) {
    if (std::isnan(used[j])) continue;
    ++finite;
    EXPECT_EQ(used[j], warp[j]) << j;
    EXPECT_TRUE(std::isfinite(u[j])) << j;
  }
  EXPECT_GT(finite, used.size() / 2);
  // The fit run (strain.gradient default) keeps no warp gradient in /dic.
  const PipelineSummary fit = Run("fit.yaml", scene_text_ + kStrainOn, "fit");
  EXPECT_EQ(fit.strain->gradient, "fit");
  EXPECT_FALSE(H5Reader(dir_->File("fit/results.h5")).Exists(L::kDicDudxWarp));
}

}  // namespace
}  // namespace impactdic
