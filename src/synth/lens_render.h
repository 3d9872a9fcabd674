// One camera frame rendered through a synthetic lens, whoever shades the panel (impact_scene.cc:
// the analytic speckle under the model's soil field; dem_scene.cc: a DEM run's grains). Internal to
// the synth module.
#ifndef IMPACTDIC_SRC_SYNTH_LENS_RENDER_H_
#define IMPACTDIC_SRC_SYNTH_LENS_RENDER_H_

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "impactdic/synth/impact_scene.h"
#include "random.h"

namespace impactdic::synth_detail {

// For each pixel: ss x ss samples at bilinear positions inside its undistorted quadrilateral
// (corner_map: ideal px of the pixel corners, (w+1) x (h+1)); each sample's grey level in [0, 1]
// is shade(q) with q its ideal position [px]; their mean, scaled to the bit depth, plus Gaussian
// noise (spec.noise_sigma grey levels, one stream per row seeded from noise_seed, so the frame
// does not depend on the thread count), rounded and clamped.
template <class Shade>
cv::Mat RenderThroughLens(const ImpactSceneSpec& spec, const std::vector<cv::Point2d>& corner_map,
                          std::uint64_t noise_seed, bool with_noise, const Shade& shade) {
  const int w = spec.width, h = spec.height, ss = spec.supersampling;
  const double full = spec.bits == 8 ? 255.0 : 65535.0;
  cv::Mat image(h, w, spec.bits == 8 ? CV_8U : CV_16U);
  const std::size_t stride = static_cast<std::size_t>(w) + 1;
  tbb::parallel_for(0, h, [&](int r) {
    Rng noise(SplitMix64(noise_seed) ^ (0x100000001B3ull * static_cast<std::uint64_t>(r + 1)));
    for (int c = 0; c < w; ++c) {
      const cv::Point2d& c00 = corner_map[r * stride + c];
      const cv::Point2d& c10 = corner_map[r * stride + c + 1];
      const cv::Point2d& c01 = corner_map[(r + 1) * stride + c];
      const cv::Point2d& c11 = corner_map[(r + 1) * stride + c + 1];
      double sum = 0;
      for (int sy = 0; sy < ss; ++sy) {
        const double b = (sy + 0.5) / ss;
        for (int sx = 0; sx < ss; ++sx) {
          const double a = (sx + 0.5) / ss;
          sum +=
              shade((1 - a) * (1 - b) * c00 + a * (1 - b) * c10 + (1 - a) * b * c01 + a * b * c11);
        }
      }
      double value = sum / (ss * ss) * full;
      if (with_noise && spec.noise_sigma > 0) value += spec.noise_sigma * noise.Normal();
      value = std::clamp(std::round(value), 0.0, full);
      if (spec.bits == 8) {
        image.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(value);
      } else {
        image.at<std::uint16_t>(r, c) = static_cast<std::uint16_t>(value);
      }
    }
  });
  return image;
}

}  // namespace impactdic::synth_detail

#endif  // IMPACTDIC_SRC_SYNTH_LENS_RENDER_H_
