// Calibration targets: their geometry and their detection (chessboard, ChArUco, circle grids).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <opencv2/aruco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <regex>
#include <string>
#include <utility>
#include <vector>

#include "calib_internal.h"
#include "impactdic/calib/calibration.h"
#include "impactdic/core/error.h"

namespace impactdic {
namespace {

// OpenCV's predefined dictionaries, in the order of cv::aruco::PREDEFINED_DICTIONARY_NAME.
constexpr const char* kDictionaries[] = {
    "DICT_4X4_50",         "DICT_4X4_100",       "DICT_4X4_250",       "DICT_4X4_1000",
    "DICT_5X5_50",         "DICT_5X5_100",       "DICT_5X5_250",       "DICT_5X5_1000",
    "DICT_6X6_50",         "DICT_6X6_100",       "DICT_6X6_250",       "DICT_6X6_1000",
    "DICT_7X7_50",         "DICT_7X7_100",       "DICT_7X7_250",       "DICT_7X7_1000",
    "DICT_ARUCO_ORIGINAL", "DICT_APRILTAG_16h5", "DICT_APRILTAG_25h9", "DICT_APRILTAG_36h10",
    "DICT_APRILTAG_36h11"};

int DictionaryIndex(const std::string& name) {
  for (std::size_t k = 0; k < std::size(kDictionaries); ++k)
    if (name == kDictionaries[k]) return static_cast<int>(k);
  return -1;
}

// COLSxROWS with both at least `minimum`; Error naming `where` otherwise.
cv::Size ParseSize(const std::string& text, const std::string& where, int minimum,
                   const std::string& expected) {
  static const std::regex pattern(R"(\s*(\d+)\s*[xX]\s*(\d+)\s*)");
  std::smatch match;
  if (!std::regex_match(text, match, pattern) || match[1].length() > 4 || match[2].length() > 4)
    throw Error(ErrorKind::kInvalidValue, where, "'" + text + "'", expected);
  const cv::Size size(std::stoi(match[1]), std::stoi(match[2]));
  CheckValue(size.width >= minimum && size.height >= minimum, where, "'" + text + "'",
             fmt::format("at least {}x{} ({})", minimum, minimum, expected));
  return size;
}

// ChArUco squares: (x, y), x in [0, cols], y in [0, rows] for a board of cols x rows inner
// corners; square (x, y) spans [(x - 1) s, x s] x [(y - 1) s, y s].
bool IsBlackSquare(const BoardSpec& board, CharucoLayout layout, int x, int y) {
  const int squares_y = board.rows + 1;
  return layout == CharucoLayout::kLegacy ? (x + (squares_y - 1 - y)) % 2 == 0 : (x + y) % 2 == 0;
}

// The square of every marker id under a layout (ids row by row over the white squares).
std::vector<cv::Point> MarkerSquares(const BoardSpec& board, CharucoLayout layout) {
  std::vector<cv::Point> squares;
  for (int y = 0; y <= board.rows; ++y)
    for (int x = 0; x <= board.cols; ++x)
      if (!IsBlackSquare(board, layout, x, y)) squares.emplace_back(x, y);
  return squares;
}

// The marker's corners on the board [mm], in detectMarkers' order (top-left, clockwise).
std::vector<cv::Point2f> MarkerCorners(const BoardSpec& board, cv::Point square) {
  const double s = board.square_mm, d = (s - board.marker_mm) / 2, m = board.marker_mm;
  const auto x0 = static_cast<float>((square.x - 1) * s + d);
  const auto y0 = static_cast<float>((square.y - 1) * s + d);
  const auto mf = static_cast<float>(m);
  return {{x0, y0}, {x0 + mf, y0}, {x0 + mf, y0 + mf}, {x0, y0 + mf}};
}

cv::Point2d Apply(const cv::Matx33d& h, cv::Point2d p) {
  const cv::Vec3d q = h * cv::Vec3d(p.x, p.y, 1);
  return {q[0] / q[2], q[1] / q[2]};
}

struct Markers {
  std::vector<std::vector<cv::Point2f>> corners;
  std::vector<int> ids;
};

// The chessboard corners of a layout with both neighbouring markers detected: for each, the
// corner's id and its position as each marker's homography (board mm -> image) predicts it.
struct CornerPredictions {
  std::vector<int> ids;
  std::vector<std::vector<cv::Point2d>> predicted;  // Per corner: one per neighbouring marker.
  std::vector<double> clear_px;  // Per corner: distance to the nearest marker edge [px].
  std::vector<double> side_px;   // Per corner: the markers' mean side [px].
};

CornerPredictions PredictCorners(const BoardSpec& board, CharucoLayout layout,
                                 const Markers& markers) {
  const std::vector<cv::Point> squares = MarkerSquares(board, layout);
  cv::Mat_<int> marker_at(board.rows + 1, board.cols + 1, -1);  // Index into markers.
  std::vector<cv::Matx33d> homography(markers.ids.size());
  for (std::size_t k = 0; k < markers.ids.size(); ++k) {
    if (markers.ids[k] < 0 || markers.ids[k] >= static_cast<int>(squares.size())) continue;
    const cv::Point sq = squares[markers.ids[k]];
    marker_at(sq.y, sq.x) = static_cast<int>(k);
    homography[k] =
        cv::Matx33d(cv::getPerspectiveTransform(MarkerCorners(board, sq), markers.corners[k]));
  }
  CornerPredictions out;
  const double d_mm = (board.square_mm - board.marker_mm) / 2;
  for (int j = 0; j < board.rows; ++j)
    for (int i = 0; i < board.cols; ++i) {
      // The two white squares of the four around corner (i, j) must both have their marker.
      std::vector<int> neighbours;
      for (const cv::Point sq :
           {cv::Point(i, j), cv::Point(i + 1, j), cv::Point(i, j + 1), cv::Point(i + 1, j + 1)})
        if (marker_at(sq.y, sq.x) >= 0) neighbours.push_back(marker_at(sq.y, sq.x));
      if (neighbours.size() < 2) continue;
      const cv::Point2d corner_mm(i * board.square_mm, j * board.square_mm);
      std::vector<cv::Point2d> predicted;
      double clear = std::numeric_limits<double>::infinity(), side = 0;
      for (const int k : neighbours) {
        const cv::Point2d p = Apply(homography[k], corner_mm);
        predicted.push_back(p);
        // The marker's corner nearest to the chessboard corner lies d_mm away along both axes.
        const cv::Point2d dx = Apply(homography[k], corner_mm + cv::Point2d(d_mm, 0)) - p;
        const cv::Point2d dy = Apply(homography[k], corner_mm + cv::Point2d(0, d_mm)) - p;
        clear = std::min({clear, cv::norm(dx), cv::norm(dy)});
        side += cv::norm(markers.corners[k][0] - markers.corners[k][2]) / std::sqrt(2.0) /
                static_cast<double>(neighbours.size());
      }
      out.ids.push_back(j * board.cols + i);
      out.predicted.push_back(std::move(predicted));
      out.clear_px.push_back(clear);
      out.side_px.push_back(side);
    }
  return out;
}

// How far apart the two markers' predictions of a corner are, in marker sides.
double Disagreement(const CornerPredictions& c, std::size_t k) {
  return cv::norm(c.predicted[k][0] - c.predicted[k][1]) / c.side_px[k];
}

// How well the markers agree with a layout: the median over the corners of Disagreement. Under
// the right layout ~0.01 (noise); under the wrong one the two "neighbours" of a corner are
// squares apart (> 1). Infinite without a corner.
double LayoutMismatch(const CornerPredictions& corners) {
  std::vector<double> errors;
  for (std::size_t k = 0; k < corners.ids.size(); ++k) errors.push_back(Disagreement(corners, k));
  if (errors.empty()) return std::numeric_limits<double>::infinity();
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  return errors[errors.size() / 2];
}

// A corner whose two markers disagree by more than this [marker sides] is dropped (a misread
// marker).
constexpr double kMaxDisagreement = 0.25;

BoardDetection DetectCharuco(const cv::Mat& image, const BoardSpec& board,
                             const DetectionOptions& options) {
  BoardDetection out;
  const cv::Mat grey8 = calib_detail::To8Bit(image);
  const cv::Ptr<cv::aruco::Dictionary> dictionary =
      cv::aruco::getPredefinedDictionary(DictionaryIndex(board.dictionary));
  Markers markers;
  cv::aruco::detectMarkers(grey8, dictionary, markers.corners, markers.ids);
  out.markers = static_cast<int>(markers.ids.size());
  if (markers.ids.empty()) {
    out.failure = fmt::format("no {} marker found", board.dictionary);
    return out;
  }
  out.layout = board.layout;
  CornerPredictions corners;
  if (out.layout == CharucoLayout::kAuto) {
    CornerPredictions current = PredictCorners(board, CharucoLayout::kCurrent, markers);
    CornerPredictions legacy = PredictCorners(board, CharucoLayout::kLegacy, markers);
    const bool is_legacy = LayoutMismatch(legacy) < LayoutMismatch(current);
    out.layout = is_legacy ? CharucoLayout::kLegacy : CharucoLayout::kCurrent;
    corners = std::move(is_legacy ? legacy : current);
  } else {
    corners = PredictCorners(board, out.layout, markers);
  }
  cv::Mat grey_float;
  image.convertTo(grey_float, CV_32F);
  for (std::size_t k = 0; k < corners.ids.size(); ++k) {
    if (Disagreement(corners, k) > kMaxDisagreement) continue;
    const cv::Point2d predicted = (corners.predicted[k][0] + corners.predicted[k][1]) * 0.5;
    // cornerSubPix's window stays inside the two black and two white squares, off the markers.
    const int w =
        std::clamp(static_cast<int>(0.8 * corners.clear_px[k]), 2, options.subpix_half_window);
    if (predicted.x < w + 1 || predicted.y < w + 1 || predicted.x > image.cols - w - 2 ||
        predicted.y > image.rows - w - 2)
      continue;
    std::vector<cv::Point2f> refined = {cv::Point2f(predicted)};
    cv::cornerSubPix(grey_float, refined, cv::Size(w, w), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS,
                                      options.subpix_max_iterations, options.subpix_epsilon_px));
    if (cv::norm(cv::Point2d(refined[0]) - predicted) > 0.5 * w) continue;  // Lost the corner.
    out.image_points.push_back(refined[0]);
    out.ids.push_back(corners.ids[k]);
  }
  if (out.image_points.empty())
    out.failure =
        fmt::format("{} markers found but no ChArUco corner between two of them", out.markers);
  return out;
}

// Whether detected grid points sit where a homography of the board puts them, to a tenth of the
// spacing (the grid finder can snap a corner point to a neighbour's blob or order a view wrongly;
// lens distortion bends a board's image by far less than that over one view).
bool ConsistentGrid(const BoardSpec& board, const std::vector<cv::Point2f>& image) {
  std::vector<cv::Point2f> object;
  for (const cv::Point3f& p : board.ObjectPoints()) object.emplace_back(p.x, p.y);
  const cv::Mat h = cv::findHomography(object, image, /*method=*/0);
  if (h.empty()) return false;
  const cv::Matx33d hm(h);
  double spacing_px = 0;
  for (int k = 0; k + 1 < board.cols; ++k) spacing_px += cv::norm(image[k + 1] - image[k]);
  spacing_px /= board.cols - 1;
  if (board.kind == BoardKind::kAsymmetricCircles) spacing_px /= 2;
  for (std::size_t k = 0; k < image.size(); ++k)
    if (cv::norm(Apply(hm, object[k]) - cv::Point2d(image[k])) > 0.1 * spacing_px) return false;
  return true;
}

// cv::findCirclesGrid, first with its default grid finder, then with CALIB_CB_CLUSTERING (more
// robust to perspective, which misleads the default finder on tilted views); a grid whose points
// are not where a homography of the board puts them (ConsistentGrid) counts as not found.
BoardDetection DetectCircles(const cv::Mat& image, const BoardSpec& board) {
  BoardDetection out;
  cv::SimpleBlobDetector::Params params;
  params.maxArea = 1e6f;  // Large circles on a big sensor (default 5000 px^2).
  const cv::Ptr<cv::FeatureDetector> blobs = cv::SimpleBlobDetector::create(params);
  const int grid = board.kind == BoardKind::kCircles ? cv::CALIB_CB_SYMMETRIC_GRID
                                                     : cv::CALIB_CB_ASYMMETRIC_GRID;
  const cv::Mat grey8 = calib_detail::To8Bit(image);
  for (const int flags : {grid, grid | cv::CALIB_CB_CLUSTERING}) {
    std::vector<cv::Point2f> centres;
    if (!cv::findCirclesGrid(grey8, board.PatternSize(), centres, flags, blobs) ||
        !ConsistentGrid(board, centres))
      continue;
    out.image_points = std::move(centres);
    for (int k = 0; k < board.cols * board.rows; ++k) out.ids.push_back(k);
    return out;
  }
  out.failure = fmt::format("the {} was not found", board.Describe());
  return out;
}

}  // namespace

namespace calib_detail {

cv::Mat To8Bit(const cv::Mat& image) {
  if (image.depth() == CV_8U) return image;
  cv::Mat out;
  cv::normalize(image, out, 0, 255, cv::NORM_MINMAX, CV_8U);
  return out;
}

void CheckImage(const cv::Mat& image, const std::string& name) {
  if (image.empty())
    throw Error(ErrorKind::kInvalidValue, name, "an empty image", "an 8/16-bit greyscale image");
  if (image.channels() != 1 || (image.depth() != CV_8U && image.depth() != CV_16U))
    throw Error(ErrorKind::kInvalidValue, name,
                fmt::format("{} channel(s), depth code {}", image.channels(), image.depth()),
                "an 8/16-bit single-channel (greyscale) image");
}

}  // namespace calib_detail

std::vector<std::string> ArucoDictionaryNames() {
  return {std::begin(kDictionaries), std::end(kDictionaries)};
}

void BoardSpec::Check() const {
  CheckValue(cols >= 2, "board.cols", std::to_string(cols), ">= 2 inner corners");
  CheckValue(rows >= 2, "board.rows", std::to_string(rows), ">= 2 inner corners");
  CheckRange(square_mm, kSquareRange, "board.square_mm", "a square size");
  if (kind != BoardKind::kCharuco) return;
  CheckValue(marker_mm > 0 && marker_mm < square_mm, "board.marker_mm",
             fmt::format("{}", marker_mm),
             fmt::format("a marker side in (0, {}) mm (smaller than the square)", square_mm));
  CheckValue(DictionaryIndex(dictionary) >= 0, "board.dictionary", "'" + dictionary + "'",
             "one of " + Join(ArucoDictionaryNames()));
  const int markers = static_cast<int>(MarkerSquares(*this, CharucoLayout::kCurrent).size());
  const int available =
      cv::aruco::getPredefinedDictionary(DictionaryIndex(dictionary))->bytesList.rows;
  CheckValue(markers <= available, "board.dictionary", dictionary,
             fmt::format("a dictionary with at least {} markers (the board has {} white squares; "
                         "{} has {})",
                         markers, markers, dictionary, available));
}

std::vector<cv::Point3f> BoardSpec::ObjectPoints() const {
  std::vector<cv::Point3f> points;
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < cols; ++i) {
      const int x = kind == BoardKind::kAsymmetricCircles ? 2 * i + j % 2 : i;
      points.emplace_back(static_cast<float>(x * square_mm), static_cast<float>(j * square_mm),
                          0.f);
    }
  return points;
}

std::string BoardSpec::Describe() const {
  switch (kind) {
    case BoardKind::kCharuco:
      return fmt::format("ChArUco board of {}x{} squares ({} mm, {} mm {} markers)", cols + 1,
                         rows + 1, square_mm, marker_mm, dictionary);
    case BoardKind::kCircles: return fmt::format("{}x{} circle grid", cols, rows);
    case BoardKind::kAsymmetricCircles:
      return fmt::format("{}x{} asymmetric circle grid", cols, rows);
    case BoardKind::kChessboard: break;
  }
  return fmt::format("{}x{} board (inner corners)", cols, rows);
}

std::vector<cv::Point3f> BoardDetection::ObjectPoints(const BoardSpec& board) const {
  const std::vector<cv::Point3f> all = board.ObjectPoints();
  std::vector<cv::Point3f> points;
  points.reserve(ids.size());
  for (const int id : ids) points.push_back(all[id]);
  return points;
}

BoardSpec ParseBoard(const std::string& text, double square_mm, const std::string& where) {
  const cv::Size size = ParseSize(
      text, where, 2, "COLSxROWS counting INNER corners, e.g. 9x6 for a board of 10x7 squares");
  BoardSpec board;
  board.cols = size.width;
  board.rows = size.height;
  board.square_mm = square_mm;
  CheckRange(square_mm, BoardSpec::kSquareRange, "board.square_mm", "a square size");
  return board;
}

BoardSpec ParseCharucoBoard(const std::string& text, double square_mm, double marker_mm,
                            const std::string& dictionary, const std::string& where) {
  const cv::Size size = ParseSize(
      text, where, 3, "COLSxROWS counting SQUARES, e.g. 11x8 for a board of 10x7 inner corners");
  BoardSpec board;
  board.kind = BoardKind::kCharuco;
  board.cols = size.width - 1;
  board.rows = size.height - 1;
  board.square_mm = square_mm;
  board.marker_mm = marker_mm;
  board.dictionary = dictionary;
  board.Check();
  return board;
}

BoardSpec ParseCircleGrid(const std::string& text, double spacing_mm, bool asymmetric,
                          const std::string& where) {
  const cv::Size size = ParseSize(text, where, 2,
                                  asymmetric ? "COLSxROWS: circles per row x rows, e.g. 4x11"
                                             : "COLSxROWS counting circles, e.g. 7x5");
  BoardSpec board;
  board.kind = asymmetric ? BoardKind::kAsymmetricCircles : BoardKind::kCircles;
  board.cols = size.width;
  board.rows = size.height;
  board.square_mm = spacing_mm;
  board.Check();
  return board;
}

BoardDetection DetectBoardPoints(const cv::Mat& image, const BoardSpec& board,
                                 const DetectionOptions& options) {
  board.Check();
  options.Check();
  calib_detail::CheckImage(image, "image");
  switch (board.kind) {
    case BoardKind::kCharuco: return DetectCharuco(image, board, options);
    case BoardKind::kCircles:
    case BoardKind::kAsymmetricCircles: return DetectCircles(image, board);
    case BoardKind::kChessboard: break;
  }
  BoardDetection out;
  const cv::Mat grey8 = calib_detail::To8Bit(image);
  int flags = 0;
  if (options.adaptive_threshold) flags |= cv::CALIB_CB_ADAPTIVE_THRESH;
  if (options.normalize_image) flags |= cv::CALIB_CB_NORMALIZE_IMAGE;
  std::vector<cv::Point2f> corners;
  if (!cv::findChessboardCorners(grey8, board.PatternSize(), corners, flags)) {
    out.failure = fmt::format("the {} was not found", board.Describe());
    return out;
  }
  // Refine on the full-depth image (float) so 16-bit data keeps its precision.
  cv::Mat grey_float;
  image.convertTo(grey_float, CV_32F);
  const int w = options.subpix_half_window;
  cv::cornerSubPix(grey_float, corners, cv::Size(w, w), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS,
                                    options.subpix_max_iterations, options.subpix_epsilon_px));
  out.image_points = std::move(corners);
  for (int k = 0; k < board.cols * board.rows; ++k) out.ids.push_back(k);
  return out;
}

std::optional<std::vector<cv::Point2f>> DetectBoard(const cv::Mat& image, const BoardSpec& board,
                                                    const DetectionOptions& options) {
  BoardDetection detection = DetectBoardPoints(image, board, options);
  if (detection.image_points.empty()) return std::nullopt;
  return std::move(detection.image_points);
}

}  // namespace impactdic
