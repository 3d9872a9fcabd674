#include "scene_inputs.h"

#include <fmt/format.h>

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "impactdic/core/error.h"
#include "impactdic/io/image_io.h"

namespace impactdic {
namespace stages {

std::vector<cv::Point> PolygonPoints(const std::vector<std::array<double, 2>>& vertices) {
  std::vector<cv::Point> points;
  for (const auto& v : vertices)
    points.emplace_back(static_cast<int>(std::lround(v[0])), static_cast<int>(std::lround(v[1])));
  return points;
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

ImpactModelParameters MakeModelParameters(const Scene& scene, double impact_velocity_m_s) {
  ImpactModelParameters p;
  p.pounder_mass_kg = scene.test.mass_kg;
  p.impact_velocity_m_s = impact_velocity_m_s;
  p.width_m = scene.test.width_m;
  p.depth_m = scene.test.depth_m;
  p.added_mass_kg = scene.model.added_mass_kg ? *scene.model.added_mass_kg : std::nan("");
  p.friction_K = scene.model.K;
  p.damping_exponent_n = scene.model.n;
  p.damping_factor_u = scene.model.u;
  p.sigmoid_delay_T_s = scene.model.T_s;
  p.sigmoid_rate_b_per_s = scene.model.b_per_s;
  p.density_kg_m3 = scene.test.density_kg_m3;
  p.gravity_m_s2 = scene.test.g_m_s2;
  p.bed_height_m = scene.test.bed_height_m;
  p.Check();
  return p;
}

}  // namespace stages

DicOptions MakeDicOptions(const SceneDic& d) {
  DicOptions o;
  o.grid.subset_size = d.subset_size;
  o.grid.step = d.step;
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
  o.icgn.interpolation = InterpolationFromString(d.interpolation);
  o.icgn.shape = ShapeFunctionFromString(d.shape);
  o.icgn.min_zncc = d.min_zncc;
  o.icgn.max_iterations = d.max_iterations;
  o.icgn.convergence_px = d.convergence_px;
  if (d.max_uncertainty_px) o.icgn.max_uncertainty_px = *d.max_uncertainty_px;
  o.init.search_radius_px = d.search_radius_px;
  o.update.mode = ReferenceUpdateFromString(d.reference_update, &o.update.every_n);
  o.Check();
  return o;
}

}  // namespace impactdic
