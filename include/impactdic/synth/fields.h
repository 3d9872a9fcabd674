// Analytic displacement fields for synthetic DIC ground truth (docs/synth.md), in material
// (reference-image) coordinates [px], x right, y down. Each field returns u(X) and its Jacobian.
//
//   DisplacementField f = Rotation(/*angle_rad=*/0.035, /*cx=*/200, /*cy=*/200);
//   cv::Vec2d d = f.u(120.0, 80.0);
#ifndef IMPACTDIC_SYNTH_FIELDS_H_
#define IMPACTDIC_SYNTH_FIELDS_H_

#include <functional>
#include <vector>

#include "impactdic/synth/speckle.h"

namespace impactdic {

// Rigid rotation by `angle_rad` (positive = clockwise on screen, since y points down) about
// (cx, cy): x = c + R (X - c).
DisplacementField Rotation(double angle_rad, double cx, double cy);

// Affine field u = u0 + L (X - c), with L = [[dudx, dudy], [dvdx, dvdy]] (uniform strain plus
// rotation), about the centre (cx, cy).
DisplacementField Affine(double u0, double v0, double dudx, double dudy, double dvdx, double dvdy,
                         double cx, double cy);

// Sinusoidal field u = amp_u sin(2 pi X / wavelength_px + phase), v = amp_v sin(2 pi Y /
// wavelength_px + phase).
DisplacementField Sinusoidal(double amp_u_px, double amp_v_px, double wavelength_px,
                             double phase_rad = 0);

// Quadratic field: u = a * (X - cx)^2 + b * (Y - cy)^2, v = c * (X - cx) * (Y - cy) [px].
DisplacementField Quadratic(double a, double b, double c, double cx, double cy);

// Vertical compression whose strain decays exponentially with depth, as under a load applied at
// the surface y = y_surface_px (y down). Compressive engineering strain
//   e(Y) = surface_strain * exp(-(Y - y_surface_px) / L),  L = decay_length_px > 0,
// i.e. dv/dY = -e(Y) and u = 0; the material at y = y_fixed_px does not move:
//   v(Y) = surface_strain * L * (exp(-(Y - y_surface_px) / L) - exp(-(y_fixed_px - y_surface_px)
//          / L)).
// The mean strain between the surface and y_fixed is v(y_surface) / (y_fixed - y_surface).
DisplacementField ExponentialCompression(double surface_strain, double decay_length_px,
                                         double y_surface_px, double y_fixed_px);

// Sum of fields (u = sum of u_i), e.g. a rigid translation plus a strain.
DisplacementField Sum(const std::vector<DisplacementField>& fields);

// Scales a field: u = s * u_f(X).
DisplacementField Scaled(const DisplacementField& field, double s);

// A sequence: frame k (0 = reference) has the field `at(k)`; `frames` is the number of frames
// including the reference.
struct DisplacementSequence {
  int frames = 0;
  std::function<DisplacementField(int frame)> at;
};

// Linear ramp: frame k has field Scaled(final, k / (frames - 1)).
DisplacementSequence LinearSequence(const DisplacementField& final_field, int frames);

}  // namespace impactdic

#endif  // IMPACTDIC_SYNTH_FIELDS_H_
