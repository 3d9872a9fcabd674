// A program of a user's own linked with the installed libraries: correlates a synthetic speckle
// pair moved by a known translation and checks the displacement. Exit code 0 when every subset
// converged within kTolerancePx of the truth.
#include <impactdic/dic/correlator.h>
#include <impactdic/dic/options.h>
#include <impactdic/synth/fields.h>
#include <impactdic/synth/speckle.h>

#include <cmath>
#include <cstdio>
#include <opencv2/core.hpp>

int main() {
  using namespace impactdic;
  constexpr int kSize = 128;
  constexpr double kU = 1.3, kV = -0.6;
  // Subpixel translations are recovered to ~0.01 px at this noise (tests/dic/icgn_test.cc);
  // 0.05 px leaves room and still fails a wrong sign, axis or scale.
  constexpr double kTolerancePx = 0.05;
  SpeckleOptions speckle;
  speckle.seed = 3;
  const SpecklePattern pattern(speckle, kSize, kSize);
  RenderOptions render;
  render.noise_sigma = 0.5;
  render.noise_seed = 1;
  const cv::Mat ref = RenderImage(pattern, kSize, kSize, ZeroField(), render);
  render.noise_seed = 2;
  const cv::Mat def = RenderImage(pattern, kSize, kSize, Translation(kU, kV), render);

  DicOptions options;
  options.grid.subset_size = 21;
  options.grid.step = 16;
  const DicResult result = CorrelateSequence({ref, def}, options);
  const FrameResult& frame = result.frames.at(0);
  int good = 0, bad = 0;
  for (std::size_t i = 0; i < frame.status.size(); ++i) {
    const bool ok = frame.status[i] == SubsetStatus::kConverged &&
                    std::abs(frame.u_px[i] - kU) < kTolerancePx &&
                    std::abs(frame.v_px[i] - kV) < kTolerancePx;
    (ok ? good : bad) += 1;
  }
  std::printf("impactdic consumer: %d subsets within %.2f px of (%.2f, %.2f), %d not\n", good,
              kTolerancePx, kU, kV, bad);
  return good > 0 && bad == 0 ? 0 : 1;
}
