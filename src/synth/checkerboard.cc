#include "impactdic/synth/checkerboard.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <numbers>
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

// Board point on the ray through normalised point n: [X Y 1] ~ H^-1 [x y 1] with H = [r1 r2 t].
struct RayToBoard {
  cv::Matx33d h_inv;
  bool Map(cv::Point2d n, cv::Point2d* board) const {
    const cv::Vec3d b = h_inv * cv::Vec3d(n.x, n.y, 1.0);
    if (!(b[2] > 0)) return false;  // Behind the camera or parallel to the plane.
    *board = {b[0] / b[2], b[1] / b[2]};
    return true;
  }
};

RayToBoard MakeRayToBoard(const BoardPose& pose) {
  cv::Matx33d r;
  cv::Rodrigues(pose.rvec, r);
  const cv::Matx33d h(r(0, 0), r(0, 1), pose.tvec[0], r(1, 0), r(1, 1), pose.tvec[1], r(2, 0),
                      r(2, 1), pose.tvec[2]);
  return {h.inv()};
}

// Region of a board point: background, margin, or the cell (i, j) it lies in.
std::int64_t RegionId(const CheckerboardSpec& board, bool on_ray, cv::Point2d p) {
  if (!on_ray || p.x < board.XMin() || p.x > board.XMax() || p.y < board.YMin() ||
      p.y > board.YMax())
    return kBackground;
  const double s = board.square_mm;
  if (p.x < -s || p.x >= board.cols * s || p.y < -s || p.y >= board.rows * s) return kMargin;
  const auto i = static_cast<std::int64_t>(std::floor(p.x / s));
  const auto j = static_cast<std::int64_t>(std::floor(p.y / s));
  return (i + 2) * 100000 + (j + 2);
}

double Reflectance(const CheckerboardSpec& board, const CheckerboardRenderOptions& options,
                   bool on_ray, cv::Point2d p) {
  const std::int64_t id = RegionId(board, on_ray, p);
  if (id == kBackground) return options.background;
  if (id == kMargin) return options.white;
  const std::int64_t i = id / 100000 - 2, j = id % 100000 - 2;
  return ((i + j) % 2 + 2) % 2 == 0 ? options.black : options.white;
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
}

cv::Point2d SynthCamera::Distort(cv::Point2d n) const {
  const double x = n.x, y = n.y, r2 = x * x + y * y;
  const auto [k1, k2, p1, p2, k3] = dist;
  const double radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3));
  const double xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x);
  const double yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y;
  return {fx * xd + cx, fy * yd + cy};
}

bool SynthCamera::Undistort(cv::Point2d pixel, cv::Point2d* normalised) const {
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
}

void CalibrationSetOptions::Check() const {
  CheckValue(views >= 1, "calibration_set.views", std::to_string(views), ">= 1");
  CheckValue(panel_distance_mm >= 0 && std::isfinite(panel_distance_mm),
             "calibration_set.panel_distance_mm", fmt::format("{}", panel_distance_mm),
             ">= 0 (0 = automatic)");
  render.Check();
}

cv::Mat RenderCheckerboard(const SynthCamera& camera, const CheckerboardSpec& board,
                           const BoardPose& pose, const CheckerboardRenderOptions& options) {
  camera.Check();
  board.Check();
  options.Check();
  const int w = camera.width, h = camera.height;
  const RayToBoard ray = MakeRayToBoard(pose);

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
        corner_id[v * stride + u] = RegionId(board, ok, p);
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
        if (id == corner_id[i10] && id == corner_id[i01] && id == corner_id[i11]) {
          // Uniform pixel (the board cells are convex and the map is smooth).
          cv::Point2d n, p;
          const bool ok = camera.Undistort({double(u), double(v)}, &n) && ray.Map(n, &p);
          level(v, u) = Reflectance(board, options, ok, p);
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
          sum += Reflectance(board, options, ok, p);
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
  const cv::Vec3d centre((board.cols - 1) * board.square_mm / 2,
                         (board.rows - 1) * board.square_mm / 2, 0);
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
  const cv::Vec3d centre((board.cols - 1) * board.square_mm / 2,
                         (board.rows - 1) * board.square_mm / 2, 0);
  BoardPose pose;
  cv::Rodrigues(r, pose.rvec);
  pose.tvec = cv::Vec3d(0, 0, distance_mm) - r * centre;
  return pose;
}

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
       << "# The camera the sample images were rendered with (ground truth, for reference).\n"
       << "truth:\n"
       << fmt::format("  image_width: {}\n  image_height: {}\n", camera.width, camera.height)
       << fmt::format("  fx: {}\n  fy: {}\n  cx: {}\n  cy: {}\n", camera.fx, camera.fy, camera.cx,
                      camera.cy)
       << fmt::format("  dist: [{}, {}, {}, {}, {}]  # k1, k2, p1, p2, k3\n", camera.dist[0],
                      camera.dist[1], camera.dist[2], camera.dist[3], camera.dist[4])
       << fmt::format("  views: {}\n  noise_sigma: {}\n  bits: {}\n", options.views,
                      options.render.noise_sigma, options.render.bits)
       << fmt::format("  plane_distance_mm: {}\n  plane_mm_per_px: {:.9g}\n", distance,
                      set.plane_mm_per_px);
  WriteTextFileAtomic(set.board_path, yaml.str());
  return set;
}

}  // namespace impactdic
