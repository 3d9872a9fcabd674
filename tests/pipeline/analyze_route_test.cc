// Issue 24: one analysis route. `impactdic analyze SCENE` runs the stages of `run` after the
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
#include <string>
#include <vector>

#include "../cli/cli_runner.h"
#include "../io/test_dir.h"
#include "../reliability/fault_util.h"
#include "impactdic/core/error.h"
#include "impactdic/io/hdf5_store.h"
#include "impactdic/io/yaml.h"

namespace impactdic {
namespace {

constexpr double kTolerance = 1e-12;  // Relative; the same stages on the same rows.

bool Equal(double a, double b) {
  if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
  return std::abs(a - b) <= kTolerance * std::max({1e-300, std::abs(a), std::abs(b)});
}

// Every dataset below `group` (recursively), as paths.
void Datasets(const H5Reader& in, const std::string& group, std::vector<std::string>* out) {
  for (const std::string& name : in.List(group)) {
    const std::string path = group + "/" + name;
    bool dataset = true;
    try {
      in.Dimensions(path);
    } catch (const Error&) {
      dataset = false;  // A group.
    }
    if (dataset) {
      out->push_back(path);
    } else {
      Datasets(in, path, out);
    }
  }
}

// The differences between two JSON values (numbers to kTolerance), each naming its key path.
void Compare(const YAML::Node& a, const YAML::Node& b, const std::string& path,
             std::vector<std::string>* differences) {
  if (a.Type() != b.Type()) {
    differences->push_back(path + ": of another type");
  } else if (a.IsMap()) {
    for (const auto& entry : b) {
      const std::string key = entry.first.as<std::string>();
      if (!a[key]) {
        differences->push_back(path + "." + key + ": missing");
      } else {
        Compare(a[key], entry.second, path + "." + key, differences);
      }
    }
    if (a.size() != b.size()) differences->push_back(path + ": other keys");
  } else if (a.IsSequence()) {
    if (a.size() != b.size()) {
      differences->push_back(path + ": another length");
      return;
    }
    for (std::size_t i = 0; i < a.size(); ++i)
      Compare(a[i], b[i], path + "[" + std::to_string(i) + "]", differences);
  } else if (a.IsScalar()) {
    double x = 0, y = 0;
    const bool numbers = a.Tag() != "!" && b.Tag() != "!" && YAML::convert<double>::decode(a, x) &&
                         YAML::convert<double>::decode(b, y);
    if (numbers ? !Equal(x, y) : a.Scalar() != b.Scalar())
      differences->push_back(path + ": " + a.Scalar() + " vs " + b.Scalar());
  }
}

TEST(AnalyzeRoute, AnalyzeOfARunsResultsEqualsTheRunsOwnAnalysis) {
  TestDir dir;
  // The sample with its strain stage (strain.enabled), without the figures and views.
  const std::string scene = SampleScene(dir, {{"xdmf: true", "xdmf: false"}});
  const CliResult run = RunCli("-q run " + scene + " -o " + dir.File("run"));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  // The run's correlation alone (its analysis groups left out: what `correlate -o` holds), in a
  // file of its own (the run folder's results.h5 belongs with its summary.json), analysed in place.
  const std::string results = dir.File("correlation.h5");
  {
    H5Writer copy(results, H5Writer::Mode::kUpdate, dir.File("run/results.h5"));
    for (const char* group :
         {"/sensor", "/kinematics", "/momentum", "/model", "/strain", "/summary"})
      copy.Remove(group);
    copy.Commit();
  }
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

}  // namespace
}  // namespace impactdic
