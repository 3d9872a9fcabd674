// `impactdic model`'s request checked by the library (pipeline/model_runs.h): which inputs each
// run needs, the values read as their scene keys, the solver options and the study's lists, each
// refusal naming the key (or the flag the command typed for it).
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "impactdic/core/error.h"
#include "impactdic/pipeline/model_runs.h"
#include "impactdic/pipeline/scene.h"

namespace impactdic {
namespace {

// The Error `f` throws (where, found, expected), or a failure.
Error Refusal(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e;
  }
  ADD_FAILURE() << "accepted";
  return Error(ErrorKind::kInvalidValue, "", "", "");
}

ModelRequest SingleRun() {
  ModelRequest r;
  r.keys["test.mass_kg"] = 10;
  r.keys["test.width_m"] = 0.15;
  r.keys["test.drop_height_m"] = 0.7;
  return r;
}

TEST(ModelRequest, ASingleRunTakesItsTestFromTheKeys) {
  ModelRequest r = SingleRun();
  r.keys["model.K"] = 40;
  const ImpactModelParameters p = ModelRequestParameters(r);
  EXPECT_EQ(p.pounder_mass_kg, 10);
  EXPECT_EQ(p.width_m, 0.15);
  EXPECT_EQ(p.friction_K, 40);
  EXPECT_DOUBLE_EQ(p.impact_velocity_m_s, std::sqrt(2 * 9.81 * 0.7));
}

TEST(ModelRequest, ASingleRunNeedsMassWidthAndOneOfHeightAndVelocity) {
  ModelRequest r = SingleRun();
  r.keys.erase("test.mass_kg");
  Error e = Refusal([&] { ModelRequestParameters(r); });
  EXPECT_EQ(e.where(), "test.mass_kg");
  EXPECT_EQ(e.found(), "missing");
  r = SingleRun();
  r.keys.erase("test.width_m");
  EXPECT_EQ(Refusal([&] { ModelRequestParameters(r); }).where(), "test.width_m");
  r = SingleRun();
  r.keys["test.impact_velocity_m_s"] = 3;
  e = Refusal([&] { ModelRequestParameters(r); });
  EXPECT_EQ(e.where(), "test.drop_height_m/test.impact_velocity_m_s");
  EXPECT_EQ(e.found(), "both given");
  r.keys.erase("test.drop_height_m");
  r.keys.erase("test.impact_velocity_m_s");
  EXPECT_EQ(Refusal([&] { ModelRequestParameters(r); }).found(), "neither given");
  // Named as the command's flags when it gives them.
  r.key_names = {{"test.drop_height_m", "--height"}, {"test.impact_velocity_m_s", "--velocity"}};
  EXPECT_EQ(Refusal([&] { ModelRequestParameters(r); }).where(), "--height/--velocity");
}

TEST(ModelRequest, ValuesAreJudgedAsTheirSceneKeys) {
  ModelRequest r = SingleRun();
  r.keys["model.u"] = 0.5;
  r.key_names["model.u"] = "--u";
  const Error e = Refusal([&] { ModelRequestParameters(r); });
  EXPECT_EQ(e.where(), "--u");
  EXPECT_NE(e.expected().find("a damping factor u"), std::string::npos) << e.what();
  // g = 0 is allowed with an impact velocity (the exact solutions), not with a drop height.
  r = SingleRun();
  r.keys["test.g_m_s2"] = 0;
  EXPECT_EQ(Refusal([&] { ModelRequestParameters(r); }).where(), "test.g_m_s2");
  r.keys.erase("test.drop_height_m");
  r.keys["test.impact_velocity_m_s"] = 3;
  EXPECT_EQ(ModelRequestParameters(r).gravity_m_s2, 0);
}

TEST(ModelRequest, Table1AndTheStudyRefuseThePerTestKeys) {
  ModelRequest r;
  r.table1 = true;
  EXPECT_NO_THROW(ModelRequestParameters(r));
  r.keys["model.added_mass_kg"] = 3;
  Error e = Refusal([&] { ModelRequestParameters(r); });
  EXPECT_EQ(e.where(), "model.added_mass_kg");
  EXPECT_EQ(e.found(), "with --table1");
  r.keys.clear();
  r.work_precision = true;
  EXPECT_EQ(Refusal([&] { ModelRequestParameters(r); }).where(), "--work-precision");
}

TEST(ModelRequest, SolverOptionsAndStudyListsAreChecked) {
  ModelRequest r = SingleRun();
  r.solver = "stiff";
  r.ode45_defaults = true;
  EXPECT_EQ(Refusal([&] { ModelRequestSolverOptions(r); }).where(), "model.ode45_defaults");
  r = SingleRun();
  r.keys["model.rtol"] = NAN;
  EXPECT_EQ(Refusal([&] { ModelRequestSolverOptions(r); }).expected(), "a number");
  r = SingleRun();
  r.keys["model.rtol"] = 1e-8;
  r.keys["model.t_max_s"] = 2;
  r.error_estimator = "local";
  const ImpactSolverOptions o = ModelRequestSolverOptions(r);
  EXPECT_EQ(o.rtol, 1e-8);
  EXPECT_EQ(o.t_max_s, 2);
  EXPECT_EQ(o.error_estimator, ErrorEstimator::kLocalSum);
  r.wp_solvers = "dopri5,rk4";
  const Error e = Refusal([&] { ModelRequestStudy(r); });
  EXPECT_EQ(e.found(), "rk4");
  EXPECT_EQ(e.expected(), "a comma-separated list of dopri5, stiff, auto, ode45");
  r.wp_solvers = "stiff";
  r.wp_cases = "exact";
  const WorkPrecisionOptions w = ModelRequestStudy(r);
  EXPECT_EQ(w.solvers, std::vector<std::string>{"stiff"});
  EXPECT_TRUE(w.exact_cases);
  EXPECT_FALSE(w.table1);
  EXPECT_EQ(w.tolerances, WorkPrecisionOptions{}.tolerances);
  r.wp_tolerances = "1e-4,1e-8";
  r.wp_timing_budget_s = 0;
  const WorkPrecisionOptions t = ModelRequestStudy(r);
  EXPECT_EQ(t.tolerances, (std::vector<double>{1e-4, 1e-8}));
  EXPECT_EQ(t.timing_budget_s, 0);
  r.wp_tolerances = "1e-4,tight";
  EXPECT_EQ(Refusal([&] { ModelRequestStudy(r); }).where(), "--wp-tolerances");
  r.wp_tolerances = "0.5";
  EXPECT_EQ(Refusal([&] { ModelRequestStudy(r); }).where(), "--wp-tolerances");
  r.wp_tolerances = "";
  r.wp_timing_budget_s = -1;
  EXPECT_EQ(Refusal([&] { ModelRequestStudy(r); }).where(), "--wp-timing-budget");
  r.wp_timing_budget_s = 0;
  r.wp_cases = ",";
  EXPECT_EQ(Refusal([&] { ModelRequestStudy(r); }).expected(), "at least one case");
  r = SingleRun();
  r.format = "xml";
  std::ostringstream out;
  EXPECT_EQ(Refusal([&] { RunModelRequest(r, out); }).where(), "--format");
}

// The solver options the command had only as flags are scene keys too (model.*), for `run`.
TEST(ModelRequest, SolverFlagsAreSceneKeys) {
  const Scene s = ParseScene(
      "inputs: {frames: f/*.png}\n"
      "model: {error_estimator: local, ode45_defaults: true, t_max_s: 0.5}\n",
      "s.yaml");
  EXPECT_EQ(s.solver.error_estimator, ErrorEstimator::kLocalSum);
  EXPECT_TRUE(s.solver.ode45_defaults);
  EXPECT_EQ(s.solver.t_max_s, 0.5);
  for (const auto& [bad, key] :
       {std::pair{"model: {t_max_s: 0}", "model.t_max_s"},
        std::pair{"model: {error_estimator: x}", "model.error_estimator"}}) {
    const Error e = Refusal(
        [bad = bad] { ParseScene("inputs: {frames: f/*.png}\n" + std::string(bad), "s.yaml"); });
    EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace impactdic
