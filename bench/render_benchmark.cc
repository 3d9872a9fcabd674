// Speed of drawing one velocity-field frame (overlay, arrows, colour bar) at the sample-scene size
// (640 x 480, subsets every 10 px) and at the camera's full size (1920 x 1440, every 20 px).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <opencv2/core.hpp>
#include <random>
#include <vector>

#include "impactdic/render/velocity_field.h"

namespace impactdic {
namespace {

VelocityFieldSequence Sequence(int width, int height, int step) {
  VelocityFieldSequence seq;
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> grey(0, 255);
  cv::Mat frame(height, width, CV_8U);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) frame.at<unsigned char>(y, x) = grey(rng);
  }
  seq.frames = {frame};
  seq.time_ms = {1.25};
  for (int y = height / 3; y < height; y += step) {
    for (int x = 0; x < width; x += step) {
      seq.x_px.push_back(x);
      seq.y_px.push_back(y);
      seq.vx_mm_s.push_back(100.0 * std::sin(0.01 * x));
      seq.vy_mm_s.push_back(500.0 + y);
    }
  }
  seq.num_subsets = seq.x_px.size();
  seq.mm_per_px = 0.2;
  return seq;
}

void BM_RenderFrame(benchmark::State& state) {
  const VelocityFieldSequence seq =
      Sequence(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)),
               static_cast<int>(state.range(2)));
  const VelocityFieldRenderer renderer(seq, {});
  for (auto _ : state) benchmark::DoNotOptimize(renderer.RenderFrame(0));
  state.counters["subsets"] = static_cast<double>(seq.num_subsets);
}
BENCHMARK(BM_RenderFrame)
    ->Args({640, 480, 10})
    ->Args({1920, 1440, 20})
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace impactdic

BENCHMARK_MAIN();
