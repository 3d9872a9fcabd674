#include "impactdic/calib/calibration.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <regex>
#include <utility>

#include "calib_internal.h"
#include "impactdic/core/error.h"
#include "impactdic/core/log.h"
#include "impactdic/core/timer.h"
#include "impactdic/io/atomic_file.h"
#include "impactdic/io/image_io.h"

namespace impactdic {
namespace {

// "k1 ...  k2 ..." for the calibration's model.
std::string DistortionText(const CameraCalibration& c) {
  if (c.model == LensModel::kFisheye)
    return fmt::format("fisheye k1 {:.6g}  k2 {:.6g}  k3 {:.6g}  k4 {:.6g}", c.dist_fisheye[0],
                       c.dist_fisheye[1], c.dist_fisheye[2], c.dist_fisheye[3]);
  std::string text = fmt::format("k1 {:.6g}  k2 {:.6g}  p1 {:.6g}  p2 {:.6g}  k3 {:.6g}", c.dist[0],
                                 c.dist[1], c.dist[2], c.dist[3], c.dist[4]);
  if (c.model == LensModel::kRational)
    text += fmt::format("  k4 {:.6g}  k5 {:.6g}  k6 {:.6g}", c.dist_rational[0], c.dist_rational[1],
                        c.dist_rational[2]);
  return text;
}

std::string SizeText(cv::Size size) { return fmt::format("{}x{}", size.width, size.height); }

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
// Partial views (ChArUco) compare only when they show the same corners.
double MaxCornerDifference(const BoardDetection& da, const BoardDetection& db) {
  const std::vector<cv::Point2f>& a = da.image_points;
  const std::vector<cv::Point2f>& b = db.image_points;
  if (da.ids != db.ids) return std::numeric_limits<double>::infinity();
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
  std::vector<BoardDetection> corners;
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
    BoardDetection corners = DetectBoardPoints(images[k], options.board, options.detection);
    if (corners.image_points.empty()) {
      reject(k, corners.failure);
      continue;
    }
    if (options.board.IsPartialViewBoard() &&
        static_cast<int>(corners.ids.size()) < options.min_corners) {
      reject(k, fmt::format("only {} ChArUco corners found ({} markers); a view needs at least {} "
                            "(calibration.min_corners)",
                            corners.ids.size(), corners.markers, options.min_corners));
      continue;
    }
    std::size_t view = 0;
    double difference = kNaN;
    for (; view < views.corners.size(); ++view) {
      difference = MaxCornerDifference(corners, views.corners[view]);
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
    views.corners.push_back(std::move(corners));
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

// The model with the lowest held-out RMS over up to 4 folds of the views (each view predicted by
// the lens fitted to the other folds), Brown-Conrady unless another beats it by more than
// CalibrationOptions::kModelMargin; Brown-Conrady alone when a fold would leave fewer than 3
// views to fit. Every candidate is returned, with its error or why it failed.
std::vector<ModelCandidate> ChooseLensModel(const calib_detail::ViewPoints& points,
                                            cv::Size image_size, const CalibrationOptions& options,
                                            LensModel* model) {
  *model = LensModel::kBrown;
  const int views = static_cast<int>(points.object.size());
  const int folds = std::min(4, views);
  if (views - (views + folds - 1) / folds < 3) return {};
  std::vector<ModelCandidate> candidates;
  for (LensModel m : {LensModel::kBrown, LensModel::kRational, LensModel::kFisheye}) {
    WallTimer timer;
    candidates.push_back(calib_detail::HeldOutError(points, image_size, m, options, folds));
    LogInfo("calibration: {} model held out in {:.2f} s", kLensModelNames.Name(m),
            timer.ElapsedSeconds());
  }
  const ModelCandidate& brown = candidates[0];
  double best = brown.failure.empty()
                    ? brown.heldout_rms_px * (1 - CalibrationOptions::kModelMargin)
                    : std::numeric_limits<double>::infinity();
  for (const ModelCandidate& c : candidates) {
    if (c.failure.empty() && c.heldout_rms_px < best) {
      best = c.heldout_rms_px;
      *model = c.model;
    }
    LogInfo("calibration: {} model: held-out RMS {:.4f} px, fit {:.4f} px{}",
            kLensModelNames.Name(c.model), c.heldout_rms_px, c.fit_rms_px,
            c.failure.empty() ? "" : " (failed: " + c.failure + ")");
  }
  LogInfo("calibration: model {} chosen by the held-out RMS over {} folds",
          kLensModelNames.Name(*model), folds);
  return candidates;
}

}  // namespace

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
  CheckRange(min_corners, kMinCornersRange, "calibration.min_corners", "a corner count");
  window.Check();
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
  t.AddChoice(
      "model", kLensModelNames.Names(), kLensModelNames.Name(o->model),
      [o](const std::string& name) { o->model = kLensModelNames.Parse(name, "calibration.model"); },
      "Distortion model: brown (k1 k2 p1 p2 k3), rational (k1-k6), fisheye, or auto (lowest "
      "held-out reprojection RMS)");
  t.Add("min_corners", &o->min_corners, CalibrationOptions::kMinCornersRange, "corner count",
        "ChArUco: a view with fewer detected corners is rejected");
  t.AddChoice(
      "charuco_layout", kCharucoLayoutNames.Names(), kCharucoLayoutNames.Name(o->board.layout),
      [o](const std::string& name) {
        o->board.layout = kCharucoLayoutNames.Parse(name, "calibration.charuco_layout");
      },
      "ChArUco marker layout: current (top-left square black), legacy (OpenCV <= 4.6, even "
      "rows), auto (the layout the markers agree with)");
  WindowOptions& w = o->window;
  YamlOptionTable window("calibration.window");
  window.Add("thickness_mm", &w.thickness_mm, WindowOptions::kThicknessRange, "a panel thickness",
             "Viewing window (panel) thickness; 0 = no window");
  window.Add("refractive_index", &w.refractive_index, WindowOptions::kIndexRange,
             "a refractive index", "The panel's refractive index (PMMA 1.49, glass 1.52)");
  window.AddChoice(
      "board_position", kBoardPositionNames.Names(), kBoardPositionNames.Name(w.board_position),
      [o](const std::string& name) {
        o->window.board_position =
            kBoardPositionNames.Parse(name, "calibration.window.board_position");
      },
      "Where the plane view's board lies: outer_face (scale carried to the soil plane through "
      "the panel) or soil (already at the soil plane)");
  return {t, detection, window};
}

std::string ResidualMap::Text() const {
  std::string out;
  for (int r = 0; r < rows; ++r) {
    out += " ";
    for (int c = 0; c < cols; ++c) {
      const double v = rms_px[static_cast<std::size_t>(r) * cols + c];
      out += std::isfinite(v) ? fmt::format(" {:7.4f}", v) : std::string("       -");
    }
    out += "\n";
  }
  return out;
}

cv::Point2d PlaneScale::ToMm(cv::Point2d px) const {
  const cv::Vec3d p = mm_from_px * cv::Vec3d(px.x, px.y, 1);
  return {p[0] / p[2], p[1] / p[2]};
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
  out += "  " + DistortionText(c) + "\n";
  for (const ViewRecord& v : c.views)
    out += fmt::format("  view {}: {} points, RMS {:.4f} px\n", v.image, v.corners, v.rms_px);
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
  out += "distortion: " + DistortionText(c) + "\n";
  out += fmt::format("model: {}{}\n", kLensModelNames.Name(c.model),
                     c.candidates.empty() ? " (given)" : " (lowest held-out RMS)");
  for (const ModelCandidate& m : c.candidates)
    out += m.failure.empty()
               ? fmt::format("  {:<8} held-out RMS {:.4f} px, fit {:.4f} px\n",
                             kLensModelNames.Name(m.model), m.heldout_rms_px, m.fit_rms_px)
               : fmt::format("  {:<8} failed: {}\n", kLensModelNames.Name(m.model), m.failure);
  out +=
      fmt::format("board: {}{}\n", c.board.Describe(),
                  c.board.kind == BoardKind::kCharuco
                      ? fmt::format(", {} marker layout", kCharucoLayoutNames.Name(c.board.layout))
                      : std::string());
  for (const ViewRecord& v : c.views)
    out += fmt::format("  view {}: {} points, RMS {:.4f} px\n", v.image, v.corners, v.rms_px);
  out += fmt::format("residual RMS [px] over the image ({}x{} cells, top row first):\n",
                     c.residual_map.cols, c.residual_map.rows) +
         c.residual_map.Text();
  if (c.plane && c.plane->window.Active())
    out += fmt::format(
        "window: {} mm, n = {}, board on the {}: {}\n", c.plane->window.thickness_mm,
        c.plane->window.refractive_index, kBoardPositionNames.Name(c.plane->window.board_position),
        c.plane->window.board_position == BoardPosition::kOuterFace
            ? fmt::format("soil-plane scale {:+.3f} % from the board's {:.6f} mm/px (homography "
                          "residual of the traced map {:.4f} mm)",
                          100 * (c.plane->mm_per_px / c.plane->board_mm_per_px - 1),
                          c.plane->board_mm_per_px, c.plane->window_nonlinearity_mm)
            : std::string("the scale is the soil plane's as measured"));
  if (c.plane)
    out += fmt::format("scale: {:.6f} +- {:.6f} mm/px (plane view {})\n", c.plane->mm_per_px,
                       c.plane->mm_per_px_uncertainty, c.plane->image);
  else
    out += "scale: none (give --plane IMAGE, a view of the board lying on the panel)\n";
  return out + "written: " + output + "\n";
}

JsonObject CalibrationSummary::ToJson(const CameraCalibration& c, const std::string& output) const {
  const cv::Mat coefficients = c.DistCoeffs();
  JsonObject j;
  j.Add("rms_px", c.rms_px)
      .Add("fx", c.fx)
      .Add("fy", c.fy)
      .Add("cx", c.cx)
      .Add("cy", c.cy)
      .Add("dist", std::vector<double>(c.dist.begin(), c.dist.end()))
      .Add("model", kLensModelNames.Name(c.model))
      .Add("model_coefficients",
           std::vector<double>(coefficients.begin<double>(), coefficients.end<double>()))
      .Add("board", c.board.Describe());
  if (c.board.kind == BoardKind::kCharuco)
    j.Add("charuco_layout", kCharucoLayoutNames.Name(c.board.layout));
  JsonObject candidates;
  for (const ModelCandidate& m : c.candidates) {
    JsonObject one;
    if (m.failure.empty())
      one.Add("heldout_rms_px", m.heldout_rms_px).Add("fit_rms_px", m.fit_rms_px);
    else
      one.Add("failure", m.failure);
    candidates.Add(kLensModelNames.Name(m.model), one);
  }
  j.Add("model_candidates", candidates);
  JsonObject views;
  for (const ViewRecord& v : c.views) {
    JsonObject one;
    one.Add("corners", v.corners).Add("rms_px", v.rms_px);
    views.Add(v.image, one);
  }
  j.Add("views", views);
  j.Add("residual_map_px", c.residual_map.rms_px)
      .Add("residual_map_cols", c.residual_map.cols)
      .Add("residual_map_rows", c.residual_map.rows);
  if (c.plane) {
    j.Add("mm_per_px", c.plane->mm_per_px);
    j.Add("mm_per_px_uncertainty", c.plane->mm_per_px_uncertainty);
    if (c.plane->window.Active()) {
      JsonObject w;
      w.Add("thickness_mm", c.plane->window.thickness_mm)
          .Add("refractive_index", c.plane->window.refractive_index)
          .Add("board_position", kBoardPositionNames.Name(c.plane->window.board_position))
          .Add("board_mm_per_px", c.plane->board_mm_per_px)
          .Add("nonlinearity_mm", c.plane->window_nonlinearity_mm);
      j.Add("window", w);
    }
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
    calib_detail::CheckImage(images[k], name_of(k));
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
  const std::vector<std::string>& used_names = views.names;
  s.detection_seconds = timer.ElapsedSeconds();
  s.images_used = static_cast<int>(views.corners.size());
  s.images_rejected = static_cast<int>(result.rejected.size());
  s.images_repeated = views.repeated;
  if (views.corners.empty() && options.board.kind == BoardKind::kChessboard)
    throw Error(ErrorKind::kInvalidValue,
                fmt::format("no board found in any of the {} calibration images: none shows a "
                            "checkerboard with {}x{} inner corners (COLSxROWS counts inner "
                            "corners: 9x6 for a board of 10x7 squares)",
                            images.size(), options.board.cols, options.board.rows));
  if (views.corners.empty())
    throw Error(ErrorKind::kInvalidValue,
                fmt::format("no board found in any of the {} calibration images: none shows the "
                            "{} (first image: {})",
                            images.size(), options.board.Describe(),
                            result.rejected.empty() ? "" : result.rejected[0].reason));
  if (s.images_used < options.min_views)
    throw Error(ErrorKind::kInvalidValue, TooFewViewsText(views, images.size(), options));

  timer.Restart();
  calib_detail::ViewPoints points;
  for (const BoardDetection& view : views.corners) {
    points.object.push_back(view.ObjectPoints(options.board));
    points.image.push_back(view.image_points);
  }
  if (options.board.kind == BoardKind::kCharuco) result.board.layout = views.corners[0].layout;
  LensModel model = options.model;
  if (model == LensModel::kAuto) {
    result.candidates = ChooseLensModel(points, images[0].size(), options, &model);
  }
  const calib_detail::LensFit fit = calib_detail::FitLens(points, images[0].size(), model, options);
  s.calibration_seconds = timer.ElapsedSeconds();
  result.model = model;
  result.fx = fit.camera.fx;
  result.fy = fit.camera.fy;
  result.cx = fit.camera.cx;
  result.cy = fit.camera.cy;
  result.dist = fit.camera.dist;
  result.dist_rational = fit.camera.dist_rational;
  result.dist_fisheye = fit.camera.dist_fisheye;

  // Per-view RMS; the overall RMS is over all corners of all views (what calibrateCamera returns).
  double total_sq = 0;
  std::size_t total_n = 0;
  s.worst_view_rms_px = 0;
  ResidualMap& map = result.residual_map;
  std::vector<double> cell_sq(static_cast<std::size_t>(map.cols * map.rows), 0.0);
  map.points.assign(cell_sq.size(), 0);
  for (std::size_t v = 0; v < points.image.size(); ++v) {
    const std::vector<cv::Point2f> projected =
        result.Project(points.object[v], fit.rvecs[v], fit.tvecs[v]);
    double sq = 0;
    for (std::size_t k = 0; k < projected.size(); ++k) {
      const cv::Point2f observed = points.image[v][k];
      const cv::Point2f d = projected[k] - observed;
      sq += d.dot(d);
      const int cx =
          std::clamp(static_cast<int>(observed.x * map.cols / result.image_width), 0, map.cols - 1);
      const int cy = std::clamp(static_cast<int>(observed.y * map.rows / result.image_height), 0,
                                map.rows - 1);
      cell_sq[cy * map.cols + cx] += d.dot(d);
      ++map.points[cy * map.cols + cx];
    }
    total_sq += sq;
    total_n += projected.size();
    const double view_rms = std::sqrt(sq / projected.size());
    result.views.push_back({used_names[v], view_rms, static_cast<int>(projected.size())});
    if (view_rms > s.worst_view_rms_px) {
      s.worst_view_rms_px = view_rms;
      s.worst_view = used_names[v];
    }
  }
  for (std::size_t c = 0; c < cell_sq.size(); ++c)
    map.rms_px.push_back(map.points[c] > 0 ? std::sqrt(cell_sq[c] / map.points[c]) : kNaN);
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

namespace calib_detail {

double LocalScale(const cv::Matx33d& h, cv::Point2d p) {
  const cv::Vec3d q = h * cv::Vec3d(p.x, p.y, 1);
  const double w = q[2];
  const double j00 = (h(0, 0) * w - q[0] * h(2, 0)) / (w * w);
  const double j01 = (h(0, 1) * w - q[0] * h(2, 1)) / (w * w);
  const double j10 = (h(1, 0) * w - q[1] * h(2, 0)) / (w * w);
  const double j11 = (h(1, 1) * w - q[1] * h(2, 1)) / (w * w);
  return std::sqrt(std::abs(j00 * j11 - j01 * j10));
}

}  // namespace calib_detail

PlaneScale MeasurePlaneScale(const cv::Mat& image, const std::string& name,
                             const CameraCalibration& calibration, const DetectionOptions& options,
                             const WindowOptions& window) {
  calib_detail::CheckImage(image, name);
  CheckFrameSize(calibration, image.size(), "plane image " + name);
  const BoardDetection corners = DetectBoardPoints(image, calibration.board, options);
  if (corners.image_points.size() < 4)
    throw Error(ErrorKind::kInvalidValue,
                fmt::format("plane image {}: the {} was not found ({}); the plane scale needs "
                            "one view of the board lying on the panel",
                            name, calibration.board.Describe(),
                            corners.failure.empty() ? fmt::format("{} corners", corners.ids.size())
                                                    : corners.failure));
  std::vector<cv::Point2d> distorted(corners.image_points.begin(), corners.image_points.end());
  const std::vector<cv::Point2d> px = calibration.UndistortPixels(distorted);
  const std::vector<cv::Point3f> object = corners.ObjectPoints(calibration.board);
  std::vector<cv::Point2d> mm;
  mm.reserve(object.size());
  for (const cv::Point3f& p : object) mm.emplace_back(p.x, p.y);
  const cv::Mat h = cv::findHomography(px, mm, /*method=*/0);
  if (h.empty() || !cv::checkRange(h))
    throw Error(ErrorKind::kNumerical, "plane image " + name + ": homography fit failed");

  PlaneScale scale;
  scale.image = name;
  scale.mm_from_px = cv::Matx33d(h);
  scale.corners = static_cast<int>(px.size());
  const auto local_scale = [&scale](cv::Point2d p) {
    return calib_detail::LocalScale(scale.mm_from_px, p);
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
  if (window.Active() && window.board_position == BoardPosition::kOuterFace)
    calib_detail::CarryToSoil(calibration, object, px, centroid, window, &scale);
  else
    scale.window = window;
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
    calibration.plane = MeasurePlaneScale(ReadGreyImage(plane_path), plane_path, calibration,
                                          options.detection, options.window);
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
