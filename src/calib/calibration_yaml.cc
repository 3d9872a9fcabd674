// Calibration YAML: writing and strict reading (keys in docs/calibration.md).
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <set>

#include "impactdic/calib/calibration.h"
#include "impactdic/core/error.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/yaml.h"

namespace impactdic {
namespace {

constexpr const char* kFormat = "impactdic-calibration-1";

std::string Number(double v) { return fmt::format("{:.17g}", v); }

// Reads `key` of `node` as T; Error(kFileFormat) naming the file and key path otherwise.
template <typename T>
T Get(const YAML::Node& node, const std::string& key, const std::string& path,
      const std::string& prefix, const std::string& expected) {
  const YAML::Node value = node[key];
  if (!value) throw Error(ErrorKind::kFileFormat, prefix + key, "missing", expected).WithFile(path);
  try {
    return value.as<T>();
  } catch (const YAML::Exception&) {
    throw Error(ErrorKind::kFileFormat, prefix + key,
                value.IsScalar() ? "'" + value.Scalar() + "'" : "a non-scalar value", expected)
        .WithFile(path, value.Mark().line + 1, value.Mark().column + 1);
  }
}

void CheckKeys(const YAML::Node& node, const std::set<std::string>& allowed,
               const std::string& path, const std::string& prefix) {
  for (const auto& item : node) {
    const std::string key = item.first.as<std::string>();
    if (!allowed.count(key)) {
      std::string list;
      for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
      throw Error(ErrorKind::kFileFormat, prefix + key, "unknown key", "one of: " + list)
          .WithFile(path, item.first.Mark().line + 1, item.first.Mark().column + 1);
    }
  }
}

}  // namespace

void SaveCalibration(const CameraCalibration& c, const std::string& path) {
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  out << YAML::Comment(
      "impactdic camera calibration (keys documented in docs/calibration.md). Pinhole + "
      "Brown-Conrady distortion, OpenCV conventions; pixel centres at integer coordinates.");
  out << YAML::BeginMap;
  out << YAML::Key << "format" << YAML::Value << kFormat;
  out << YAML::Key << "image_width" << YAML::Value << c.image_width;
  out << YAML::Key << "image_height" << YAML::Value << c.image_height;
  out << YAML::Key << "board" << YAML::Value << YAML::Flow << YAML::BeginMap;
  out << YAML::Key << "cols" << YAML::Value << c.board.cols;
  out << YAML::Key << "rows" << YAML::Value << c.board.rows;
  out << YAML::Key << "square_mm" << YAML::Value << c.board.square_mm << YAML::EndMap;
  out << YAML::Key << "fx" << YAML::Value << c.fx;
  out << YAML::Key << "fy" << YAML::Value << c.fy;
  out << YAML::Key << "cx" << YAML::Value << c.cx;
  out << YAML::Key << "cy" << YAML::Value << c.cy;
  out << YAML::Key << "dist" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (double d : c.dist) out << d;
  out << YAML::EndSeq << YAML::Comment("k1, k2, p1, p2, k3");
  out << YAML::Key << "rms_px" << YAML::Value << c.rms_px;
  out << YAML::Key << "views" << YAML::Value << YAML::BeginSeq;
  for (const ViewRecord& v : c.views)
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "image" << YAML::Value << v.image
        << YAML::Key << "rms_px" << YAML::Value << v.rms_px << YAML::EndMap;
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
  CheckKeys(root,
            {"format", "image_width", "image_height", "board", "fx", "fy", "cx", "cy", "dist",
             "rms_px", "views", "rejected", "plane"},
            path, "");
  const std::string format = Get<std::string>(root, "format", path, "", kFormat);
  if (format != kFormat)
    throw Error(ErrorKind::kFileFormat, "format", "'" + format + "'", kFormat).WithFile(path);

  CameraCalibration c;
  c.image_width = Get<int>(root, "image_width", path, "", "an integer > 0 [px]");
  c.image_height = Get<int>(root, "image_height", path, "", "an integer > 0 [px]");
  if (c.image_width <= 0 || c.image_height <= 0)
    throw Error(ErrorKind::kFileFormat, "image_width/image_height",
                fmt::format("{}x{}", c.image_width, c.image_height), "positive sizes")
        .WithFile(path);
  const YAML::Node board = root["board"];
  if (!board || !board.IsMap())
    throw Error(ErrorKind::kFileFormat, "board", "missing or not a map", "{cols, rows, square_mm}")
        .WithFile(path);
  CheckKeys(board, {"cols", "rows", "square_mm"}, path, "board.");
  c.board.cols = Get<int>(board, "cols", path, "board.", "an integer >= 2");
  c.board.rows = Get<int>(board, "rows", path, "board.", "an integer >= 2");
  c.board.square_mm = Get<double>(board, "square_mm", path, "board.", "a number > 0 [mm]");
  try {
    c.board.Check();
  } catch (Error& e) {
    throw e.WithFile(path);
  }
  c.fx = Get<double>(root, "fx", path, "", "a number > 0 [px]");
  c.fy = Get<double>(root, "fy", path, "", "a number > 0 [px]");
  c.cx = Get<double>(root, "cx", path, "", "a number [px]");
  c.cy = Get<double>(root, "cy", path, "", "a number [px]");
  if (!(c.fx > 0 && c.fy > 0 && std::isfinite(c.fx) && std::isfinite(c.fy) && std::isfinite(c.cx) &&
        std::isfinite(c.cy)))
    throw Error(ErrorKind::kFileFormat, "fx/fy/cx/cy",
                fmt::format("{}, {}, {}, {}", c.fx, c.fy, c.cx, c.cy),
                "finite values with fx, fy > 0")
        .WithFile(path);
  const auto dist = Get<std::vector<double>>(root, "dist", path, "", "[k1, k2, p1, p2, k3]");
  if (dist.size() != 5)
    throw Error(ErrorKind::kFileFormat, "dist", fmt::format("{} values", dist.size()),
                "5 values [k1, k2, p1, p2, k3]")
        .WithFile(path);
  for (int k = 0; k < 5; ++k) {
    if (!std::isfinite(dist[k]))
      throw Error(ErrorKind::kFileFormat, "dist", "a non-finite value", "finite numbers")
          .WithFile(path);
    c.dist[k] = dist[k];
  }
  c.rms_px = root["rms_px"] && !root["rms_px"].IsNull()
                 ? Get<double>(root, "rms_px", path, "", "a number >= 0 [px]")
                 : std::nan("");
  if (const YAML::Node views = root["views"]; views && views.IsSequence())
    for (const auto& v : views)
      c.views.push_back({Get<std::string>(v, "image", path, "views[].", "a file name"),
                         Get<double>(v, "rms_px", path, "views[].", "a number [px]")});
  if (const YAML::Node rejected = root["rejected"]; rejected && rejected.IsSequence())
    for (const auto& r : rejected)
      c.rejected.push_back({Get<std::string>(r, "image", path, "rejected[].", "a file name"),
                            Get<std::string>(r, "reason", path, "rejected[].", "text")});
  if (const YAML::Node plane = root["plane"]; plane && !plane.IsNull()) {
    if (!plane.IsMap())
      throw Error(ErrorKind::kFileFormat, "plane", "not a map", "the plane scale map")
          .WithFile(path);
    CheckKeys(plane,
              {"image", "mm_per_px", "mm_per_px_uncertainty", "local_scale_spread_rel",
               "residual_rms_mm", "corners", "mm_from_px"},
              path, "plane.");
    PlaneScale p;
    p.image = plane["image"] ? Get<std::string>(plane, "image", path, "plane.", "a file name") : "";
    p.mm_per_px = Get<double>(plane, "mm_per_px", path, "plane.", "a number > 0 [mm/px]");
    if (!(p.mm_per_px > 0 && std::isfinite(p.mm_per_px)))
      throw Error(ErrorKind::kFileFormat, "plane.mm_per_px", Number(p.mm_per_px), "> 0")
          .WithFile(path);
    p.mm_per_px_uncertainty =
        Get<double>(plane, "mm_per_px_uncertainty", path, "plane.", "a number >= 0 [mm/px]");
    if (plane["local_scale_spread_rel"])
      p.local_scale_spread_rel =
          Get<double>(plane, "local_scale_spread_rel", path, "plane.", "a number >= 0");
    if (plane["residual_rms_mm"])
      p.residual_rms_mm = Get<double>(plane, "residual_rms_mm", path, "plane.", "a number [mm]");
    if (plane["corners"]) p.corners = Get<int>(plane, "corners", path, "plane.", "an integer");
    const auto h = Get<std::vector<double>>(plane, "mm_from_px", path, "plane.",
                                            "9 numbers (3x3 homography, row-major)");
    if (h.size() != 9)
      throw Error(ErrorKind::kFileFormat, "plane.mm_from_px", fmt::format("{} values", h.size()),
                  "9 numbers (3x3 homography, row-major)")
          .WithFile(path);
    for (int k = 0; k < 9; ++k) p.mm_from_px(k / 3, k % 3) = h[k];
    c.plane = p;
  }
  return c;
}

}  // namespace impactdic
