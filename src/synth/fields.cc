#include "impactdic/synth/fields.h"

#include <cmath>
#include <numbers>
#include <opencv2/core.hpp>
#include <string>

#include "impactdic/core/error.h"

namespace impactdic {

DisplacementField ZeroField() {
  return {[](double, double) { return cv::Vec2d(0, 0); },
          [](double, double) { return cv::Vec4d(0, 0, 0, 0); }};
}

DisplacementField Translation(double u_px, double v_px) {
  return {[=](double, double) { return cv::Vec2d(u_px, v_px); },
          [](double, double) { return cv::Vec4d(0, 0, 0, 0); }};
}

DisplacementField Rotation(double angle_rad, double cx, double cy) {
  const double c = std::cos(angle_rad), s = std::sin(angle_rad);
  return {[=](double X, double Y) {
            const double dx = X - cx, dy = Y - cy;
            return cv::Vec2d(c * dx - s * dy - dx, s * dx + c * dy - dy);
          },
          [=](double, double) { return cv::Vec4d(c - 1, -s, s, c - 1); }};
}

DisplacementField Affine(double u0, double v0, double dudx, double dudy, double dvdx, double dvdy,
                         double cx, double cy) {
  return {[=](double X, double Y) {
            const double dx = X - cx, dy = Y - cy;
            return cv::Vec2d(u0 + dudx * dx + dudy * dy, v0 + dvdx * dx + dvdy * dy);
          },
          [=](double, double) { return cv::Vec4d(dudx, dudy, dvdx, dvdy); }};
}

DisplacementField Sinusoidal(double amp_u_px, double amp_v_px, double wavelength_px,
                             double phase_rad) {
  CheckValue(wavelength_px > 0, "Sinusoidal.wavelength_px", std::to_string(wavelength_px), "> 0");
  const double k = 2 * std::numbers::pi / wavelength_px;
  return {[=](double X, double Y) {
            return cv::Vec2d(amp_u_px * std::sin(k * X + phase_rad),
                             amp_v_px * std::sin(k * Y + phase_rad));
          },
          [=](double X, double Y) {
            return cv::Vec4d(amp_u_px * k * std::cos(k * X + phase_rad), 0, 0,
                             amp_v_px * k * std::cos(k * Y + phase_rad));
          }};
}

DisplacementField Quadratic(double a, double b, double c, double cx, double cy) {
  return {[=](double X, double Y) {
            const double dx = X - cx, dy = Y - cy;
            return cv::Vec2d(a * dx * dx + b * dy * dy, c * dx * dy);
          },
          [=](double X, double Y) {
            const double dx = X - cx, dy = Y - cy;
            return cv::Vec4d(2 * a * dx, 2 * b * dy, c * dy, c * dx);
          }};
}

DisplacementField ExponentialCompression(double surface_strain, double decay_length_px,
                                         double y_surface_px, double y_fixed_px) {
  CheckValue(decay_length_px > 0, "ExponentialCompression.decay_length_px",
             std::to_string(decay_length_px), "> 0");
  const double e0 = surface_strain, L = decay_length_px;
  const double v_fixed = e0 * L * std::exp(-(y_fixed_px - y_surface_px) / L);
  return {[=](double, double Y) {
            return cv::Vec2d(0, e0 * L * std::exp(-(Y - y_surface_px) / L) - v_fixed);
          },
          [=](double, double Y) {
            return cv::Vec4d(0, 0, 0, -e0 * std::exp(-(Y - y_surface_px) / L));
          }};
}

DisplacementField Sum(const std::vector<DisplacementField>& fields) {
  return {[=](double X, double Y) {
            cv::Vec2d s(0, 0);
            for (const auto& f : fields) s += f.u(X, Y);
            return s;
          },
          [=](double X, double Y) {
            cv::Vec4d s(0, 0, 0, 0);
            for (const auto& f : fields) s += f.gradient(X, Y);
            return s;
          }};
}

DisplacementField Scaled(const DisplacementField& field, double s) {
  return {[=](double X, double Y) { return s * field.u(X, Y); },
          [=](double X, double Y) { return s * field.gradient(X, Y); }};
}

DisplacementSequence LinearSequence(const DisplacementField& final_field, int frames) {
  CheckValue(frames >= 2, "LinearSequence.frames", std::to_string(frames), ">= 2");
  return {frames, [=](int k) { return Scaled(final_field, double(k) / (frames - 1)); }};
}

}  // namespace impactdic
