// Time per frame of long sequences of large frames ("Throughput on large frames"), as
// `impactdic correlate` runs them: the one driver (CorrelateFrames) over a FrameStream of JPEG
// files (decoding, the pre-filter,
// coefficients, reference updates, initial guesses, IC-GN), default options but the grid, the
// `auto` reference update, a Gaussian pre-filter of sigma 0.7 px (5x5; what `correlate`'s `auto`
// pre-filter picks on the real sand) and 2 threads.
//
//   BM_LargeFrames/generated   4096x3000 speckle, subset 25, step 50 (4,920 subsets), 9 frames
//   BM_LargeFrames/real_sand   the same grid on the 11 real sand frames (skipped when absent)
//   BM_MidFrames               1920x1440 speckle, subset 25, step 10, 9 frames
//
// The generated frames (translation of 0.35, -0.2 px per frame plus a 0.1 % stretch per frame,
// noise sigma 2 grey levels, JPEG quality 95, one sample per pixel) are rendered once into the
// cache folder (a few minutes for the 4096x3000 frames). The
// counters give the time per deformed frame (s_per_frame, and its best over the repetitions) and
// the correlator's phase times per frame (t_coef, t_ref, t_init, t_icgn).
//
//   dic_throughput_benchmark [--threads N] [--cache DIR] [--real-sand DIR] [benchmark flags]
//   e.g. dic_throughput_benchmark --benchmark_repetitions=3
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "impactdic/core/timer.h"
#include "impactdic/dic/correlate_frames.h"
#include "impactdic/dic/correlator.h"
#include "impactdic/dic/options.h"
#include "impactdic/io/frame_source.h"
#include "impactdic/pipeline/frame_stream.h"
#include "impactdic/preprocess/preprocess.h"
#include "impactdic/synth/fields.h"
#include "impactdic/synth/speckle.h"

namespace impactdic {
namespace {

namespace fs = std::filesystem;

constexpr int kFrames = 9;  // Reference + 8 deformed frames.
std::string g_cache = "/tmp/impactdic_throughput_bench";
std::string g_real_sand = "/work/shared/data/real-sand/test48";
int g_threads = 2;

// Frames 0..kFrames-1 of a width x height speckle sequence, rendered once (JPEG, quality 95).
std::vector<std::string> GeneratedFrames(int width, int height) {
  const std::string dir = g_cache + "/" + std::to_string(width) + "x" + std::to_string(height);
  fs::create_directories(dir);
  SpeckleOptions speckle;
  speckle.blob_radius_px = 2.0;
  const SpecklePattern pattern(speckle, width, height);
  std::vector<std::string> paths;
  for (int k = 0; k < kFrames; ++k) {
    paths.push_back(dir + "/frame_" + std::to_string(k) + ".jpg");
    if (fs::exists(paths.back())) continue;
    RenderOptions render;
    render.supersampling = 1;  // Fast enough for 12 MP frames; the content is what matters.
    render.noise_sigma = 2;
    render.noise_seed = 500 + k;
    const double stretch = 0.001 * k;
    std::fprintf(stderr, "rendering %s\n", paths.back().c_str());
    const cv::Mat image = RenderImage(
        pattern, width, height,
        Affine(0.35 * k, -0.2 * k, stretch, 0, 0, stretch, width / 2.0, height / 2.0), render);
    cv::imwrite(paths.back(), image, {cv::IMWRITE_JPEG_QUALITY, 95});
  }
  return paths;
}

std::vector<std::string> RealSandFrames() {
  std::vector<std::string> paths;
  if (!fs::is_directory(g_real_sand)) return paths;
  for (const auto& entry : fs::directory_iterator(g_real_sand)) {
    if (entry.path().extension() == ".jpg") paths.push_back(entry.path().string());
  }
  std::sort(paths.begin(), paths.end());
  return paths;
}

// Gaussian blur, sigma 0.7 px, 5x5 (correlate's `auto` pre-filter on the real sand), through the
// one preprocessing route.
PreprocessOptions Prefilter() {
  PreprocessOptions o;
  o.gaussian.mode = GaussianMode::kOn;
  o.gaussian.sigma_px = 0.7;
  o.gaussian.kernel_size = 5;
  return o;
}

void Run(benchmark::State& state, const std::vector<std::string>& paths, int step) {
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, g_threads);
  DicOptions options;
  options.grid.subset_size = 25;
  options.grid.step = step;
  const int frames = static_cast<int>(paths.size()) - 1;
  double best = 1e300;
  for (auto _ : state) {
    WallTimer timer;
    FrameStream stream(MakeImageFileSource(paths), Prefilter(), /*calibration=*/nullptr);
    const DicResult result = CorrelateFrames(stream, options);
    const double per_frame = timer.ElapsedSeconds() / frames;
    best = std::min(best, per_frame);
    state.SetIterationTime(per_frame);
    const DicSummary& s = result.summary;
    state.counters["subsets"] = s.subsets;
    state.counters["frames"] = frames;
    state.counters["valid_pct"] = 100 * s.valid_fraction;
    state.counters["updates"] = s.reference_updates;
    state.counters["s_per_frame"] = per_frame;
    state.counters["t_coef"] = s.seconds_coefficients / frames;
    state.counters["t_ref"] = s.seconds_reference / frames;
    state.counters["t_init"] = s.seconds_initial_guess / frames;
    state.counters["t_icgn"] = s.seconds_icgn / frames;
  }
  state.counters["best_s_per_frame"] = best;
}

void BM_LargeFrames_Generated(benchmark::State& state) {
  Run(state, GeneratedFrames(4096, 3000), /*step=*/50);
}

void BM_LargeFrames_RealSand(benchmark::State& state) {
  const std::vector<std::string> paths = RealSandFrames();
  if (paths.size() < 2) {
    state.SkipWithError(("no real sand frames (*.jpg) in " + g_real_sand).c_str());
    return;
  }
  Run(state, paths, /*step=*/50);
}

void BM_MidFrames(benchmark::State& state) { Run(state, GeneratedFrames(1920, 1440), 10); }

}  // namespace
}  // namespace impactdic

int main(int argc, char** argv) {
  using namespace impactdic;
  std::vector<char*> rest = {argv[0]};
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--threads" && i + 1 < argc) {
      g_threads = std::atoi(argv[++i]);
    } else if (arg == "--cache" && i + 1 < argc) {
      g_cache = argv[++i];
    } else if (arg == "--real-sand" && i + 1 < argc) {
      g_real_sand = argv[++i];
    } else {
      rest.push_back(argv[i]);
    }
  }
  int n = static_cast<int>(rest.size());
  benchmark::Initialize(&n, rest.data());
  benchmark::RegisterBenchmark("BM_LargeFrames/generated", BM_LargeFrames_Generated)
      ->UseManualTime()
      ->Unit(benchmark::kMillisecond)
      ->Iterations(1);
  benchmark::RegisterBenchmark("BM_LargeFrames/real_sand", BM_LargeFrames_RealSand)
      ->UseManualTime()
      ->Unit(benchmark::kMillisecond)
      ->Iterations(1);
  benchmark::RegisterBenchmark("BM_MidFrames", BM_MidFrames)
      ->UseManualTime()
      ->Unit(benchmark::kMillisecond)
      ->Iterations(1);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
