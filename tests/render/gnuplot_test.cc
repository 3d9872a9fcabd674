// The gnuplot driver: valid PNGs of the requested size, clear errors (missing or failing gnuplot,
// inconsistent plots, unwritable folders) that leave no output file behind.
#include "impactdic/render/gnuplot.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "../../src/render/subprocess.h"
#include "impactdic/core/error.h"
#include "test_util.h"

namespace impactdic {
namespace {

using test::IsPngOfSize;
using test::ScratchDir;

// Restores IMPACTDIC_GNUPLOT at the end of a test.
class EnvGuard {
 public:
  EnvGuard() {
    const char* v = std::getenv("IMPACTDIC_GNUPLOT");
    had_ = v != nullptr;
    if (had_) old_ = v;
  }
  ~EnvGuard() {
    if (had_)
      setenv("IMPACTDIC_GNUPLOT", old_.c_str(), 1);
    else
      unsetenv("IMPACTDIC_GNUPLOT");
  }

 private:
  bool had_ = false;
  std::string old_;
};

Plot SinePlot() {
  Plot plot;
  plot.title = "sine and cosine";
  plot.x_label = "time [ms]";
  plot.y_label = "amplitude [-]";
  PlotSeries s, c;
  for (int i = 0; i <= 100; ++i) {
    s.x.push_back(0.1 * i);
    s.y.push_back(std::sin(0.1 * i));
    c.x.push_back(0.1 * i);
    c.y.push_back(std::cos(0.1 * i));
  }
  s.label = "sin";
  c.label = "cos";
  c.style = SeriesStyle::kPoints;
  c.second_y_axis = true;
  plot.y2_label = "other [-]";
  plot.series = {s, c};
  plot.markers.push_back({MarkerOrientation::kVertical, 5.0, "t = 5", "#505050", false});
  plot.markers.push_back({MarkerOrientation::kHorizontal, 2.0, "level 2", "#000000", false});
  return plot;
}

TEST(Gnuplot, WritesPngOfRequestedSize) {
  ScratchDir dir("gp");
  PlotOptions options;
  options.width_px = 900;
  options.height_px = 600;
  const PlotSummary summary = RenderPlot(SinePlot(), dir / "sine.png", options);
  EXPECT_EQ(summary.path, dir / "sine.png");
  EXPECT_EQ(summary.series, 2);
  EXPECT_EQ(summary.points, 202u);
  EXPECT_TRUE(IsPngOfSize(dir / "sine.png", 900, 600));
  const cv::Mat img = cv::imread(dir / "sine.png");
  EXPECT_EQ(img.cols, 900);
  EXPECT_EQ(img.rows, 600);
  // Only the final file remains (no temporary PNG).
  EXPECT_EQ(dir.Entries().size(), 1u);
}

TEST(Gnuplot, PrefersPngcairo) {
  // The Debian gnuplot-nox package has cairo; the png (libgd) terminal is the fallback.
  EXPECT_EQ(DetectPngTerminal(ResolveGnuplotBinary({})), "pngcairo");
}

TEST(Gnuplot, ScriptHasAxesLegendMarkersAndLogScales) {
  Plot plot = SinePlot();
  plot.log_x = true;
  const std::string script = GnuplotScript(plot, {}, "pngcairo", "/tmp/d.dat", "/tmp/o.png");
  EXPECT_NE(script.find("set terminal pngcairo size 1200,800"), std::string::npos) << script;
  EXPECT_NE(script.find("set xlabel 'time [ms]'"), std::string::npos);
  EXPECT_NE(script.find("set y2label 'other [-]'"), std::string::npos);
  EXPECT_NE(script.find("axes x1y2"), std::string::npos);
  EXPECT_NE(script.find("set logscale x"), std::string::npos);
  EXPECT_NE(script.find("title 'sin'"), std::string::npos);
  EXPECT_NE(script.find("set label 'level 2'"), std::string::npos);
  // The horizontal marker at 2 lies above the data (max 1): the y range is extended to show it.
  EXPECT_NE(script.find("set yrange ["), std::string::npos) << script;
}

TEST(Gnuplot, QuotesLabelsSafely) {
  Plot plot = SinePlot();
  plot.title = "it's \"quoted\"";
  const std::string script = GnuplotScript(plot, {}, "png", "/tmp/d.dat", "/tmp/o.png");
  EXPECT_NE(script.find("set title 'it''s \"quoted\"'"), std::string::npos) << script;
}

TEST(Gnuplot, LogLogSkipsNonPositiveValues) {
  ScratchDir dir("gp");
  Plot plot;
  plot.x_label = "wall time [s]";
  plot.y_label = "error [-]";
  plot.log_x = plot.log_y = true;
  PlotSeries s;
  s.x = {1e-4, 1e-3, 0.0, 1e-2, 1e-1};
  s.y = {1e-2, 1e-5, 1e-6, -1.0, 1e-9};
  s.style = SeriesStyle::kLinesPoints;
  plot.series = {s};
  const PlotSummary summary = RenderPlot(plot, dir / "wp.png");
  EXPECT_EQ(summary.points, 3u);  // (0, 1e-6) and (1e-2, -1) cannot be drawn on log axes
  EXPECT_TRUE(IsPngOfSize(dir / "wp.png", 640, 480));
}

TEST(Gnuplot, MissingBinaryIsAClearErrorAndWritesNothing) {
  EnvGuard guard;
  ScratchDir dir("gp");
  setenv("IMPACTDIC_GNUPLOT", "/nonexistent/bin/gnuplot", 1);
  try {
    RenderPlot(SinePlot(), dir / "x.png");
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kFileNotFound);
    const std::string msg = e.what();
    EXPECT_NE(msg.find("/nonexistent/bin/gnuplot"), std::string::npos) << msg;
    EXPECT_NE(msg.find("IMPACTDIC_GNUPLOT"), std::string::npos) << msg;
    EXPECT_NE(msg.find("gnuplot-nox"), std::string::npos) << msg;
  }
  EXPECT_TRUE(dir.Entries().empty());
}

TEST(Gnuplot, FailingGnuplotShowsItsStderrAndWritesNothing) {
  ScratchDir dir("gp");
  // A stand-in gnuplot that lists a pngcairo terminal but fails to plot.
  const std::string fake = dir / "fake_gnuplot.sh";
  {
    std::ofstream out(fake);
    out << "#!/bin/sh\n"
           "if [ \"$1\" = \"-e\" ]; then echo '   pngcairo  png terminal based on cairo'; exit 0; "
           "fi\n"
           "echo 'line 7: undefined variable: frobnicate' >&2\nexit 1\n";
  }
  chmod(fake.c_str(), 0755);
  std::filesystem::create_directories(dir / "out");
  PlotOptions options;
  options.gnuplot_binary = fake;
  try {
    RenderPlot(SinePlot(), dir / "out/x.png", options);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kIo);
    EXPECT_NE(std::string(e.what()).find("undefined variable: frobnicate"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("exit code 1"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir.path() / "out"));
}

TEST(Gnuplot, RejectsInconsistentOrEmptyPlots) {
  ScratchDir dir("gp");
  Plot bad = SinePlot();
  bad.series[0].y.pop_back();
  try {
    RenderPlot(bad, dir / "bad.png");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kInvalidValue);
    EXPECT_NE(std::string(e.what()).find("'sin'"), std::string::npos) << e.what();
  }
  Plot empty;
  PlotSeries nan_series;
  nan_series.x = {1, 2};
  nan_series.y = {std::numeric_limits<double>::quiet_NaN(), HUGE_VAL};
  empty.series = {nan_series};
  EXPECT_THROW(RenderPlot(empty, dir / "empty.png"), Error);
  EXPECT_TRUE(dir.Entries().empty());
}

TEST(Gnuplot, UnwritableFolderIsAnIoError) {
  ScratchDir dir("gp");
  std::ofstream(dir / "a_file") << "x";
  try {
    RenderPlot(SinePlot(), dir / "a_file/plot.png");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::kIo);
    EXPECT_NE(std::string(e.what()).find("does not exist"), std::string::npos) << e.what();
  }
}

TEST(Gnuplot, OptionsCheckNamesTheField) {
  PlotOptions options;
  EXPECT_NO_THROW(options.Check());
  options.width_px = 10;
  try {
    options.Check();
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("width_px"), std::string::npos);
  }
}

TEST(Gnuplot, EnumsRoundTrip) {
  for (auto s : {SeriesStyle::kLines, SeriesStyle::kDashed, SeriesStyle::kPoints,
                 SeriesStyle::kLinesPoints}) {
    EXPECT_EQ(SeriesStyleFromString(ToString(s)), s);
  }
  EXPECT_THROW(SeriesStyleFromString("wiggly"), Error);
}

// A gnuplot temporary is written without ever being made again: once removed (as a signal's
// cleanup removes it), Write fails and the file stays absent, so an interrupted run leaves nothing
// in TMPDIR. Until then Write replaces its contents.
TEST(GnuplotTempFile, WriteNeverMakesARemovedFileAgain) {
  render_internal::TempFile file(".gp");
  ASSERT_TRUE(std::filesystem::exists(file.path()));
  file.Write("plot 1\nplot 2\n");
  file.Write("plot 3\n");
  std::ifstream in(file.path());
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text, "plot 3\n");
  std::filesystem::remove(file.path());
  EXPECT_THROW(file.Write("plot 4\n"), Error);
  EXPECT_FALSE(std::filesystem::exists(file.path()));
}

}  // namespace
}  // namespace impactdic
