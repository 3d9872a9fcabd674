#include "impactdic/kinematics/kinematics.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "impactdic/core/error.h"
#include "impactdic/core/numeric.h"
#include "impactdic/core/timer.h"

namespace impactdic {
namespace {}  // namespace

void PanelMapping::Check() const {
  if (homography) {
    for (double h : *homography)
      CheckValue(std::isfinite(h), "homography", "a non-finite entry", "finite entries");
    const auto& h = *homography;
    const double det = h[0] * (h[4] * h[8] - h[5] * h[7]) - h[1] * (h[3] * h[8] - h[5] * h[6]) +
                       h[2] * (h[3] * h[7] - h[4] * h[6]);
    CheckValue(det != 0, "homography", "a singular matrix", "an invertible 3x3 matrix");
  } else {
    CheckValue(std::isfinite(mm_per_px) && mm_per_px > 0, "mm_per_px", fmt::format("{}", mm_per_px),
               "> 0 mm/px (or a homography)");
  }
}

void PanelMapping::Map(double x_px, double y_px, double* x_mm, double* y_mm) const {
  if (!homography) {
    *x_mm = mm_per_px * x_px;
    *y_mm = mm_per_px * y_px;
    return;
  }
  const auto& h = *homography;
  const double w = h[6] * x_px + h[7] * y_px + h[8];
  *x_mm = (h[0] * x_px + h[1] * y_px + h[2]) / w;
  *y_mm = (h[3] * x_px + h[4] * y_px + h[5]) / w;
}

double PanelMapping::LocalScale(double x_px, double y_px) const {
  if (!homography) return mm_per_px;
  const double e = 0.5;
  double x0, y0, x1, y1, x2, y2;
  Map(x_px - e, y_px, &x0, &y0);
  Map(x_px + e, y_px, &x1, &y1);
  const double dxx = x1 - x0, dyx = y1 - y0;
  Map(x_px, y_px - e, &x0, &y0);
  Map(x_px, y_px + e, &x2, &y2);
  const double dxy = x2 - x0, dyy = y2 - y0;
  return std::sqrt(std::abs(dxx * dyy - dxy * dyx));
}

void CorrelationSeries::Check() const {
  CheckValue(frames >= 4, "correlation frames", fmt::format("{}", frames),
             ">= 4 frames (second derivatives need 4 samples)");
  CheckValue(subsets >= 1, "correlation subsets", fmt::format("{}", subsets), ">= 1");
  CheckValue(x_px.size() == subsets && y_px.size() == subsets, "x_px / y_px",
             fmt::format("{} / {} entries", x_px.size(), y_px.size()),
             fmt::format("one per subset ({})", subsets));
  const std::size_t n = frames * subsets;
  CheckValue(u_px.size() == n && v_px.size() == n, "u_px / v_px",
             fmt::format("{} / {} entries", u_px.size(), v_px.size()),
             fmt::format("frames x subsets = {}", n));
  CheckValue(valid.empty() || valid.size() == n, "valid", fmt::format("{} entries", valid.size()),
             fmt::format("empty or frames x subsets = {}", n));
  CheckValue(
      sigma_u_px.size() == sigma_v_px.size() && (sigma_u_px.empty() || sigma_u_px.size() == n),
      "sigma_u_px / sigma_v_px",
      fmt::format("{} / {} entries", sigma_u_px.size(), sigma_v_px.size()),
      fmt::format("both empty or frames x subsets = {}", n));
  for (std::size_t i = 0; i < subsets; ++i)
    CheckValue(std::isfinite(x_px[i]) && std::isfinite(y_px[i]), "x_px / y_px",
               fmt::format("a non-finite position at subset {}", i), "finite grid positions");
}

std::size_t ExcludeUncertainSamples(double max_sigma_px, const std::string& where,
                                    CorrelationSeries* series) {
  CheckValue(max_sigma_px > 0, where, fmt::format("{}", max_sigma_px), "> 0 px");
  CorrelationSeries& s = *series;
  s.Check();
  CheckValue(!s.sigma_u_px.empty(), where, "set, but the correlation results have no sigma_u_px",
             "results with per-subset sigmas (correlate them again with this version)");
  const std::size_t n = s.frames * s.subsets;
  if (s.valid.empty()) s.valid.assign(n, 1);
  std::size_t excluded = 0;
  for (std::size_t j = 0; j < n; ++j) {
    if (!s.valid[j] || !(s.sigma_u_px[j] > max_sigma_px || s.sigma_v_px[j] > max_sigma_px))
      continue;
    s.valid[j] = 0;
    ++excluded;
  }
  return excluded;
}

std::string ExcludeUncertainSamplesWithWarning(double max_sigma_px, const std::string& where,
                                               CorrelationSeries* series) {
  const std::size_t excluded = ExcludeUncertainSamples(max_sigma_px, where, series);
  return fmt::format(
      "kinematics: {} of {} subset samples left out (sigma_u or sigma_v > {} = {} px)", excluded,
      series->frames * series->subsets, where, max_sigma_px);
}

std::size_t ExcludeSamplesAboveMedianSigma(double ratio, const std::string& where,
                                           CorrelationSeries* series) {
  CheckValue(ratio > 1, where, fmt::format("{}", ratio), "> 1");
  CorrelationSeries& s = *series;
  s.Check();
  CheckValue(!s.sigma_u_px.empty(), where, "set, but the correlation results have no sigma_u_px",
             "results with per-subset sigmas (correlate them again with this version)");
  if (s.valid.empty()) s.valid.assign(s.frames * s.subsets, 1);
  std::size_t excluded = 0;
  std::vector<float> sigma;
  for (std::size_t f = 0; f < s.frames; ++f) {
    const std::size_t row = f * s.subsets;
    sigma.clear();
    for (std::size_t i = row; i < row + s.subsets; ++i) {
      const float larger = std::max(s.sigma_u_px[i], s.sigma_v_px[i]);
      if (s.valid[i] && larger > 0) sigma.push_back(larger);
    }
    if (sigma.size() < 3) continue;  // The reference frame (sigma 0), or too few to judge.
    std::nth_element(sigma.begin(), sigma.begin() + sigma.size() / 2, sigma.end());
    const double limit = ratio * sigma[sigma.size() / 2];
    for (std::size_t i = row; i < row + s.subsets; ++i) {
      if (!s.valid[i] || !(s.sigma_u_px[i] > limit || s.sigma_v_px[i] > limit)) continue;
      s.valid[i] = 0;
      ++excluded;
    }
  }
  return excluded;
}

std::string ExcludeSamplesAboveMedianSigmaWithWarning(double ratio, const std::string& where,
                                                      CorrelationSeries* series) {
  const std::size_t excluded = ExcludeSamplesAboveMedianSigma(ratio, where, series);
  if (excluded == 0) return "";
  return fmt::format(
      "kinematics: {} of {} subset samples left out (sigma_u or sigma_v > {} = {} x the frame's "
      "median sigma)",
      excluded, series->frames * series->subsets, where, ratio);
}

void KinematicsOptions::Check() const {
  CheckValue(std::isfinite(fps) && fps > 0, "kinematics.fps", fmt::format("{}", fps), "> 0 1/s");
}

std::string KinematicsSummary::BriefReport() const {
  return fmt::format("{} valid / {} invalid subset samples, {:.3f} s", valid_samples,
                     invalid_samples, seconds);
}

std::vector<double> FirstDerivative(const std::vector<double>& f, double h) {
  const std::size_t n = f.size();
  CheckValue(n >= 3, "FirstDerivative", fmt::format("{} samples", n), ">= 3 samples");
  std::vector<double> d(n);
  // NaN propagates through the arithmetic: exactly the derivatives that use a NaN are NaN.
  d[0] = (-3 * f[0] + 4 * f[1] - f[2]) / (2 * h);
  for (std::size_t k = 1; k + 1 < n; ++k) d[k] = (f[k + 1] - f[k - 1]) / (2 * h);
  d[n - 1] = (3 * f[n - 1] - 4 * f[n - 2] + f[n - 3]) / (2 * h);
  return d;
}

std::vector<double> SecondDerivative(const std::vector<double>& f, double h) {
  const std::size_t n = f.size();
  CheckValue(n >= 4, "SecondDerivative", fmt::format("{} samples", n), ">= 4 samples");
  std::vector<double> d(n);
  const double h2 = h * h;
  d[0] = (2 * f[0] - 5 * f[1] + 4 * f[2] - f[3]) / h2;
  for (std::size_t k = 1; k + 1 < n; ++k) d[k] = (f[k + 1] - 2 * f[k] + f[k - 1]) / h2;
  d[n - 1] = (2 * f[n - 1] - 5 * f[n - 2] + 4 * f[n - 3] - f[n - 4]) / h2;
  return d;
}

KinematicsResult ComputeKinematics(const CorrelationSeries& dic, const PanelMapping& mapping,
                                   const KinematicsOptions& options) {
  WallTimer timer;
  dic.Check();
  mapping.Check();
  options.Check();
  KinematicsResult r;
  const std::size_t nf = dic.frames, ns = dic.subsets, n = nf * ns;
  r.frames = nf;
  r.subsets = ns;
  const double dt = 1 / options.fps;
  for (std::size_t k = 0; k < nf; ++k) r.time_s.push_back(static_cast<double>(k) * dt);
  r.x_mm.resize(ns);
  r.y_mm.resize(ns);
  for (std::size_t i = 0; i < ns; ++i)
    mapping.Map(dic.x_px[i], dic.y_px[i], &r.x_mm[i], &r.y_mm[i]);
  r.disp_x_mm.assign(n, kNaN);
  r.disp_y_mm.assign(n, kNaN);
  r.vel_x_mm_s.assign(n, kNaN);
  r.vel_y_mm_s.assign(n, kNaN);
  r.acc_x_mm_s2.assign(n, kNaN);
  r.acc_y_mm_s2.assign(n, kNaN);
  const bool sigmas = dic.sigma_v_px.size() == n;
  if (sigmas) r.disp_y_sigma_mm.assign(n, std::numeric_limits<float>::quiet_NaN());
  std::vector<double> sx(nf), sy(nf);
  for (std::size_t i = 0; i < ns; ++i) {
    for (std::size_t k = 0; k < nf; ++k) {
      const std::size_t j = k * ns + i;
      const double u = dic.u_px[j], v = dic.v_px[j];
      const bool ok =
          (dic.valid.empty() || dic.valid[j] != 0) && std::isfinite(u) && std::isfinite(v);
      if (!ok) {
        sx[k] = sy[k] = kNaN;
        ++r.summary.invalid_samples;
        continue;
      }
      ++r.summary.valid_samples;
      double xm, ym;
      mapping.Map(dic.x_px[i] + u, dic.y_px[i] + v, &xm, &ym);
      sx[k] = xm - r.x_mm[i];
      sy[k] = ym - r.y_mm[i];
      if (sigmas) {
        r.disp_y_sigma_mm[j] = static_cast<float>(
            dic.sigma_v_px[j] * mapping.LocalScale(dic.x_px[i] + u, dic.y_px[i] + v));
      }
    }
    const std::vector<double> vx = FirstDerivative(sx, dt), vy = FirstDerivative(sy, dt);
    const std::vector<double> ax = SecondDerivative(sx, dt), ay = SecondDerivative(sy, dt);
    for (std::size_t k = 0; k < nf; ++k) {
      const std::size_t j = k * ns + i;
      r.disp_x_mm[j] = sx[k];
      r.disp_y_mm[j] = sy[k];
      r.vel_x_mm_s[j] = vx[k];
      r.vel_y_mm_s[j] = vy[k];
      r.acc_x_mm_s2[j] = ax[k];
      r.acc_y_mm_s2[j] = ay[k];
    }
  }
  if (r.summary.invalid_samples > 0) {
    r.summary.warnings.push_back(
        fmt::format("{} of {} subset samples are invalid (NaN); derivatives using them are NaN",
                    r.summary.invalid_samples, n));
  }
  r.summary.seconds = timer.ElapsedSeconds();
  return r;
}

double MeanOverSubsets(const std::vector<double>& field, std::size_t subsets, std::size_t frame,
                       const std::vector<std::size_t>& ids, std::size_t* count) {
  double sum = 0;
  std::size_t c = 0;
  for (std::size_t id : ids) {
    const double v = field[frame * subsets + id];
    if (std::isfinite(v)) {
      sum += v;
      ++c;
    }
  }
  if (count) *count = c;
  return c ? sum / static_cast<double>(c) : kNaN;
}

}  // namespace impactdic
