// One analysis route. `impactdic analyze SCENE` runs the stages of `run` after the
// correlation on the /dic group of a results file (pipeline/scene_analysis.h: a load_dic stage in
// place of frames and correlate), so on a run's own results.h5 it gives the run's analysis: every
// dataset of /sensor, /kinematics, /momentum, /model and /strain, and every key figure of
// summary.json, equal to 1e-12 (relative). Before, `analyze` had a route of its own (its own
// uncertain-sample rule, mm/px and frame timing) and wrote no /model or /strain.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "../cli/cli_runner.h"
#include "../core/route_compare.h"
#include "../io/test_dir.h"
#include "../reliability/fault_util.h"
#include "impactdic/core/error.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/yaml.h"
#include "impactdic/momentum/scene_analysis.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/pipeline/scene_analysis.h"

namespace impactdic {
namespace {

// The sample with its strain stage (strain.enabled), without the figures and views, run once
// per process; `correlation` is the run's correlation alone (its analysis groups left out: what
// `correlate -o` holds), in a file of its own (the run folder's results.h5 belongs with its
// summary.json).
struct Prepared {
  TestDir dir;
  std::string scene, correlation, run_output;
  bool ok = false;
};

const Prepared& Prepare() {
  static Prepared* p = [] {
    auto* q = new Prepared;
    q->scene = SampleScene(q->dir, {{"xdmf: true", "xdmf: false"}});
    const CliResult run = RunCli("-q run " + q->scene + " -o " + q->dir.File("run"));
    q->run_output = run.output;
    if (run.exit_code != 0) return q;
    q->correlation = q->dir.File("correlation.h5");
    H5Writer copy(q->correlation, H5Writer::Mode::kUpdate, q->dir.File("run/results.h5"));
    for (const char* group :
         {"/sensor", "/kinematics", "/momentum", "/model", "/strain", "/summary"})
      copy.Remove(group);
    copy.Commit();
    q->ok = true;
    return q;
  }();
  return *p;
}

TEST(AnalyzeRoute, AnalyzeOfARunsResultsEqualsTheRunsOwnAnalysis) {
  const Prepared& p = Prepare();
  ASSERT_TRUE(p.ok) << p.run_output;
  const TestDir& dir = p.dir;
  const std::string& scene = p.scene;
  const std::string results = dir.File("analysed.h5");
  std::filesystem::copy_file(p.correlation, results);
  const CliResult analyze =
      RunCli("-q analyze " + scene + " --results " + results + " --format json");
  ASSERT_EQ(analyze.exit_code, 0) << analyze.output;

  // Every dataset of the analysis groups, in both files, equal.
  const H5Reader ran(dir.File("run/results.h5"));
  const H5Reader analysed(results);
  std::size_t compared = 0;
  for (const std::string group : {"/sensor", "/kinematics", "/momentum", "/model", "/strain"}) {
    ASSERT_TRUE(ran.Exists(group)) << group;
    ASSERT_TRUE(analysed.Exists(group)) << group << " not written by analyze";
    std::vector<std::string> in_run, in_analysis;
    Datasets(ran, group, &in_run);
    Datasets(analysed, group, &in_analysis);
    std::sort(in_run.begin(), in_run.end());
    std::sort(in_analysis.begin(), in_analysis.end());
    EXPECT_EQ(in_run, in_analysis) << group;
    for (const std::string& path : in_run) {
      if (!analysed.Exists(path)) continue;
      Dims run_dims, analysis_dims;
      const std::vector<double> a = ran.ReadDouble(path, &run_dims);
      const std::vector<double> b = analysed.ReadDouble(path, &analysis_dims);
      ASSERT_EQ(run_dims, analysis_dims) << path;
      std::size_t differ = 0, first = a.size();
      for (std::size_t i = 0; i < a.size(); ++i) {
        if (Equal(a[i], b[i])) continue;
        if (differ++ == 0) first = i;
      }
      EXPECT_EQ(differ, 0u) << path << ": " << differ << " of " << a.size()
                            << " values differ, the first at " << first << ": "
                            << (first < a.size() ? a[first] : 0) << " vs "
                            << (first < b.size() ? b[first] : 0);
      ++compared;
    }
  }
  EXPECT_GE(compared, 40u);  // The groups are not empty.
  EXPECT_EQ(analysed.ReadNumberAttribute("/kinematics", "mm_per_px"),
            ran.ReadNumberAttribute("/kinematics", "mm_per_px"));

  // Every key figure (summary.json: measured and modelled, strain, usable, failures, warnings)
  // equal: analyze's JSON carries them under "summary".
  const YAML::Node run_summary = LoadYamlFile(dir.File("run/summary.json"), "summary.json");
  const std::string& out = analyze.output;
  const YAML::Node analysis =
      YAML::Load(out.substr(out.find('{'), out.rfind('}') + 1 - out.find('{')));
  ASSERT_TRUE(analysis["summary"]) << out;
  std::vector<std::string> differences;
  Compare(analysis["summary"], run_summary, "summary", &differences);
  std::string listed;
  for (const std::string& d : differences) listed += "  " + d + "\n";
  EXPECT_TRUE(differences.empty()) << "analyze's figures differ from the run's:\n" << listed;
  EXPECT_GE(run_summary.size(), 20u);
}

// The stages hand each other typed outputs in SceneRunData (the summary is only
// written): the model's v0 is the sensor record's, the peak stage is t_e from the momentum stage
// and the measured peak deceleration is read over it (it was read back out of the summary's
// figures by a step outside the stages).
TEST(AnalyzeRoute, StagesHandEachOtherTypedOutputs) {
  const Prepared& p = Prepare();
  ASSERT_TRUE(p.ok) << p.run_output;
  const std::string results = p.dir.File("typed.h5");
  std::filesystem::copy_file(p.correlation, results);
  const SceneAnalysisRun run = AnalyzeSceneResults(LoadScene(p.scene), results);
  const SceneRunData& d = run.data;
  ASSERT_TRUE(d.sensor && d.momentum && d.model && d.strain);
  EXPECT_EQ(d.model_parameters.impact_velocity_m_s, d.sensor->summary.impact_velocity_m_s);
  const double t_e = d.momentum->summary.t_end_peak_s;
  ASSERT_TRUE(std::isfinite(t_e));
  EXPECT_EQ(d.peak_stage_s, t_e);
  EXPECT_EQ(d.peak_deceleration_measured_g, MeasuredPeakDeceleration(*d.sensor, t_e));
  const SceneFigures& f = run.summary.figures;
  EXPECT_EQ(f.peak_deceleration_measured_g, d.peak_deceleration_measured_g);
  EXPECT_EQ(f.t_end_peak_s, t_e);
  ASSERT_TRUE(run.summary.strain);
  EXPECT_EQ(run.summary.strain->crater_depth_model_mm, 1e3 * d.model->summary.crater_depth_m);
  // The stages that ran, in the graph's order, load_dic in place of frames and correlate.
  std::string stages;
  for (const StageReport& s : run.summary.stages) stages += s.name + (s.ran ? "+ " : "- ");
  EXPECT_EQ(stages, "calibrate+ sensor+ load_dic+ kinematics+ momentum+ model+ strain+ ");
}

}  // namespace
}  // namespace impactdic
