// Refraction through a plane-parallel viewing window: the soil plane's scale from a board lying
// on the panel's outer face (docs/calibration.md, "The viewing window").
//
// Paraxially, a point t behind the outer face of a panel of index n appears t / n behind it, so
// from a camera at distance D the soil's scale is (D + t / n) / D times the board's: +1.33 % for
// t = 20 mm, n = 1.5, D = 1 m. Off the axis the ray is traced exactly (Snell's law at the outer
// face); the soil-plane map is then not exactly a homography (the apparent shift grows with the
// ray's angle), and what one homography leaves over is reported (window_nonlinearity_mm).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <vector>

#include "calib_internal.h"
#include "impactdic/calib/calibration.h"
#include "impactdic/core/error.h"
#include "impactdic/core/log.h"

namespace impactdic {

void WindowOptions::Check() const {
  CheckRange(thickness_mm, kThicknessRange, "calibration.window.thickness_mm",
             "a panel thickness (0 = no window)");
  CheckRange(refractive_index, kIndexRange, "calibration.window.refractive_index",
             "a refractive index");
}

bool TraceToSoil(const CameraCalibration& calibration, const cv::Vec3d& rvec, const cv::Vec3d& tvec,
                 const WindowOptions& window, cv::Point2d undistorted_px, cv::Point2d* soil_mm) {
  cv::Matx33d r;
  cv::Rodrigues(rvec, r);
  // Camera centre and ray direction in board coordinates (the outer face is Z = 0).
  const cv::Vec3d centre = -(r.t() * tvec);
  const cv::Vec3d ray = r.t() * cv::Vec3d((undistorted_px.x - calibration.cx) / calibration.fx,
                                          (undistorted_px.y - calibration.cy) / calibration.fy, 1);
  const double side = centre[2] < 0 ? -1 : 1;  // The camera's side of the face.
  if (!(ray[2] * side < 0)) return false;      // The ray points away from the panel.
  const cv::Vec3d on_face = centre + ray * (-centre[2] / ray[2]);
  // Snell's law in vector form: i the unit incident direction, m the face normal towards the
  // camera, eta = n_air / n: t = eta i + (eta cos_i - cos_t) m.
  const cv::Vec3d i = cv::normalize(ray);
  const cv::Vec3d m(0, 0, side);
  const double eta = 1 / window.refractive_index;
  const double cos_i = -m.dot(i);
  const double cos_t = std::sqrt(1 - eta * eta * (1 - cos_i * cos_i));
  const cv::Vec3d refracted = eta * i + (eta * cos_i - cos_t) * m;
  const double depth = -side * window.thickness_mm;  // The inner face: Z = -side t.
  const cv::Vec3d on_soil = on_face + refracted * (depth / refracted[2]);
  *soil_mm = {on_soil[0], on_soil[1]};
  return true;
}

namespace calib_detail {

void CarryToSoil(const CameraCalibration& calibration, const std::vector<cv::Point3f>& object,
                 const std::vector<cv::Point2d>& undistorted_px, cv::Point2d centroid_px,
                 const WindowOptions& window, PlaneScale* scale) {
  window.Check();
  cv::Vec3d rvec, tvec;
  cv::solvePnP(object, undistorted_px, calibration.CameraMatrix(), cv::noArray(), rvec, tvec);
  // The soil point of a 33 x 25 grid over the whole image, and one homography through them.
  std::vector<cv::Point2d> px, mm;
  constexpr int kCols = 33, kRows = 25;
  for (int j = 0; j < kRows; ++j)
    for (int i = 0; i < kCols; ++i) {
      const cv::Point2d p((calibration.image_width - 1) * i / (kCols - 1.0),
                          (calibration.image_height - 1) * j / (kRows - 1.0));
      cv::Point2d soil;
      if (!TraceToSoil(calibration, rvec, tvec, window, p, &soil)) continue;
      px.push_back(p);
      mm.push_back(soil);
    }
  if (px.size() < 4)
    throw Error(ErrorKind::kNumerical,
                fmt::format("plane image {}: the camera's rays do not reach the window (the "
                            "board's pose from the plane view puts the camera behind it)",
                            scale->image));
  const cv::Mat h = cv::findHomography(px, mm, /*method=*/0);
  if (h.empty() || !cv::checkRange(h))
    throw Error(ErrorKind::kNumerical, "plane image " + scale->image + ": soil-plane fit failed");
  // The scale at the centroid from the traced map itself (central differences, 1 px): the
  // homography through the whole image averages the off-axis part in.
  cv::Point2d soil[4];
  const cv::Point2d steps[4] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
  for (int k = 0; k < 4; ++k)
    if (!TraceToSoil(calibration, rvec, tvec, window, centroid_px + steps[k], &soil[k]))
      throw Error(ErrorKind::kNumerical,
                  "plane image " + scale->image + ": the centre's ray does not reach the window");
  const cv::Point2d du = (soil[0] - soil[1]) * 0.5, dv = (soil[2] - soil[3]) * 0.5;
  const double relative_uncertainty = scale->mm_per_px_uncertainty / scale->mm_per_px;
  scale->board_mm_per_px = scale->mm_per_px;
  scale->mm_from_px = cv::Matx33d(h);
  scale->mm_per_px = std::sqrt(std::abs(du.x * dv.y - du.y * dv.x));
  scale->mm_per_px_uncertainty = relative_uncertainty * scale->mm_per_px;
  scale->window = window;
  scale->window_nonlinearity_mm = 0;
  for (std::size_t k = 0; k < px.size(); ++k)
    scale->window_nonlinearity_mm =
        std::max(scale->window_nonlinearity_mm, cv::norm(scale->ToMm(px[k]) - mm[k]));
  LogInfo(
      "window: {} mm panel, n = {}: soil-plane scale {:.6f} mm/px, {:+.3f} % from the board's "
      "{:.6f} mm/px on the outer face; the homography leaves {:.4f} mm of the traced map",
      window.thickness_mm, window.refractive_index, scale->mm_per_px,
      100 * (scale->mm_per_px / scale->board_mm_per_px - 1), scale->board_mm_per_px,
      scale->window_nonlinearity_mm);
}

}  // namespace calib_detail
}  // namespace impactdic
