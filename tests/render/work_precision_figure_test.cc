#include "impactdic/render/work_precision_figure.h"

#include <gtest/gtest.h>

#include <vector>

#include "impactdic/core/error.h"

namespace impactdic {
namespace {

WorkPrecisionRow Row(const std::string& case_name, const std::string& solver, double time_s,
                     double error) {
  WorkPrecisionRow r;
  r.case_name = case_name;
  r.solver = solver;
  r.wall_time_s = time_s;
  r.depth_error = error;
  return r;
}

TEST(WorkPrecisionFigure, OneLogLogSeriesPerSolverOfTheCase) {
  const std::vector<WorkPrecisionRow> rows = {
      Row("default", "dopri5", 1e-5, 1e-6),
      Row("harmonic-exact", "dopri5", 2e-5, 1e-7),
      Row("default", "stiff", 3e-5, 1e-5),
      Row("default", "dopri5", 2e-5, 0.0),
  };
  const Plot plot = WorkPrecisionPlot(rows, "default");
  EXPECT_TRUE(plot.log_x && plot.log_y);
  ASSERT_EQ(plot.series.size(), 2u);
  EXPECT_EQ(plot.series[0].label, "dopri5");
  EXPECT_EQ(plot.series[0].x, (std::vector<double>{1e-5, 2e-5}));
  // An exact result (error 0) is drawn at 1e-17 so that the log axis keeps it.
  EXPECT_EQ(plot.series[0].y, (std::vector<double>{1e-6, 1e-17}));
  EXPECT_EQ(plot.series[1].label, "stiff");
  EXPECT_NE(plot.title.find("default"), std::string::npos);
}

TEST(WorkPrecisionFigure, UnknownCaseIsAnErrorNamingIt) {
  try {
    WorkPrecisionPlot({Row("default", "dopri5", 1e-5, 1e-6)}, "table1-max");
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("table1-max"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace impactdic
