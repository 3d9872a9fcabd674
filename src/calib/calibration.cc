#include "impactdic/calib/calibration.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <regex>
#include <utility>

#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/core/timer.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/image_io.h"

namespace impactdic {
namespace {

std::string SizeText(cv::Size size) { return fmt::format("{}x{}", size.width, size.height); }

// 16-bit images are stretched to the full 8-bit range for the corner detector (a 12-bit camera's
// data would otherwise sit in the lowest 16th of the range).
cv::Mat To8Bit(const cv::Mat& image) {
  if (image.depth() == CV_8U) return image;
  cv::Mat out;
  cv::normalize(image, out, 0, 255, cv::NORM_MINMAX, CV_8U);
  return out;
}

// FNV-1a over the pixels, row by row (a Mat need not be continuous): finds repeated images.
std::uint64_t PixelHash(const cv::Mat& image) {
  std::uint64_t hash = 14695981039346656037ULL;
  const std::size_t row_bytes = static_cast<std::size_t>(image.cols) * image.elemSize();
  for (int y = 0; y < image.rows; ++y) {
    const unsigned char* row = image.ptr<unsigned char>(y);
    for (std::size_t i = 0; i < row_bytes; ++i) hash = (hash ^ row[i]) * 1099511628211ULL;
  }
  return hash;
}

// Largest distance between corresponding corners of two detections of one board [px], in either
// order of the corners (the detector may number a near-identical view from the opposite corner).
double MaxCornerDifference(const std::vector<cv::Point2f>& a, const std::vector<cv::Point2f>& b) {
  double forward = 0, backward = 0;
  const std::size_t n = a.size();
  for (std::size_t i = 0; i < n; ++i) {
    forward = std::max(forward, cv::norm(a[i] - b[i]));
    backward = std::max(backward, cv::norm(a[i] - b[n - 1 - i]));
  }
  return std::min(forward, backward);
}

// The views the calibration uses: one per distinct pose of the board.
struct DetectedViews {
  std::vector<std::vector<cv::Point2f>> corners;
  std::vector<std::string> names;
  std::vector<std::size_t> image;  // Per view: its index in the images.
  std::vector<int> repeats;  // Per view: how many other images repeated it (and were dropped).
  int repeated = 0;          // Images dropped as repeats.
};

// Detects the board in every image. Rejected (logged, listed in result->rejected with the
// reason): an image without the board; a repeat of an earlier view (identical pixels, or every
// corner within options.duplicate_tolerance_px of that view's): a repeat adds no constraint on
// the lens, but calibrateCamera would count it as another view, and a set of repeats fits a
// wrong camera with a tiny RMS.
DetectedViews DetectViews(const std::vector<cv::Mat>& images,
                          const std::function<std::string(std::size_t)>& name_of,
                          const CalibrationOptions& options, CameraCalibration* result) {
  DetectedViews views;
  std::map<std::uint64_t, std::size_t> view_of_hash;  // Pixel hash -> view.
  const auto reject = [&](std::size_t k, const std::string& reason) {
    LogWarning("calibration: rejected {}: {}", name_of(k), reason);
    result->rejected.push_back({name_of(k), reason});
  };
  const auto repeat = [&](std::size_t k, std::size_t view, const std::string& why) {
    if (name_of(k) == views.names[view]) {
      reject(k, "given a second time; a view counts once");
    } else {
      reject(k, fmt::format("a repeat of {} ({}); a view counts once", views.names[view], why));
    }
    ++views.repeats[view];
    ++views.repeated;
  };
  for (std::size_t k = 0; k < images.size(); ++k) {
    const std::uint64_t hash = PixelHash(images[k]);
    const auto same = view_of_hash.find(hash);
    if (same != view_of_hash.end() &&
        cv::norm(images[k], images[views.image[same->second]], cv::NORM_INF) == 0) {
      repeat(k, same->second, "identical pixels");
      continue;
    }
    auto corners = DetectBoard(images[k], options.board, options.detection);
    if (!corners) {
      reject(k, fmt::format("the {}x{} board (inner corners) was not found", options.board.cols,
                            options.board.rows));
      continue;
    }
    std::size_t view = 0;
    double difference = kNaN;
    for (; view < views.corners.size(); ++view) {
      difference = MaxCornerDifference(*corners, views.corners[view]);
      if (difference <= options.duplicate_tolerance_px) break;
    }
    if (view < views.corners.size()) {
      repeat(k, view,
             fmt::format("every corner within {:.3f} px of that view's, calibration."
                         "duplicate_tolerance_px = {} px",
                         difference, options.duplicate_tolerance_px));
      continue;
    }
    view_of_hash.emplace(hash, views.corners.size());
    views.corners.push_back(std::move(*corners));
    views.names.push_back(name_of(k));
    views.repeats.push_back(0);
    views.image.push_back(k);
  }
  return views;
}

// "...; at least 6 distinct views are needed (...)": the text of too few distinct views.
std::string TooFewViewsText(const DetectedViews& views, std::size_t images,
                            const CalibrationOptions& options) {
  const std::size_t found = views.corners.size() + static_cast<std::size_t>(views.repeated);
  std::string text = fmt::format(
      "too few calibration images: the board was found in {} of {} images", found, images);
  if (views.repeated > 0) {
    std::string repeated;
    for (std::size_t v = 0; v < views.names.size(); ++v)
      if (views.repeats[v] > 0)
        repeated += fmt::format("{}{} repeated {} time{}", repeated.empty() ? "" : ", ",
                                views.names[v], views.repeats[v], views.repeats[v] == 1 ? "" : "s");
    text += fmt::format(
        ", but {} of them repeat another view ({}), which leaves {} distinct view{}",
        views.repeated, repeated, views.corners.size(), views.corners.size() == 1 ? "" : "s");
  }
  return text + fmt::format(
                    "; at least {} distinct views are needed (calibration.min_views): each view "
                    "of the flat board gives 2 constraints on the camera matrix (Zhang 2000), so "
                    "fx, fy, cx, cy need 3 views at different tilts, and the distortion model "
                    "(k1, k2, p1, p2, k3) needs more, with corners spread over the image; move "
                    "and tilt the board between views",
                    options.min_views);
}

void CheckImage(const cv::Mat& image, const std::string& name) {
  if (image.empty())
    throw Error(ErrorKind::kInvalidValue, name, "an empty image", "an 8/16-bit greyscale image");
  if (image.channels() != 1 || (image.depth() != CV_8U && image.depth() != CV_16U))
    throw Error(ErrorKind::kInvalidValue, name,
                fmt::format("{} channel(s), depth code {}", image.channels(), image.depth()),
                "an 8/16-bit single-channel (greyscale) image");
}

}  // namespace

void BoardSpec::Check() const {
  CheckValue(cols >= 2, "board.cols", std::to_string(cols), ">= 2 inner corners");
  CheckValue(rows >= 2, "board.rows", std::to_string(rows), ">= 2 inner corners");
  CheckRange(square_mm, kSquareRange, "board.square_mm", "a square size");
}

std::vector<cv::Point3f> BoardSpec::ObjectPoints() const {
  std::vector<cv::Point3f> points;
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < cols; ++i)
      points.emplace_back(static_cast<float>(i * square_mm), static_cast<float>(j * square_mm),
                          0.f);
  return points;
}

BoardSpec ParseBoard(const std::string& text, double square_mm, const std::string& where) {
  static const std::regex pattern(R"(\s*(\d+)\s*[xX]\s*(\d+)\s*)");
  std::smatch match;
  if (!std::regex_match(text, match, pattern) || match[1].length() > 4 || match[2].length() > 4)
    throw Error(ErrorKind::kInvalidValue, where, "'" + text + "'",
                "COLSxROWS counting INNER corners, e.g. 9x6 for a board of 10x7 squares");
  BoardSpec board;
  board.cols = std::stoi(match[1]);
  board.rows = std::stoi(match[2]);
  CheckValue(board.cols >= 2 && board.rows >= 2, where, "'" + text + "'",
             "at least 2x2 inner corners");
  board.square_mm = square_mm;
  CheckRange(square_mm, BoardSpec::kSquareRange, "board.square_mm", "a square size");
  return board;
}

void DetectionOptions::Check() const {
  CheckRange(subpix_half_window, kHalfWindowRange, "calibration.detection.subpix_half_window",
             "a search half-window");
  CheckRange(subpix_max_iterations, kMaxIterationsRange,
             "calibration.detection.subpix_max_iterations", "an iteration count");
  CheckRange(subpix_epsilon_px, kEpsilonRange, "calibration.detection.subpix_epsilon_px",
             "a corner movement");
}

void CalibrationOptions::Check() const {
  board.Check();
  detection.Check();
  CheckRange(min_views, kMinViewsRange, "calibration.min_views", "a view count");
  CheckRange(max_rms_px, kMaxRmsRange, "calibration.max_rms_px", "a reprojection RMS");
  CheckRange(duplicate_tolerance_px, kDuplicateToleranceRange, "calibration.duplicate_tolerance_px",
             "a corner distance");
}

std::vector<YamlOptionTable> CalibrationOptionTables(CalibrationOptions* o) {
  YamlOptionTable t("calibration");
  t.Add("min_views", &o->min_views, CalibrationOptions::kMinViewsRange, "view count",
        "Fewest distinct views with a detected board (Zhang needs 3; 10-20 for distortion)");
  t.Add("max_rms_px", &o->max_rms_px, CalibrationOptions::kMaxRmsRange, "a reprojection RMS",
        "Refuse a calibration whose reprojection RMS exceeds this");
  t.Add("fix_k3", &o->fix_k3, "Hold k3 = 0 (fewer views or mild distortion)");
  t.Add("zero_tangential", &o->zero_tangential, "Hold p1 = p2 = 0 (no tangential distortion)");
  t.Add("duplicate_tolerance_px", &o->duplicate_tolerance_px,
        CalibrationOptions::kDuplicateToleranceRange, "a corner distance",
        "A view whose corners all lie this close to an earlier view's repeats it (counted once)");
  DetectionOptions& d = o->detection;
  YamlOptionTable detection("calibration.detection");
  detection.Add("adaptive_threshold", &d.adaptive_threshold,
                "Adaptive thresholding in the board search (uneven light)");
  detection.Add("normalize_image", &d.normalize_image,
                "Equalise the image's histogram before the board search");
  detection.Add("subpix_half_window", &d.subpix_half_window, DetectionOptions::kHalfWindowRange,
                "search half-window", "Sub-pixel corner search half-window (< half a square)");
  detection.Add("subpix_max_iterations", &d.subpix_max_iterations,
                DetectionOptions::kMaxIterationsRange, "iteration count",
                "Sub-pixel corner refinement: iteration cap");
  detection.Add("subpix_epsilon_px", &d.subpix_epsilon_px, DetectionOptions::kEpsilonRange,
                "a corner movement", "... and stop when a corner moves less than this");
  return {t, detection};
}

cv::Point2d PlaneScale::ToMm(cv::Point2d px) const {
  const cv::Vec3d p = mm_from_px * cv::Vec3d(px.x, px.y, 1);
  return {p[0] / p[2], p[1] / p[2]};
}

cv::Mat CameraCalibration::DistCoeffs() const {
  cv::Mat d(1, 5, CV_64F);
  for (int k = 0; k < 5; ++k) d.at<double>(k) = dist[k];
  return d;
}

bool CameraCalibration::HasDistortion() const {
  return std::any_of(dist.begin(), dist.end(), [](double d) { return d != 0; });
}

std::vector<cv::Point2d> CameraCalibration::UndistortPixels(
    const std::vector<cv::Point2d>& distorted) const {
  if (distorted.empty()) return {};
  std::vector<cv::Point2d> out;
  const cv::Matx33d k = CameraMatrix();
  cv::undistortPoints(
      distorted, out, k, DistCoeffs(), cv::noArray(), k,
      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-12));
  return out;
}

std::string CalibrationSummary::BriefReport() const {
  return fmt::format(
      "calibration: {} of {} images used ({} rejected{}), RMS {:.4f} px (worst view {} {:.4f} px), "
      "detection {:.2f} s, calibration {:.2f} s",
      images_used, images_total, images_rejected,
      images_repeated > 0 ? fmt::format(", {} of them repeats of another view", images_repeated)
                          : std::string(),
      rms_px, worst_view, worst_view_rms_px, detection_seconds, calibration_seconds);
}

std::string CalibrationSummary::FullReport(const CameraCalibration& c) const {
  std::string out = BriefReport() + "\n";
  out += fmt::format("  image size {}x{}, board {}x{} inner corners, {} mm squares\n",
                     c.image_width, c.image_height, c.board.cols, c.board.rows, c.board.square_mm);
  out += fmt::format("  fx {:.4f}  fy {:.4f}  cx {:.4f}  cy {:.4f} [px]\n", c.fx, c.fy, c.cx, c.cy);
  out += fmt::format("  k1 {:.6g}  k2 {:.6g}  p1 {:.6g}  p2 {:.6g}  k3 {:.6g}\n", c.dist[0],
                     c.dist[1], c.dist[2], c.dist[3], c.dist[4]);
  for (const ViewRecord& v : c.views)
    out += fmt::format("  view {}: RMS {:.4f} px\n", v.image, v.rms_px);
  for (const RejectedView& r : c.rejected)
    out += fmt::format("  rejected {}: {}\n", r.image, r.reason);
  return out;
}

std::string CalibrationSummary::CommandReport(const CameraCalibration& c,
                                              const std::string& output) const {
  std::string out = fmt::format("images: {} used, {} rejected (of {})\n", images_used,
                                images_rejected, images_total);
  for (const RejectedView& r : c.rejected)
    out += fmt::format("  rejected {}: {}\n", r.image, r.reason);
  out += fmt::format("reprojection RMS: {:.4f} px (worst view {} {:.4f} px)\n", c.rms_px,
                     worst_view, worst_view_rms_px);
  out += fmt::format("intrinsics: fx {:.4f}  fy {:.4f}  cx {:.4f}  cy {:.4f} [px], image {}x{}\n",
                     c.fx, c.fy, c.cx, c.cy, c.image_width, c.image_height);
  out += fmt::format("distortion: k1 {:.6g}  k2 {:.6g}  p1 {:.6g}  p2 {:.6g}  k3 {:.6g}\n",
                     c.dist[0], c.dist[1], c.dist[2], c.dist[3], c.dist[4]);
  if (c.plane)
    out += fmt::format("scale: {:.6f} +- {:.6f} mm/px (plane view {})\n", c.plane->mm_per_px,
                       c.plane->mm_per_px_uncertainty, c.plane->image);
  else
    out += "scale: none (give --plane IMAGE, a view of the board lying on the panel)\n";
  return out + "written: " + output + "\n";
}

JsonObject CalibrationSummary::ToJson(const CameraCalibration& c, const std::string& output) const {
  JsonObject j;
  j.Add("rms_px", c.rms_px)
      .Add("fx", c.fx)
      .Add("fy", c.fy)
      .Add("cx", c.cx)
      .Add("cy", c.cy)
      .Add("dist", std::vector<double>(c.dist.begin(), c.dist.end()));
  if (c.plane) {
    j.Add("mm_per_px", c.plane->mm_per_px);
    j.Add("mm_per_px_uncertainty", c.plane->mm_per_px_uncertainty);
  } else {
    j.AddNull("mm_per_px");
    j.AddNull("mm_per_px_uncertainty");
  }
  std::vector<std::string> rejected;
  for (const RejectedView& r : c.rejected) rejected.push_back(r.image);
  j.Add("images_used", images_used)
      .Add("images_rejected", images_rejected)
      .Add("images_repeated", images_repeated)
      .Add("rejected_images", rejected)
      .Add("image_width", c.image_width)
      .Add("image_height", c.image_height)
      .Add("output", output);
  return j;
}

std::optional<std::vector<cv::Point2f>> DetectBoard(const cv::Mat& image, const BoardSpec& board,
                                                    const DetectionOptions& options) {
  board.Check();
  options.Check();
  CheckImage(image, "image");
  const cv::Mat grey8 = To8Bit(image);
  int flags = 0;
  if (options.adaptive_threshold) flags |= cv::CALIB_CB_ADAPTIVE_THRESH;
  if (options.normalize_image) flags |= cv::CALIB_CB_NORMALIZE_IMAGE;
  std::vector<cv::Point2f> corners;
  if (!cv::findChessboardCorners(grey8, board.PatternSize(), corners, flags)) return std::nullopt;
  // Refine on the full-depth image (float) so 16-bit data keeps its precision.
  cv::Mat grey_float;
  image.convertTo(grey_float, CV_32F);
  const int w = options.subpix_half_window;
  cv::cornerSubPix(grey_float, corners, cv::Size(w, w), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS,
                                    options.subpix_max_iterations, options.subpix_epsilon_px));
  return corners;
}

CameraCalibration CalibrateCamera(const std::vector<cv::Mat>& images,
                                  const std::vector<std::string>& names,
                                  const CalibrationOptions& options, CalibrationSummary* summary) {
  options.Check();
  if (images.empty())
    throw Error(ErrorKind::kInvalidValue, "calibration images", "none",
                fmt::format("at least {} views of the checkerboard", options.min_views));
  CheckValue(names.empty() || names.size() == images.size(), "calibration image names",
             std::to_string(names.size()), fmt::format("{} names (one per image)", images.size()));
  auto name_of = [&](std::size_t k) {
    return names.empty() ? fmt::format("image {}", k) : names[k];
  };
  for (std::size_t k = 0; k < images.size(); ++k) {
    CheckImage(images[k], name_of(k));
    if (images[k].size() != images[0].size())
      throw Error(ErrorKind::kInvalidValue,
                  fmt::format("mixed image sizes: {} is {} but {} is {}; all calibration images "
                              "must come from the same camera at the same resolution",
                              name_of(k), SizeText(images[k].size()), name_of(0),
                              SizeText(images[0].size())));
  }

  CalibrationSummary local;
  CalibrationSummary& s = summary ? *summary : local;
  s = CalibrationSummary{};
  s.images_total = static_cast<int>(images.size());

  CameraCalibration result;
  result.board = options.board;
  result.image_width = images[0].cols;
  result.image_height = images[0].rows;

  WallTimer timer;
  const DetectedViews views = DetectViews(images, name_of, options, &result);
  const std::vector<std::vector<cv::Point2f>>& image_points = views.corners;
  const std::vector<std::string>& used_names = views.names;
  s.detection_seconds = timer.ElapsedSeconds();
  s.images_used = static_cast<int>(image_points.size());
  s.images_rejected = static_cast<int>(result.rejected.size());
  s.images_repeated = views.repeated;
  if (image_points.empty())
    throw Error(ErrorKind::kInvalidValue,
                fmt::format("no board found in any of the {} calibration images: none shows a "
                            "checkerboard with {}x{} inner corners (COLSxROWS counts inner "
                            "corners: 9x6 for a board of 10x7 squares)",
                            images.size(), options.board.cols, options.board.rows));
  if (s.images_used < options.min_views)
    throw Error(ErrorKind::kInvalidValue, TooFewViewsText(views, images.size(), options));

  timer.Restart();
  const std::vector<std::vector<cv::Point3f>> object_points(image_points.size(),
                                                            options.board.ObjectPoints());
  cv::Mat camera_matrix, dist;
  std::vector<cv::Mat> rvecs, tvecs;
  int flags = 0;
  if (options.fix_k3) flags |= cv::CALIB_FIX_K3;
  if (options.zero_tangential) flags |= cv::CALIB_ZERO_TANGENT_DIST;
  const double rms = cv::calibrateCamera(
      object_points, image_points, images[0].size(), camera_matrix, dist, rvecs, tvecs, flags,
      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 200, 1e-15));
  s.calibration_seconds = timer.ElapsedSeconds();
  if (!std::isfinite(rms) || !cv::checkRange(camera_matrix) || !cv::checkRange(dist))
    throw Error(ErrorKind::kNumerical,
                "calibration failed: cv::calibrateCamera returned non-finite values (views too "
                "similar? vary the board's tilt and position)");
  result.fx = camera_matrix.at<double>(0, 0);
  result.fy = camera_matrix.at<double>(1, 1);
  result.cx = camera_matrix.at<double>(0, 2);
  result.cy = camera_matrix.at<double>(1, 2);
  for (int k = 0; k < 5; ++k) result.dist[k] = k < dist.cols * dist.rows ? dist.at<double>(k) : 0;

  // Per-view RMS; the overall RMS is over all corners of all views (what calibrateCamera returns).
  double total_sq = 0;
  std::size_t total_n = 0;
  s.worst_view_rms_px = 0;
  for (std::size_t v = 0; v < image_points.size(); ++v) {
    std::vector<cv::Point2f> projected;
    cv::projectPoints(object_points[v], rvecs[v], tvecs[v], camera_matrix, dist, projected);
    double sq = 0;
    for (std::size_t k = 0; k < projected.size(); ++k) {
      const cv::Point2f d = projected[k] - image_points[v][k];
      sq += d.dot(d);
    }
    total_sq += sq;
    total_n += projected.size();
    const double view_rms = std::sqrt(sq / projected.size());
    result.views.push_back({used_names[v], view_rms});
    if (view_rms > s.worst_view_rms_px) {
      s.worst_view_rms_px = view_rms;
      s.worst_view = used_names[v];
    }
  }
  result.rms_px = std::sqrt(total_sq / total_n);
  s.rms_px = result.rms_px;
  LogInfo("{}", s.BriefReport());
  if (!(result.rms_px <= options.max_rms_px))
    throw Error(
        ErrorKind::kNumerical,
        fmt::format("implausible calibration: reprojection RMS {:.3f} px exceeds the "
                    "limit {:.3f} px (calibration.max_rms_px); worst view {} "
                    "with {:.3f} px. Check the board size (inner corners, square size), blurred or "
                    "mis-detected views",
                    result.rms_px, options.max_rms_px, s.worst_view, s.worst_view_rms_px));
  return result;
}

PlaneScale MeasurePlaneScale(const cv::Mat& image, const std::string& name,
                             const CameraCalibration& calibration,
                             const DetectionOptions& options) {
  CheckImage(image, name);
  CheckFrameSize(calibration, image.size(), "plane image " + name);
  auto corners = DetectBoard(image, calibration.board, options);
  if (!corners)
    throw Error(ErrorKind::kInvalidValue,
                fmt::format("plane image {}: the {}x{} board (inner corners) was not found; the "
                            "plane scale needs one view of the board lying on the panel",
                            name, calibration.board.cols, calibration.board.rows));
  std::vector<cv::Point2d> distorted(corners->begin(), corners->end());
  const std::vector<cv::Point2d> px = calibration.UndistortPixels(distorted);
  std::vector<cv::Point2d> mm;
  for (const cv::Point3f& p : calibration.board.ObjectPoints()) mm.emplace_back(p.x, p.y);
  const cv::Mat h = cv::findHomography(px, mm, /*method=*/0);
  if (h.empty() || !cv::checkRange(h))
    throw Error(ErrorKind::kNumerical, "plane image " + name + ": homography fit failed");

  PlaneScale scale;
  scale.image = name;
  scale.mm_from_px = cv::Matx33d(h);
  scale.corners = static_cast<int>(px.size());
  const cv::Matx33d& H = scale.mm_from_px;
  // Local isotropic scale sqrt|det J| of the homography at an image point.
  auto local_scale = [&H](cv::Point2d p) {
    const cv::Vec3d q = H * cv::Vec3d(p.x, p.y, 1);
    const double w = q[2];
    const double j00 = (H(0, 0) * w - q[0] * H(2, 0)) / (w * w);
    const double j01 = (H(0, 1) * w - q[0] * H(2, 1)) / (w * w);
    const double j10 = (H(1, 0) * w - q[1] * H(2, 0)) / (w * w);
    const double j11 = (H(1, 1) * w - q[1] * H(2, 1)) / (w * w);
    return std::sqrt(std::abs(j00 * j11 - j01 * j10));
  };
  cv::Point2d centroid(0, 0);
  for (const auto& p : px) centroid += p;
  centroid *= 1.0 / px.size();
  scale.mm_per_px = local_scale(centroid);

  double mean = 0, sq = 0, res_sq = 0, spread_px_sq = 0;
  for (std::size_t k = 0; k < px.size(); ++k) {
    const double s = local_scale(px[k]);
    mean += s;
    sq += s * s;
    const cv::Point2d d = scale.ToMm(px[k]) - mm[k];
    res_sq += d.dot(d);
    spread_px_sq += (px[k] - centroid).dot(px[k] - centroid);
  }
  const double n = static_cast<double>(px.size());
  mean /= n;
  const double local_std = std::sqrt(std::max(0.0, sq / n - mean * mean));
  scale.local_scale_spread_rel = local_std / mean;
  scale.residual_rms_mm = std::sqrt(res_sq / n);
  // Statistical error of the scale of a similarity fit y = s R x + t: var(s) = sigma_y^2 /
  // sum |x - mean x|^2, sigma_y per coordinate from the residuals with 2n - 8 degrees of freedom
  // (8 homography parameters).
  const double sigma_coord_mm = std::sqrt(res_sq / std::max(1.0, 2 * n - 8));
  const double stat = sigma_coord_mm / std::sqrt(spread_px_sq);
  scale.mm_per_px_uncertainty = std::sqrt(stat * stat + local_std * local_std);
  LogInfo(
      "plane scale from {}: {:.6f} +- {:.6f} mm/px (local scale spread {:.3f} %, residual "
      "{:.4f} mm RMS over {} corners)",
      name, scale.mm_per_px, scale.mm_per_px_uncertainty, 100 * scale.local_scale_spread_rel,
      scale.residual_rms_mm, scale.corners);
  return scale;
}

CameraCalibration CalibrateFromFiles(const std::vector<std::string>& image_sources,
                                     const std::string& plane_path,
                                     const CalibrationOptions& options,
                                     CalibrationSummary* summary) {
  options.Check();
  if (image_sources.empty())
    throw Error(ErrorKind::kInvalidValue, "calibration images", "none",
                "checkerboard images (files, folders or globs)");
  std::vector<std::string> paths;
  for (const std::string& source : image_sources) {
    const auto listed = ListFrames(source);
    paths.insert(paths.end(), listed.begin(), listed.end());
  }
  std::vector<cv::Mat> images;
  images.reserve(paths.size());
  for (const std::string& path : paths) images.push_back(ReadGreyImage(path));
  CameraCalibration calibration = CalibrateCamera(images, paths, options, summary);
  if (!plane_path.empty())
    calibration.plane =
        MeasurePlaneScale(ReadGreyImage(plane_path), plane_path, calibration, options.detection);
  return calibration;
}

CameraCalibration CalibrateToFile(const std::vector<std::string>& image_sources,
                                  const std::string& plane_path, const CalibrationOptions& options,
                                  const std::string& output, CalibrationSummary* summary) {
  options.Check();
  CheckValue(
      !image_sources.empty(), "calibration images", "none",
      fmt::format("at least {} checkerboard images (files, folders or globs)", options.min_views));
  CheckValue(!output.empty(), "output", "an empty name", "the calibration YAML to write");
  if (!plane_path.empty()) CheckImageFileExists(plane_path);
  // The calibration is YAML; an image name (-o calcopy/view_00.png) would overwrite an input.
  std::vector<std::string> inputs = {plane_path};
  for (const std::string& source : image_sources) {
    const std::vector<std::string> listed = ListFrames(source);
    inputs.insert(inputs.end(), listed.begin(), listed.end());
  }
  CheckOutputLocation(output, {"output", {".yaml", ".yml"}, inputs, {kCalibrationFirstLine}});
  CameraCalibration calibration = CalibrateFromFiles(image_sources, plane_path, options, summary);
  SaveCalibration(calibration, output);
  return calibration;
}

void CheckFrameSize(const CameraCalibration& calibration, cv::Size frame_size,
                    const std::string& what) {
  if (frame_size == calibration.ImageSize()) return;
  throw Error(ErrorKind::kInvalidValue,
              fmt::format("{} has size {} but the calibration was made for {} images; frames and "
                          "calibration must come from the same camera at the same resolution",
                          what, SizeText(frame_size), SizeText(calibration.ImageSize())));
}

}  // namespace impactdic
