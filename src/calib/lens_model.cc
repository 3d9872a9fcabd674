// The lens distortion models (Brown-Conrady, rational, fisheye): fitting, projection and the
// held-out error that chooses between them (CalibrationOptions::model).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <opencv2/calib3d.hpp>
#include <string>
#include <vector>

#include "calib_internal.h"
#include "impactdic/calib/calibration.h"
#include "impactdic/core/error.h"

namespace impactdic {
namespace {

const cv::TermCriteria kFitCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 200, 1e-15);
// The held-out fits compare models to ~1 % of their error: 50 iterations, a relative change of
// 1e-10 (the rational model's k4-k6 on a mild lens otherwise take all 200 iterations).
const cv::TermCriteria kHeldOutCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 50, 1e-10);

// Squared reprojection error of one view through `camera` at its pose, and the point count.
double SquaredError(const CameraCalibration& camera, const std::vector<cv::Point3f>& object,
                    const std::vector<cv::Point2f>& image, const cv::Vec3d& rvec,
                    const cv::Vec3d& tvec) {
  const std::vector<cv::Point2f> projected = camera.Project(object, rvec, tvec);
  double sq = 0;
  for (std::size_t k = 0; k < projected.size(); ++k) {
    const cv::Point2f d = projected[k] - image[k];
    sq += d.dot(d);
  }
  return sq;
}

std::size_t PointCount(const calib_detail::ViewPoints& views) {
  std::size_t n = 0;
  for (const auto& v : views.image) n += v.size();
  return n;
}

}  // namespace

cv::Mat CameraCalibration::DistCoeffs() const {
  if (model == LensModel::kFisheye) return cv::Mat(cv::Matx14d(dist_fisheye.data())).clone();
  const int n = model == LensModel::kRational ? 8 : 5;
  cv::Mat d(1, n, CV_64F);
  for (int k = 0; k < 5; ++k) d.at<double>(k) = dist[k];
  for (int k = 5; k < n; ++k) d.at<double>(k) = dist_rational[k - 5];
  return d;
}

bool CameraCalibration::HasDistortion() const {
  const auto non_zero = [](double d) { return d != 0; };
  if (model == LensModel::kFisheye)
    return std::any_of(dist_fisheye.begin(), dist_fisheye.end(), non_zero);
  return std::any_of(dist.begin(), dist.end(), non_zero) ||
         (model == LensModel::kRational &&
          std::any_of(dist_rational.begin(), dist_rational.end(), non_zero));
}

std::vector<cv::Point2d> CameraCalibration::UndistortPixels(
    const std::vector<cv::Point2d>& distorted) const {
  if (distorted.empty()) return {};
  std::vector<cv::Point2d> out;
  const cv::Matx33d k = CameraMatrix();
  if (model == LensModel::kFisheye) {
    cv::fisheye::undistortPoints(distorted, out, k, DistCoeffs(), cv::noArray(), k);
    return out;
  }
  cv::undistortPoints(
      distorted, out, k, DistCoeffs(), cv::noArray(), k,
      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-12));
  return out;
}

std::vector<cv::Point2f> CameraCalibration::Project(const std::vector<cv::Point3f>& points,
                                                    const cv::Vec3d& rvec,
                                                    const cv::Vec3d& tvec) const {
  std::vector<cv::Point2f> out;
  if (points.empty()) return out;
  if (model == LensModel::kFisheye)
    cv::fisheye::projectPoints(points, out, rvec, tvec, CameraMatrix(), DistCoeffs());
  else
    cv::projectPoints(points, rvec, tvec, CameraMatrix(), DistCoeffs(), out);
  return out;
}

namespace calib_detail {

LensFit FitLens(const ViewPoints& views, cv::Size image_size, LensModel model,
                const CalibrationOptions& options, bool held_out) {
  const cv::TermCriteria& criteria = held_out ? kHeldOutCriteria : kFitCriteria;
  LensFit fit;
  CameraCalibration& c = fit.camera;
  c.model = model;
  c.image_width = image_size.width;
  c.image_height = image_size.height;
  cv::Mat k, d;
  std::vector<cv::Mat> rvecs, tvecs;
  try {
    if (model == LensModel::kFisheye) {
      const int flags = cv::fisheye::CALIB_RECOMPUTE_EXTRINSIC | cv::fisheye::CALIB_FIX_SKEW;
      cv::fisheye::calibrate(views.object, views.image, image_size, k, d, rvecs, tvecs, flags,
                             criteria);
    } else {
      int flags = model == LensModel::kRational ? cv::CALIB_RATIONAL_MODEL : 0;
      if (options.fix_k3) flags |= cv::CALIB_FIX_K3;
      if (options.zero_tangential) flags |= cv::CALIB_ZERO_TANGENT_DIST;
      cv::calibrateCamera(views.object, views.image, image_size, k, d, rvecs, tvecs, flags,
                          criteria);
    }
  } catch (const cv::Exception& e) {
    throw Error(ErrorKind::kNumerical,
                fmt::format("calibration failed: the {} model could not be fitted ({})",
                            kLensModelNames.Name(model), e.err));
  }
  if (!cv::checkRange(k) || !cv::checkRange(d))
    throw Error(ErrorKind::kNumerical,
                fmt::format("calibration failed: the {} model's fit returned non-finite values "
                            "(views too similar? vary the board's tilt and position)",
                            kLensModelNames.Name(model)));
  k.convertTo(k, CV_64F);
  d.convertTo(d, CV_64F);
  c.fx = k.at<double>(0, 0);
  c.fy = k.at<double>(1, 1);
  c.cx = k.at<double>(0, 2);
  c.cy = k.at<double>(1, 2);
  const auto coefficient = [&d](int i) {
    return i < static_cast<int>(d.total()) ? d.at<double>(i) : 0.0;
  };
  if (model == LensModel::kFisheye) {
    for (int i = 0; i < 4; ++i) c.dist_fisheye[i] = coefficient(i);
  } else {
    for (int i = 0; i < 5; ++i) c.dist[i] = coefficient(i);
    if (model == LensModel::kRational)
      for (int i = 0; i < 3; ++i) c.dist_rational[i] = coefficient(5 + i);
  }
  double sq = 0;
  for (std::size_t v = 0; v < views.object.size(); ++v) {
    fit.rvecs.emplace_back(rvecs[v]);
    fit.tvecs.emplace_back(tvecs[v]);
    sq += SquaredError(c, views.object[v], views.image[v], fit.rvecs[v], fit.tvecs[v]);
  }
  fit.rms_px = std::sqrt(sq / static_cast<double>(PointCount(views)));
  return fit;
}

ModelCandidate HeldOutError(const ViewPoints& views, cv::Size image_size, LensModel model,
                            const CalibrationOptions& options, int folds) {
  ModelCandidate candidate;
  candidate.model = model;
  try {
    candidate.fit_rms_px = FitLens(views, image_size, model, options, /*held_out=*/true).rms_px;
    double sq = 0;
    std::size_t n = 0;
    for (int fold = 0; fold < folds; ++fold) {
      ViewPoints train, test;
      for (std::size_t v = 0; v < views.object.size(); ++v) {
        ViewPoints& to = static_cast<int>(v % folds) == fold ? test : train;
        to.object.push_back(views.object[v]);
        to.image.push_back(views.image[v]);
      }
      const CameraCalibration lens =
          FitLens(train, image_size, model, options, /*held_out=*/true).camera;
      for (std::size_t v = 0; v < test.object.size(); ++v) {
        // The held-out view's pose, fitted alone on the points the lens undistorts.
        const std::vector<cv::Point2d> distorted(test.image[v].begin(), test.image[v].end());
        const std::vector<cv::Point2d> ideal = lens.UndistortPixels(distorted);
        cv::Vec3d rvec, tvec;
        cv::solvePnP(test.object[v], ideal, lens.CameraMatrix(), cv::noArray(), rvec, tvec);
        sq += SquaredError(lens, test.object[v], test.image[v], rvec, tvec);
        n += test.object[v].size();
      }
    }
    candidate.heldout_rms_px = std::sqrt(sq / static_cast<double>(n));
  } catch (const Error& e) {
    candidate.failure = e.what();
  } catch (const cv::Exception& e) {
    candidate.failure = e.err;
  }
  if (candidate.failure.empty() && !std::isfinite(candidate.heldout_rms_px))
    candidate.failure = "non-finite held-out error";
  return candidate;
}

}  // namespace calib_detail
}  // namespace impactdic
