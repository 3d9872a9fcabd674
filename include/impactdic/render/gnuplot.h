// A small gnuplot driver: a Plot description (title, labelled axes with units, line/point series,
// an optional second y axis, horizontal/vertical marker lines) becomes a PNG.
//
// gnuplot runs as a child process (no shell): the series go to a temporary data file, the commands
// to a temporary script, the PNG to a temporary name in the output folder that is renamed to the
// final name only when gnuplot succeeded and wrote a valid PNG. The binary is `gnuplot` from PATH
// unless PlotOptions::gnuplot_binary or the environment variable IMPACTDIC_GNUPLOT names another.
// The terminal is pngcairo when the binary offers it (anti-aliased, real fonts), else png (libgd).
//
//   Plot plot;
//   plot.title = "Work precision";
//   plot.x_label = "wall time [s]";
//   plot.y_label = "relative error [-]";
//   plot.log_x = plot.log_y = true;
//   plot.series.push_back({.x = time, .y = error, .label = "Dormand-Prince 5(4)",
//                          .style = SeriesStyle::kLinesPoints});
//   RenderPlot(plot, "out/work_precision.png");
#ifndef IMPACTDIC_RENDER_GNUPLOT_H_
#define IMPACTDIC_RENDER_GNUPLOT_H_

#include <cstddef>
#include <string>
#include <vector>

#include "impactdic/core/numeric.h"
#include "impactdic/core/range.h"

namespace impactdic {

enum class SeriesStyle {
  kLines,        // solid line
  kDashed,       // dashed line
  kPoints,       // markers only
  kLinesPoints,  // line with markers
  kBand,         // shaded band y +- y_u (PlotSeries::y_u), translucent
};
const char* ToString(SeriesStyle style);
SeriesStyle SeriesStyleFromString(const std::string& text);  // Error kInvalidValue if unknown

// One curve. x and y have the same length; NaN values break the line (gnuplot "missing").
struct PlotSeries {
  std::vector<double> x;
  std::vector<double> y;
  // kBand: the band's half-width at each x (drawn from y - y_u to y + y_u; NaN breaks it).
  std::vector<double> y_u;
  std::string label;  // legend entry; empty = not in the legend
  SeriesStyle style = SeriesStyle::kLines;
  std::string color;           // "#rrggbb"; empty = the next colour of the palette
  double line_width = 2.5;     // in gnuplot line-width units (>0)
  bool second_y_axis = false;  // plotted against the right-hand y axis (Plot::y2_label)
  // gnuplot point type of the markers (kPoints, kLinesPoints): 7 filled circle, 5 filled square,
  // 9 filled triangle, 13 filled diamond, 11 filled downward triangle; [1, 15].
  int point_type = 7;
  double point_size = 1.1;  // marker size, in gnuplot's units (>0)
};

enum class MarkerOrientation { kVertical, kHorizontal };
const char* ToString(MarkerOrientation orientation);

// A straight dashed line across the plot at x = value (vertical) or y = value (horizontal), with
// an optional text label beside it. Non-finite values are ignored (with no line drawn).
struct PlotMarker {
  MarkerOrientation orientation = MarkerOrientation::kVertical;
  double value = 0.0;
  std::string label;
  std::string color = "#505050";
  bool second_y_axis = false;  // horizontal marker in the y2 coordinates
};

enum class LegendPosition {
  kTopRight,
  kTopLeft,
  kBottomRight,
  kBottomLeft,
  kOutsideRight,
  kBelow,  // under the plot, entries side by side
  kNone,
};
const char* ToString(LegendPosition position);

// Coloured cells drawn under the series (a space-time diagram, a map): cell i is centred at
// (x[i], y[i]) with half sizes half_width x half_height, coloured by value[i] on a diverging
// palette (blue < 0 < red) symmetric about 0 over +-max |value| (or +-value_limit when finite);
// a cell whose value is not finite is not drawn.
struct PlotCells {
  std::vector<double> x, y, value;
  double half_width = 0, half_height = 0;
  double value_limit = kNaN;
  std::string label;  // The colour bar's label, with units.
  bool empty() const { return value.empty(); }
};

struct Plot {
  std::string title;
  std::string x_label;   // with units, e.g. "time since impact [ms]"
  std::string y_label;   // with units
  std::string y2_label;  // right axis; used when a series has second_y_axis
  std::vector<PlotSeries> series;
  std::vector<PlotMarker> markers;
  PlotCells cells;         // None when empty.
  bool reverse_y = false;  // y grows downward (a depth axis).
  bool log_x = false;      // logarithmic axes (non-positive values are not drawn)
  bool log_y = false;
  bool log_y2 = false;
  // Axis ranges; NaN = automatic.
  double x_min = kNaN;
  double x_max = kNaN;
  double y_min = kNaN;
  double y_max = kNaN;
  LegendPosition legend = LegendPosition::kTopRight;
  // gnuplot "enhanced" text in the title, labels and legend: a_{b} subscripts, x^{2}
  // superscripts. Off by default so that file names with underscores print as they are.
  bool enhanced_text = false;
};

struct PlotOptions {
  int width_px = 1200;    // PNG size, in kWidthRange
  int height_px = 800;    // in kHeightRange
  int font_size_pt = 15;  // base font size, in kFontSizeRange
  static constexpr ValueRange kWidthRange{320, 8000, "px"};
  static constexpr ValueRange kHeightRange{240, 8000, "px"};
  static constexpr ValueRange kFontSizeRange{6, 72, "pt"};
  std::string font = "DejaVu Sans";
  // gnuplot binary; empty = environment variable IMPACTDIC_GNUPLOT, else "gnuplot" from PATH.
  std::string gnuplot_binary;

  void Check() const;  // Error kInvalidValue naming the field
};

struct PlotSummary {
  std::string path;      // the PNG written
  std::string terminal;  // "pngcairo" or "png"
  std::string gnuplot_binary;
  int series = 0;
  std::size_t points = 0;        // data points written
  std::string gnuplot_messages;  // what gnuplot printed (warnings) on success
  double wall_s = 0.0;
};

// The gnuplot binary that RenderPlot would run for these options.
std::string ResolveGnuplotBinary(const PlotOptions& options);

// The PNG terminal `binary` offers: "pngcairo" if listed by `set terminal`, else "png". Cached per
// binary. Error kFileNotFound if the binary cannot be run, kIo if it offers no PNG terminal.
std::string DetectPngTerminal(const std::string& binary);

// Draws `plot` into `png_path` (written atomically). Errors: kInvalidValue for an empty or
// inconsistent plot (series with different x/y lengths, nothing finite to draw); kFileNotFound when
// gnuplot is missing (naming the binary and IMPACTDIC_GNUPLOT); kIo when gnuplot fails (with its
// stderr) or the output folder is not writable. No output file exists after an error.
PlotSummary RenderPlot(const Plot& plot, const std::string& png_path,
                       const PlotOptions& options = {});

// The gnuplot script RenderPlot would run (data file and output names given); for tests and
// debugging.
std::string GnuplotScript(const Plot& plot, const PlotOptions& options, const std::string& terminal,
                          const std::string& data_path, const std::string& output_path);

// True if the file starts with the 8-byte PNG signature.
bool HasPngSignature(const std::string& path);

}  // namespace impactdic

#endif  // IMPACTDIC_RENDER_GNUPLOT_H_
