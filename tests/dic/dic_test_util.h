// Shared helpers of the dic tests: synthetic speckle images with a known displacement field.
#ifndef IMPACTDIC_TESTS_DIC_DIC_TEST_UTIL_H_
#define IMPACTDIC_TESTS_DIC_DIC_TEST_UTIL_H_

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <opencv2/core.hpp>
#include <vector>

#include "impactdic/dic/correlator.h"
#include "impactdic/dic/options.h"
#include "impactdic/synth/speckle.h"

namespace impactdic::testing {

struct Scene {
  SpecklePattern pattern;
  int width, height;
  RenderOptions render;
  Scene(int w, int h, double noise_sigma, std::uint64_t seed = 1, int supersampling = 3)
      : pattern(MakeSpeckle(seed), w, h), width(w), height(h) {
    render.noise_sigma = noise_sigma;
    render.supersampling = supersampling;
  }
  static SpeckleOptions MakeSpeckle(std::uint64_t seed) {
    SpeckleOptions o;
    o.seed = seed;
    o.blob_radius_px = 2.0;
    o.contrast = 1.0;
    return o;
  }
  // Each image gets its own noise realisation.
  cv::Mat Render(const DisplacementField& field, std::uint64_t noise_seed) {
    RenderOptions r = render;
    r.noise_seed = noise_seed;
    return RenderImage(pattern, width, height, field, r);
  }
};

// Errors of the converged subsets of `frame` against the field's exact displacement of the
// subset centres (the material points X: u_true = u(X)).
struct ErrorStats {
  double bias_u = 0, bias_v = 0, sd_u = 0, sd_v = 0, rms = 0, max_abs = 0;
  int valid = 0;
};

inline ErrorStats Errors(const std::vector<cv::Point2d>& positions, const FrameResult& frame,
                         const DisplacementField& truth) {
  ErrorStats e;
  std::vector<double> eu, ev;
  for (std::size_t i = 0; i < positions.size(); ++i) {
    if (frame.status[i] != SubsetStatus::kConverged) continue;
    const cv::Vec2d u = truth.u(positions[i].x, positions[i].y);
    eu.push_back(frame.u_px[i] - u[0]);
    ev.push_back(frame.v_px[i] - u[1]);
  }
  e.valid = static_cast<int>(eu.size());
  if (eu.empty()) return e;
  for (std::size_t k = 0; k < eu.size(); ++k) {
    e.bias_u += eu[k] / eu.size();
    e.bias_v += ev[k] / ev.size();
    e.rms += (eu[k] * eu[k] + ev[k] * ev[k]) / eu.size();
    e.max_abs = std::max({e.max_abs, std::abs(eu[k]), std::abs(ev[k])});
  }
  for (std::size_t k = 0; k < eu.size(); ++k) {
    e.sd_u += (eu[k] - e.bias_u) * (eu[k] - e.bias_u) / std::max<std::size_t>(1, eu.size() - 1);
    e.sd_v += (ev[k] - e.bias_v) * (ev[k] - e.bias_v) / std::max<std::size_t>(1, ev.size() - 1);
  }
  e.sd_u = std::sqrt(e.sd_u);
  e.sd_v = std::sqrt(e.sd_v);
  e.rms = std::sqrt(e.rms);
  return e;
}

}  // namespace impactdic::testing

#endif  // IMPACTDIC_TESTS_DIC_DIC_TEST_UTIL_H_
