// Calibration YAML: writing and strict reading (keys in docs/calibration.md).
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <functional>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "impactdic/calib/calibration.h"
#include "impactdic/core/enum_names.h"
#include "impactdic/core/error.h"
#include "impactdic/core/range.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/yaml.h"

namespace impactdic {
namespace {

constexpr const char* kFormat = "impactdic-calibration-1";

constexpr ValueRange kAnyFinite{-1e300, 1e300, ""};
constexpr ValueRange kPositive{0, 1e300, "", /*min_open=*/true};
constexpr ValueRange kNonNegative{0, 1e300, ""};

// A required number.
void Required(YamlSection& s, const std::string& key, double* out, const ValueRange& range,
              const std::string& what) {
  if (s.Require(key, what)) s.Read(key, out, range, what);
}

// A list of exactly n finite numbers.
void Numbers(YamlSection& s, const std::string& key, double* out, std::size_t n,
             const std::string& expected) {
  if (!s.Require(key, expected)) return;
  s.ReadWith(
      key,
      [out, n](const YAML::Node& node) {
        if (!node.IsSequence() || node.size() != n) return false;
        for (std::size_t k = 0; k < n; ++k) {
          if (!node[k].IsScalar() || !YAML::convert<double>::decode(node[k], out[k]) ||
              !std::isfinite(out[k]))
            return false;
        }
        return true;
      },
      expected);
}

// `views` / `rejected`: lists of {image, <second>, ...} maps; `parse` reads the map's other keys.
template <typename Item>
void Items(YamlSection& s, const std::string& key, const std::string& second,
           const std::function<bool(const YAML::Node&, Item*)>& parse, std::vector<Item>* out) {
  s.ReadWith(
      key,
      [&](const YAML::Node& list) {
        if (!list.IsSequence()) return false;
        for (const auto& node : list) {
          Item item;
          if (!node.IsMap() || !node["image"].IsScalar() || !parse(node, &item)) return false;
          item.image = node["image"].Scalar();
          out->push_back(item);
        }
        return true;
      },
      "a list of {image, " + second + "}");
}

// An optional name of `names` (absent: *out unchanged).
template <typename E, std::size_t N>
void ReadEnum(YamlSection& s, const std::string& key, const EnumNames<E, N>& names, E* out) {
  std::string text;
  if (s.ReadChoice(key, &text, names.Names())) *out = names.Parse(text, s.PathOf(key));
}

// The distortion coefficients of `c.model` in OpenCV's order (DistCoeffs).
void ReadDistortion(YamlSection& top, CameraCalibration* c) {
  // Files without `model` (written before the rational and fisheye models) are Brown-Conrady.
  ReadEnum(top, "model", kLensModelNames, &c->model);
  if (c->model == LensModel::kAuto) {
    top.Problem("model", "got 'auto'; expected the fitted model: brown, rational or fisheye");
    return;
  }
  if (c->model == LensModel::kFisheye) {
    Numbers(top, "dist", c->dist_fisheye.data(), 4, "4 numbers [k1, k2, k3, k4] (fisheye)");
    return;
  }
  if (c->model == LensModel::kBrown) {
    Numbers(top, "dist", c->dist.data(), 5, "5 numbers [k1, k2, p1, p2, k3]");
    return;
  }
  double d[8] = {};
  Numbers(top, "dist", d, 8, "8 numbers [k1, k2, p1, p2, k3, k4, k5, k6] (rational)");
  for (int k = 0; k < 5; ++k) c->dist[k] = d[k];
  for (int k = 0; k < 3; ++k) c->dist_rational[k] = d[5 + k];
}

void ReadBoard(YamlSection& top, BoardSpec* board) {
  YamlSection b = top.Sub("board");
  if (!top.Require("board", "{cols, rows, square_mm}")) return;
  for (const char* key : {"cols", "rows"}) {
    if (b.Require(key, "an integer >= 2"))
      b.Read(key, key[0] == 'c' ? &board->cols : &board->rows, ValueRange{2, 1e4, ""}, ">= 2");
  }
  Required(b, "square_mm", &board->square_mm, kPositive, "a square side [mm]");
  // Files without `kind` (before ChArUco and circle grids) are chessboards.
  ReadEnum(b, "kind", kBoardKindNames, &board->kind);
  b.Read("marker_mm", &board->marker_mm, kNonNegative, "a marker side [mm]");
  b.Read("dictionary", &board->dictionary);
  ReadEnum(b, "layout", kCharucoLayoutNames, &board->layout);
  b.Finish();
}

std::optional<PlaneScale> ReadPlane(YamlSection& top) {
  if (!top.Has("plane")) {
    top.Get("plane");
    return std::nullopt;
  }
  YamlSection s = top.Sub("plane");
  PlaneScale p;
  s.Read("image", &p.image);
  Required(s, "mm_per_px", &p.mm_per_px, kPositive, "a plane scale [mm/px]");
  Required(s, "mm_per_px_uncertainty", &p.mm_per_px_uncertainty, kNonNegative,
           "a scale uncertainty [mm/px]");
  s.Read("local_scale_spread_rel", &p.local_scale_spread_rel, kNonNegative, "a relative spread");
  s.Read("residual_rms_mm", &p.residual_rms_mm, kAnyFinite, "a residual [mm]");
  s.Read("corners", &p.corners, ValueRange{0, 1e9, ""}, "a corner count");
  if (s.Has("window")) {
    YamlSection w = s.Sub("window");
    Required(w, "thickness_mm", &p.window.thickness_mm, kNonNegative, "a panel thickness [mm]");
    Required(w, "refractive_index", &p.window.refractive_index, kPositive, "a refractive index");
    ReadEnum(w, "board_position", kBoardPositionNames, &p.window.board_position);
    w.Read("board_mm_per_px", &p.board_mm_per_px, kPositive, "the board's scale [mm/px]");
    w.Read("nonlinearity_mm", &p.window_nonlinearity_mm, kNonNegative, "a distance [mm]");
    w.Finish();
  } else {
    s.Get("window");
  }
  double h[9] = {};
  Numbers(s, "mm_from_px", h, 9, "9 numbers (3x3 homography, row-major)");
  for (int k = 0; k < 9; ++k) p.mm_from_px(k / 3, k % 3) = h[k];
  s.Finish();
  return p;
}

}  // namespace

void SaveCalibration(const CameraCalibration& c, const std::string& path) {
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  out << YAML::Comment(
      "impactdic camera calibration (keys documented in docs/calibration.md). Pinhole + "
      "distortion of `model` (brown, rational or fisheye), OpenCV conventions; pixel centres at "
      "integer coordinates.");
  out << YAML::BeginMap;
  out << YAML::Key << "format" << YAML::Value << kFormat;
  out << YAML::Key << "image_width" << YAML::Value << c.image_width;
  out << YAML::Key << "image_height" << YAML::Value << c.image_height;
  out << YAML::Key << "board" << YAML::Value << YAML::Flow << YAML::BeginMap;
  out << YAML::Key << "cols" << YAML::Value << c.board.cols;
  out << YAML::Key << "rows" << YAML::Value << c.board.rows;
  out << YAML::Key << "square_mm" << YAML::Value << c.board.square_mm;
  if (c.board.kind != BoardKind::kChessboard)
    out << YAML::Key << "kind" << YAML::Value << kBoardKindNames.Name(c.board.kind);
  if (c.board.kind == BoardKind::kCharuco) {
    out << YAML::Key << "marker_mm" << YAML::Value << c.board.marker_mm;
    out << YAML::Key << "dictionary" << YAML::Value << c.board.dictionary;
    out << YAML::Key << "layout" << YAML::Value << kCharucoLayoutNames.Name(c.board.layout);
  }
  out << YAML::EndMap;
  out << YAML::Key << "fx" << YAML::Value << c.fx;
  out << YAML::Key << "fy" << YAML::Value << c.fy;
  out << YAML::Key << "cx" << YAML::Value << c.cx;
  out << YAML::Key << "cy" << YAML::Value << c.cy;
  out << YAML::Key << "model" << YAML::Value << kLensModelNames.Name(c.model);
  out << YAML::Key << "dist" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  const cv::Mat dist = c.DistCoeffs();
  for (int k = 0; k < static_cast<int>(dist.total()); ++k) out << dist.at<double>(k);
  out << YAML::EndSeq
      << YAML::Comment(c.model == LensModel::kFisheye    ? "fisheye k1, k2, k3, k4"
                       : c.model == LensModel::kRational ? "k1, k2, p1, p2, k3, k4, k5, k6"
                                                         : "k1, k2, p1, p2, k3");
  out << YAML::Key << "rms_px" << YAML::Value << c.rms_px;
  out << YAML::Key << "views" << YAML::Value << YAML::BeginSeq;
  for (const ViewRecord& v : c.views)
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "image" << YAML::Value << v.image
        << YAML::Key << "rms_px" << YAML::Value << v.rms_px << YAML::Key << "corners" << YAML::Value
        << v.corners << YAML::EndMap;
  out << YAML::EndSeq;
  out << YAML::Key << "rejected" << YAML::Value << YAML::BeginSeq;
  for (const RejectedView& r : c.rejected)
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "image" << YAML::Value << r.image
        << YAML::Key << "reason" << YAML::Value << r.reason << YAML::EndMap;
  out << YAML::EndSeq;
  if (c.plane) {
    const PlaneScale& p = *c.plane;
    out << YAML::Key << "plane" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "image" << YAML::Value << p.image;
    out << YAML::Key << "mm_per_px" << YAML::Value << p.mm_per_px;
    out << YAML::Key << "mm_per_px_uncertainty" << YAML::Value << p.mm_per_px_uncertainty;
    out << YAML::Key << "local_scale_spread_rel" << YAML::Value << p.local_scale_spread_rel;
    out << YAML::Key << "residual_rms_mm" << YAML::Value << p.residual_rms_mm;
    out << YAML::Key << "corners" << YAML::Value << p.corners;
    if (p.window.Active()) {
      out << YAML::Key << "window" << YAML::Value << YAML::BeginMap;
      out << YAML::Key << "thickness_mm" << YAML::Value << p.window.thickness_mm;
      out << YAML::Key << "refractive_index" << YAML::Value << p.window.refractive_index;
      out << YAML::Key << "board_position" << YAML::Value
          << kBoardPositionNames.Name(p.window.board_position);
      if (std::isfinite(p.board_mm_per_px))
        out << YAML::Key << "board_mm_per_px" << YAML::Value << p.board_mm_per_px;
      out << YAML::Key << "nonlinearity_mm" << YAML::Value << p.window_nonlinearity_mm;
      out << YAML::EndMap;
    }
    out << YAML::Key << "mm_from_px" << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (int k = 0; k < 9; ++k) out << p.mm_from_px(k / 3, k % 3);
    out << YAML::EndSeq << YAML::Comment("3x3 homography, row-major: undistorted px -> plane mm");
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  if (!out.good())
    throw Error(ErrorKind::kIo, "cannot encode calibration YAML: " + out.GetLastError());
  WriteTextFileAtomic(path, std::string(out.c_str()) + "\n");
}

CameraCalibration LoadCalibration(const std::string& path) {
  constexpr const char* kWhat = "a calibration file (YAML written by `impactdic calibrate`)";
  const YAML::Node root = LoadYamlFile(path, kWhat);
  if (!root.IsMap())
    throw Error(ErrorKind::kFileFormat, "", "not a YAML map", kWhat).WithFile(path);
  YamlProblems problems(path);
  YamlSection top(root, "", &problems);
  CameraCalibration c;
  std::string format;
  if (top.Require("format", kFormat) && top.Read("format", &format) && format != kFormat)
    top.Problem("format", fmt::format("got '{}'; expected {}", format, kFormat));
  for (const char* key : {"image_width", "image_height"}) {
    if (top.Require(key, "an image size > 0 [px]"))
      top.Read(key, key[6] == 'w' ? &c.image_width : &c.image_height, ValueRange{1, 1e6, "px"},
               "an image size");
  }
  ReadBoard(top, &c.board);
  Required(top, "fx", &c.fx, kPositive, "a focal length [px]");
  Required(top, "fy", &c.fy, kPositive, "a focal length [px]");
  Required(top, "cx", &c.cx, kAnyFinite, "a principal point [px]");
  Required(top, "cy", &c.cy, kAnyFinite, "a principal point [px]");
  ReadDistortion(top, &c);
  c.rms_px = std::nan("");
  top.Read("rms_px", &c.rms_px, kNonNegative, "a reprojection RMS [px]");
  Items<ViewRecord>(
      top, "views", "rms_px",
      [](const YAML::Node& n, ViewRecord* v) {
        // `corners` was added with partial views (ChArUco); older files have none (0).
        return n["rms_px"].IsScalar() && YAML::convert<double>::decode(n["rms_px"], v->rms_px) &&
               (!n["corners"] ||
                (n["corners"].IsScalar() && YAML::convert<int>::decode(n["corners"], v->corners)));
      },
      &c.views);
  Items<RejectedView>(
      top, "rejected", "reason",
      [](const YAML::Node& n, RejectedView* r) {
        if (!n["reason"].IsScalar()) return false;
        r->reason = n["reason"].Scalar();
        return true;
      },
      &c.rejected);
  c.plane = ReadPlane(top);
  top.Finish();
  problems.ThrowIfAny("calibration file", ErrorKind::kFileFormat);
  try {
    c.board.Check();
  } catch (Error& e) {
    throw e.WithFile(path);
  }
  return c;
}

}  // namespace impactdic
