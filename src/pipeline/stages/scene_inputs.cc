#include "scene_inputs.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <string>

#include "impactdic/core/error.h"
#include "impactdic/dic/options.h"
#include "impactdic/io/image_io.h"
#include "impactdic/pipeline/pipeline.h"
#include "impactdic/pipeline/scene.h"
#include "impactdic/preprocess/preprocess.h"

namespace impactdic {
namespace stages {

std::vector<cv::Point> PolygonPoints(const std::vector<std::array<double, 2>>& vertices) {
  std::vector<cv::Point> points;
  points.reserve(vertices.size());
  for (const auto& v : vertices)
    points.emplace_back(static_cast<int>(std::lround(v[0])), static_cast<int>(std::lround(v[1])));
  return points;
}

double RequireScale(const Scene& scene, double mm_per_px) {
  if (!(mm_per_px > 0)) {
    throw Error(ErrorKind::kInvalidValue, "inputs.mm_per_px", "no scale",
                "inputs.mm_per_px > 0 or a calibration with a plane scale")
        .WithFile(scene.path);
  }
  return mm_per_px;
}

std::string ExcludeUncertainSamplesOfScene(const Scene& scene, CorrelationSeries* series) {
  if (scene.momentum.max_sigma_px) {
    return ExcludeUncertainSamplesWithWarning(*scene.momentum.max_sigma_px, "momentum.max_sigma_px",
                                              series);
  }
  if (!std::isfinite(scene.momentum.max_sigma_ratio) || series->sigma_u_px.empty()) return "";
  return ExcludeSamplesAboveMedianSigmaWithWarning(scene.momentum.max_sigma_ratio,
                                                   "momentum.max_sigma_ratio", series);
}

cv::Mat SceneMask(const Scene& scene, cv::Size frame_size) {
  const SceneDic& d = scene.dic;
  cv::Mat mask;
  if (!d.mask.empty()) {
    const cv::Mat image = ReadGreyImage(d.mask);
    if (image.size() != frame_size) {
      throw Error(ErrorKind::kInvalidValue, "dic.mask",
                  fmt::format("a {}x{} image", image.cols, image.rows),
                  fmt::format("a mask of the frames' size {}x{} (non-zero = correlate)",
                              frame_size.width, frame_size.height))
          .WithFile(d.mask);
    }
    mask = image != 0;
  }
  if (!d.roi_polygon.empty()) {
    cv::Mat inside = cv::Mat::zeros(frame_size, CV_8U);
    cv::fillPoly(inside, std::vector<std::vector<cv::Point>>{PolygonPoints(d.roi_polygon)},
                 cv::Scalar(255));
    if (cv::countNonZero(inside) == 0) {
      throw Error(
          ErrorKind::kInvalidValue, "dic.roi_polygon", "a polygon outside the frames",
          fmt::format("vertices inside the {}x{} frames", frame_size.width, frame_size.height))
          .WithFile(scene.path);
    }
    mask = mask.empty() ? inside : (mask & inside);
  }
  return mask;
}

}  // namespace stages

DicOptions MakeDicOptions(const SceneDic& d) {
  DicOptions o = d.options;
  // Pairs never update the reference: a policy other than the default or fixed is a mistake.
  if (o.mode == SequenceMode::kPairs && o.update.policy != "fixed" &&
      o.update.policy != UpdateOptions{}.policy) {
    throw Error(ErrorKind::kInvalidValue, "dic.reference_update",
                o.update.policy + " with dic.mode pairs",
                "no dic.reference_update (or fixed): pairs never update the reference");
  }
  if (d.roi[2] > d.roi[0] && d.roi[3] > d.roi[1]) {
    o.grid.roi = cv::Rect(d.roi[0], d.roi[1], d.roi[2] - d.roi[0], d.roi[3] - d.roi[1]);
  }
  if (!d.roi_polygon.empty()) {
    // The grid covers the polygon's bounding box (within `roi`); SceneMask leaves out the
    // subsets whose centre is outside the polygon.
    const cv::Rect box = cv::boundingRect(stages::PolygonPoints(d.roi_polygon));
    if (o.grid.roi.area() > 0 && (o.grid.roi & box).area() == 0) {
      throw Error(ErrorKind::kInvalidValue, "dic.roi_polygon", "a polygon outside dic.roi",
                  "a polygon that overlaps dic.roi (or no dic.roi)");
    }
    o.grid.roi = o.grid.roi.area() > 0 ? (o.grid.roi & box) : box;
  }
  o.Check();
  return o;
}

PreprocessOptions MakePreprocessOptions(const Scene& scene) {
  PreprocessOptions o = scene.preprocess;
  const DicOptions dic = MakeDicOptions(scene.dic);
  o.undistortion.roi = dic.grid.roi;
  o.subset_size = dic.grid.subset_size;  // The auto pre-filter weighs its random error.
  o.roi = o.undistortion.roi;            // Where the automatic pre-filter measures the first frame.
  return o;
}

}  // namespace impactdic
