#include "impactdic/synth/checkerboard.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <limits>
#include <numbers>
#include <opencv2/aruco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <sstream>
#include <system_error>
#include <utility>

#include "impactdic/core/error.h"
#include "impactdic/core/interrupt.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/image_io.h"

namespace impactdic {
namespace {

constexpr std::int64_t kBackground = -1;
constexpr std::int64_t kMargin = -2;
constexpr std::int64_t kMixed = -3;  // Never uniform: always supersampled (a circle's rim).
constexpr std::int64_t kMarkerCell = 2000000000;  // + (marker * 64 + row) * 64 + column
constexpr std::int64_t kCircle = 3000000000;      // + circle id

// Board point on the ray through normalised point n: [X Y 1] ~ H^-1 [x y 1] with H = [r1 r2 t];
// with a panel, the ray is traced in board coordinates and refracted at the panel's outer face.
struct RayToBoard {
  cv::Matx33d h_inv;
  cv::Matx33d r_t;   // R^T: camera -> board directions
  cv::Vec3d centre;  // Camera centre in board coordinates
  double thickness = 0, index = 1;
  bool Map(cv::Point2d n, cv::Point2d* board) const {
    if (thickness > 0) return MapThroughPanel(n, board);
    const cv::Vec3d b = h_inv * cv::Vec3d(n.x, n.y, 1.0);
    if (!(b[2] > 0)) return false;  // Behind the camera or parallel to the plane.
    *board = {b[0] / b[2], b[1] / b[2]};
    return true;
  }
  // The panel fills the slab between the board (Z = 0) and Z = side * thickness, side the camera's.
  // At the outer face the direction's component along the face is divided by n (Snell) and the
  // normal component follows from the unit length.
  bool MapThroughPanel(cv::Point2d n, cv::Point2d* board) const {
    const double side = centre[2] < 0 ? -1 : 1;
    const cv::Vec3d d = cv::normalize(r_t * cv::Vec3d(n.x, n.y, 1.0));
    const double face = side * thickness;
    const double lambda = (face - centre[2]) / d[2];
    if (!(lambda > 0)) return false;
    const cv::Vec3d on_face = centre + lambda * d;
    const double tx = d[0] / index, ty = d[1] / index;
    const double tz = -side * std::sqrt(1 - tx * tx - ty * ty);
    const double mu = -face / tz;
    *board = {on_face[0] + mu * tx, on_face[1] + mu * ty};
    return true;
  }
};

RayToBoard MakeRayToBoard(const BoardPose& pose, const CheckerboardRenderOptions& options) {
  cv::Matx33d r;
  cv::Rodrigues(pose.rvec, r);
  const cv::Matx33d h(r(0, 0), r(0, 1), pose.tvec[0], r(1, 0), r(1, 1), pose.tvec[1], r(2, 0),
                      r(2, 1), pose.tvec[2]);
  return {h.inv(), r.t(), -(r.t() * pose.tvec), options.panel_thickness_mm,
          options.panel_refractive_index};
}

// The board's pattern: the uniform region a board point lies in (background, margin, a square, a
// marker cell, a circle) and its reflectance.
class Pattern {
 public:
  Pattern(const CheckerboardSpec& board, const CheckerboardRenderOptions& options)
      : board_(board), options_(options) {
    if (board.kind != TargetKind::kCharuco) return;
    const cv::Ptr<cv::aruco::Dictionary> dictionary =
        cv::aruco::getPredefinedDictionary(board.dictionary);
    cells_ = dictionary->markerSize + 2;
    marker_at_ = cv::Mat_<int>(board.rows + 1, board.cols + 1, -1);
    int id = 0;
    for (int y = 0; y <= board.rows; ++y)
      for (int x = 0; x <= board.cols; ++x) {
        if (IsBlack(x, y)) continue;
        marker_at_(y, x) = id;
        cv::Mat bits;
        cv::aruco::drawMarker(dictionary, id, cells_, bits, /*borderBits=*/1);
        markers_.push_back(bits);
        ++id;
      }
  }

  std::int64_t Region(bool on_ray, cv::Point2d p) const {
    const CheckerboardSpec& b = board_;
    if (!on_ray || p.x < b.XMin() || p.x > b.XMax() || p.y < b.YMin() || p.y > b.YMax())
      return kBackground;
    if (b.kind == TargetKind::kCircles || b.kind == TargetKind::kAsymmetricCircles)
      return CircleRegion(p);
    const double s = b.square_mm;
    if (p.x < -s || p.x >= b.cols * s || p.y < -s || p.y >= b.rows * s) return kMargin;
    const auto i = static_cast<std::int64_t>(std::floor(p.x / s));
    const auto j = static_cast<std::int64_t>(std::floor(p.y / s));
    if (b.kind == TargetKind::kCharuco &&
        !IsBlack(static_cast<int>(i + 1), static_cast<int>(j + 1))) {
      const int marker = marker_at_(static_cast<int>(j + 1), static_cast<int>(i + 1));
      const double d = (s - b.marker_mm) / 2;
      const double lx = (p.x - i * s - d) / b.marker_mm, ly = (p.y - j * s - d) / b.marker_mm;
      if (lx >= 0 && lx < 1 && ly >= 0 && ly < 1) {
        const auto cx = static_cast<std::int64_t>(lx * cells_);
        const auto cy = static_cast<std::int64_t>(ly * cells_);
        return kMarkerCell + (std::int64_t{marker} * 64 + cy) * 64 + cx;
      }
    }
    return (i + 2) * 100000 + (j + 2);
  }

  double Reflectance(bool on_ray, cv::Point2d p) const {
    const std::int64_t id = Region(on_ray, p);
    if (id == kBackground) return options_.background;
    if (id == kMargin) return options_.white;
    if (id == kMixed) return options_.white;  // Outside the circle, near its rim.
    if (id >= kCircle) return options_.black;
    if (id >= kMarkerCell) {
      const std::int64_t cell = id - kMarkerCell;
      const auto& bits = markers_[static_cast<std::size_t>(cell / 4096)];
      return bits.at<std::uint8_t>(static_cast<int>(cell / 64 % 64), static_cast<int>(cell % 64))
                 ? options_.white
                 : options_.black;
    }
    const std::int64_t i = id / 100000 - 2, j = id % 100000 - 2;
    if (board_.kind == TargetKind::kCharuco)
      return IsBlack(static_cast<int>(i + 1), static_cast<int>(j + 1)) ? options_.black
                                                                       : options_.white;
    return ((i + j) % 2 + 2) % 2 == 0 ? options_.black : options_.white;
  }

 private:
  // Square (x, y) of the ChArUco board, x in [0, cols], y in [0, rows].
  bool IsBlack(int x, int y) const {
    return board_.legacy_layout ? (x + board_.rows - y) % 2 == 0 : (x + y) % 2 == 0;
  }

  // Inside a circle: kCircle + id; within a quarter spacing outside one: kMixed; else the margin.
  std::int64_t CircleRegion(cv::Point2d p) const {
    const double s = board_.square_mm, r = board_.circle_radius_mm;
    const bool asymmetric = board_.kind == TargetKind::kAsymmetricCircles;
    const int j0 = static_cast<int>(std::lround(p.y / s));
    double nearest = std::numeric_limits<double>::infinity();
    std::int64_t id = kMargin;
    for (int j = std::max(0, j0 - 1); j <= std::min(board_.rows - 1, j0 + 1); ++j) {
      const double offset = asymmetric ? j % 2 : 0;
      const double pitch = asymmetric ? 2 : 1;
      const int i =
          std::clamp(static_cast<int>(std::lround((p.x / s - offset) / pitch)), 0, board_.cols - 1);
      const double distance = std::hypot(p.x - (pitch * i + offset) * s, p.y - j * s);
      if (distance < nearest) {
        nearest = distance;
        id = kCircle + std::int64_t{j} * board_.cols + i;
      }
    }
    if (nearest < r) return id;
    if (nearest < r + 0.25 * s) return kMixed;
    return kMargin;
  }

  CheckerboardSpec board_;
  CheckerboardRenderOptions options_;
  int cells_ = 0;                 // Marker side in cells, border included.
  cv::Mat_<int> marker_at_;       // ChArUco: marker id of each square (-1: black).
  std::vector<cv::Mat> markers_;  // ChArUco: each marker's cells (0 black, 255 white).
};

// The middle of the board's corners (circle centres) [mm].
cv::Vec3d BoardCentre(const CheckerboardSpec& board) {
  const int x_span =
      board.kind == TargetKind::kAsymmetricCircles ? 2 * board.cols - 1 : board.cols - 1;
  return {x_span * board.square_mm / 2, (board.rows - 1) * board.square_mm / 2, 0};
}

cv::Point3d ToCamera(const cv::Matx33d& r, const cv::Vec3d& t, double x, double y) {
  const cv::Vec3d c = r * cv::Vec3d(x, y, 0) + t;
  return {c[0], c[1], c[2]};
}

}  // namespace

void SynthCamera::Check() const {
  CheckValue(width >= 16, "camera.width", std::to_string(width), ">= 16");
  CheckValue(height >= 16, "camera.height", std::to_string(height), ">= 16");
  CheckValue(fx > 0 && std::isfinite(fx), "camera.fx", fmt::format("{}", fx), "> 0");
  CheckValue(fy > 0 && std::isfinite(fy), "camera.fy", fmt::format("{}", fy), "> 0");
  CheckValue(std::isfinite(cx) && std::isfinite(cy), "camera.cx/cy", "non-finite", "finite");
  for (double d : dist) CheckValue(std::isfinite(d), "camera.dist", "non-finite", "finite");
  for (double d : rational) CheckValue(std::isfinite(d), "camera.rational", "non-finite", "finite");
  for (double d : fisheye_k)
    CheckValue(std::isfinite(d), "camera.fisheye_k", "non-finite", "finite");
}

namespace {

// Rational or fisheye distortion of a normalised point, in normalised units (x_d, y_d).
cv::Point2d DistortGeneral(const SynthCamera& c, cv::Point2d n) {
  const double x = n.x, y = n.y, r2 = x * x + y * y;
  if (c.fisheye) {
    const double r = std::sqrt(r2);
    if (r < 1e-15) return n;
    const double theta = std::atan(r), t2 = theta * theta;
    const auto [k1, k2, k3, k4] = c.fisheye_k;
    const double theta_d = theta * (1 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4))));
    return {theta_d / r * x, theta_d / r * y};
  }
  const auto [k1, k2, p1, p2, k3] = c.dist;
  const auto [k4, k5, k6] = c.rational;
  const double radial =
      (1 + r2 * (k1 + r2 * (k2 + r2 * k3))) / (1 + r2 * (k4 + r2 * (k5 + r2 * k6)));
  return {x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x),
          y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y};
}

bool IsGeneral(const SynthCamera& c) {
  return c.fisheye || c.rational[0] != 0 || c.rational[1] != 0 || c.rational[2] != 0;
}

}  // namespace

cv::Point2d SynthCamera::Distort(cv::Point2d n) const {
  if (IsGeneral(*this)) {
    const cv::Point2d d = DistortGeneral(*this, n);
    return {fx * d.x + cx, fy * d.y + cy};
  }
  const double x = n.x, y = n.y, r2 = x * x + y * y;
  const auto [k1, k2, p1, p2, k3] = dist;
  const double radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3));
  const double xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x);
  const double yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y;
  return {fx * xd + cx, fy * yd + cy};
}

bool SynthCamera::Undistort(cv::Point2d pixel, cv::Point2d* normalised) const {
  if (fisheye) {
    // Radial only: solve theta_d(theta) = |m| for theta by Newton's method, then r = tan(theta).
    const cv::Point2d m((pixel.x - cx) / fx, (pixel.y - cy) / fy);
    const double rd = std::hypot(m.x, m.y);
    if (rd < 1e-15) {
      *normalised = m;
      return true;
    }
    const auto [k1, k2, k3, k4] = fisheye_k;
    double theta = rd;
    for (int iteration = 0; iteration < 50; ++iteration) {
      const double t2 = theta * theta;
      const double f = theta * (1 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4)))) - rd;
      const double df = 1 + t2 * (3 * k1 + t2 * (5 * k2 + t2 * (7 * k3 + t2 * 9 * k4)));
      if (!(df > 0)) return false;
      theta -= f / df;
      if (std::abs(f / df) < 1e-14) {
        if (!(theta > 0 && theta < 1.5)) return false;  // Behind or beyond ~86 degrees.
        const double r = std::tan(theta);
        *normalised = {m.x * r / rd, m.y * r / rd};
        return true;
      }
    }
    return false;
  }
  if (IsGeneral(*this)) {
    // Newton's method with a central-difference Jacobian (the rational model is smooth).
    const cv::Point2d m((pixel.x - cx) / fx, (pixel.y - cy) / fy);
    cv::Point2d x = m;
    for (int iteration = 0; iteration < 100; ++iteration) {
      const cv::Point2d e = DistortGeneral(*this, x) - m;
      constexpr double h = 1e-7;
      const cv::Point2d jx = (DistortGeneral(*this, x + cv::Point2d(h, 0)) -
                              DistortGeneral(*this, x - cv::Point2d(h, 0))) /
                             (2 * h);
      const cv::Point2d jy = (DistortGeneral(*this, x + cv::Point2d(0, h)) -
                              DistortGeneral(*this, x - cv::Point2d(0, h))) /
                             (2 * h);
      const double det = jx.x * jy.y - jy.x * jx.y;
      if (!(std::abs(det) > 1e-12)) return false;
      const cv::Point2d step((jy.y * e.x - jy.x * e.y) / det, (jx.x * e.y - jx.y * e.x) / det);
      x -= step;
      if (std::abs(step.x) + std::abs(step.y) < 1e-13) {
        *normalised = x;
        return true;
      }
    }
    return false;
  }
  const auto [k1, k2, p1, p2, k3] = dist;
  const double mx = (pixel.x - cx) / fx, my = (pixel.y - cy) / fy;
  double x = mx, y = my;
  for (int iteration = 0; iteration < 50; ++iteration) {
    const double r2 = x * x + y * y;
    const double radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3));
    const double dradial = k1 + r2 * (2 * k2 + 3 * k3 * r2);  // d radial / d r2
    const double ex = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x) - mx;
    const double ey = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y - my;
    // Jacobian of the distortion (derivation in the header's formulas).
    const double a = radial + 2 * x * x * dradial + 2 * p1 * y + 6 * p2 * x;
    const double b = 2 * x * y * dradial + 2 * p1 * x + 2 * p2 * y;
    const double d = radial + 2 * y * y * dradial + 6 * p1 * y + 2 * p2 * x;
    const double det = a * d - b * b;
    if (!(std::abs(det) > 1e-12)) return false;
    const double dx = (d * ex - b * ey) / det, dy = (a * ey - b * ex) / det;
    x -= dx;
    y -= dy;
    if (std::abs(dx) + std::abs(dy) < 1e-14) {
      *normalised = {x, y};
      return true;
    }
  }
  return false;
}

SynthCamera SampleCamera() {
  SynthCamera camera;
  camera.fx = 820;
  camera.fy = 822;
  camera.cx = 323.2;
  camera.cy = 236.8;
  camera.dist = {-0.08, 0.05, 4e-4, -3e-4, 0};
  return camera;
}

void CheckerboardSpec::Check() const {
  CheckValue(cols >= 2, "board.cols", std::to_string(cols), ">= 2 inner corners");
  CheckValue(rows >= 2, "board.rows", std::to_string(rows), ">= 2 inner corners");
  CheckValue(square_mm > 0 && std::isfinite(square_mm), "board.square_mm",
             fmt::format("{}", square_mm), "> 0");
  CheckValue(margin_squares >= 0 && std::isfinite(margin_squares), "board.margin_squares",
             fmt::format("{}", margin_squares), ">= 0");
  if (kind == TargetKind::kCharuco) {
    CheckValue(marker_mm > 0 && marker_mm < square_mm, "board.marker_mm",
               fmt::format("{}", marker_mm), "in (0, square_mm)");
    CheckValue(dictionary >= 0 && dictionary <= cv::aruco::DICT_APRILTAG_36h11, "board.dictionary",
               std::to_string(dictionary), "an OpenCV predefined dictionary number");
  }
  if (kind == TargetKind::kCircles || kind == TargetKind::kAsymmetricCircles)
    CheckValue(circle_radius_mm > 0 && circle_radius_mm <= 0.45 * square_mm,
               "board.circle_radius_mm", fmt::format("{}", circle_radius_mm),
               "in (0, 0.45 square_mm]");
}

std::vector<cv::Point2d> CheckerboardSpec::Points() const {
  std::vector<cv::Point2d> points;
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < cols; ++i)
      points.emplace_back((kind == TargetKind::kAsymmetricCircles ? 2 * i + j % 2 : i) * square_mm,
                          j * square_mm);
  return points;
}

void CheckerboardRenderOptions::Check() const {
  CheckValue(supersampling >= 1 && supersampling <= 32, "render.supersampling",
             std::to_string(supersampling), "in [1, 32]");
  for (auto [name, v] : {std::pair{"render.black", black}, std::pair{"render.white", white},
                         std::pair{"render.background", background}})
    CheckValue(v >= 0 && v <= 1, name, fmt::format("{}", v), "in [0, 1]");
  CheckValue(noise_sigma >= 0 && std::isfinite(noise_sigma), "render.noise_sigma",
             fmt::format("{}", noise_sigma), ">= 0");
  CheckValue(psf_sigma_px >= 0 && psf_sigma_px <= 5, "render.psf_sigma_px",
             fmt::format("{}", psf_sigma_px), "in [0, 5]");
  CheckValue(bits == 8 || bits == 16, "render.bits", std::to_string(bits), "8 or 16");
  CheckValue(panel_thickness_mm >= 0 && std::isfinite(panel_thickness_mm),
             "render.panel_thickness_mm", fmt::format("{}", panel_thickness_mm), ">= 0");
  CheckValue(panel_refractive_index >= 1 && std::isfinite(panel_refractive_index),
             "render.panel_refractive_index", fmt::format("{}", panel_refractive_index), ">= 1");
}

bool BoardPointOnRay(const BoardPose& pose, const CheckerboardRenderOptions& options,
                     cv::Point2d normalised, cv::Point2d* board_mm) {
  return MakeRayToBoard(pose, options).Map(normalised, board_mm);
}

void CalibrationSetOptions::Check() const {
  CheckValue(views >= 1, "calibration_set.views", std::to_string(views), ">= 1");
  CheckValue(panel_distance_mm >= 0 && std::isfinite(panel_distance_mm),
             "calibration_set.panel_distance_mm", fmt::format("{}", panel_distance_mm),
             ">= 0 (0 = automatic)");
  CheckValue(partial_every == 0 || partial_every >= 2, "calibration_set.partial_every",
             std::to_string(partial_every), "0 (none) or >= 2");
  render.Check();
}

cv::Mat RenderCheckerboard(const SynthCamera& camera, const CheckerboardSpec& board,
                           const BoardPose& pose, const CheckerboardRenderOptions& options) {
  camera.Check();
  board.Check();
  options.Check();
  const int w = camera.width, h = camera.height;
  const RayToBoard ray = MakeRayToBoard(pose, options);
  const Pattern pattern(board, options);

  // Board point and region of every pixel corner (u - 0.5, v - 0.5), on a (w + 1) x (h + 1)
  // lattice.
  const std::size_t stride = static_cast<std::size_t>(w) + 1;
  cv::Mat_<double> level(h, w);
  std::vector<cv::Point2d> corner_point((h + 1) * stride);
  std::vector<std::int64_t> corner_id((h + 1) * stride);
  cv::parallel_for_(cv::Range(0, h + 1), [&](const cv::Range& range) {
    for (int v = range.start; v < range.end; ++v)
      for (int u = 0; u <= w; ++u) {
        cv::Point2d n, p(0, 0);
        const bool ok = camera.Undistort({u - 0.5, v - 0.5}, &n) && ray.Map(n, &p);
        corner_point[v * stride + u] = p;
        corner_id[v * stride + u] = pattern.Region(ok, p);
      }
  });
  // Sample offsets inside the pixel: an n x n sheared lattice, x = (sx + (sy + 0.5) / n) / n and
  // y = (sy + (sx + 0.5) / n) / n, one sample per stratum but n^2 distinct abscissae and
  // ordinates, so an edge parallel to the pixel grid is resolved to 1 / n^2 of a pixel, not 1 / n.
  const int ss = options.supersampling;
  std::vector<cv::Point2d> offsets;
  for (int sy = 0; sy < ss; ++sy)
    for (int sx = 0; sx < ss; ++sx)
      offsets.emplace_back((sx + (sy + 0.5) / ss) / ss, (sy + (sx + 0.5) / ss) / ss);
  cv::parallel_for_(cv::Range(0, h), [&](const cv::Range& range) {
    for (int v = range.start; v < range.end; ++v)
      for (int u = 0; u < w; ++u) {
        const std::size_t i00 = v * stride + u, i10 = i00 + 1, i01 = i00 + stride, i11 = i01 + 1;
        const std::int64_t id = corner_id[i00];
        if (id != kMixed && id == corner_id[i10] && id == corner_id[i01] && id == corner_id[i11]) {
          // Uniform pixel (the board cells are convex and the map is smooth).
          cv::Point2d n, p;
          const bool ok = camera.Undistort({double(u), double(v)}, &n) && ray.Map(n, &p);
          level(v, u) = pattern.Reflectance(ok, p);
          continue;
        }
        // Edge pixel: mean over the samples (box filter of the pixel area). Within one pixel the
        // image-to-board map is affine to ~1e-6 px (its curvature from perspective and
        // distortion is tiny at this scale), so samples are placed by bilinear interpolation of
        // the four corner points instead of inverting the distortion for each.
        const cv::Point2d p00 = corner_point[i00], p10 = corner_point[i10], p01 = corner_point[i01],
                          p11 = corner_point[i11];
        const bool exact = id == kBackground || corner_id[i10] == kBackground ||
                           corner_id[i01] == kBackground || corner_id[i11] == kBackground;
        double sum = 0;
        for (const cv::Point2d& o : offsets) {
          cv::Point2d p;
          bool ok = true;
          if (exact) {  // At the board's outer edge a corner may miss the plane: invert exactly.
            cv::Point2d n;
            ok = camera.Undistort({u - 0.5 + o.x, v - 0.5 + o.y}, &n) && ray.Map(n, &p);
          } else {
            p = (1 - o.y) * ((1 - o.x) * p00 + o.x * p10) + o.y * ((1 - o.x) * p01 + o.x * p11);
          }
          sum += pattern.Reflectance(ok, p);
        }
        level(v, u) = sum / offsets.size();
      }
  });

  if (options.psf_sigma_px > 0)
    cv::GaussianBlur(level, level, cv::Size(0, 0), options.psf_sigma_px, options.psf_sigma_px,
                     cv::BORDER_REPLICATE);
  const double full_scale = options.bits == 8 ? 255.0 : 65535.0;
  cv::RNG rng(options.seed);
  cv::Mat out(h, w, options.bits == 8 ? CV_8U : CV_16U);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      double value = level(v, u) * full_scale;
      if (options.noise_sigma > 0) value += rng.gaussian(options.noise_sigma);
      value = std::clamp(std::round(value), 0.0, full_scale);
      if (options.bits == 8)
        out.at<std::uint8_t>(v, u) = static_cast<std::uint8_t>(value);
      else
        out.at<std::uint16_t>(v, u) = static_cast<std::uint16_t>(value);
    }
  return out;
}

std::vector<cv::Point2d> ProjectCorners(const SynthCamera& camera, const CheckerboardSpec& board,
                                        const BoardPose& pose) {
  cv::Matx33d r;
  cv::Rodrigues(pose.rvec, r);
  std::vector<cv::Point2d> out;
  for (int j = 0; j < board.rows; ++j)
    for (int i = 0; i < board.cols; ++i) {
      const cv::Point3d c = ToCamera(r, pose.tvec, i * board.square_mm, j * board.square_mm);
      out.push_back(camera.Distort({c.x / c.z, c.y / c.z}));
    }
  return out;
}

std::vector<cv::Point2d> ProjectCornersPinhole(const SynthCamera& camera,
                                               const CheckerboardSpec& board,
                                               const BoardPose& pose) {
  SynthCamera pinhole = camera;
  pinhole.dist = {0, 0, 0, 0, 0};
  return ProjectCorners(pinhole, board, pose);
}

std::vector<BoardPose> CalibrationPoses(const SynthCamera& camera, const CheckerboardSpec& board,
                                        int count, std::uint64_t seed) {
  camera.Check();
  board.Check();
  CheckValue(count >= 1, "count", std::to_string(count), ">= 1");
  std::mt19937_64 rng(seed);
  auto uniform = [&rng](double lo, double hi) {
    return lo + (hi - lo) * (static_cast<double>(rng() >> 11) * 0x1.0p-53);
  };
  const double deg = std::numbers::pi / 180;
  const double board_w = board.XMax() - board.XMin();
  const cv::Vec3d centre = BoardCentre(board);
  // Outline of the board including the margin, sampled densely enough that distortion cannot
  // push an unsampled point outside the image.
  std::vector<cv::Vec3d> outline;
  for (int k = 0; k < 40; ++k) {
    const double f = k / 40.0;
    const double x0 = board.XMin(), x1 = board.XMax(), y0 = board.YMin(), y1 = board.YMax();
    outline.emplace_back(x0 + f * (x1 - x0), y0, 0);
    outline.emplace_back(x1, y0 + f * (y1 - y0), 0);
    outline.emplace_back(x1 - f * (x1 - x0), y1, 0);
    outline.emplace_back(x0, y1 - f * (y1 - y0), 0);
  }
  std::vector<BoardPose> poses;
  for (int attempt = 0; static_cast<int>(poses.size()) < count; ++attempt) {
    CheckValue(attempt < 100000, "CalibrationPoses", "no pose fits",
               "a board small enough to fit the image");
    const double tilt = uniform(15, 40) * deg, axis = uniform(0, 2 * std::numbers::pi);
    const double roll = uniform(-20, 20) * deg;
    // Views cycle through the four image corners and the whole field, so that the lens
    // distortion is sampled out to the corners (not only where a big centred board would be).
    const int slot = static_cast<int>(poses.size()) % 5;
    const double width_fraction = uniform(0.4, 0.65);
    const double z = board_w * camera.fx / (width_fraction * camera.width);
    const double sx = slot == 4 ? uniform(-0.2, 0.2) : (slot % 2 ? 1 : -1) * uniform(0.15, 0.35);
    const double sy = slot == 4 ? uniform(-0.2, 0.2) : (slot / 2 ? 1 : -1) * uniform(0.15, 0.35);
    const double x0 = sx * camera.width / camera.fx;
    const double y0 = sy * camera.height / camera.fy;
    cv::Matx33d r_tilt, r_roll;
    cv::Rodrigues(cv::Vec3d(std::cos(axis), std::sin(axis), 0) * tilt, r_tilt);
    cv::Rodrigues(cv::Vec3d(0, 0, roll), r_roll);
    const cv::Matx33d r = r_tilt * r_roll;
    BoardPose pose;
    cv::Rodrigues(r, pose.rvec);
    pose.tvec = cv::Vec3d(x0 * z, y0 * z, z) - r * centre;
    bool inside = true;
    for (const cv::Vec3d& p : outline) {
      const cv::Vec3d c = r * p + pose.tvec;
      if (c[2] <= 0) {
        inside = false;
        break;
      }
      const cv::Point2d px = camera.Distort({c[0] / c[2], c[1] / c[2]});
      if (px.x < 6 || px.y < 6 || px.x > camera.width - 7 || px.y > camera.height - 7) {
        inside = false;
        break;
      }
    }
    if (inside) poses.push_back(pose);
  }
  return poses;
}

BoardPose PanelPose(const SynthCamera& camera, const CheckerboardSpec& board, double distance_mm,
                    double roll_deg) {
  camera.Check();
  board.Check();
  CheckValue(distance_mm > 0, "distance_mm", fmt::format("{}", distance_mm), "> 0");
  cv::Matx33d r;
  cv::Rodrigues(cv::Vec3d(0, 0, roll_deg * std::numbers::pi / 180), r);
  const cv::Vec3d centre = BoardCentre(board);
  BoardPose pose;
  cv::Rodrigues(r, pose.rvec);
  pose.tvec = cv::Vec3d(0, 0, distance_mm) - r * centre;
  return pose;
}

namespace {

// board.yaml lines of the targets other than the chessboard (none for it).
std::string TargetYaml(const CheckerboardSpec& board) {
  switch (board.kind) {
    case TargetKind::kCharuco:
      return fmt::format(
          "kind: charuco  # cols x rows count inner corners: {}x{} squares\nmarker_mm: {}\n"
          "dictionary: {}  # cv::aruco predefined dictionary number (0 = DICT_4X4_50)\n"
          "legacy_layout: {}\n",
          board.cols + 1, board.rows + 1, board.marker_mm, board.dictionary,
          board.legacy_layout ? "true" : "false");
    case TargetKind::kCircles:
    case TargetKind::kAsymmetricCircles:
      return fmt::format("kind: {}  # cols x rows count circles\ncircle_radius_mm: {}\n",
                         board.kind == TargetKind::kCircles ? "circles" : "asymmetric_circles",
                         board.circle_radius_mm);
    case TargetKind::kChessboard: break;
  }
  return "";
}

// board.yaml truth lines of the rational and fisheye lenses (none for Brown-Conrady).
std::string LensYaml(const SynthCamera& camera) {
  if (camera.fisheye)
    return fmt::format("  fisheye_k: [{}, {}, {}, {}]  # the fisheye model; dist unused\n",
                       camera.fisheye_k[0], camera.fisheye_k[1], camera.fisheye_k[2],
                       camera.fisheye_k[3]);
  if (IsGeneral(camera))
    return fmt::format("  rational: [{}, {}, {}]  # k4, k5, k6\n", camera.rational[0],
                       camera.rational[1], camera.rational[2]);
  return "";
}

}  // namespace

CalibrationSet RenderCalibrationSet(const SynthCamera& camera, const CheckerboardSpec& board,
                                    const CalibrationSetOptions& options,
                                    const std::string& out_dir) {
  camera.Check();
  board.Check();
  options.Check();
  namespace fs = std::filesystem;
  std::error_code ec;
  MakeFolders(out_dir, ec);
  if (ec) throw Error(ErrorKind::kIo, "cannot create folder " + out_dir + ": " + ec.message());

  CalibrationSet set;
  set.poses = CalibrationPoses(camera, board, options.views, options.seed);
  for (int k = 0; options.partial_every > 0 && k < options.views; ++k) {
    if (k % options.partial_every != options.partial_every - 1) continue;
    // Outwards, towards the image corner the view was placed near: part of the board leaves.
    cv::Vec3d& t = set.poses[k].tvec;
    const double shift = 0.45 * (board.XMax() - board.XMin());
    t[0] += (t[0] < 0 ? -1 : 1) * shift;
    t[1] += (t[1] < 0 ? -1 : 1) * 0.2 * shift;
  }
  auto write = [](const std::string& path, const cv::Mat& image) { WriteImage(path, image); };
  for (int k = 0; k < options.views; ++k) {
    CheckerboardRenderOptions render = options.render;
    render.seed = options.render.seed + 1000003ULL * (k + 1);
    const std::string path = (fs::path(out_dir) / fmt::format("view_{:02d}.png", k)).string();
    write(path, RenderCheckerboard(camera, board, set.poses[k], render));
    set.view_paths.push_back(path);
  }
  const double distance = options.panel_distance_mm > 0
                              ? options.panel_distance_mm
                              : (board.XMax() - board.XMin()) * camera.fx / (0.6 * camera.width);
  set.plane_pose = PanelPose(camera, board, distance, /*roll_deg=*/2.0);
  set.plane_mm_per_px = distance / std::sqrt(camera.fx * camera.fy);
  set.plane_path = (fs::path(out_dir) / "plane.png").string();
  write(set.plane_path, RenderCheckerboard(camera, board, set.plane_pose, options.render));

  set.board_path = (fs::path(out_dir) / "board.yaml").string();
  std::ostringstream yaml;
  yaml << "# Checkerboard definition (the board and square size `impactdic calibrate` needs).\n"
       << "# cols x rows count INNER corners; a 9x6 board has 10x7 squares.\n"
       << fmt::format("cols: {}\nrows: {}\nsquare_mm: {}\nmargin_squares: {}\n", board.cols,
                      board.rows, board.square_mm, board.margin_squares)
       << TargetYaml(board)
       << "# The camera the sample images were rendered with (ground truth, for reference).\n"
       << "truth:\n"
       << fmt::format("  image_width: {}\n  image_height: {}\n", camera.width, camera.height)
       << fmt::format("  fx: {}\n  fy: {}\n  cx: {}\n  cy: {}\n", camera.fx, camera.fy, camera.cx,
                      camera.cy)
       << fmt::format("  dist: [{}, {}, {}, {}, {}]  # k1, k2, p1, p2, k3\n", camera.dist[0],
                      camera.dist[1], camera.dist[2], camera.dist[3], camera.dist[4])
       << LensYaml(camera)
       << fmt::format("  views: {}\n  noise_sigma: {}\n  bits: {}\n", options.views,
                      options.render.noise_sigma, options.render.bits)
       << fmt::format("  plane_distance_mm: {}\n  plane_mm_per_px: {:.9g}\n", distance,
                      set.plane_mm_per_px);
  WriteTextFileAtomic(set.board_path, yaml.str());
  return set;
}

namespace {

CheckerboardSpec CircleGrid(TargetKind kind, int cols, int rows, double spacing_mm,
                            double radius_mm) {
  return {.cols = cols,
          .rows = rows,
          .square_mm = spacing_mm,
          .kind = kind,
          .circle_radius_mm = radius_mm};
}

}  // namespace

CalibrationPreset CalibrationPresetNamed(const std::string& name) {
  CalibrationPreset p;
  p.camera = SampleCamera();
  p.options.views = 12;
  p.options.seed = 11;
  CheckerboardSpec& b = p.board;
  if (name == "charuco" || name == "charuco_legacy" || name == "wide_angle") {
    b.kind = TargetKind::kCharuco;
    b.cols = 7;  // 8 x 6 squares
    b.rows = 5;
    b.square_mm = 30;
    b.marker_mm = 21;
    b.legacy_layout = name == "charuco_legacy";
    // The sample lens at twice the resolution: markers of 4x4 bits need ~5 px a bit, and the
    // corner search window must stay between the markers.
    SynthCamera& c = p.camera;
    c.width = 1280;
    c.height = 960;
    c.fx *= 2;
    c.fy *= 2;
    c.cx = 2 * c.cx + 0.5;
    c.cy = 2 * c.cy + 0.5;
    if (name == "wide_angle") {
      c.fx = 600;
      c.fy = 600;
      c.dist = {0, 0, 0, 0, 0};
      c.fisheye = true;
      c.fisheye_k = {-0.02, 0.004, 0, 0};
    } else {
      p.options.partial_every = 3;
    }
  } else if (name == "circles") {
    b = CircleGrid(TargetKind::kCircles, /*cols=*/7, /*rows=*/5, /*spacing_mm=*/30,
                   /*radius_mm=*/9);
  } else if (name == "asymmetric_circles") {
    b = CircleGrid(TargetKind::kAsymmetricCircles, /*cols=*/4, /*rows=*/9, /*spacing_mm=*/20,
                   /*radius_mm=*/6);
  } else if (name == "window") {
    b.square_mm = 45;
    p.options.panel_distance_mm = 1000;
    p.panel_thickness_mm = 20;
    p.panel_refractive_index = 1.5;
  } else {
    std::string names;
    for (const char* n : kCalibrationSetNames) names += std::string(names.empty() ? "" : ", ") + n;
    throw Error(ErrorKind::kInvalidValue, "--calibration-set", "'" + name + "'", "one of " + names);
  }
  return p;
}

CalibrationSet RenderCalibrationPreset(const CalibrationPreset& preset,
                                       const std::string& out_dir) {
  CalibrationSet set = RenderCalibrationSet(preset.camera, preset.board, preset.options, out_dir);
  if (!(preset.panel_thickness_mm > 0)) return set;
  // The same board, moved straight back by the panel's thickness: it lies against the inner
  // face, and the view goes through the panel.
  CheckerboardRenderOptions render = preset.options.render;
  render.panel_thickness_mm = preset.panel_thickness_mm;
  render.panel_refractive_index = preset.panel_refractive_index;
  cv::Matx33d r;
  cv::Rodrigues(set.plane_pose.rvec, r);
  set.soil_pose = set.plane_pose;
  set.soil_pose.tvec += r * cv::Vec3d(0, 0, preset.panel_thickness_mm);
  set.soil_path = (std::filesystem::path(out_dir) / "soil.png").string();
  WriteImage(set.soil_path, RenderCheckerboard(preset.camera, preset.board, set.soil_pose, render));
  // True soil-plane scale at the principal point: sqrt |det J| of the ideal pixel -> soil map.
  const SynthCamera& c = preset.camera;
  const auto soil = [&](double du, double dv) {
    cv::Point2d p;
    CheckValue(BoardPointOnRay(set.soil_pose, render, {du / c.fx, dv / c.fy}, &p), "window",
               "a ray that misses the soil plane", "the board in front of the camera");
    return p;
  };
  const cv::Point2d ju = (soil(1, 0) - soil(-1, 0)) / 2, jv = (soil(0, 1) - soil(0, -1)) / 2;
  set.soil_mm_per_px = std::sqrt(std::abs(ju.x * jv.y - ju.y * jv.x));
  std::string yaml = ReadTextFile(set.board_path);
  yaml += fmt::format(
      "  # The window: a {} mm panel of n = {} with plane.png's board on its outer face at {} mm\n"
      "  # and soil.png's board against its inner face (the soil plane), seen through it.\n"
      "  panel_thickness_mm: {}\n  panel_refractive_index: {}\n  soil_mm_per_px: {:.9g}\n",
      preset.panel_thickness_mm, preset.panel_refractive_index, preset.options.panel_distance_mm,
      preset.panel_thickness_mm, preset.panel_refractive_index, set.soil_mm_per_px);
  WriteTextFileAtomic(set.board_path, yaml);
  return set;
}

}  // namespace impactdic
