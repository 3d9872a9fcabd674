#include "impactdic/render/gnuplot.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <mutex>
#include <sstream>
#include <system_error>
#include <utility>

#include "impactdic/core/error.h"
#include "impactdic/core/interrupt.h"
#include "impactdic/core/log.h"
#include "impactdic/core/timer.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/image_io.h"
#include "impactdic/io/output_generation.h"
#include "subprocess.h"

namespace impactdic {
namespace fs = std::filesystem;
using render_internal::RunProcess;
using render_internal::TempFile;

const char* ToString(SeriesStyle style) {
  switch (style) {
    case SeriesStyle::kLines: return "lines";
    case SeriesStyle::kDashed: return "dashed";
    case SeriesStyle::kPoints: return "points";
    case SeriesStyle::kLinesPoints: return "linespoints";
    case SeriesStyle::kBand: return "band";
  }
  return "?";
}

SeriesStyle SeriesStyleFromString(const std::string& text) {
  for (SeriesStyle s : {SeriesStyle::kLines, SeriesStyle::kDashed, SeriesStyle::kPoints,
                        SeriesStyle::kLinesPoints, SeriesStyle::kBand}) {
    if (text == ToString(s)) return s;
  }
  throw Error(ErrorKind::kInvalidValue, "series style", text,
              "one of lines, dashed, points, linespoints");
}

const char* ToString(MarkerOrientation orientation) {
  return orientation == MarkerOrientation::kVertical ? "vertical" : "horizontal";
}

const char* ToString(LegendPosition position) {
  switch (position) {
    case LegendPosition::kTopRight: return "top_right";
    case LegendPosition::kTopLeft: return "top_left";
    case LegendPosition::kBottomRight: return "bottom_right";
    case LegendPosition::kBottomLeft: return "bottom_left";
    case LegendPosition::kOutsideRight: return "outside_right";
    case LegendPosition::kBelow: return "below";
    case LegendPosition::kNone: return "none";
  }
  return "?";
}

void PlotOptions::Check() const {
  CheckRange(width_px, kWidthRange, "PlotOptions.width_px", "a figure width");
  CheckRange(height_px, kHeightRange, "PlotOptions.height_px", "a figure height");
  CheckRange(font_size_pt, kFontSizeRange, "PlotOptions.font_size_pt", "a font size");
  CheckValue(!font.empty() && font.find_first_of("'\"\n") == std::string::npos, "PlotOptions.font",
             font, "a font name without quotes");
}

std::string ResolveGnuplotBinary(const PlotOptions& options) {
  if (!options.gnuplot_binary.empty()) return options.gnuplot_binary;
  if (const char* env = std::getenv("IMPACTDIC_GNUPLOT"); env != nullptr && *env != '\0') {
    return env;
  }
  return "gnuplot";
}

namespace {

// Colour-blind safe palette (Okabe & Ito, "Color Universal Design", 2008).
constexpr const char* kPalette[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7",
                                    "#E69F00", "#56B4E9", "#000000", "#F0E442"};

// A gnuplot single-quoted string: no escapes are processed, a quote is written twice.
std::string Quote(const std::string& text) {
  std::string out = "'";
  for (char c : text) {
    if (c == '\'')
      out += "''";
    else if (c == '\n')
      out += ' ';
    else
      out += c;
  }
  return out + "'";
}

std::string Number(double value) {
  std::ostringstream s;
  s.precision(17);
  s << value;
  return s.str();
}

std::string MissingGnuplotMessage(const std::string& binary) {
  return "gnuplot is needed to draw figures but '" + binary +
         "' cannot be run; install it (Debian: apt-get install gnuplot-nox) or set "
         "IMPACTDIC_GNUPLOT to the gnuplot binary";
}

// A point is drawn if it is finite and, on a log axis, positive.
bool Drawable(double x, double y, bool log_x, bool log_y) {
  return std::isfinite(x) && std::isfinite(y) && (!log_x || x > 0) && (!log_y || y > 0);
}

bool SeriesHasPoints(const PlotSeries& s, const Plot& plot) {
  const bool log_y = s.second_y_axis ? plot.log_y2 : plot.log_y;
  for (std::size_t i = 0; i < s.x.size(); ++i) {
    if (Drawable(s.x[i], s.y[i], plot.log_x, log_y)) return true;
  }
  return false;
}

bool MarkerDrawable(const PlotMarker& m, const Plot& plot) {
  if (!std::isfinite(m.value)) return false;
  if (m.orientation == MarkerOrientation::kVertical) return !plot.log_x || m.value > 0;
  return !(m.second_y_axis ? plot.log_y2 : plot.log_y) || m.value > 0;
}

bool CellDrawable(const PlotCells& c, std::size_t i) {
  return std::isfinite(c.x[i]) && std::isfinite(c.y[i]) && std::isfinite(c.value[i]);
}

bool CellsDrawable(const Plot& plot) {
  if (plot.log_x || plot.log_y) return false;
  for (std::size_t i = 0; i < plot.cells.value.size(); ++i)
    if (CellDrawable(plot.cells, i)) return true;
  return false;
}

// Writes the drawable series as data blocks (gnuplot `index` k = k-th drawable series); a single
// blank line inside a block breaks the line at non-drawable points. Returns the points written.
std::size_t WriteData(const Plot& plot, std::ostream& out) {
  std::size_t points = 0;
  bool first_block = true;
  for (const auto& s : plot.series) {
    if (!SeriesHasPoints(s, plot)) continue;
    if (!first_block) out << "\n\n";
    first_block = false;
    const bool log_y = s.second_y_axis ? plot.log_y2 : plot.log_y;
    bool wrote_any = false, last_blank = false;
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      const bool band = s.style == SeriesStyle::kBand;
      const double u = band && i < s.y_u.size() ? s.y_u[i] : 0.0;
      if (Drawable(s.x[i], s.y[i], plot.log_x, log_y) && std::isfinite(u)) {
        out << Number(s.x[i]) << ' ' << Number(s.y[i] - u);
        if (band) out << ' ' << Number(s.y[i] + u);
        out << '\n';
        wrote_any = true;
        last_blank = false;
        ++points;
      } else if (wrote_any && !last_blank) {
        out << '\n';
        last_blank = true;
      }
    }
  }
  if (CellsDrawable(plot)) {  // The last block: x y half-width half-height value.
    if (!first_block) out << "\n\n";
    const PlotCells& c = plot.cells;
    for (std::size_t i = 0; i < c.value.size(); ++i) {
      if (!CellDrawable(c, i)) continue;
      out << Number(c.x[i]) << ' ' << Number(c.y[i]) << ' ' << Number(c.half_width) << ' '
          << Number(c.half_height) << ' ' << Number(c.value[i]) << '\n';
      ++points;
    }
  }
  return points;
}

// The colour limit of the cells: value_limit, else max |value| (1 when all are 0).
double CellLimit(const PlotCells& c) {
  if (std::isfinite(c.value_limit) && c.value_limit > 0) return c.value_limit;
  double m = 0;
  for (std::size_t i = 0; i < c.value.size(); ++i)
    if (CellDrawable(c, i)) m = std::max(m, std::abs(c.value[i]));
  return m > 0 ? m : 1;
}

// The finite, drawable range of the data along x (axis 0), y1 (1) or y2 (2).
bool DataRange(const Plot& plot, int axis, double* lo, double* hi) {
  *lo = HUGE_VAL;
  *hi = -HUGE_VAL;
  for (const auto& s : plot.series) {
    if (axis == 1 && s.second_y_axis) continue;
    if (axis == 2 && !s.second_y_axis) continue;
    const bool log_y = s.second_y_axis ? plot.log_y2 : plot.log_y;
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      if (!Drawable(s.x[i], s.y[i], plot.log_x, log_y)) continue;
      const double v = axis == 0 ? s.x[i] : s.y[i];
      *lo = std::min(*lo, v);
      *hi = std::max(*hi, v);
    }
  }
  if (axis != 2 && CellsDrawable(plot)) {
    const PlotCells& c = plot.cells;
    const double half = axis == 0 ? c.half_width : c.half_height;
    for (std::size_t i = 0; i < c.value.size(); ++i) {
      if (!CellDrawable(c, i)) continue;
      const double v = axis == 0 ? c.x[i] : c.y[i];
      *lo = std::min(*lo, v - half);
      *hi = std::max(*hi, v + half);
    }
  }
  return *lo <= *hi;
}

// An explicit range when a marker lies outside the data (gnuplot's autoscale ignores markers).
std::string RangeCommand(const Plot& plot, int axis, double given_lo, double given_hi) {
  const char* name = axis == 0 ? "xrange" : axis == 1 ? "yrange" : "y2range";
  double lo = given_lo, hi = given_hi;
  double data_lo = 0, data_hi = 0;
  if (DataRange(plot, axis, &data_lo, &data_hi)) {
    double want_lo = data_lo, want_hi = data_hi;
    bool extend = false;
    for (const auto& m : plot.markers) {
      if (!MarkerDrawable(m, plot)) continue;
      const int marker_axis =
          m.orientation == MarkerOrientation::kVertical ? 0 : (m.second_y_axis ? 2 : 1);
      if (marker_axis != axis) continue;
      if (m.value < want_lo || m.value > want_hi) extend = true;
      want_lo = std::min(want_lo, m.value);
      want_hi = std::max(want_hi, m.value);
    }
    const bool log = axis == 0 ? plot.log_x : axis == 1 ? plot.log_y : plot.log_y2;
    if (extend && !log) {
      const double pad = 0.05 * std::max(want_hi - want_lo, 1e-300);
      if (!std::isfinite(lo)) lo = want_lo - pad;
      if (!std::isfinite(hi)) hi = want_hi + pad;
    }
  }
  if (!std::isfinite(lo) && !std::isfinite(hi)) return "";
  return std::string("set ") + name + " [" + (std::isfinite(lo) ? Number(lo) : "*") + ":" +
         (std::isfinite(hi) ? Number(hi) : "*") + "]\n";
}

const char* KeyPlacement(LegendPosition p) {
  switch (p) {
    case LegendPosition::kTopRight: return "inside top right";
    case LegendPosition::kTopLeft: return "inside top left";
    case LegendPosition::kBottomRight: return "inside bottom right";
    case LegendPosition::kBottomLeft: return "inside bottom left";
    case LegendPosition::kOutsideRight: return "outside right top";
    case LegendPosition::kBelow: return "outside bottom center horizontal maxrows 1";
    case LegendPosition::kNone: return "";
  }
  return "";
}

// The legend's placement; below the plot, room for the x label and its rows.
std::string LegendCommands(const Plot& plot) {
  std::ostringstream g;
  if (plot.legend == LegendPosition::kBelow) {
    // Room for the x label and the legend's rows: entries side by side, as many as fit (two of
    // the longer labels per row), 1.5 character heights each.
    const long entries = std::count_if(plot.series.begin(), plot.series.end(), [&](const auto& s) {
      return !s.label.empty() && SeriesHasPoints(s, plot);
    });
    g << "set bmargin " << std::max(6L, 4 + 3 * ((entries + 1) / 2) / 2 + 1) << "\n";
  }
  if (plot.legend == LegendPosition::kNone) {
    g << "set key off\n";
  } else {
    g << "set key " << KeyPlacement(plot.legend)
      << " box lw 1 lc rgb '#b0b0b0' opaque spacing 1.3 samplen 3 width 1\n";
  }
  return g.str();
}

// The marker lines and their labels (`lit`: " noenhanced" unless the plot's texts are enhanced).
std::string MarkerCommands(const Plot& plot, const std::string& lit) {
  std::ostringstream g;
  int arrow = 1;
  for (const auto& m : plot.markers) {
    if (!MarkerDrawable(m, plot)) continue;
    const std::string color = m.color.empty() ? "#505050" : m.color;
    const std::string v = Number(m.value);
    if (m.orientation == MarkerOrientation::kVertical) {
      g << "set arrow " << arrow++ << " from first " << v << ", graph 0 to first " << v
        << ", graph 1 nohead dt 2 lw 2 lc rgb " << Quote(color) << " back\n";
      if (!m.label.empty()) {
        g << "set label " << Quote(m.label) << " at first " << v
          << ", graph 0.97 offset character 0.6,0 left front textcolor rgb " << Quote(color) << lit
          << "\n";
      }
    } else {
      const char* sys = m.second_y_axis ? "second" : "first";
      g << "set arrow " << arrow++ << " from graph 0, " << sys << " " << v << " to graph 1, " << sys
        << " " << v << " nohead dt 2 lw 2 lc rgb " << Quote(color) << " back\n";
      if (!m.label.empty()) {
        g << "set label " << Quote(m.label) << " at graph 0.98, " << sys << " " << v
          << " offset 0,character 0.7 right front textcolor rgb " << Quote(color) << lit << "\n";
      }
    }
  }
  return g.str();
}

// The cells' palette and colour bar; their plot element (the last data block) goes first into
// `elements`, under the series.
std::string CellCommands(const Plot& plot, const std::string& data_path, const std::string& lit,
                         std::ostringstream& elements) {
  std::ostringstream g;
  const double limit = CellLimit(plot.cells);
  g << "set palette defined (-1 '#2166ac', -0.5 '#92c5de', 0 '#f7f7f7', 0.5 '#f4a582', 1 "
       "'#b2182b')\n";
  g << "set cbrange [" << Number(-limit) << ":" << Number(limit) << "]\n";
  g << "set cblabel " << Quote(plot.cells.label) << lit << "\n";
  g << "set colorbox\n";
  const long drawn = std::count_if(plot.series.begin(), plot.series.end(),
                                   [&](const PlotSeries& s) { return SeriesHasPoints(s, plot); });
  elements << Quote(data_path) << " index " << drawn
           << " using 1:2:3:4:5 with boxxyerror fs solid 1.0 noborder lc palette notitle";
  if (drawn > 0) elements << ", \\\n     ";
  return g.str();
}

}  // namespace

std::string GnuplotScript(const Plot& plot, const PlotOptions& options, const std::string& terminal,
                          const std::string& data_path, const std::string& output_path) {
  std::ostringstream g;
  const std::string font = options.font + "," + std::to_string(options.font_size_pt);
  g << "set encoding utf8\n";
  g << "set terminal " << terminal << " size " << options.width_px << "," << options.height_px
    << " enhanced font " << Quote(font);
  if (terminal == "pngcairo") g << " linewidth 1.0 rounded";
  g << " background '#ffffff'\n";
  g << "set output " << Quote(output_path) << "\n";
  // Enhanced text is on for the terminal (tick formats like 10^{%L}); texts given by the caller
  // are printed literally unless plot.enhanced_text.
  const std::string lit = plot.enhanced_text ? "" : " noenhanced";
  if (!plot.title.empty()) {
    g << "set title " << Quote(plot.title) << " font "
      << Quote("," + std::to_string(options.font_size_pt + 3)) << lit << "\n";
  }
  g << "set xlabel " << Quote(plot.x_label) << lit << "\n";
  g << "set ylabel " << Quote(plot.y_label) << lit << "\n";
  g << "set border 3 lw 1.5 lc rgb '#303030'\n";
  g << "set grid xtics ytics mxtics mytics lw 1 lc rgb '#e0e0e0', lw 0.5 lc rgb '#f0f0f0'\n";
  g << "set tics out nomirror\n";
  g << "set mxtics\nset mytics\n";
  const bool any_y2 = std::any_of(plot.series.begin(), plot.series.end(),
                                  [](const PlotSeries& s) { return s.second_y_axis; });
  if (any_y2) {
    g << "set border 11 lw 1.5 lc rgb '#303030'\n";
    g << "set y2tics out\nset my2tics\n";
    g << "set y2label " << Quote(plot.y2_label) << lit << "\n";
  }
  if (plot.log_x) g << "set logscale x 10\nset format x '10^{%L}'\n";
  if (plot.log_y) g << "set logscale y 10\nset format y '10^{%L}'\n";
  if (plot.log_y2 && any_y2) g << "set logscale y2 10\nset format y2 '10^{%L}'\n";
  g << RangeCommand(plot, 0, plot.x_min, plot.x_max);
  std::string y_range = RangeCommand(plot, 1, plot.y_min, plot.y_max);
  if (plot.reverse_y) {
    if (y_range.empty()) y_range = "set yrange [*:*]\n";
    y_range.insert(y_range.size() - 1, " reverse");
  }
  g << y_range;
  if (any_y2) g << RangeCommand(plot, 2, NAN, NAN);
  // Head room above the data (autoscale then extends to the next tic).
  if (!plot.log_y && !plot.reverse_y) g << "set offsets 0, 0, graph 0.05, 0\n";
  g << LegendCommands(plot);
  g << MarkerCommands(plot, lit);
  // The plot command: the cells (under everything), then one element per drawable series.
  std::ostringstream elements;
  int index = 0;
  int palette_index = 0;
  const bool cells = CellsDrawable(plot);
  if (cells) g << CellCommands(plot, data_path, lit, elements);
  for (const auto& s : plot.series) {
    const std::string color =
        s.color.empty() ? kPalette[palette_index % std::size(kPalette)] : s.color;
    ++palette_index;
    if (!SeriesHasPoints(s, plot)) continue;
    if (index > 0) elements << ", \\\n     ";
    elements << Quote(data_path) << " index " << index++
             << (s.style == SeriesStyle::kBand ? " using 1:2:3" : " using 1:2");
    if (s.second_y_axis) elements << " axes x1y2";
    switch (s.style) {
      case SeriesStyle::kLines:
        elements << " with lines lw " << Number(s.line_width) << " dt 1";
        break;
      case SeriesStyle::kDashed:
        elements << " with lines lw " << Number(s.line_width) << " dt (8,5)";
        break;
      case SeriesStyle::kPoints:
        elements << " with points pt " << s.point_type << " ps " << Number(s.point_size);
        break;
      case SeriesStyle::kLinesPoints:
        elements << " with linespoints lw " << Number(s.line_width) << " pt " << s.point_type
                 << " ps " << Number(s.point_size);
        break;
      case SeriesStyle::kBand:
        elements << " with filledcurves fs transparent solid 0.25 noborder";
        break;
    }
    elements << " lc rgb " << Quote(color);
    elements << (s.label.empty() ? " notitle" : " title " + Quote(s.label) + lit);
  }
  if (index > 0 || cells) {
    g << "plot " << elements.str() << "\n";
  } else {
    // Markers only: an empty frame over the given range.
    g << "set key off\nplot NaN notitle\n";
  }
  g << "unset output\n";
  return g.str();
}

std::string DetectPngTerminal(const std::string& binary) {
  static std::mutex mutex;
  static std::map<std::string, std::string> cache;
  std::lock_guard<std::mutex> lock(mutex);
  if (auto it = cache.find(binary); it != cache.end()) return it->second;
  const auto result = RunProcess(binary, {"-e", "set terminal"});
  if (!result.started) {
    throw Error(ErrorKind::kFileNotFound,
                MissingGnuplotMessage(binary) + " (" + std::strerror(result.start_errno) + ")");
  }
  std::string terminal;
  if (result.output.find("pngcairo") != std::string::npos) {
    terminal = "pngcairo";
  } else if (result.output.find(" png ") != std::string::npos ||
             result.output.find("\npng") != std::string::npos) {
    terminal = "png";
  } else {
    throw Error(ErrorKind::kIo, "gnuplot '" + binary + "' offers no PNG terminal (exit code " +
                                    std::to_string(result.exit_code) +
                                    "); it printed: " + result.output.substr(0, 2000));
  }
  cache[binary] = terminal;
  return terminal;
}

bool HasPngSignature(const std::string& path) {
  static constexpr unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  std::ifstream in(path, std::ios::binary);
  unsigned char head[8] = {};
  in.read(reinterpret_cast<char*>(head), 8);
  return in.gcount() == 8 && std::memcmp(head, kSignature, 8) == 0;
}

PlotSummary RenderPlot(const Plot& plot, const std::string& png_path, const PlotOptions& options) {
  WallTimer timer;
  options.Check();
  for (std::size_t i = 0; i < plot.series.size(); ++i) {
    const auto& s = plot.series[i];
    CheckValue(
        s.x.size() == s.y.size(), "plot series " + std::to_string(i) + " ('" + s.label + "')",
        std::to_string(s.x.size()) + " x values and " + std::to_string(s.y.size()) + " y values",
        "as many x as y values");
    CheckValue(s.line_width > 0, "plot series line_width", Number(s.line_width), "> 0");
    CheckValue(s.point_type >= 1 && s.point_type <= 15, "plot series point_type",
               std::to_string(s.point_type), "1..15");
    CheckValue(s.point_size > 0, "plot series point_size", Number(s.point_size), "> 0");
  }
  const PlotCells& c = plot.cells;
  CheckValue(c.x.size() == c.value.size() && c.y.size() == c.value.size(), "plot cells",
             std::to_string(c.x.size()) + " x, " + std::to_string(c.y.size()) + " y and " +
                 std::to_string(c.value.size()) + " values",
             "as many x and y as values");
  CheckValue(c.empty() || (c.half_width > 0 && c.half_height > 0), "plot cells' half sizes",
             Number(c.half_width) + " x " + Number(c.half_height), "> 0");
  const bool any_points = CellsDrawable(plot) || std::any_of(plot.series.begin(), plot.series.end(),
                                                             [&](const PlotSeries& s) {
                                                               return SeriesHasPoints(s, plot);
                                                             });
  const bool any_marker = std::any_of(plot.markers.begin(), plot.markers.end(),
                                      [&](const PlotMarker& m) { return MarkerDrawable(m, plot); });
  if (!any_points && !any_marker) {
    throw Error(ErrorKind::kInvalidValue, "plot '" + plot.title + "'",
                "no finite data point (or no positive one on a log axis)",
                "at least one drawable point")
        .WithFile(OutputPathForMessages(png_path));
  }
  CheckOutputLocation(png_path);

  PlotSummary summary;
  summary.gnuplot_binary = ResolveGnuplotBinary(options);
  summary.terminal = DetectPngTerminal(summary.gnuplot_binary);

  TempFile data(".dat");
  TempFile script(".gp");
  {
    std::ostringstream text;
    summary.points = WriteData(plot, text);
    data.Write(text.str());
  }
  summary.series = static_cast<int>(
      std::count_if(plot.series.begin(), plot.series.end(),
                    [&](const PlotSeries& s) { return SeriesHasPoints(s, plot); }));

  const std::string temp_png = render_internal::TempSiblingPath(png_path, ".png");
  struct Cleanup {
    std::string path;
    bool keep = false;
    ~Cleanup() {
      if (!keep) {
        std::error_code ec;
        fs::remove(path, ec);
      }
    }
  } cleanup{temp_png};
  const RemoveOnInterrupt png_on_interrupt(temp_png);
  script.Write(GnuplotScript(plot, options, summary.terminal, data.path(), temp_png));
  const auto result = RunProcess(summary.gnuplot_binary, {script.path()});
  if (!result.started) {
    throw Error(ErrorKind::kFileNotFound, MissingGnuplotMessage(summary.gnuplot_binary));
  }
  if (result.exit_code != 0) {
    throw Error(ErrorKind::kIo, "gnuplot failed drawing '" + OutputPathForMessages(png_path) +
                                    "' (exit code " + std::to_string(result.exit_code) +
                                    "); gnuplot said:\n" + result.output.substr(0, 4000));
  }
  std::error_code ec;
  // gnuplot exits 0 even when its writes failed; a full disk leaves a truncated PNG.
  if (!fs::is_regular_file(temp_png, ec) || !IsCompletePng(temp_png)) {
    if (DiskFull(temp_png)) throw WriteError(png_path, ENOSPC);
    throw Error(ErrorKind::kIo, "gnuplot exited normally but wrote no valid PNG for '" +
                                    OutputPathForMessages(png_path) + "'; gnuplot said:\n" +
                                    result.output.substr(0, 4000));
  }
  fs::rename(temp_png, png_path, ec);
  if (ec) {
    throw Error(ErrorKind::kIo, OutputPathForMessages(png_path),
                "cannot rename the temporary PNG: " + ec.message(), "a writable output location");
  }
  cleanup.keep = true;
  summary.path = png_path;
  summary.gnuplot_messages = result.output;
  if (!result.output.empty()) LogDebug("gnuplot ({}): {}", png_path, result.output);
  summary.wall_s = timer.ElapsedSeconds();
  return summary;
}

}  // namespace impactdic
